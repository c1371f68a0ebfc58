//! The neighbour grid (paper, Section 2.1): a uniform grid of cells no smaller than the kernel
//! support, cell indices in x-major order (so that an x-slab of cells is a contiguous range),
//! and the counting sort that orders particles by cell.

use crate::boundary::{BoundaryKind, SimBox};

/// A uniform grid; every cell side is ≥ the kernel support, so all partners of a particle lie
/// in its own or the adjacent cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid<const D: usize> {
    pub lo: [f64; D],
    pub cell: [f64; D],
    pub n: [usize; D],
}

impl<const D: usize> Grid<D> {
    /// Covers the box plus one layer of ghost cells on closed axes (periodic, reflecting),
    /// with cells dividing the box exactly; on open axes it covers the particles' extent.
    pub fn new(bx: &SimBox<D>, support: f64, pos: &[Vec<f64>; D]) -> Self {
        let mut lo = [0.0; D];
        let mut cell = [support; D];
        let mut n = [1; D];
        for d in 0..D {
            if bx.kinds[d] == BoundaryKind::Open {
                let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
                for &x in &pos[d] {
                    a = a.min(x);
                    b = b.max(x);
                }
                if !a.is_finite() {
                    (a, b) = (bx.min[d], bx.max[d]);
                }
                lo[d] = a;
                n[d] = ((b - a) / support).floor() as usize + 1;
            } else {
                let inner = ((bx.length(d) / support).floor() as usize).max(1);
                cell[d] = bx.length(d) / inner as f64;
                lo[d] = bx.min[d] - cell[d];
                n[d] = inner + 2;
            }
        }
        Self { lo, cell, n }
    }

    pub fn num_cells(&self) -> usize {
        self.n.iter().product()
    }

    /// Cells in one x-slab.
    pub fn cells_per_slab(&self) -> usize {
        self.n[1..].iter().product()
    }

    /// Integer coordinates of the cell holding `x`, clamped to the grid.
    #[inline]
    pub fn coords(&self, x: [f64; D]) -> [usize; D] {
        std::array::from_fn(|d| {
            let c = ((x[d] - self.lo[d]) / self.cell[d]).floor();
            if c <= 0.0 {
                0
            } else {
                (c as usize).min(self.n[d] - 1)
            }
        })
    }

    /// Linear index, x-major: `((cx · ny) + cy) · nz + cz`.
    #[inline]
    pub fn index(&self, c: [usize; D]) -> usize {
        let mut k = 0;
        for d in 0..D {
            k = k * self.n[d] + c[d];
        }
        k
    }

    /// Counting sort of particles by cell: returns `(order, cell_start)` where `order[k]` is
    /// the source index of the k-th particle in cell order and the particles of cell `c` are
    /// `order[cell_start[c]..cell_start[c + 1]]`. Stable: equal cells keep source order.
    pub fn sort(&self, pos: &[Vec<f64>; D]) -> (Vec<u32>, Vec<u32>) {
        let n = pos[0].len();
        let keys: Vec<u32> = (0..n)
            .map(|i| self.index(self.coords(std::array::from_fn(|d| pos[d][i]))) as u32)
            .collect();
        let mut start = vec![0u32; self.num_cells() + 1];
        for &k in &keys {
            start[k as usize + 1] += 1;
        }
        for c in 0..self.num_cells() {
            start[c + 1] += start[c];
        }
        let mut next = start.clone();
        let mut order = vec![0u32; n];
        for (i, &k) in keys.iter().enumerate() {
            let slot = &mut next[k as usize];
            order[*slot as usize] = i as u32;
            *slot += 1;
        }
        (order, start)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_axes_get_a_ghost_layer_and_exact_cells() {
        let bx = SimBox {
            min: [0.0, -1.0],
            max: [1.0, 1.0],
            kinds: [BoundaryKind::Periodic, BoundaryKind::Reflecting],
        };
        let g = Grid::new(&bx, 0.3, &[vec![], vec![]]);
        assert_eq!(g.n, [5, 8]);
        assert!((g.cell[0] - 1.0 / 3.0).abs() < 1e-15 && g.cell[0] >= 0.3);
        assert!((g.lo[1] + 1.0 + 2.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn sort_groups_particles_by_x_major_cell() {
        let bx = SimBox {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
            kinds: [BoundaryKind::Open; 2],
        };
        let pos = [vec![0.9, 0.1, 0.5, 0.1], vec![0.1, 0.9, 0.5, 0.1]];
        let g = Grid::new(&bx, 0.4, &pos);
        let (order, start) = g.sort(&pos);
        assert_eq!(*start.last().unwrap(), 4);
        // x-slab 0 holds particles 1 and 3 (x = 0.1), in y order 3 then 1.
        assert_eq!(&order[..2], &[3, 1]);
        assert_eq!(order[3], 0);
    }
}
