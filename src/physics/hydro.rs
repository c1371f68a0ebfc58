//! The hydro scheme behind one fixed set of pair functions (as SWIFT does): the sweep finds
//! each pair once and calls these for the three SPH sums, so the neighbour loop is written
//! once and the physics once.
//!
//! For a pair (i, j) with separation `dx = r_i − r_j`, distance `r`, kernel value `w = W_ij`
//! and `f = (1/r) dW/dr` (so that ∇_i W_ij = f·dx):
//! 1. density, Eq. (5): ρ_i += m_j W_ij and ρ_j += m_i W_ij;
//! 2. first derivatives, Eq. (10): [`gradient_pair`];
//! 3. right-hand sides, Eq. (7), physical viscosity Eq. (8), and the energy equation:
//!    [`force_pair`].

use crate::lanes::{F64x2, Real};
use crate::physics::artificial_viscosity::ArtificialViscosity;
use crate::physics::pressure_energy::pair_weights;

/// G_αβ = (v_j − v_i)_α f dx_β: particle i adds (m_j/ρ_j) G and particle j adds (m_i/ρ_i) G to
/// its velocity gradient V_αβ of Eq. (10) (the same sign for both, since both the velocity
/// difference and the kernel gradient change sign).
#[inline]
pub fn gradient_pair<const D: usize>(
    dx: &[f64; D],
    f: f64,
    vi: &[f64; D],
    vj: &[f64; D],
) -> [[f64; D]; D] {
    std::array::from_fn(|a| {
        let dv = vj[a] - vi[a];
        std::array::from_fn(|b| dv * f * dx[b])
    })
}

/// What the force sum needs of one partner: `T = f64` for one pair, a [`Real`] with lanes
/// for several pairs' partners side by side.
#[derive(Clone, Copy, Debug)]
pub struct ForceSide<const D: usize, T: Real = f64> {
    pub v: [T; D],
    /// The velocity the artificial viscosity measures ([`av_velocity`]): `v`, or `v`
    /// relative to the circular orbit at the particle's position.
    ///
    /// [`av_velocity`]: crate::physics::artificial_viscosity::av_velocity
    pub v_av: [T; D],
    pub rho: T,
    /// 1/ρ, stored per particle with ρ: the viscous terms take it without a division per
    /// pair (read only with the physical viscosity).
    pub rho_inv: T,
    pub p: T,
    pub cs: T,
    /// The particle's factor on α: Balsara's factor times α_i/α_max with the
    /// Morris–Monaghan switch (1 with neither).
    pub av_scale: T,
    /// Viscous stress S = ν σ (Eq. 9, plus bulk part); zero without physical viscosity.
    pub stress: [[T; D]; D],
    /// Specific internal energy (for the artificial conductivity).
    pub u: T,
    /// (γ − 1) u with the pressure–energy formulation (`p` is then p̄); unused otherwise.
    pub y: T,
}

impl<const D: usize> ForceSide<D> {
    /// `a` in lane 0, `b` in lane 1: two partners side by side (`zip(s, s)`: `s` in both).
    #[inline(always)]
    pub fn zip(a: &Self, b: &Self) -> ForceSide<D, F64x2> {
        let z = |x: f64, y: f64| F64x2::new(x, y);
        ForceSide {
            v: std::array::from_fn(|d| z(a.v[d], b.v[d])),
            v_av: std::array::from_fn(|d| z(a.v_av[d], b.v_av[d])),
            rho: z(a.rho, b.rho),
            rho_inv: z(a.rho_inv, b.rho_inv),
            p: z(a.p, b.p),
            cs: z(a.cs, b.cs),
            av_scale: z(a.av_scale, b.av_scale),
            stress: std::array::from_fn(|r| {
                std::array::from_fn(|c| z(a.stress[r][c], b.stress[r][c]))
            }),
            u: z(a.u, b.u),
            y: z(a.y, b.y),
        }
    }
}

/// Which terms a pair evaluation includes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PairTerms {
    /// Physical viscosity, Eq. (8).
    pub viscous: bool,
    /// The pressure–energy formulation (`physics::pressure_energy`) instead of Eq. (7)'s
    /// pressure term.
    pub pressure_energy: bool,
}

