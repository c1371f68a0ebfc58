//! The particle store: structure-of-arrays `Vec<f64>`s for every per-particle quantity, and
//! the conserved totals (mass, momentum, angular momentum, energy) computed from them.

use crate::physics::gravity::PointMass;

/// All real (time-integrated) particles of one process, in structure-of-arrays layout.
///
/// Primary state (`pos`, `vel`, `mass`, `u`) is integrated in time; everything else is
/// recomputed by each right-hand-side evaluation (the sweep).
#[derive(Clone, Debug)]
pub struct Particles<const D: usize> {
    /// Stable 64-bit particle identifiers; never reused within a run.
    pub id: Vec<u64>,
    pub pos: [Vec<f64>; D],
    pub vel: [Vec<f64>; D],
    pub mass: Vec<f64>,
    /// Specific internal energy e_i.
    pub u: Vec<f64>,
    /// The particle's own artificial-viscosity coefficient α_i, integrated in time with the
    /// Morris–Monaghan switch (`physics::av_switch`); unused with a constant α.
    pub alpha: Vec<f64>,
    /// Density by summation, Eq. (5).
    pub rho: Vec<f64>,
    pub p: Vec<f64>,
    /// Sound speed.
    pub cs: Vec<f64>,
    /// Acceleration dv/dt: Eq. (7) plus artificial (and, later, physical) viscosity.
    pub acc: [Vec<f64>; D],
    /// du/dt from the energy equation (pressure work + viscous heating).
    pub du: Vec<f64>,
    /// Specific dissipation rate: the viscous heating part of du/dt (energy / mass / time).
    pub diss: Vec<f64>,
    /// Largest signal velocity over the particle's neighbours (time-step control).
    pub vsig: Vec<f64>,
    /// Velocity gradient V_αβ = ∂v_α/∂x_β of Eq. (10), stored `vgrad[α][β][i]`.
    pub vgrad: [[Vec<f64>; D]; D],
    /// Kinematic shear viscosity ν used in the last evaluation (0 without viscosity).
    pub nu: Vec<f64>,
    /// Number of neighbours each particle interacted with in the last evaluation.
    pub interactions: Vec<u32>,
}

fn vecs<const N: usize>() -> [Vec<f64>; N] {
    std::array::from_fn(|_| Vec::new())
}

