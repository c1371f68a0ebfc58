//! The dimension-free particle snapshot: what an HDF5 snapshot file holds, in memory. Written
//! from `Particles<D>` at output times, read back by `render`, `analyse` and `run --from`.
//! Coordinates and velocities are always three columns (SWIFT's convention); the ones beyond
//! the run's dimension are zero.

use crate::particles::Particles;

/// One snapshot: the gas particles with their state, the box, the time, and any point masses.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Snapshot {
    /// 1, 2 or 3: the dimension of the run (2D: `rho` is the surface density Σ).
    pub dimension: usize,
    pub time: f64,
    /// Step number at which the snapshot was written.
    pub step: u64,
    /// Lower and upper corners of the simulation box (unused axes: 0 and 1).
    pub box_lo: [f64; 3],
    pub box_hi: [f64; 3],
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
    /// Point masses (central star, binary components): position and mass.
    pub point_masses: Vec<PointMassRecord>,
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
        let mut box_lo = [0.0; 3];
        let mut box_hi = [1.0; 3];
        box_lo[..D].copy_from_slice(&lo);
        box_hi[..D].copy_from_slice(&hi);
        Self {
            dimension: D,
            time,
            step,
            box_lo,
            box_hi,
            id: p.id.clone(),
            pos: pad(&p.pos),
            vel: pad(&p.vel),
            mass: p.mass.clone(),
            h: vec![h; n],
            rho: p.rho.clone(),
            u: p.u.clone(),
            p: p.p.clone(),
            diss: p.diss.clone(),
            point_masses: Vec::new(),
        }
    }
}
