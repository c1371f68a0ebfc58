//! The dimension-free particle snapshot: what an HDF5 snapshot file holds, in memory. Written
//! from `Particles<D>` at output times, read back by `render`, `analyse` and `run --from`.
//! Coordinates and velocities are always three columns (SWIFT's convention); the ones beyond
//! the run's dimension are zero. As in SWIFT, coordinates are stored in a box that starts at
//! the origin, `[0, BoxSize]`, which yt and swiftsimio assume: a run whose box starts
//! elsewhere is shifted by `shift` (file position = run position + shift), and
//! `to_particles` shifts back (exact to the last bit when the box starts at 0, else to
//! round-off of the coordinates).

use anyhow::{Result, bail};

use crate::kernel::KernelKind;
use crate::particles::Particles;

/// One snapshot: the gas particles with their state, the box, the time, and any point masses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// 1, 2 or 3: the dimension of the run (2D: `rho` is the surface density Σ).
    pub dimension: usize,
    pub time: f64,
    /// Step number at which the snapshot was written.
    pub step: u64,
    /// Lower and upper corners of the simulation box in the file's frame (unused axes: 0
    /// and 1); `box_lo` is 0 for snapshots written by sphdisk.
    pub box_lo: [f64; 3],
    pub box_hi: [f64; 3],
    /// What was added to the run's positions (SWIFT's `Header/Shift`): −(run box corner).
    pub shift: [f64; 3],
    pub id: Vec<u64>,
    pub pos: [Vec<f64>; 3],
    pub vel: [Vec<f64>; 3],
    pub mass: Vec<f64>,
    /// Smoothing length h (kernel support 2h), per particle.
    pub h: Vec<f64>,
    pub rho: Vec<f64>,
    /// Specific internal energy.
    pub u: Vec<f64>,
    pub p: Vec<f64>,
    /// Specific viscous dissipation rate (energy / mass / time).
    pub diss: Vec<f64>,
    /// Each particle's artificial-viscosity α from a switch (`ViscosityParameters`, as
    /// SWIFT's SPHENIX names it); empty when the run had none.
    pub alpha: Vec<f64>,
    /// Point masses (central star, binary components): position and mass.
    pub point_masses: Vec<PointMassRecord>,
    /// The kernel the run used (`particles.kernel`; SWIFT's `/HydroScheme` names it):
    /// pictures spread each particle with it.
    pub kernel: KernelKind,
}

/// A point mass as stored in a snapshot (SWIFT particle type 4 would be stars; we use type 3).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PointMassRecord {
    pub id: u64,
    pub pos: [f64; 3],
    pub vel: [f64; 3],
    pub mass: f64,
}

impl Snapshot {
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// The snapshot of `p` (smoothing length `h`, box corners `lo`, `hi`) at `time`.
    pub fn from_particles<const D: usize>(
        p: &Particles<D>,
        h: f64,
        lo: [f64; D],
        hi: [f64; D],
        time: f64,
        step: u64,
    ) -> Self {
        let n = p.len();
        let pad = |v: &[Vec<f64>; D]| -> [Vec<f64>; 3] {
            std::array::from_fn(|d| if d < D { v[d].clone() } else { vec![0.0; n] })
        };
        let mut shift = [0.0; 3];
        let mut box_hi = [1.0; 3];
        for d in 0..D {
            shift[d] = -lo[d];
            box_hi[d] = hi[d] - lo[d];
        }
        let pos = std::array::from_fn(|d| {
            if d < D {
                p.pos[d].iter().map(|x| x + shift[d]).collect()
            } else {
                vec![0.0; n]
            }
        });
        Self {
            dimension: D,
            time,
            step,
            box_lo: [0.0; 3],
            box_hi,
            shift,
            id: p.id.clone(),
            pos,
            vel: pad(&p.vel),
            mass: p.mass.clone(),
            h: vec![h; n],
            rho: p.rho.clone(),
            u: p.u.clone(),
            p: p.p.clone(),
            diss: p.diss.clone(),
            alpha: Vec::new(),
            point_masses: Vec::new(),
            // The caller knows the run's kernel (`Simulation::snapshot` sets it).
            kernel: KernelKind::default(),
        }
    }

