//! The neighbour grid (paper, Section 2.1): a uniform grid of cells no smaller than the kernel
//! support, cell indices in x-major order (so that an x-slab of cells is a contiguous range),
//! and the sort that orders particles by cell.
//!
//! The index of occupied cells ([`CellIndex`]) is dense (one entry per cell, counting sort)
//! when the grid has no more cells than a few per particle, and sparse otherwise (only the
//! occupied cells, sorted by key, found by binary search): a box that is mostly empty — a
//! binary's stream and disk, a particle flung far out — costs memory and time in proportion
//! to the particles, not to its volume.

use rayon::prelude::*;

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

    /// Linear index as a 64-bit key (a sparse grid may have more cells than `u32` counts).
    #[inline]
    pub fn key(&self, c: [usize; D]) -> u64 {
        let mut k = 0u64;
        for d in 0..D {
            k = k * self.n[d] as u64 + c[d] as u64;
        }
        k
    }

    /// Cells in the grid, as a 64-bit count (saturating).
    pub fn num_cells_u64(&self) -> u64 {
        self.n.iter().fold(1u64, |a, &b| a.saturating_mul(b as u64))
    }

    /// Sorts particles by cell into a [`CellIndex`]: returns `(order, index)` where
    /// `order[k]` is the source index of the k-th particle in cell order (stable: equal
    /// cells keep source order).
    pub fn index_particles(&self, pos: &[Vec<f64>; D]) -> (Vec<u32>, CellIndex) {
        let n = pos[0].len();
        let cells = self.num_cells_u64();
        // Dense while the cell array is no larger than a few entries per particle.
        if cells <= (4 * n as u64).max(1024) {
            let (order, start) = self.sort(pos);
            let cps = self.cells_per_slab();
            let slab_start = (0..=self.n[0]).map(|s| start[s * cps]).collect();
            return (
                order,
                CellIndex {
                    keys: None,
                    start,
                    slab_start,
                    cells_per_slab: cps as u64,
                },
            );
        }
        let keys: Vec<u64> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| self.key(self.coords(std::array::from_fn(|d| pos[d][i]))))
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        // Stable, as the dense counting sort.
        order.par_sort_by_key(|&i| keys[i as usize]);
        let mut occupied = Vec::new();
        let mut start = Vec::new();
        for (k, &o) in order.iter().enumerate() {
            let key = keys[o as usize];
            if occupied.last() != Some(&key) {
                occupied.push(key);
                start.push(k as u32);
            }
        }
        start.push(n as u32);
        let cps = self.n[1..].iter().product::<usize>() as u64;
        // First particle of each x-slab: the first occupied cell with key ≥ s · cps.
        let slab_start = (0..=self.n[0] as u64)
            .map(|s| start[occupied.partition_point(|&k| k < s * cps)])
            .collect();
        (
            order,
            CellIndex {
                keys: Some(occupied),
                start,
                slab_start,
                cells_per_slab: cps,
            },
        )
    }

    /// Counting sort of particles by cell: returns `(order, cell_start)` where `order[k]` is
    /// the source index of the k-th particle in cell order and the particles of cell `c` are
    /// `order[cell_start[c]..cell_start[c + 1]]`. Stable: equal cells keep source order. In
    /// parallel: the cells are counted by blocks of particles, and the cells are then cut
    /// into one range per thread of about equal particle count, each thread placing its
    /// range's particles (the result does not depend on the threads).
    pub fn sort(&self, pos: &[Vec<f64>; D]) -> (Vec<u32>, Vec<u32>) {
        let n = pos[0].len();
        let nc = self.num_cells();
        let keys: Vec<u32> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| self.index(self.coords(std::array::from_fn(|d| pos[d][i]))) as u32)
            .collect();
        let tasks = rayon::current_num_threads().max(1);
        let counts = keys
            .par_chunks(n.div_ceil(tasks).max(1 << 14))
            .map(|ks| {
                let mut c = vec![0u32; nc];
                for &k in ks {
                    c[k as usize] += 1;
                }
                c
            })
            .reduce_with(|mut a, b| {
                for (x, y) in a.iter_mut().zip(&b) {
                    *x += y;
                }
                a
            })
            .unwrap_or_else(|| vec![0; nc]);
        let mut start = vec![0u32; nc + 1];
        for c in 0..nc {
            start[c + 1] = start[c] + counts[c];
        }
        // Cell ranges of about n / tasks particles each, and their parts of `order`.
        let mut order = vec![0u32; n];
        let mut pieces = Vec::with_capacity(tasks);
        let (mut rest, mut c0) = (order.as_mut_slice(), 0);
        for t in 1..=tasks {
            let c1 = if t == tasks {
                nc
            } else {
                start
                    .partition_point(|&s| (s as usize) < t * n / tasks)
                    .min(nc)
            };
            let c1 = c1.max(c0);
            let (part, tail) = rest.split_at_mut((start[c1] - start[c0]) as usize);
            pieces.push((c0, c1, part));
            (rest, c0) = (tail, c1);
        }
        pieces.into_par_iter().for_each(|(c0, c1, part)| {
            let mut next: Vec<u32> = start[c0..c1].iter().map(|&s| s - start[c0]).collect();
            for (i, &k) in keys.iter().enumerate() {
                let k = k as usize;
                if (c0..c1).contains(&k) {
                    let slot = &mut next[k - c0];
                    part[*slot as usize] = i as u32;
                    *slot += 1;
                }
            }
        });
        (order, start)
    }
}