impl<const D: usize> Default for Particles<D> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const D: usize> Particles<D> {
    pub fn new() -> Self {
        Self {
            id: Vec::new(),
            pos: vecs(),
            vel: vecs(),
            mass: Vec::new(),
            u: Vec::new(),
            alpha: Vec::new(),
            rho: Vec::new(),
            p: Vec::new(),
            cs: Vec::new(),
            acc: vecs(),
            du: Vec::new(),
            diss: Vec::new(),
            vsig: Vec::new(),
            vgrad: std::array::from_fn(|_| vecs()),
            nu: Vec::new(),
            interactions: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// The per-particle scalars an evaluation recomputes (ρ, p, c_s, du/dt, dissipation,
    /// v_sig, ν), for operations that treat them all alike.
    fn derived_scalars_mut(&mut self) -> [&mut Vec<f64>; 7] {
        [
            &mut self.rho,
            &mut self.p,
            &mut self.cs,
            &mut self.du,
            &mut self.diss,
            &mut self.vsig,
            &mut self.nu,
        ]
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Appends a particle; derived quantities start at zero, and so does α (a switch
    /// raises it to α_min at the particle's first step; a run's set-up starts every
    /// particle at α_max).
    pub fn push(&mut self, id: u64, pos: [f64; D], vel: [f64; D], mass: f64, u: f64) {
        self.id.push(id);
        for d in 0..D {
            self.pos[d].push(pos[d]);
            self.vel[d].push(vel[d]);
            self.acc[d].push(0.0);
            for b in 0..D {
                self.vgrad[d][b].push(0.0);
            }
        }
        self.mass.push(mass);
        self.u.push(u);
        self.alpha.push(0.0);
        for v in self.derived_scalars_mut() {
            v.push(0.0);
        }
        self.interactions.push(0);
    }

    pub fn position(&self, i: usize) -> [f64; D] {
        std::array::from_fn(|d| self.pos[d][i])
    }

    pub fn velocity(&self, i: usize) -> [f64; D] {
        std::array::from_fn(|d| self.vel[d][i])
    }

    /// Mass, momentum, angular momentum and energy of the whole set, with the potential
    /// energy in the field of `gravity` if given.
    pub fn totals(&self, gravity: Option<&PointMass>) -> Totals<D> {
        let mut t = Totals {
            mass: 0.0,
            momentum: [0.0; D],
            momentum_scale: 0.0,
            angular_momentum: 0.0,
            kinetic: 0.0,
            internal: 0.0,
            potential: 0.0,
        };
        for i in 0..self.len() {
            let m = self.mass[i];
            let mut v2 = 0.0;
            for d in 0..D {
                let v = self.vel[d][i];
                t.momentum[d] += m * v;
                v2 += v * v;
            }
            t.momentum_scale += m * v2.sqrt();
            t.mass += m;
            t.kinetic += 0.5 * m * v2;
            t.internal += m * self.u[i];
            t.angular_momentum += m * self.angular_momentum_z(i);
            if let Some(g) = gravity {
                t.potential += m * g.potential(&self.position(i));
            }
        }
        t
    }

    /// Specific angular momentum about the z axis, x v_y − y v_x (0 in 1D).
    #[inline]
    pub fn angular_momentum_z(&self, i: usize) -> f64 {
        if D < 2 {
            0.0
        } else {
            self.pos[0][i] * self.vel[1][i] - self.pos[1][i] * self.vel[0][i]
        }
    }

    /// Every `f64` array with a name (`pos0`, `vgrad01`, `rho`, …), primary and derived: what a
    /// checkpoint must hold for a restart to continue bit for bit.
    pub fn named_arrays_mut(&mut self) -> Vec<(String, &mut Vec<f64>)> {
        let mut out: Vec<(String, &mut Vec<f64>)> = Vec::new();
        for (d, v) in self.pos.iter_mut().enumerate() {
            out.push((format!("pos{d}"), v));
        }
        for (d, v) in self.vel.iter_mut().enumerate() {
            out.push((format!("vel{d}"), v));
        }
        for (d, v) in self.acc.iter_mut().enumerate() {
            out.push((format!("acc{d}"), v));
        }
        for (a, row) in self.vgrad.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                out.push((format!("vgrad{a}{b}"), v));
            }
        }
        let scalars = [
            ("mass", &mut self.mass),
            ("u", &mut self.u),
            ("alpha", &mut self.alpha),
            ("rho", &mut self.rho),
            ("p", &mut self.p),
            ("cs", &mut self.cs),
            ("du", &mut self.du),
            ("diss", &mut self.diss),
            ("vsig", &mut self.vsig),
            ("nu", &mut self.nu),
        ];
        out.extend(scalars.into_iter().map(|(k, v)| (k.to_string(), v)));
        out
    }

    /// Number of values [`Particles::state_of`] writes per particle.
    pub const STATE_LEN: usize = 2 + 3 * D + D * D + 10;

    /// Appends particle `i`'s whole state to `out`: id (as bits), interactions, then every
    /// array in [`Particles::named_arrays_mut`] order. For moving particles between ranks.
    pub fn state_of(&self, i: usize, out: &mut Vec<f64>) {
        out.push(f64::from_bits(self.id[i]));
        out.push(self.interactions[i] as f64);
        out.extend((0..D).map(|d| self.pos[d][i]));
        out.extend((0..D).map(|d| self.vel[d][i]));
        out.extend((0..D).map(|d| self.acc[d][i]));
        for a in 0..D {
            out.extend((0..D).map(|b| self.vgrad[a][b][i]));
        }
        out.extend([
            self.mass[i],
            self.u[i],
            self.alpha[i],
            self.rho[i],
            self.p[i],
            self.cs[i],
            self.du[i],
            self.diss[i],
            self.vsig[i],
            self.nu[i],
        ]);
    }

    /// Appends the particles whose states [`Particles::state_of`] wrote into `buf`.
    pub fn push_states(&mut self, buf: &[f64]) {
        let rows = || buf.chunks_exact(Self::STATE_LEN);
        self.id.extend(rows().map(|c| c[0].to_bits()));
        self.interactions.extend(rows().map(|c| c[1] as u32));
        for (k, (_, arr)) in self.named_arrays_mut().into_iter().enumerate() {
            arr.extend(rows().map(|c| c[2 + k]));
        }
    }

    /// Keeps the particles with `keep[i]` true, in order, in every array.
    pub fn retain(&mut self, keep: &[bool]) {
        retain_by(&mut self.id, keep);
        for d in 0..D {
            retain_by(&mut self.pos[d], keep);
            retain_by(&mut self.vel[d], keep);
            retain_by(&mut self.acc[d], keep);
            for b in 0..D {
                retain_by(&mut self.vgrad[d][b], keep);
            }
        }
        retain_by(&mut self.mass, keep);
        retain_by(&mut self.u, keep);
        retain_by(&mut self.alpha, keep);
        for v in self.derived_scalars_mut() {
            retain_by(v, keep);
        }
        retain_by(&mut self.interactions, keep);
    }
}

/// Keeps the entries of `v` with `keep[i]` true, in order.
pub fn retain_by<T>(v: &mut Vec<T>, keep: &[bool]) {
    let mut k = 0;
    v.retain(|_| {
        k += 1;
        keep[k - 1]
    });
}

/// Conserved totals of a particle set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Totals<const D: usize> {
    pub mass: f64,
    pub momentum: [f64; D],
    /// Σ m|v|: the scale against which a momentum change is relative (the total momentum
    /// itself may be zero).
    pub momentum_scale: f64,
    /// Σ m (x v_y − y v_x).
    pub angular_momentum: f64,
    pub kinetic: f64,
    pub internal: f64,
    /// Σ m Φ in the external field (0 without one).
    pub potential: f64,
}

impl<const D: usize> Totals<D> {
    /// Kinetic + internal + potential energy.
    pub fn energy(&self) -> f64 {
        self.kinetic + self.internal + self.potential
    }

