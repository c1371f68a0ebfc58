//! One block of the sweep's interaction window: the pairs whose first partner lies in one
//! x-slab (the second in the same or the previous slab), found once from the grid's half
//! stencil, and the three sums gathered from them in parallel without write conflicts.

use rayon::prelude::*;

use crate::kernel::Kernel;
use crate::physics::artificial_viscosity::ArtificialViscosity;
use crate::physics::hydro::{ForceSide, PairForce, force_pair, gradient_pair};
use crate::sweep::local::{Local, Work};

/// An interacting pair with its kernel values, computed once and reused by all three sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// Local index of the partner in the block's slab (the larger index).
    pub i: u32,
    /// Local index of the other partner (same or previous slab; `j < i`).
    pub j: u32,
    pub r: f64,
    pub w: f64,
    /// (1/r) dW/dr.
    pub f: f64,
}

/// Bytes one stored pair costs in the window (pair + its place in the by-j index).
pub const BYTES_PER_PAIR: usize = std::mem::size_of::<Pair>() + std::mem::size_of::<u32>();

/// Particles per parallel task when finding pairs or gathering sums.
const GRAIN: usize = 64;

/// The pairs of x-slab `slab`, indexed both by first partner (contiguous) and by second.
pub struct PairBlock {
    pub slab: usize,
    /// Local range of the slab's particles (the i's).
    i_start: usize,
    i_end: usize,
    /// Start of the previous slab: the j's lie in `j_start..i_end`.
    j_start: usize,
    pub pairs: Vec<Pair>,
    /// `pairs[i_off[i − i_start]..i_off[i − i_start + 1]]` have first partner i.
    i_off: Vec<u32>,
    /// `j_perm[j_off[j − j_start]..j_off[j − j_start + 1]]` index the pairs with second partner j.
    j_off: Vec<u32>,
    j_perm: Vec<u32>,
}

/// Offsets of the half stencil: the neighbour cells with a smaller x-major index, i.e. the
/// offsets in {−1, 0, 1}^D whose first non-zero component is −1: (3^D − 1)/2 cells.
fn half_stencil<const D: usize>() -> Vec<[isize; D]> {
    let mut out = Vec::new();
    let total = 3usize.pow(D as u32);
    for code in 0..total {
        let mut c = code;
        let mut o = [0isize; D];
        for d in (0..D).rev() {
            o[d] = (c % 3) as isize - 1;
            c /= 3;
        }
        if let Some(first) = o.iter().find(|&&x| x != 0)
            && *first == -1
        {
            out.push(o);
        }
    }
    out
}

