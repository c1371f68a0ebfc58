//! The working set of one evaluation: real particles and their ghosts, copied in cell order
//! (x-major, so every x-slab is a contiguous range), with the per-particle accumulators.

use crate::boundary::{Ghost, SimBox, make_ghosts};
use crate::grid::Grid;
use crate::particles::Particles;

/// Per-particle accumulators of the three sums. Kept apart from [`Local`] so that the sums can
/// write them in parallel while reading the particles' state.
#[derive(Clone, Copy, Debug)]
pub struct Work<const D: usize> {
    /// Σ m_j W_ij without the self term.
    pub rho: f64,
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
            grad: [[0.0; D]; D],
            acc: [0.0; D],
            du: 0.0,
            diss: 0.0,
            vsig: 0.0,
            interactions: 0,
        }
    }
}

/// Real particles and ghosts of one evaluation, sorted by cell.
pub struct Local<const D: usize> {
    pub grid: Grid<D>,
    /// First local index of each cell; `cell_start[c]..cell_start[c + 1]`.
    pub cell_start: Vec<u32>,
    /// Cell index of each local particle.
    pub cell: Vec<u32>,
    /// Index of the real particle (for a ghost: its owner) in the [`Particles`] store.
    pub src: Vec<u32>,
    /// Local index of the owner (itself for a real particle).
    pub owner: Vec<u32>,
    pub is_ghost: Vec<bool>,
    pub fold: Vec<bool>,
    /// ±1 per axis: a ghost's vectors are its owner's times `sign`.
    pub sign: Vec<[f64; D]>,
    pub pos: [Vec<f64>; D],
    pub vel: [Vec<f64>; D],
    pub mass: Vec<f64>,
    pub u: Vec<f64>,
    // Filled as the sweep finishes each stage of a slab (and copied to ghosts).
    pub rho: Vec<f64>,
    pub p: Vec<f64>,
    pub cs: Vec<f64>,
    pub balsara: Vec<f64>,
    pub vgrad: Vec<[[f64; D]; D]>,
    /// Kinematic viscosity and viscous stress S = ν σ (Eq. 9), set after the gradient sum.
    pub nu: Vec<f64>,
    pub stress: Vec<[[f64; D]; D]>,
}

impl<const D: usize> Local<D> {
    /// Makes the ghosts, builds the grid over reals and ghosts, and copies both in cell order.
    pub fn build(parts: &Particles<D>, bx: &SimBox<D>, support: f64) -> Self {
        let n = parts.len();
        let ghosts: Vec<Ghost<D>> = make_ghosts(bx, &parts.pos, support);
        let all_pos: [Vec<f64>; D] = std::array::from_fn(|d| {
            let mut v = parts.pos[d].clone();
            v.extend(ghosts.iter().map(|g| g.pos[d]));
            v
        });
        let grid = Grid::new(bx, support, &all_pos);
        let (order, cell_start) = grid.sort(&all_pos);
        let total = order.len();
        let mut local_of_real = vec![0u32; n];
        let mut cell = vec![0u32; total];
        for c in 0..grid.num_cells() {
            for k in cell_start[c]..cell_start[c + 1] {
                cell[k as usize] = c as u32;
            }
        }
        let mut src = Vec::with_capacity(total);
        let mut is_ghost = Vec::with_capacity(total);
        let mut fold = Vec::with_capacity(total);
        let mut sign = Vec::with_capacity(total);
        for (k, &o) in order.iter().enumerate() {
            let o = o as usize;
            if o < n {
                local_of_real[o] = k as u32;
                src.push(o as u32);
                is_ghost.push(false);
                fold.push(false);
                sign.push([1.0; D]);
            } else {
                let g = &ghosts[o - n];
                src.push(g.owner);
                is_ghost.push(true);
                fold.push(g.fold);
                sign.push(g.sign);
            }
        }
        let owner: Vec<u32> = src.iter().map(|&s| local_of_real[s as usize]).collect();
        let pos = std::array::from_fn(|d| order.iter().map(|&o| all_pos[d][o as usize]).collect());
        let vel = std::array::from_fn(|d| {
            src.iter()
                .zip(&sign)
                .map(|(&s, sg)| parts.vel[d][s as usize] * sg[d])
                .collect()
        });
        let mass = src.iter().map(|&s| parts.mass[s as usize]).collect();
        let u = src.iter().map(|&s| parts.u[s as usize]).collect();
        Self {
            grid,
            cell_start,
            cell,
            src,
            owner,
            is_ghost,
            fold,
            sign,
            pos,
            vel,
            mass,
            u,
            rho: vec![0.0; total],
            p: vec![0.0; total],
            cs: vec![0.0; total],
            balsara: vec![1.0; total],
            vgrad: vec![[[0.0; D]; D]; total],
            nu: vec![0.0; total],
            stress: vec![[[0.0; D]; D]; total],
        }
    }

    pub fn len(&self) -> usize {
        self.mass.len()
    }

    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
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
        let cps = self.grid.cells_per_slab();
        self.cell_start[s * cps] as usize..self.cell_start[(s + 1) * cps] as usize
    }

    /// x-slab of local particle `k`.
    pub fn slab_of(&self, k: usize) -> usize {
        self.cell[k] as usize / self.grid.cells_per_slab()
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