/// Where each cell's particles lie in cell order.
#[derive(Clone, Debug, PartialEq)]
pub struct CellIndex {
    /// Sparse: the occupied cells' keys, ascending (`start` has one entry per key, plus the
    /// end). Dense (None): `start` has one entry per cell of the grid, plus the end.
    keys: Option<Vec<u64>>,
    start: Vec<u32>,
    /// First particle of each x-slab, plus the end.
    slab_start: Vec<u32>,
    cells_per_slab: u64,
}

impl CellIndex {
    /// The particles of the cell with `key`: `start..end` in cell order (empty if none).
    #[inline]
    pub fn range(&self, key: u64) -> (usize, usize) {
        match &self.keys {
            None => (
                self.start[key as usize] as usize,
                self.start[key as usize + 1] as usize,
            ),
            Some(keys) => match keys.binary_search(&key) {
                Ok(c) => (self.start[c] as usize, self.start[c + 1] as usize),
                Err(_) => (0, 0),
            },
        }
    }

    /// The particles of x-slab `s`.
    pub fn slab_range(&self, s: usize) -> std::ops::Range<usize> {
        self.slab_start[s] as usize..self.slab_start[s + 1] as usize
    }

    /// x-slab of the cell with `key`.
    #[inline]
    pub fn slab_of_key(&self, key: u64) -> usize {
        (key / self.cells_per_slab) as usize
    }

    /// Whether the index holds only the occupied cells.
    pub fn is_sparse(&self) -> bool {
        self.keys.is_some()
    }

    /// Bytes the index holds.
    pub fn bytes(&self) -> usize {
        4 * (self.start.len() + self.slab_start.len())
            + 8 * self.keys.as_ref().map_or(0, |k| k.len())
    }

    /// Key of every particle in cell order.
    pub fn keys_in_order(&self) -> Vec<u64> {
        let mut out = Vec::with_capacity(*self.start.last().unwrap_or(&0) as usize);
        let cells = self.start.len().saturating_sub(1);
        for c in 0..cells {
            let key = self.keys.as_ref().map_or(c as u64, |k| k[c]);
            for _ in self.start[c]..self.start[c + 1] {
                out.push(key);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parallel counting sort gives the stable order of a plain sort by cell key, and
    /// the same cell starts, on 1, 2, 3 and 7 threads (its pieces split by thread count):
    /// 20 000 particles, clumped so that cells hold from none to hundreds.
    #[test]
    fn counting_sort_is_stable_on_any_thread_count() {
        let bx = SimBox {
            min: [0.0; 3],
            max: [1.0; 3],
            kinds: [BoundaryKind::Periodic; 3],
        };
        let mut rng = crate::rng::Rng::new(11);
        let mut pos: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::new());
        for i in 0..20_000 {
            for d in 0..3 {
                let x = if i % 3 == 0 {
                    rng.uniform()
                } else {
                    (0.3 + 0.05 * rng.normal()).clamp(0.0, 0.999)
                };
                pos[d].push(x);
            }
        }
        let g = Grid::new(&bx, 0.04, &pos);
        let key = |i: usize| g.index(g.coords(std::array::from_fn(|d| pos[d][i])));
        let mut expected: Vec<u32> = (0..20_000).collect();
        expected.sort_by_key(|&i| key(i as usize));
        let mut expected_start = vec![0u32; g.num_cells() + 1];
        for &i in &expected {
            expected_start[key(i as usize) + 1] += 1;
        }
        for c in 0..g.num_cells() {
            expected_start[c + 1] += expected_start[c];
        }
        for threads in [1, 2, 3, 7] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (order, start) = pool.install(|| g.sort(&pos));
            assert_eq!(order, expected, "{threads} threads");
            assert_eq!(start, expected_start, "{threads} threads");
        }
    }

    /// The sparse index finds the same particles in every cell and slab as the dense one,
    /// and holds only the occupied cells.
    #[test]
    fn sparse_index_matches_the_dense_one() {
        let bx = SimBox {
            min: [-5.0; 3],
            max: [5.0; 3],
            kinds: [BoundaryKind::Open; 3],
        };
        let mut rng = crate::rng::Rng::new(3);
        let mut pos: [Vec<f64>; 3] = std::array::from_fn(|_| Vec::new());
        for i in 0..300 {
            for d in 0..3 {
                // A tight clump and a few far-flung particles: a mostly empty box.
                let x = if i % 50 == 0 {
                    4.0 * (2.0 * rng.uniform() - 1.0)
                } else {
                    0.1 * rng.normal()
                };
                pos[d].push(x);
            }
        }
        let g = Grid::new(&bx, 0.05, &pos);
        assert!(g.num_cells_u64() > 4 * 300);
        let (order, idx) = g.index_particles(&pos);
        assert!(idx.is_sparse());
        let (dense_order, start) = g.sort(&pos);
        assert_eq!(order, dense_order, "same stable cell order");
        for c in 0..g.num_cells() {
            let (a, b) = idx.range(c as u64);
            if start[c] < start[c + 1] {
                assert_eq!((a, b), (start[c] as usize, start[c + 1] as usize));
            } else {
                assert_eq!(a, b);
            }
        }
        let cps = g.cells_per_slab();
        for s in 0..g.n[0] {
            assert_eq!(
                idx.slab_range(s),
                start[s * cps] as usize..start[(s + 1) * cps] as usize
            );
        }
        assert!(
            idx.bytes() < 64 * 300,
            "{} bytes for 300 particles",
            idx.bytes()
        );
    }

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