impl PairBlock {
    /// Finds every pair with first partner in slab `slab` and the second in the same cell
    /// (lower index), a lower neighbour cell of the same slab, or the previous slab.
    /// Ghost–ghost pairs are skipped: they stand for pairs that are evaluated between reals.
    pub fn find<const D: usize>(local: &Local<D>, kernel: &Kernel<D>, slab: usize) -> Self {
        let range = local.slab_range(slab);
        let (i_start, i_end) = (range.start, range.end);
        let j_start = if slab == 0 {
            i_start
        } else {
            local.slab_range(slab - 1).start
        };
        let stencil = half_stencil::<D>();
        let support2 = kernel.support() * kernel.support();
        let grid = &local.grid;

        let groups: Vec<(Vec<Pair>, Vec<u32>)> = (i_start..i_end)
            .into_par_iter()
            .step_by(GRAIN)
            .map(|g0| {
                let g1 = (g0 + GRAIN).min(i_end);
                let mut pairs = Vec::new();
                let mut counts = Vec::with_capacity(g1 - g0);
                for i in g0..g1 {
                    let before = pairs.len();
                    let xi = local.position(i);
                    let gi = local.is_ghost[i];
                    let c = local.cell[i] as usize;
                    let visit = |j: usize, pairs: &mut Vec<Pair>| {
                        if gi && local.is_ghost[j] {
                            return;
                        }
                        let mut r2 = 0.0;
                        for d in 0..D {
                            let dx = xi[d] - local.pos[d][j];
                            r2 += dx * dx;
                        }
                        if r2 < support2 {
                            let r = r2.sqrt();
                            let (w, f) = kernel.w_and_f(r);
                            pairs.push(Pair {
                                i: i as u32,
                                j: j as u32,
                                r,
                                w,
                                f,
                            });
                        }
                    };
                    for j in local.cell_start[c] as usize..i {
                        visit(j, &mut pairs);
                    }
                    let ci = cell_coords(grid.n, c);
                    for o in &stencil {
                        let mut nc = [0usize; D];
                        let mut inside = true;
                        for d in 0..D {
                            let x = ci[d] as isize + o[d];
                            if x < 0 || x >= grid.n[d] as isize {
                                inside = false;
                                break;
                            }
                            nc[d] = x as usize;
                        }
                        if !inside {
                            continue;
                        }
                        let cc = grid.index(nc);
                        for j in local.cell_start[cc] as usize..local.cell_start[cc + 1] as usize {
                            visit(j, &mut pairs);
                        }
                    }
                    counts.push((pairs.len() - before) as u32);
                }
                (pairs, counts)
            })
            .collect();

        let total: usize = groups.iter().map(|g| g.0.len()).sum();
        let mut pairs = Vec::with_capacity(total);
        let mut i_off = Vec::with_capacity(i_end - i_start + 1);
        i_off.push(0u32);
        for (p, counts) in groups {
            pairs.extend_from_slice(&p);
            for c in counts {
                let last = *i_off.last().unwrap();
                i_off.push(last + c);
            }
        }

        // Counting sort of the pairs by second partner.
        let nj = i_end - j_start;
        let mut j_off = vec![0u32; nj + 1];
        for p in &pairs {
            j_off[p.j as usize - j_start + 1] += 1;
        }
        for k in 0..nj {
            j_off[k + 1] += j_off[k];
        }
        let mut next = j_off.clone();
        let mut j_perm = vec![0u32; pairs.len()];
        for (idx, p) in pairs.iter().enumerate() {
            let slot = &mut next[p.j as usize - j_start];
            j_perm[*slot as usize] = idx as u32;
            *slot += 1;
        }

        Self {
            slab,
            i_start,
            i_end,
            j_start,
            pairs,
            i_off,
            j_off,
            j_perm,
        }
    }

    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Pairs with first partner `k` (empty if `k` is not in the block's slab).
    #[inline]
    fn as_first(&self, k: usize) -> &[Pair] {
        if k < self.i_start {
            return &[];
        }
        let o = k - self.i_start;
        &self.pairs[self.i_off[o] as usize..self.i_off[o + 1] as usize]
    }

    /// Indices of the pairs with second partner `k`.
    #[inline]
    fn as_second(&self, k: usize) -> &[u32] {
        let o = k - self.j_start;
        &self.j_perm[self.j_off[o] as usize..self.j_off[o + 1] as usize]
    }

    /// Runs `f(k, work_k)` in parallel for every particle touched by this block.
    fn for_each_touched<const D: usize, F>(&self, work: &mut [Work<D>], f: F)
    where
        F: Fn(usize, &mut Work<D>) + Sync + Send,
    {
        work[self.j_start..self.i_end]
            .par_iter_mut()
            .enumerate()
            .with_min_len(GRAIN)
            .for_each(|(o, wk)| f(self.j_start + o, wk));
    }

    /// First sum, Eq. (5): ρ_k += Σ m W over this block's pairs.
    pub fn density<const D: usize>(&self, local: &Local<D>, work: &mut [Work<D>]) {
        let m = &local.mass;
        self.for_each_touched(work, |k, wk| {
            let mut rho = 0.0;
            let first = self.as_first(k);
            for p in first {
                rho += m[p.j as usize] * p.w;
            }
            let second = self.as_second(k);
            for &q in second {
                let p = &self.pairs[q as usize];
                rho += m[p.i as usize] * p.w;
            }
            wk.rho += rho;
            wk.interactions += (first.len() + second.len()) as u32;
        });
    }

    /// Second sum, Eq. (10): the velocity gradient, needing every partner's density.
    pub fn gradient<const D: usize>(&self, local: &Local<D>, work: &mut [Work<D>]) {
        let dx_of = |p: &Pair| -> [f64; D] {
            std::array::from_fn(|d| local.pos[d][p.i as usize] - local.pos[d][p.j as usize])
        };
        self.for_each_touched(work, |k, wk| {
            let mut acc = [[0.0; D]; D];
            let mut add = |g: [[f64; D]; D], s: f64| {
                for a in 0..D {
                    for b in 0..D {
                        acc[a][b] += s * g[a][b];
                    }
                }
            };
            for p in self.as_first(k) {
                let (i, j) = (p.i as usize, p.j as usize);
                let g = gradient_pair(&dx_of(p), p.f, &local.velocity(i), &local.velocity(j));
                add(g, local.mass[j] / local.rho[j]);
            }
            for &q in self.as_second(k) {
                let p = &self.pairs[q as usize];
                let (i, j) = (p.i as usize, p.j as usize);
                let g = gradient_pair(&dx_of(p), p.f, &local.velocity(i), &local.velocity(j));
                add(g, local.mass[i] / local.rho[i]);
            }
            for a in 0..D {
                for b in 0..D {
                    wk.grad[a][b] += acc[a][b];
                }
            }
        });
    }

    /// Third sum: accelerations (Eq. 7 + viscosity) and du/dt. Each pair is evaluated once
    /// into a buffer, then gathered by both partners.
    pub fn force<const D: usize>(
        &self,
        local: &Local<D>,
        av: &ArtificialViscosity,
        work: &mut [Work<D>],
    ) {
        let side = |k: usize| ForceSide {
            v: local.velocity(k),
            rho: local.rho[k],
            p: local.p[k],
            cs: local.cs[k],
            balsara: local.balsara[k],
        };
        let mut out: Vec<PairForce<D>> = Vec::new();
        self.pairs
            .par_iter()
            .with_min_len(GRAIN)
            .map(|p| {
                let (i, j) = (p.i as usize, p.j as usize);
                let dx: [f64; D] = std::array::from_fn(|d| local.pos[d][i] - local.pos[d][j]);
                force_pair(&dx, p.r, p.f, &side(i), &side(j), av)
            })
            .collect_into_vec(&mut out);
        let m = &local.mass;
        self.for_each_touched(work, |k, wk| {
            let first = self.as_first(k);
            let base = if first.is_empty() {
                0
            } else {
                self.i_off[k - self.i_start] as usize
            };
            for (o, p) in first.iter().enumerate() {
                let pf = &out[base + o];
                let mj = m[p.j as usize];
                for d in 0..D {
                    wk.acc[d] += mj * pf.accel[d];
                }
                wk.du += mj * (pf.work_i + pf.heat_viscous);
                wk.diss += mj * pf.heat_viscous;
                wk.vsig = wk.vsig.max(pf.vsig);
            }
            for &q in self.as_second(k) {
                let pf = &out[q as usize];
                let mi = m[self.pairs[q as usize].i as usize];
                for d in 0..D {
                    wk.acc[d] -= mi * pf.accel[d];
                }
                wk.du += mi * (pf.work_j + pf.heat_viscous);
                wk.diss += mi * pf.heat_viscous;
                wk.vsig = wk.vsig.max(pf.vsig);
            }
        });
    }
}

/// Integer cell coordinates from an x-major linear index.
#[inline]
fn cell_coords<const D: usize>(n: [usize; D], mut c: usize) -> [usize; D] {
    let mut out = [0; D];
    for d in (0..D).rev() {
        out[d] = c % n[d];
        c /= n[d];
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_stencil_has_lower_cells_only() {
        assert_eq!(half_stencil::<1>(), vec![[-1]]);
        assert_eq!(half_stencil::<2>().len(), 4);
        assert_eq!(half_stencil::<3>().len(), 13);
        for o in half_stencil::<3>() {
            let lin = o[0] * 9 + o[1] * 3 + o[2];
            assert!(lin < 0, "{o:?}");
        }
    }
}
