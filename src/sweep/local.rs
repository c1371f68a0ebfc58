//! The working set of one evaluation: real particles and their ghosts, copied in cell order
//! (x-major, so every x-slab is a contiguous range), with the per-particle accumulators.

use rayon::prelude::*;

use crate::boundary::{Ghost, SimBox, make_ghosts};
use crate::grid::{CellIndex, Grid};
use crate::particles::{Particles, retain_by};
use crate::physics::artificial_viscosity::ArtificialViscosity;

/// Per-particle accumulators of the three sums. Kept apart from [`Local`] so that the sums can
/// write them in parallel while reading the particles' state.
#[derive(Clone, Copy, Debug)]
pub struct Work<const D: usize> {
    /// Σ m_j W_ij without the self term.
    pub rho: f64,
    /// Σ m_j u_j W_ij without the self term (the pressure–energy formulation's p̄).
    pub mu_w: f64,
    /// Σ of Eq. (10).
    pub grad: [[f64; D]; D],
    pub acc: [f64; D],
    pub du: f64,
    pub diss: f64,
    pub vsig: f64,
    pub interactions: u32,
}

impl<const D: usize> Default for Work<D> {
    fn default() -> Self {
        Self {
            rho: 0.0,
            mu_w: 0.0,
            grad: [[0.0; D]; D],
            acc: [0.0; D],
            du: 0.0,
            diss: 0.0,
            vsig: 0.0,
            interactions: 0,
        }
    }
}

/// Pair classes of a local particle: a pair is evaluated unless both partners share a class
/// bit (`IMAGE`: both are boundary images; `AWAY`: both lie in other ranks' regions) or
/// either is `NO_PAIR`.
pub mod class {
    /// A boundary image (periodic or mirror ghost).
    pub const IMAGE: u8 = 1;
    /// Lies in a higher rank's region (a rank ghost, paper 2.3): pairs only with particles
    /// of this rank's region.
    pub const AWAY: u8 = 2;
    /// Lies in a lower rank's region: every pair of it is evaluated there.
    pub const NO_PAIR: u8 = 4;

    #[inline]
    pub fn pairs(a: u8, b: u8) -> bool {
        (a & b) == 0 && ((a | b) & NO_PAIR) == 0
    }

    /// The bits a partner of class `a` must not have: `b` pairs with `a` when
    /// `b & excluded(a) == 0` ([`pairs`] as one test per candidate). `None`: `a` pairs
    /// with nothing.
    #[inline]
    pub fn excluded(a: u8) -> Option<u8> {
        (a & NO_PAIR == 0).then_some(a | NO_PAIR)
    }
}

/// No local owner: the particle is a copy of another rank's particle.
pub const REMOTE: u32 = u32::MAX;

/// The particles one evaluation works on, in any order, before sorting by cell: the reals
/// of the [`Particles`] store (`src[k] = k` for the first `n_real`), their boundary images,
/// and (distributed runs) copies of other ranks' particles.
#[derive(Clone, Debug)]
pub struct Elements<const D: usize> {
    pub pos: [Vec<f64>; D],
    /// Already multiplied by `sign`.
    pub vel: [Vec<f64>; D],
    pub mass: Vec<f64>,
    pub u: Vec<f64>,
    pub sign: Vec<[f64; D]>,
    pub fold: Vec<bool>,
    pub class: Vec<u8>,
    /// Index in the store of the real particle this is (or is an image of); [`REMOTE`] for
    /// another rank's particle.
    pub src: Vec<u32>,
    /// The first `n_real` elements are the store's reals, in store order.
    pub n_real: usize,
}

impl<const D: usize> Default for Elements<D> {
    fn default() -> Self {
        Self {
            pos: std::array::from_fn(|_| Vec::new()),
            vel: std::array::from_fn(|_| Vec::new()),
            mass: Vec::new(),
            u: Vec::new(),
            sign: Vec::new(),
            fold: Vec::new(),
            class: Vec::new(),
            src: Vec::new(),
            n_real: 0,
        }
    }
}