    /// Relative drifts of `self` against a reference `start`: (mass, momentum, energy).
    /// Momentum is relative to the start's Σ m|v| (or the end's, if larger).
    pub fn drift_from(&self, start: &Totals<D>) -> (f64, f64, f64) {
        let dm = (self.mass - start.mass).abs() / start.mass.abs().max(f64::MIN_POSITIVE);
        let dp2: f64 = (0..D)
            .map(|d| (self.momentum[d] - start.momentum[d]).powi(2))
            .sum();
        let pscale = start.momentum_scale.max(self.momentum_scale);
        let dp = if pscale > 0.0 {
            dp2.sqrt() / pscale
        } else {
            0.0
        };
        let e0 = start.energy();
        let de = (self.energy() - e0).abs() / e0.abs().max(f64::MIN_POSITIVE);
        (dm, dp, de)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn totals_sum_mass_momentum_energy() {
        let mut p = Particles::<2>::new();
        p.push(0, [0.0, 0.0], [1.0, 0.0], 2.0, 0.5);
        p.push(1, [1.0, 0.0], [-1.0, 2.0], 1.0, 1.0);
        let t = p.totals(None);
        assert_eq!(t.mass, 3.0);
        assert_eq!(t.angular_momentum, 1.0 * 2.0);
        assert_eq!(t.momentum, [1.0, 2.0]);
        assert_eq!(t.kinetic, 0.5 * 2.0 + 0.5 * 5.0);
        assert_eq!(t.internal, 2.0);
        let (dm, dp, de) = t.drift_from(&t);
        assert_eq!((dm, dp, de), (0.0, 0.0, 0.0));
    }

    #[test]
    fn retain_keeps_every_array_aligned() {
        let mut p = Particles::<2>::new();
        for i in 0..5 {
            p.push(i, [i as f64, 0.0], [0.0, i as f64], 1.0 + i as f64, 0.0);
        }
        p.retain(&[true, false, true, false, true]);
        assert_eq!(p.id, vec![0, 2, 4]);
        assert_eq!(p.pos[0], vec![0.0, 2.0, 4.0]);
        assert_eq!(p.vel[1], vec![0.0, 2.0, 4.0]);
        assert_eq!(p.mass, vec![1.0, 3.0, 5.0]);
        assert_eq!(p.nu.len(), 3);
    }

    #[test]
    fn state_round_trips_every_array() {
        let mut p = Particles::<3>::new();
        for i in 0..3 {
            p.push(
                i,
                [i as f64, 1.0, 2.0],
                [3.0, 4.0, i as f64],
                1.0 + i as f64,
                0.5,
            );
        }
        for (k, (_, v)) in p.named_arrays_mut().into_iter().enumerate() {
            for (i, x) in v.iter_mut().enumerate() {
                *x = (100 * k + i) as f64;
            }
        }
        p.interactions = vec![7, 8, 9];
        let mut buf = Vec::new();
        for i in 0..3 {
            p.state_of(i, &mut buf);
        }
        assert_eq!(buf.len(), 3 * Particles::<3>::STATE_LEN);
        let mut q = Particles::<3>::new();
        q.push_states(&buf);
        assert_eq!(q.id, p.id);
        assert_eq!(q.interactions, p.interactions);
        let (a, b) = (p.named_arrays_mut(), q.named_arrays_mut());
        for ((_, x), (_, y)) in a.iter().zip(b.iter()) {
            assert_eq!(x, y);
        }
    }
}