/// One pair's contribution to the right-hand sides, independent of the partners' masses:
/// a_i += m_j `accel`, a_j −= m_i `accel`; du_i += m_j (`work_i` + `heat_i`),
/// du_j += m_i (`work_j` + `heat_j`). The pairwise antisymmetry makes Σ m a = 0 (momentum
/// conservation), and the work and heat terms add up to minus the pair's change of kinetic
/// energy, so d(E_kin + E_int)/dt = 0 exactly.
#[derive(Clone, Copy, Debug)]
pub struct PairForce<const D: usize, T: Real = f64> {
    pub accel: [T; D],
    /// p_i/(ρ_i ρ_j) v_ij·∇_i W_ij: particle i's share of the pressure work, plus the heat
    /// conducted to i (artificial conductivity; −m_i/m_j times j's share, so it adds no
    /// energy).
    pub work_i: T,
    /// p_j/(ρ_i ρ_j) v_ij·∇_i W_ij.
    pub work_j: T,
    /// Dissipation at i: ½ Π_ij v_ij·∇_i W_ij (artificial, shared equally) plus
    /// −S_i : (v_ij ⊗ ∇_i W_ij) / ρ_j (physical, with i's own stress).
    pub heat_i: T,
    pub heat_j: T,
    pub vsig: T,
}