impl<const D: usize> Elements<D> {
    /// The reals of `parts` (pair class `class_of(i)`) and their boundary images. Every
    /// array is filled in one parallel pass over reals and images.
    pub fn reals_and_images(
        parts: &Particles<D>,
        bx: &SimBox<D>,
        support: f64,
        class_of: impl Fn(usize) -> u8 + Sync,
    ) -> Self {
        let n = parts.len();
        let ghosts: Vec<Ghost<D>> = make_ghosts(bx, &parts.pos, support);
        // The reals' values, then the images', each part written in place in parallel.
        fn fill<T: Send, const D: usize>(
            reals: impl IndexedParallelIterator<Item = T>,
            ghosts: &[Ghost<D>],
            image: impl Fn(&Ghost<D>) -> T + Sync + Send,
        ) -> Vec<T> {
            let mut v = Vec::with_capacity(reals.len() + ghosts.len());
            v.par_extend(reals.with_min_len(1 << 14));
            v.par_extend(ghosts.par_iter().with_min_len(1 << 12).map(image));
            v
        }
        fn copy(x: &[f64]) -> rayon::iter::Copied<rayon::slice::Iter<'_, f64>> {
            x.par_iter().copied()
        }
        let owner = |g: &Ghost<D>| g.owner as usize;
        Self {
            pos: std::array::from_fn(|d| fill(copy(&parts.pos[d]), &ghosts, |g| g.pos[d])),
            vel: std::array::from_fn(|d| {
                fill(copy(&parts.vel[d]), &ghosts, |g| {
                    parts.vel[d][owner(g)] * g.sign[d]
                })
            }),
            mass: fill(copy(&parts.mass), &ghosts, |g| parts.mass[owner(g)]),
            u: fill(copy(&parts.u), &ghosts, |g| parts.u[owner(g)]),
            sign: fill(rayon::iter::repeat_n([1.0; D], n), &ghosts, |g| g.sign),
            fold: fill(rayon::iter::repeat_n(false, n), &ghosts, |g| g.fold),
            class: fill((0..n).into_par_iter().map(&class_of), &ghosts, |_| {
                class::IMAGE
            }),
            src: fill((0..n as u32).into_par_iter(), &ghosts, |g| g.owner),
            n_real: n,
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        pos: [f64; D],
        vel: [f64; D],
        mass: f64,
        u: f64,
        sign: [f64; D],
        fold: bool,
        class: u8,
        src: u32,
    ) {
        for d in 0..D {
            self.pos[d].push(pos[d]);
            self.vel[d].push(vel[d]);
        }
        self.mass.push(mass);
        self.u.push(u);
        self.sign.push(sign);
        self.fold.push(fold);
        self.class.push(class);
        self.src.push(src);
    }

    pub fn len(&self) -> usize {
        self.mass.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Keeps the elements with `keep[k]` true, in order (the first `n_real` must stay).
    pub fn retain(&mut self, keep: &[bool]) {
        debug_assert!(keep[..self.n_real].iter().all(|&k| k), "reals stay");
        for d in 0..D {
            retain_by(&mut self.pos[d], keep);
            retain_by(&mut self.vel[d], keep);
        }
        retain_by(&mut self.mass, keep);
        retain_by(&mut self.u, keep);
        retain_by(&mut self.sign, keep);
        retain_by(&mut self.fold, keep);
        retain_by(&mut self.class, keep);
        retain_by(&mut self.src, keep);
    }
}

/// Real particles and ghosts of one evaluation, sorted by cell.
pub struct Local<const D: usize> {
    pub grid: Grid<D>,
    /// Where each occupied cell's particles lie (dense or sparse, `grid::CellIndex`).
    pub cells: CellIndex,
    /// Cell key (x-major linear index) of each local particle.
    pub cell: Vec<u64>,
    /// Index of the real particle (for a ghost: its owner) in the [`Particles`] store;
    /// [`REMOTE`] for another rank's particle.
    pub src: Vec<u32>,
    /// Local index of the owner (itself for a real particle; [`REMOTE`] for another rank's).
    pub owner: Vec<u32>,
    /// Everything but this rank's reals: boundary images and other ranks' particles.
    pub is_ghost: Vec<bool>,
    pub fold: Vec<bool>,
    /// Pair class bits ([`class`]).
    pub class: Vec<u8>,
    /// Position of each local particle in the [`Elements`] it was built from.
    pub element: Vec<u32>,
    /// Local index of each of this rank's reals, in store order (the inverse of `src` over
    /// the reals).
    pub real_at: Vec<u32>,
    /// ±1 per axis: a ghost's vectors are its owner's times `sign`.
    pub sign: Vec<[f64; D]>,
    pub pos: [Vec<f64>; D],
    pub vel: [Vec<f64>; D],
    pub mass: Vec<f64>,
    pub u: Vec<f64>,
    /// The velocity the artificial viscosity measures, relative to circular orbits
    /// (`artificial_viscosity.orbital`; set once at the start of the sweep); empty when the
    /// AV measures `vel` itself.
    pub v_av: Vec<[f64; D]>,
    // Filled as the sweep finishes each stage of a slab (and copied to ghosts).
    pub rho: Vec<f64>,
    /// m/ρ, the particle's volume (Eq. 10's weight), and 1/ρ (the viscous force's), set
    /// with ρ: a load per pair in the sums instead of a division.
    pub vol: Vec<f64>,
    pub rho_inv: Vec<f64>,
    pub p: Vec<f64>,
    pub cs: Vec<f64>,
    /// Each particle's factor on the artificial viscosity's α: α_i/α_max from the
    /// particle's own α with the Morris–Monaghan switch (set at build), times Balsara's
    /// factor once the gradient is known; 1 with neither.
    pub av_scale: Vec<f64>,
    pub vgrad: Vec<[[f64; D]; D]>,
    /// Kinematic viscosity and viscous stress S = ν σ (Eq. 9), set after the gradient sum.
    pub nu: Vec<f64>,
    pub stress: Vec<[[f64; D]; D]>,
}

/// The largest arrays go back to `memory`'s pool for the next evaluation.
impl<const D: usize> Drop for Local<D> {
    fn drop(&mut self) {
        crate::memory::keep_vec(std::mem::take(&mut self.vgrad));
        crate::memory::keep_vec(std::mem::take(&mut self.stress));
    }
}

impl<const D: usize> Local<D> {
    /// Makes the ghosts, builds the grid over reals and ghosts, and copies both in cell order.
    pub fn build(parts: &Particles<D>, bx: &SimBox<D>, support: f64) -> Self {
        let e = Elements::reals_and_images(parts, bx, support, |_| 0);
        let grid = Grid::new(bx, support, &e.pos);
        Self::from_elements(e, grid)
    }