    /// The gas particles as `Particles<D>` (primary state, and ρ, p, dissipation as stored);
    /// refuses a snapshot of another dimension.
    pub fn to_particles<const D: usize>(&self) -> Result<Particles<D>> {
        if self.dimension != D {
            bail!(
                "the snapshot is {}D but the problem is {D}D (key `problem.dimension`)",
                self.dimension
            );
        }
        let mut p = Particles::new();
        for i in 0..self.len() {
            let x = std::array::from_fn(|d| self.pos[d][i] - self.shift[d]);
            let v = std::array::from_fn(|d| self.vel[d][i]);
            p.push(self.id[i], x, v, self.mass[i], self.u[i]);
        }
        p.rho.clone_from(&self.rho);
        p.p.clone_from(&self.p);
        p.diss.clone_from(&self.diss);
        Ok(p)
    }

    /// Refuses what no run writes, naming the dataset and the first particle at fault:
    /// coordinates, velocities, densities, internal energies, pressures or dissipation
    /// rates that are not finite, masses that are not positive, smoothing lengths, densities
    /// or internal energies below 0, an id twice; a box, shift or time that is not finite.
    /// (GADGET initial conditions without smoothing lengths or densities read as 0.)
    pub fn validate(&self) -> Result<()> {
        let names = ["x", "y", "z"];
        for a in 0..3 {
            let side = self.box_hi[a] - self.box_lo[a];
            if !(side > 0.0 && side.is_finite()) {
                bail!(
                    "Header/BoxSize: side {side} along {} is not a positive number",
                    names[a]
                );
            }
            if !self.shift[a].is_finite() {
                bail!(
                    "Header/Shift: {} along {} is not finite",
                    self.shift[a],
                    names[a]
                );
            }
        }
        if !self.time.is_finite() {
            bail!("Header/Time: {} is not finite", self.time);
        }
        type Check = fn(f64) -> bool;
        let finite: Check = f64::is_finite;
        let positive: Check = |x| x > 0.0 && x.is_finite();
        let non_negative: Check = |x| x >= 0.0 && x.is_finite();
        let columns: [(&str, &[f64], Check, &str); 14] = [
            ("Coordinates (x)", &self.pos[0], finite, "finite"),
            ("Coordinates (y)", &self.pos[1], finite, "finite"),
            ("Coordinates (z)", &self.pos[2], finite, "finite"),
            ("Velocities (x)", &self.vel[0], finite, "finite"),
            ("Velocities (y)", &self.vel[1], finite, "finite"),
            ("Velocities (z)", &self.vel[2], finite, "finite"),
            ("Masses", &self.mass, positive, "> 0"),
            ("SmoothingLengths", &self.h, non_negative, "≥ 0"),
            ("Densities", &self.rho, non_negative, "≥ 0"),
            ("InternalEnergies", &self.u, non_negative, "≥ 0"),
            ("Pressures", &self.p, finite, "finite"),
            ("DissipationRates", &self.diss, finite, "finite"),
            ("ViscosityParameters", &self.alpha, non_negative, "≥ 0"),
            ("ParticleIDs", &[], finite, ""),
        ];
        if !self.alpha.is_empty() && self.alpha.len() != self.len() {
            bail!(
                "PartType0/ViscosityParameters: {} entries for {} particles",
                self.alpha.len(),
                self.len()
            );
        }
        for (name, v, ok, what) in columns {
            if let Some(i) = v.iter().position(|&x| !ok(x)) {
                bail!(
                    "PartType0/{name}: particle {} has {}, expected {what}",
                    self.id.get(i).copied().unwrap_or(i as u64),
                    v[i]
                );
            }
        }
        let mut ids = self.id.clone();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            bail!("PartType0/ParticleIDs: id {} appears twice", w[0]);
        }
        Ok(())
    }

    /// [`Snapshot::validate`] and a positive smoothing length on every particle, which a
    /// picture or an analysis interpolates with.
    pub fn validate_for_interpolation(&self) -> Result<()> {
        self.validate()?;
        if let Some(i) = self.h.iter().position(|&h| !(h > 0.0)) {
            bail!(
                "PartType0/SmoothingLengths: particle {} has {}, expected > 0",
                self.id[i],
                self.h[i]
            );
        }
        Ok(())
    }

    /// The snapshot in the run's own frame (positions and box shifted back by `shift`), for
    /// pictures whose axes should read as the problem file's coordinates.
    pub fn in_run_frame(mut self) -> Self {
        for a in 0..3 {
            let s = self.shift[a];
            if s != 0.0 {
                self.pos[a].iter_mut().for_each(|x| *x -= s);
                self.box_lo[a] -= s;
                self.box_hi[a] -= s;
                for pm in &mut self.point_masses {
                    pm.pos[a] -= s;
                }
            }
        }
        self.shift = [0.0; 3];
        self
    }
}