/// Eq. (7) with Monaghan's artificial viscosity Π_ij:
/// dv_i/dt = −Σ_j m_j [(p_i + p_j)/(ρ_i ρ_j) + Π_ij] ∇_i W_ij, and the energy equation in
/// the form that conserves total energy exactly together with Eq. (7):
/// du_i/dt = Σ_j m_j [p_i/(ρ_i ρ_j) + ½ Π_ij] v_ij · ∇_i W_ij.
/// The pressure part is (p_i/ρ_i) Σ_j (m_j/ρ_j) v_ij·∇_i W_ij ≈ −(p_i/ρ_i) ∇·v, the first
/// law for particle i; each partner's work uses its own pressure. (Splitting the pair's
/// work equally, ½ (p_i + p_j)/(ρ_i ρ_j), also conserves energy but heats an expanding cold
/// particle with its hot neighbour's pressure, which traps the energy of a point blast.)
///
/// With `viscous`, physical viscosity, Eq. (8):
/// dv_i/dt += Σ_j m_j (S_j/ρ_i + S_i/ρ_j) · ∇_i W_ij with S = ν σ, σ from Eq. (9), and the
/// viscous work of the pair given to each partner with its own stress:
/// du_i/dt += −Σ_j m_j (S_i/ρ_j) : (v_ij ⊗ ∇_i W_ij) ≈ ν_i σ_i : V_i = ½ ν_i σ_i:σ_i ≥ 0,
/// which conserves total energy exactly (Riffert et al. 1995).
///
/// With `terms.pressure_energy`, the pressure part is Saitoh & Makino's (2013) instead
/// (`physics::pressure_energy`): dv_i/dt = −Σ_j m_j [(γ−1)² u_i u_j (1/p̄_i + 1/p̄_j) + Π_ij]
/// ∇_i W_ij, du_i/dt = Σ_j m_j [(γ−1)² u_i u_j/p̄_i + ½ Π_ij] v_ij·∇_i W_ij.
///
/// With α_u = `av.conductivity` > 0, Price's (2008) artificial conductivity:
/// du_i/dt += Σ_j m_j α_u v_sig,u (u_i − u_j) f r / ρ̄_ij (r̂_ij·∇_i W_ij = f r), with
/// v_sig,u = √(|p_i − p_j| / ρ̄_ij) (or |v_ij·r̂_ij|, `av.conductivity_signal`),
/// ρ̄_ij = (ρ_i + ρ_j)/2; j gets the opposite, so the pair
/// exchanges heat without changing the total energy.
///
/// Over [`Real`]: `T = f64` for one pair, [`crate::lanes::F64x2`] for two pairs at once
/// with, lane by lane, the same results to the bit.
#[inline(always)]
pub fn force_pair<const D: usize, T: Real>(
    dx: &[T; D],
    r: T,
    f: T,
    i: &ForceSide<D, T>,
    j: &ForceSide<D, T>,
    av: &ArtificialViscosity,
    terms: PairTerms,
) -> PairForce<D, T> {
    let zero = T::splat(0.0);
    let mut vdotr = zero;
    for d in 0..D {
        vdotr += (i.v[d] - j.v[d]) * dx[d];
    }
    let mut vdotr_av = zero;
    for d in 0..D {
        vdotr_av += (i.v_av[d] - j.v_av[d]) * dx[d];
    }
    let (pi, vsig) = av.pi(
        vdotr_av,
        r,
        (i.cs, j.cs),
        (i.rho, j.rho),
        T::splat(0.5) * (i.av_scale + j.av_scale),
    );
    let (pterm, work_i, work_j) = if terms.pressure_energy {
        let (a_i, a_j) =
            T::from_fn2(|l| pair_weights(i.y.lane(l), i.p.lane(l), j.y.lane(l), j.p.lane(l)));
        (a_i + a_j, a_i * f * vdotr, a_j * f * vdotr)
    } else {
        let gv = f * vdotr / (i.rho * j.rho);
        ((i.p + j.p) / (i.rho * j.rho), i.p * gv, j.p * gv)
    };
    let coef = -(pterm + pi) * f;
    let heat_av = T::splat(0.5) * pi * f * vdotr;
    let mut out = PairForce {
        accel: std::array::from_fn(|d| coef * dx[d]),
        work_i,
        work_j,
        heat_i: heat_av,
        heat_j: heat_av,
        vsig,
    };
    if av.conductivity > 0.0 {
        let rho_mean = T::splat(0.5) * (i.rho + j.rho);
        let vsig_u = T::from_fn(|l| {
            av.conductivity_signal.speed(
                i.p.lane(l),
                j.p.lane(l),
                rho_mean.lane(l),
                vdotr.lane(l),
                r.lane(l),
            )
        });
        let cond = T::splat(av.conductivity) * vsig_u * (i.u - j.u) * f * r / rho_mean;
        out.work_i += cond;
        out.work_j -= cond;
    }
    if terms.viscous {
        // With the stresses applied to ∇_i W_ij first, S_i·∇W and S_j·∇W, each partner's
        // force and heat are dot products of these: 72 flops per pair in 3D, where summing
        // (S_j/ρ_i + S_i/ρ_j)_αβ ∇_β W and S_αβ v_α ∇_β W entry by entry takes 114.
        let g: [T; D] = std::array::from_fn(|d| f * dx[d]);
        let (inv_i, inv_j) = (i.rho_inv, j.rho_inv);
        let (mut si_g, mut sj_g) = ([zero; D], [zero; D]);
        for a in 0..D {
            for b in 0..D {
                si_g[a] += i.stress[a][b] * g[b];
                sj_g[a] += j.stress[a][b] * g[b];
            }
        }
        let (mut si_vg, mut sj_vg) = (zero, zero);
        for a in 0..D {
            let va = i.v[a] - j.v[a];
            out.accel[a] += sj_g[a] * inv_i + si_g[a] * inv_j;
            si_vg += va * si_g[a];
            sj_vg += va * sj_g[a];
        }
        out.heat_i -= si_vg * inv_j;
        out.heat_j -= sj_vg * inv_i;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernel::Kernel;

    fn side(v: [f64; 2], rho: f64, p: f64, stress: [[f64; 2]; 2]) -> ForceSide<2> {
        ForceSide {
            v,
            v_av: v,
            rho,
            rho_inv: 1.0 / rho,
            p,
            cs: 1.0,
            av_scale: 1.0,
            stress,
            u: 1.5 * p / rho,
            y: p / rho,
        }
    }

    const PLAIN: PairTerms = PairTerms {
        viscous: false,
        pressure_energy: false,
    };

    /// A partner in 3D with every field drawn at random (p ≥ 0, ρ > 0).
    fn random_side(rng: &mut crate::rng::Rng) -> ForceSide<3> {
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        let rho = u(0.2, 3.0);
        let p = if u(0.0, 1.0) < 0.1 { 0.0 } else { u(0.0, 2.0) };
        ForceSide {
            v: [u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)],
            v_av: [u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0)],
            rho,
            rho_inv: 1.0 / rho,
            p,
            cs: u(0.1, 2.0),
            av_scale: u(0.0, 1.0),
            stress: std::array::from_fn(|_| std::array::from_fn(|_| u(-0.5, 0.5))),
            u: u(0.1, 3.0),
            y: u(0.0, 2.0),
        }
    }

    fn bits<const D: usize>(pf: &PairForce<D>) -> Vec<u64> {
        let mut out: Vec<u64> = pf.accel.iter().map(|a| a.to_bits()).collect();
        out.extend([pf.work_i, pf.work_j, pf.heat_i, pf.heat_j, pf.vsig].map(f64::to_bits));
        out
    }

    fn lane<const D: usize>(pf: &PairForce<D, F64x2>, l: usize) -> PairForce<D> {
        PairForce {
            accel: pf.accel.map(|a| a.lane(l)),
            work_i: pf.work_i.lane(l),
            work_j: pf.work_j.lane(l),
            heat_i: pf.heat_i.lane(l),
            heat_j: pf.heat_j.lane(l),
            vsig: pf.vsig.lane(l),
        }
    }

    /// The force sum takes its pairs two at a time in the lanes of `F64x2`: each lane must
    /// be the scalar evaluation of its pair to the bit, with every term on, for
    /// approaching and receding pairs, zero pressures and a pair at zero distance.
    #[test]
    fn force_pair_in_lanes_is_the_scalar_force_to_the_bit() {
        use crate::physics::artificial_viscosity::ConductivitySignal;
        let mut rng = crate::rng::Rng::new(7);
        let k = Kernel::<3>::new(0.5);
        let mut avs = Vec::new();
        for (alpha, conductivity, signal) in [
            (1.0, 0.0, ConductivitySignal::Pressure),
            (0.0, 0.0, ConductivitySignal::Pressure),
            (1.0, 1.0, ConductivitySignal::Pressure),
            (0.5, 0.7, ConductivitySignal::Velocity),
        ] {
            avs.push(ArtificialViscosity {
                alpha,
                beta: 2.0 * alpha,
                conductivity,
                conductivity_signal: signal,
                ..ArtificialViscosity::default()
            });
        }
        let mut compared = 0;
        for trial in 0..400 {
            let i = random_side(&mut rng);
            let (j0, j1) = (random_side(&mut rng), random_side(&mut rng));
            let dx: [[f64; 3]; 2] = std::array::from_fn(|l| {
                if trial % 50 == 0 && l == 1 {
                    [0.0; 3]
                } else {
                    std::array::from_fn(|_| 0.6 * rng.uniform() - 0.3)
                }
            });
            let r = dx.map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
            let f = r.map(|r| k.f(r));
            let dx2: [F64x2; 3] = std::array::from_fn(|d| F64x2::new(dx[0][d], dx[1][d]));
            let (r2, f2) = (F64x2::new(r[0], r[1]), F64x2::new(f[0], f[1]));
            let (si, sj) = (ForceSide::zip(&i, &i), ForceSide::zip(&j0, &j1));
            for av in &avs {
                for (viscous, pressure_energy) in
                    [(false, false), (true, false), (false, true), (true, true)]
                {
                    let terms = PairTerms {
                        viscous,
                        pressure_energy,
                    };
                    let both = force_pair(&dx2, r2, f2, &si, &sj, av, terms);
                    for (l, j) in [j0, j1].iter().enumerate() {
                        let one = force_pair(&dx[l], r[l], f[l], &i, j, av, terms);
                        assert_eq!(
                            bits(&lane(&both, l)),
                            bits(&one),
                            "lane {l}, trial {trial}, {terms:?}, {av:?}"
                        );
                        compared += 1;
                    }
                }
            }
        }
        assert_eq!(compared, 400 * 4 * 4 * 2);
    }

    #[test]
    fn pair_force_conserves_momentum_and_energy() {
        let k = Kernel::<2>::new(0.5);
        let (xi, xj): ([f64; 2], [f64; 2]) = ([0.1, 0.2], [0.4, -0.1]);
        let dx = [xi[0] - xj[0], xi[1] - xj[1]];
        let r = (dx[0] * dx[0] + dx[1] * dx[1]).sqrt();
        let (mi, mj) = (1.3, 0.7);
        let a = side([1.0, -0.5], 1.1, 2.0, [[0.3, -0.2], [-0.2, -0.3]]);
        let b = side([-0.3, 0.4], 0.8, 1.5, [[-0.1, 0.5], [0.5, 0.1]]);
        let mut av = ArtificialViscosity::for_shocks();
        av.conductivity = 1.0;
        for (viscous, pressure_energy) in
            [(false, false), (true, false), (false, true), (true, true)]
        {
            let terms = PairTerms {
                viscous,
                pressure_energy,
            };
            let pf = force_pair(&dx, r, k.f(r), &a, &b, &av, terms);
            // dE/dt = m_i v_i·a_i + m_j v_j·a_j + m_i du_i + m_j du_j = 0.
            let mut de = 0.0;
            for d in 0..2 {
                de += mi * a.v[d] * (mj * pf.accel[d]) - mj * b.v[d] * (mi * pf.accel[d]);
            }
            de += mi * mj * (pf.work_i + pf.heat_i) + mj * mi * (pf.work_j + pf.heat_j);
            assert!(de.abs() < 1e-12, "{terms:?}: {de}");
        }
        let pf = force_pair(&dx, r, k.f(r), &a, &b, &av, PLAIN);
        assert!(pf.heat_i > 0.0, "approaching pair must heat");
    }

    #[test]
    fn conductivity_moves_heat_from_hot_to_cold_and_only_where_pressure_differs() {
        let k = Kernel::<2>::new(0.5);
        let (dx, r) = ([0.3, 0.0], 0.3);
        let cond = ArtificialViscosity {
            conductivity: 1.0,
            ..ArtificialViscosity::default()
        };
        let off = ArtificialViscosity::default();
        // At rest: no pressure work, only the conducted heat.
        let (hot, cold) = (
            side([0.0; 2], 1.0, 2.0, [[0.0; 2]; 2]),
            side([0.0; 2], 1.0, 1.0, [[0.0; 2]; 2]),
        );
        let pf = force_pair(&dx, r, k.f(r), &hot, &cold, &cond, PLAIN);
        assert!(
            pf.work_i < 0.0 && pf.work_j > 0.0,
            "{} {}",
            pf.work_i,
            pf.work_j
        );
        // m_i du_i + m_j du_j = m_i m_j (work_i + work_j) = 0.
        assert_eq!(pf.work_i + pf.work_j, 0.0);
        let none = force_pair(&dx, r, k.f(r), &hot, &cold, &off, PLAIN);
        assert_eq!((none.work_i, none.work_j), (0.0, 0.0));
        // A contact in pressure balance: u differs, p does not, nothing flows.
        let mut dense = side([0.0; 2], 8.0, 1.0, [[0.0; 2]; 2]);
        dense.u = 1.5 / 8.0;
        let pf = force_pair(&dx, r, k.f(r), &cold, &dense, &cond, PLAIN);
        assert_eq!((pf.work_i, pf.work_j), (0.0, 0.0));
        // The velocity signal: at rest nothing flows whatever the pressures; approaching or
        // receding, heat flows from hot to cold at |v_ij·r̂_ij|.
        let by_velocity = ArtificialViscosity {
            conductivity_signal: crate::physics::artificial_viscosity::ConductivitySignal::Velocity,
            ..cond
        };
        let pf = force_pair(&dx, r, k.f(r), &hot, &cold, &by_velocity, PLAIN);
        assert_eq!((pf.work_i, pf.work_j), (0.0, 0.0));
        for vx in [-0.5, 0.5] {
            let moving = side([vx, 0.0], 1.0, 2.0, [[0.0; 2]; 2]);
            let pf = force_pair(&dx, r, k.f(r), &moving, &cold, &by_velocity, PLAIN);
            let none = force_pair(&dx, r, k.f(r), &moving, &cold, &off, PLAIN);
            let (ci, cj) = (pf.work_i - none.work_i, pf.work_j - none.work_j);
            assert!(ci < 0.0 && (ci + cj).abs() < 1e-15, "{ci} {cj}");
        }
    }

    #[test]
    fn pressure_energy_pair_matches_eq7_where_the_gas_is_uniform() {
        // Same ρ and u on both sides: p̄ = (γ − 1) ρ u, and the two formulations agree term
        // by term (physics::pressure_energy); they differ only where ρ or u vary.
        let k = Kernel::<2>::new(0.5);
        let (dx, r) = ([0.2, -0.1], (0.05f64).sqrt());
        let (rho, u, gamma) = (1.3, 2.0, 5.0 / 3.0);
        let p = (gamma - 1.0) * rho * u;
        let mut a = side([0.4, 0.1], rho, p, [[0.0; 2]; 2]);
        let mut b = side([-0.2, 0.3], rho, p, [[0.0; 2]; 2]);
        for s in [&mut a, &mut b] {
            s.u = u;
            s.y = (gamma - 1.0) * u;
        }
        let av = ArtificialViscosity::for_shocks();
        let de = force_pair(&dx, r, k.f(r), &a, &b, &av, PLAIN);
        let pe = force_pair(
            &dx,
            r,
            k.f(r),
            &a,
            &b,
            &av,
            PairTerms {
                pressure_energy: true,
                ..PLAIN
            },
        );
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-13 * x.abs().max(y.abs());
        for d in 0..2 {
            assert!(close(de.accel[d], pe.accel[d]), "{de:?} {pe:?}");
        }
        assert!(close(de.work_i, pe.work_i) && close(de.work_j, pe.work_j));
    }
}