    /// Sorts `e` into the cells of `grid` (the copies in parallel: every array is a gather
    /// through the cell order).
    pub fn from_elements(e: Elements<D>, grid: Grid<D>) -> Self {
        let n = e.n_real;
        let (order, cells) = grid.index_particles(&e.pos);
        let total = order.len();
        // Two serial loops side by side.
        let (real_at, cell) = rayon::join(
            || {
                let mut real_at = vec![0u32; n];
                for (k, &o) in order.iter().enumerate() {
                    if (o as usize) < n {
                        real_at[o as usize] = k as u32;
                    }
                }
                real_at
            },
            || cells.keys_in_order(),
        );
        let filled = |x: f64| -> Vec<f64> {
            (0..total)
                .into_par_iter()
                .with_min_len(1 << 14)
                .map(|_| x)
                .collect()
        };
        fn pick<T: Copy + Send + Sync>(order: &[u32], v: &[T]) -> Vec<T> {
            order
                .par_iter()
                .with_min_len(4096)
                .map(|&o| v[o as usize])
                .collect()
        }
        let src: Vec<u32> = pick(&order, &e.src);
        let owner = src
            .par_iter()
            .with_min_len(4096)
            .map(|&s| {
                if s == REMOTE {
                    REMOTE
                } else {
                    real_at[s as usize]
                }
            })
            .collect();
        Self {
            grid,
            cells,
            cell,
            owner,
            is_ghost: order
                .par_iter()
                .with_min_len(4096)
                .map(|&o| o as usize >= n)
                .collect(),
            fold: pick(&order, &e.fold),
            class: pick(&order, &e.class),
            sign: pick(&order, &e.sign),
            pos: std::array::from_fn(|d| pick(&order, &e.pos[d])),
            vel: std::array::from_fn(|d| pick(&order, &e.vel[d])),
            mass: pick(&order, &e.mass),
            u: pick(&order, &e.u),
            src,
            element: order,
            real_at,
            v_av: Vec::new(),
            rho: filled(0.0),
            vol: filled(0.0),
            rho_inv: filled(0.0),
            p: filled(0.0),
            cs: filled(0.0),
            av_scale: filled(1.0),
            vgrad: crate::memory::filled_vec(total, [[0.0; D]; D]),
            nu: filled(0.0),
            stress: crate::memory::filled_vec(total, [[0.0; D]; D]),
        }
    }

    pub fn len(&self) -> usize {
        self.mass.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// With the Morris–Monaghan switch, each particle's factor α_i/α_max from the store's
    /// `alpha` (reals and their images; another rank's particles get theirs with the
    /// gradient stage's exchange).
    pub fn set_alpha_factors(&mut self, alpha: &[f64], av: &ArtificialViscosity) {
        if av.switch().is_none() {
            return;
        }
        for (k, &s) in self.src.iter().enumerate() {
            if s != REMOTE {
                self.av_scale[k] = av.alpha_factor(alpha[s as usize]);
            }
        }
    }

    pub fn num_ghosts(&self) -> usize {
        self.is_ghost.iter().filter(|&&g| g).count()
    }

    /// Number of x-slabs.
    pub fn num_slabs(&self) -> usize {
        self.grid.n[0]
    }

    /// Local index range of x-slab `s`.
    pub fn slab_range(&self, s: usize) -> std::ops::Range<usize> {
        self.cells.slab_range(s)
    }

    /// x-slab of local particle `k`.
    pub fn slab_of(&self, k: usize) -> usize {
        self.cells.slab_of_key(self.cell[k])
    }

    #[inline]
    pub fn position(&self, k: usize) -> [f64; D] {
        std::array::from_fn(|d| self.pos[d][k])
    }

    #[inline]
    pub fn velocity(&self, k: usize) -> [f64; D] {
        std::array::from_fn(|d| self.vel[d][k])
    }
}

#[cfg(test)]
mod tests {
    use super::class;

    #[test]
    fn excluded_bits_give_the_same_pairs_as_the_class_rule() {
        for a in 0..8u8 {
            for b in 0..8u8 {
                let by_mask = class::excluded(a).is_some_and(|m| b & m == 0);
                assert_eq!(by_mask, class::pairs(a, b), "classes {a} and {b}");
            }
        }
    }
}
