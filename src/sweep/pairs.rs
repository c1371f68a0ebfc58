//! One block of the sweep's interaction window: the pairs whose first partner lies in one
//! x-slab (the second in the same or the previous slab), found once from the grid's half
//! stencil, and the three sums accumulated from them in parallel without write conflicts
//! (each task into its own buffer over the particles its pairs touch, merged afterwards).

use rayon::prelude::*;

use crate::kernel::Kernel;
use crate::lanes::{F64x2, Real};
use crate::physics::hydro::{ForceSide, PairForce, PairTerms, force_pair, gradient_pair};
use crate::sweep::Physics;
use crate::sweep::local::{Local, Work, class};

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

/// Bytes one stored pair costs in the window.
pub const BYTES_PER_PAIR: usize = std::mem::size_of::<Pair>();

/// Particles per parallel task when finding pairs.
const GRAIN: usize = 64;

thread_local! {
    /// The capacity each thread gives a group's list: room for the largest group it has
    /// found so far, with a quarter to spare.
    static GROUP_CAPACITY: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// The pairs of x-slab `slab`, in the order of their first partner, kept in the groups the
/// parallel search found them in (of [`GRAIN`] first partners each; never copied into one
/// list).
pub struct PairBlock {
    pub slab: usize,
    /// Start of the previous slab: every partner lies in `j_start..i_end`.
    j_start: usize,
    /// Start of the block's own slab (of its first partners).
    i_start: usize,
    i_end: usize,
    groups: Vec<Group>,
    /// What each group's pairs reach below its first partners.
    reach: Vec<Reach>,
    len: usize,
}

/// The pairs of one group of [`GRAIN`] first partners (from `first` on), in order, and how
/// many each of them has: the sums take a particle's pairs by its count instead of
/// comparing every pair's first partner with the next one's (a pass over the pairs before
/// each particle's run).
struct Group {
    first: u32,
    pairs: Vec<Pair>,
    counts: [u32; GRAIN],
}

impl Group {
    /// Each first partner with pairs, and its pairs.
    #[inline]
    fn runs(&self) -> impl Iterator<Item = (usize, &[Pair])> {
        let mut rest = &self.pairs[..];
        self.counts
            .iter()
            .enumerate()
            .filter(|&(_, &c)| c > 0)
            .map(move |(k, &c)| {
                let (ps, tail) = rest.split_at(c as usize);
                rest = tail;
                (self.first as usize + k, ps)
            })
    }
}

/// The second partners of one group's pairs: those in the previous slab lie in
/// `prev_lo..prev_hi` (empty when there are none), those in the group's own slab at or
/// above `cur_lo` (at most the group's first particle, so that its first partners are
/// included). A sum's task touches only these particles and its first partners.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Reach {
    prev_lo: u32,
    prev_hi: u32,
    cur_lo: u32,
}

impl Reach {
    /// The extent of `pairs`, found for first partners from `g0` on in a slab starting at
    /// `i_start`. Without branches: whether a partner lies in the previous slab follows no
    /// pattern the predictor could learn.
    fn of(pairs: &[Pair], g0: usize, i_start: usize) -> Self {
        let is = i_start as u32;
        let mut r = Reach {
            prev_lo: u32::MAX,
            prev_hi: 0,
            cur_lo: g0 as u32,
        };
        for p in pairs {
            let prev = p.j < is;
            r.prev_lo = r.prev_lo.min(if prev { p.j } else { u32::MAX });
            r.prev_hi = r.prev_hi.max(if prev { p.j + 1 } else { 0 });
            r.cur_lo = r.cur_lo.min(if prev { u32::MAX } else { p.j });
        }
        r
    }
}

/// The partners of one particle among its candidates, with their squared distances, found
/// without a branch per candidate: the squared distances of a range of candidates are
/// taken first, in a loop the compiler runs in SIMD lanes; then every candidate is written
/// at the next free place and the count advances only for a partner, so that loop is
/// straight-line code whatever the distances (whether a candidate lies within the support
/// follows no pattern a branch predictor could learn: about one in five does). The two
/// loops find pairs 1.13–1.17× faster at 10⁶ particles on one thread than the one loop
/// doing both (BENCHMARKS.md). The partners come out in candidate order, as a branch per
/// candidate would find them.
#[derive(Default)]
struct Hits {
    j: Vec<u32>,
    r2: Vec<f64>,
    /// Squared distances of the candidates of one range.
    d2: Vec<f64>,
    /// Partners found: the first `n` entries of `j` and `r2`.
    n: usize,
}

impl Hits {
    fn clear(&mut self) {
        self.n = 0;
    }

    /// Adds the candidates `range` of a particle at `xi` that lie within the support
    /// (squared: `support2`) and pair with it: their class has none of the bits
    /// `excluded` ([`class::excluded`]).
    #[inline]
    fn gather<const D: usize>(
        &mut self,
        pos: &[Vec<f64>; D],
        classes: &[u8],
        xi: [f64; D],
        excluded: u8,
        range: std::ops::Range<usize>,
        support2: f64,
    ) {
        let (a, len) = (range.start, range.len());
        // Room for every candidate being a partner: the k-th candidate is written at
        // n ≤ self.n + k < need (past the partners when it is not one).
        let need = self.n + len;
        if self.j.len() < need {
            self.j.resize(need, 0);
            self.r2.resize(need, 0.0);
        }
        let xs: [&[f64]; D] = std::array::from_fn(|d| &pos[d][range.clone()]);
        // The squared distances first, in a loop without a dependence between candidates
        // (the compiler takes them in SIMD lanes); then the partners picked out of them.
        if self.d2.len() < len {
            self.d2.resize(len, 0.0);
        }
        let d2 = &mut self.d2[..len];
        for (k, r2) in d2.iter_mut().enumerate() {
            let mut s = 0.0;
            for d in 0..D {
                let dx = xi[d] - xs[d][k];
                s += dx * dx;
            }
            *r2 = s;
        }
        let classes = &classes[range];
        let (js, r2s) = (&mut self.j[..need], &mut self.r2[..need]);
        let mut n = self.n;
        for (k, (&r2, &cj)) in d2.iter().zip(classes).enumerate() {
            // Never clamps (n < need); it lets the compiler drop the bounds checks.
            let m = n.min(need - 1);
            js[m] = (a + k) as u32;
            r2s[m] = r2;
            n += usize::from((r2 < support2) & (cj & excluded == 0));
        }
        self.n = n;
    }
}

/// The particles one task of a sum writes, as offsets from the block's `j_start`: two
/// ranges, one in the previous slab and one in the block's own. Its buffer is cleared and
/// merged over these only.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Span {
    prev: std::ops::Range<usize>,
    cur: std::ops::Range<usize>,
}

impl Span {
    #[inline]
    fn covers(&self, o: usize) -> bool {
        self.prev.contains(&o) || self.cur.contains(&o)
    }
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

/// An occupied stencil cell as pair finding reads it for each particle: its particle range
/// and box (lower, upper corner).
pub type StencilCell<const D: usize> = (usize, usize, [f64; D], [f64; D]);

/// The candidate partners of the particles of one cell: the occupied cells of its half
/// stencil with their boxes, so that each particle skips the cells lying wholly beyond the
/// kernel's support from it (in 3D about a quarter of the candidates: the stencil's edge
/// and corner cells reach past the sphere). Pair finding and the count of candidates
/// ([`candidates`]) both walk it.
struct StencilCells<'a, const D: usize> {
    stencil: &'a [[isize; D]],
    /// Cell key the ranges belong to.
    cell: u64,
    /// Start of that cell's own particles (looked up once per cell: with the sparse index
    /// a lookup is a binary search).
    own_start: usize,
    /// Particle range and box (lower, upper corner) of each occupied stencil cell.
    ranges: Vec<StencilCell<D>>,
    /// Rounding allowance on the boxes' corners (relative 1e-9 of the grid's extent, far
    /// below the support and far above the error of `lo + c · cell`).
    margin: [f64; D],
}

impl<'a, const D: usize> StencilCells<'a, D> {
    /// Over `local`'s grid, with the offsets of [`half_stencil`].
    fn new(local: &Local<D>, stencil: &'a [[isize; D]]) -> Self {
        let g = &local.grid;
        let ranges = Vec::with_capacity(stencil.len());
        Self {
            stencil,
            cell: u64::MAX,
            own_start: 0,
            ranges,
            margin: std::array::from_fn(|d| 1e-9 * (g.lo[d].abs() + g.n[d] as f64 * g.cell[d])),
        }
    }

    /// Makes the ranges those of cell `c` (nothing to do when they already are).
    #[inline]
    fn set_cell(&mut self, local: &Local<D>, c: u64) {
        if c == self.cell {
            return;
        }
        self.cell = c;
        self.own_start = local.cells.range(c).0;
        self.ranges.clear();
        let g = &local.grid;
        let ci = cell_coords(g.n, c);
        for o in self.stencil {
            if let Some(nc) = offset_cell(g.n, &ci, o) {
                let (a, b) = local.cells.range(g.key(nc));
                if a < b {
                    // Particles beyond the grid are clamped into its outer cells: those
                    // reach to infinity on that side.
                    let lo = std::array::from_fn(|d| {
                        if nc[d] == 0 {
                            f64::NEG_INFINITY
                        } else {
                            g.lo[d] + nc[d] as f64 * g.cell[d] - self.margin[d]
                        }
                    });
                    let hi = std::array::from_fn(|d| {
                        if nc[d] + 1 == g.n[d] {
                            f64::INFINITY
                        } else {
                            g.lo[d] + (nc[d] + 1) as f64 * g.cell[d] + self.margin[d]
                        }
                    });
                    self.ranges.push((a, b, lo, hi));
                }
            }
        }
    }

    /// The ranges of the current cell that may hold partners of a particle at `x`.
    #[inline]
    fn near(&self, x: [f64; D], support2: f64) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.ranges.iter().filter_map(move |&(a, b, lo, hi)| {
            let mut d2 = 0.0;
            for d in 0..D {
                let e = (lo[d] - x[d]).max(x[d] - hi[d]).max(0.0);
                d2 += e * e;
            }
            (d2 < support2).then_some((a, b))
        })
    }
}

/// Per-particle sums of one stage, accumulated privately by each task and then merged.
trait Accumulator: Copy + Send + Sync {
    fn zero() -> Self;
    fn add(&mut self, o: &Self);
}

/// A sum's two terms for a pair: (first partner's, second partner's), computed one pair at a
/// time, or with `TWO` two pairs of the same first partner at once (lanes). `two` must give
/// for each pair what `one` gives, to the bit: the terms are then added in the same order
/// either way.
trait PairSum<S, A>: Sync {
    const TWO: bool = false;
    fn one(&self, s: &S, p: &Pair) -> (A, A);
    #[inline(always)]
    fn two(&self, s: &S, p: &Pair, q: &Pair) -> [(A, A); 2] {
        [self.one(s, p), self.one(s, q)]
    }
}

/// A sum computed one pair at a time by a closure.
struct Each<F>(F);

impl<S, A, F: Fn(&S, &Pair) -> (A, A) + Sync> PairSum<S, A> for Each<F> {
    #[inline(always)]
    fn one(&self, s: &S, p: &Pair) -> (A, A) {
        (self.0)(s, p)
    }
}

/// A sum with a closure for one pair and one for two pairs at once.
struct InTwos<F, G>(F, G);

impl<S, A, F, G> PairSum<S, A> for InTwos<F, G>
where
    F: Fn(&S, &Pair) -> (A, A) + Sync,
    G: Fn(&S, &Pair, &Pair) -> [(A, A); 2] + Sync,
{
    const TWO: bool = true;
    #[inline(always)]
    fn one(&self, s: &S, p: &Pair) -> (A, A) {
        (self.0)(s, p)
    }
    #[inline(always)]
    fn two(&self, s: &S, p: &Pair, q: &Pair) -> [(A, A); 2] {
        (self.1)(s, p, q)
    }
}

impl Accumulator for (f64, u32) {
    fn zero() -> Self {
        (0.0, 0)
    }
    fn add(&mut self, o: &Self) {
        self.0 += o.0;
        self.1 += o.1;
    }
}

impl<const D: usize> Accumulator for [[f64; D]; D] {
    fn zero() -> Self {
        [[0.0; D]; D]
    }
    fn add(&mut self, o: &Self) {
        for a in 0..D {
            for b in 0..D {
                self[a][b] += o[a][b];
            }
        }
    }
}

/// Density-stage sums of the pressure–energy formulation: Σ m W, Σ m u W, neighbours.
#[derive(Clone, Copy, Debug)]
pub struct DensitySum {
    rho: f64,
    mu_w: f64,
    n: u32,
}

impl Accumulator for DensitySum {
    fn zero() -> Self {
        Self {
            rho: 0.0,
            mu_w: 0.0,
            n: 0,
        }
    }
    fn add(&mut self, o: &Self) {
        self.rho += o.rho;
        self.mu_w += o.mu_w;
        self.n += o.n;
    }
}

/// Force-stage sums: acceleration, du/dt, viscous heating, largest signal velocity (`T`
/// with lanes: several pairs' terms side by side).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ForceSum<const D: usize, T: Real = f64> {
    acc: [T; D],
    du: T,
    diss: T,
    vsig: T,
}

impl<const D: usize, T: Real> ForceSum<D, T> {
    /// The two partners' terms of a pair (or pairs, lane by lane) with masses `mi`, `mj`.
    #[inline(always)]
    fn of_pair(pf: &PairForce<D, T>, mi: T, mj: T) -> [Self; 2] {
        [
            ForceSum {
                acc: std::array::from_fn(|d| mj * pf.accel[d]),
                du: mj * (pf.work_i + pf.heat_i),
                diss: mj * pf.heat_i,
                vsig: pf.vsig,
            },
            ForceSum {
                acc: std::array::from_fn(|d| -mi * pf.accel[d]),
                du: mi * (pf.work_j + pf.heat_j),
                diss: mi * pf.heat_j,
                vsig: pf.vsig,
            },
        ]
    }

    /// Lane `l`'s terms.
    #[inline(always)]
    fn lane(&self, l: usize) -> ForceSum<D> {
        ForceSum {
            acc: self.acc.map(|a| a.lane(l)),
            du: self.du.lane(l),
            diss: self.diss.lane(l),
            vsig: self.vsig.lane(l),
        }
    }
}

impl<const D: usize> Accumulator for ForceSum<D> {
    fn zero() -> Self {
        Self {
            acc: [0.0; D],
            du: 0.0,
            diss: 0.0,
            vsig: 0.0,
        }
    }
    fn add(&mut self, o: &Self) {
        for d in 0..D {
            self.acc[d] += o.acc[d];
        }
        self.du += o.du;
        self.diss += o.diss;
        // One `maxsd` (`f64::max` adds a test for NaN; a NaN o.vsig is skipped by both,
        // and self.vsig, from 0, is never NaN).
        self.vsig = if o.vsig > self.vsig {
            o.vsig
        } else {
            self.vsig
        };
    }
}

/// Parts of a sum held back (`PairBlock::scatter`): a block that had a sum before the block
/// before it keeps its buffers' part over the previous slab here until that block has
/// merged its own terms, by sum and slab.
#[derive(Default)]
pub struct Held {
    parts: Vec<(u8, usize, Box<dyn std::any::Any + Send>)>,
}

impl Held {
    /// Nothing held (every block's part merged).
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    fn put<A: Send + 'static>(&mut self, sum: u8, slab: usize, bufs: Vec<(Vec<A>, Span)>) {
        self.parts.push((sum, slab, Box::new(bufs)));
    }

    fn take<A: 'static>(&mut self, sum: u8, slab: usize) -> Option<Vec<(Vec<A>, Span)>> {
        let k = self
            .parts
            .iter()
            .position(|(s, t, _)| *s == sum && *t == slab)?;
        let (_, _, b) = self.parts.swap_remove(k);
        Some(*b.downcast().expect("held parts of this sum's type"))
    }
}

impl PairBlock {
    /// Finds every pair with first partner in slab `slab` and the second in the same cell
    /// (lower index), a lower neighbour cell of the same slab, or the previous slab.
    /// Pairs of two ghosts are skipped ([`class::pairs`]): they stand for pairs evaluated
    /// between reals, or on another rank. Each particle's partners are listed first
    /// ([`Hits`]), then their distances taken and the kernel evaluated in loops over the
    /// list: 1.12× faster at 10⁶ particles on one thread than a branch per candidate
    /// (BENCHMARKS.md), with the same pairs in the same order; the kernel two pairs at a
    /// time ([`Kernel::w_and_f_two`]: 1.1–1.2× faster pair finding, the same bits).
    pub fn find<const D: usize>(local: &Local<D>, kernel: &Kernel<D>, slab: usize) -> Self {
        let range = local.slab_range(slab);
        let (i_start, i_end) = (range.start, range.end);
        let j_start = if slab == 0 {
            i_start
        } else {
            local.slab_range(slab - 1).start
        };
        let support2 = kernel.support() * kernel.support();
        let pos = &local.pos;
        let stencil = half_stencil::<D>();

        let (groups, reach): (Vec<Group>, Vec<Reach>) = (i_start..i_end)
            .into_par_iter()
            .step_by(GRAIN)
            // One partner list per task of rayon's, reused by its groups.
            .map_init(Hits::default, |hits, g0| {
                let g1 = (g0 + GRAIN).min(i_end);
                let mut pairs = Vec::with_capacity(GROUP_CAPACITY.get());
                let mut counts = [0u32; GRAIN];
                let mut cells = StencilCells::new(local, &stencil);
                for i in g0..g1 {
                    let c = local.cell[i];
                    cells.set_cell(local, c);
                    let xi: [f64; D] = std::array::from_fn(|d| pos[d][i]);
                    // The particle's own cell below it, then the stencil cells in reach:
                    // their partners first (`Hits::gather`), then their kernel values.
                    let own = (cells.own_start, i);
                    hits.clear();
                    if let Some(excluded) = class::excluded(local.class[i]) {
                        for (a, b) in std::iter::once(own).chain(cells.near(xi, support2)) {
                            hits.gather(pos, &local.class, xi, excluded, a..b, support2);
                        }
                    }
                    // Distances in a loop of their own: independent square roots, which
                    // overlap (taken beside each kernel value, pair finding was 1.05–1.1×
                    // slower at 10⁵ on one thread).
                    let rs = &mut hits.r2[..hits.n];
                    for r2 in rs.iter_mut() {
                        *r2 = r2.sqrt();
                    }
                    counts[i - g0] = hits.n as u32;
                    // Kernel values two pairs at a time (`Kernel::w_and_f_two`: the cubic
                    // spline in SIMD lanes, without a branch), stored in order.
                    let js = &hits.j[..rs.len()];
                    let pair = |j: u32, r: f64, (w, f): (f64, f64)| Pair {
                        i: i as u32,
                        j,
                        r,
                        w,
                        f,
                    };
                    pairs.reserve(rs.len());
                    let (r_twos, j_twos) = (rs.chunks_exact(2), js.chunks_exact(2));
                    let (r_odd, j_odd) = (r_twos.remainder(), j_twos.remainder());
                    for (r, j) in r_twos.zip(j_twos) {
                        let [a, b] = kernel.w_and_f_two([r[0], r[1]]);
                        pairs.push(pair(j[0], r[0], a));
                        pairs.push(pair(j[1], r[1], b));
                    }
                    if let (&[r], &[j]) = (r_odd, j_odd) {
                        pairs.push(pair(j, r, kernel.w_and_f(r)));
                    }
                }
                // Stored at its exact size: the allocator shrinks the block where it lies,
                // so no pair is copied (a list that outgrew its capacity was, once).
                GROUP_CAPACITY.set(GROUP_CAPACITY.get().max(pairs.len() + pairs.len() / 4));
                pairs.shrink_to_fit();
                let reach = Reach::of(&pairs, g0, i_start);
                let first = g0 as u32;
                (
                    Group {
                        first,
                        pairs,
                        counts,
                    },
                    reach,
                )
            })
            .unzip();

        let len = groups.iter().map(|g| g.pairs.len()).sum();
        Self {
            slab,
            j_start,
            i_start,
            i_end,
            groups,
            reach,
            len,
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Every pair, in order.
    pub fn pairs(&self) -> impl Iterator<Item = &Pair> {
        self.groups.iter().flat_map(|g| &g.pairs)
    }

    /// The groups cut into runs of at least `chunk` pairs (the last may be shorter), in
    /// order, as ranges of group indices: the tasks of a sum. Depends only on the pairs and
    /// `chunk`, so that a sum adds its terms in the same order in every run with the same
    /// thread count.
    fn runs(&self, chunk: usize) -> Vec<std::ops::Range<usize>> {
        let mut out = Vec::new();
        let (mut first, mut count) = (0, 0);
        for (k, g) in self.groups.iter().enumerate() {
            count += g.pairs.len();
            if count >= chunk {
                out.push(first..k + 1);
                (first, count) = (k + 1, 0);
            }
        }
        if first < self.groups.len() {
            out.push(first..self.groups.len());
        }
        out
    }

    /// The particles the pairs of groups `run` touch, as offsets from `j_start`: their
    /// first partners and their second partners in either slab.
    fn span(&self, run: std::ops::Range<usize>) -> Span {
        let end = (self.i_start + run.end * GRAIN).min(self.i_end);
        let (mut prev_lo, mut prev_hi, mut cur_lo) = (u32::MAX, 0, u32::MAX);
        for r in &self.reach[run] {
            prev_lo = prev_lo.min(r.prev_lo);
            prev_hi = prev_hi.max(r.prev_hi);
            cur_lo = cur_lo.min(r.cur_lo);
        }
        let at = |k: u32| k as usize - self.j_start;
        Span {
            prev: if prev_lo < prev_hi {
                at(prev_lo)..at(prev_hi)
            } else {
                0..0
            },
            cur: at(cur_lo)..end - self.j_start,
        }
    }

    /// Runs `f` on every pair of every block in `blocks`, each task adding the two partners'
    /// contributions into its own buffer (no write conflicts, streaming access), then merges
    /// the buffers into `work` with `merge`, block after block in the order given (slab
    /// order). The blocks' pairs are summed in parallel — several small blocks at once, or a
    /// large one's runs of groups —, the merges in a fixed order: every particle has its own
    /// block's terms merged before the next block's, even where the next block ran first
    /// (its part over this slab waits in `held`), so that the result depends neither on how
    /// many blocks went together nor on which became ready first. `sum` is this sum's
    /// stage; `pair_stage` tells which blocks had it in earlier calls. A task clears and merges only the particles its pairs
    /// touch ([`Span`]: on two threads its half of the slab and the part of the previous
    /// slab next to it, about half the block), in a buffer kept between sums
    /// ([`crate::memory::scratch_vec`]) whose other entries are never read; a particle
    /// outside a task's span would have had zero merged from it, which changes no sum.
    ///
    /// A particle's pairs as first partner are consecutive: what `prep` reads of it is read
    /// once for all of them, and its own terms are added up in `acc` and stored once. Its
    /// buffer entry is still zero when they are (its pairs as second partner come later,
    /// from larger first partners), so the sum is the same to the bit as adding each term
    /// into the buffer. A sum that computes two pairs at once ([`PairSum::TWO`], the force
    /// sum in SIMD lanes) takes a particle's pairs two by two and the odd one alone, and
    /// adds their terms in the same order as one at a time.
    fn scatter<const D: usize, S, A, P, F, M>(
        blocks: &[&PairBlock],
        work: &mut [Work<D>],
        (sum, pair_stage, held): (u8, &[u8], &mut Held),
        prep: P,
        f: F,
        merge: M,
    ) where
        A: Accumulator + 'static,
        P: Fn(usize) -> S + Sync,
        F: PairSum<S, A>,
        M: Fn(&mut Work<D>, &A) + Sync,
    {
        let tasks = rayon::current_num_threads().max(1);
        let partial = |b: &PairBlock| -> Vec<(Vec<A>, Span)> {
            if b.is_empty() {
                return Vec::new();
            }
            let n = b.i_end - b.j_start;
            let chunk = b.len.div_ceil(tasks).max(4096);
            let run = |run: std::ops::Range<usize>| {
                let span = b.span(run.clone());
                let mut buf = crate::memory::scratch_vec(n, A::zero());
                buf[span.prev.clone()].fill(A::zero());
                buf[span.cur.clone()].fill(A::zero());
                for g in &b.groups[run] {
                    for (i, ps) in g.runs() {
                        let si = prep(i);
                        let mut acc = A::zero();
                        let mut rest = ps;
                        if F::TWO {
                            let mut twos = ps.chunks_exact(2);
                            for c in &mut twos {
                                let [(ci, cj), (ck, cl)] = f.two(&si, &c[0], &c[1]);
                                acc.add(&ci);
                                buf[c[0].j as usize - b.j_start].add(&cj);
                                acc.add(&ck);
                                buf[c[1].j as usize - b.j_start].add(&cl);
                            }
                            rest = twos.remainder();
                        }
                        for p in rest {
                            let (ci, cj) = f.one(&si, p);
                            acc.add(&ci);
                            buf[p.j as usize - b.j_start].add(&cj);
                        }
                        buf[i - b.j_start].add(&acc);
                    }
                }
                (buf, span)
            };
            let mut runs = b.runs(chunk);
            if runs.len() == 1 {
                vec![run(runs.pop().expect("one run"))]
            } else {
                runs.into_par_iter().map(run).collect()
            }
        };
        let partials: Vec<Vec<(Vec<A>, Span)>> = match blocks {
            [b] => vec![partial(b)],
            _ => blocks
                .par_iter()
                .with_min_len(1)
                .map(|b| partial(b))
                .collect(),
        };
        // Merged block after block: a block's own slab, and the previous slab where the
        // block before it has had this sum (earlier, or earlier in this call); otherwise
        // that part is held until it has, and merged after it (`Held`).
        let mut merged_now: Option<usize> = None;
        for (b, bufs) in blocks.iter().zip(partials) {
            let prev_ready = b.j_start == b.i_start
                || pair_stage[b.slab - 1] >= sum
                || merged_now == Some(b.slab - 1);
            let next: Vec<(Vec<A>, Span)> = held.take(sum, b.slab + 1).unwrap_or_default();
            let lo = if prev_ready { b.j_start } else { b.i_start };
            if !bufs.is_empty() || !next.is_empty() {
                let (bufs, next) = (&bufs, &next);
                work[lo..b.i_end]
                    .par_iter_mut()
                    .enumerate()
                    .with_min_len(1024)
                    .for_each(|(k, wk)| {
                        let o = lo + k - b.j_start;
                        for (buf, span) in bufs {
                            if span.covers(o) {
                                merge(wk, &buf[o]);
                            }
                        }
                        // The next block's part over this slab, held since it ran: its
                        // offsets count from this slab's start.
                        if let Some(o) = (lo + k).checked_sub(b.i_start) {
                            for (buf, span) in next {
                                if span.covers(o) {
                                    merge(wk, &buf[o]);
                                }
                            }
                        }
                    });
            }
            for (buf, _) in next {
                crate::memory::keep_scratch(buf);
            }
            if prev_ready || bufs.is_empty() {
                for (buf, _) in bufs {
                    crate::memory::keep_scratch(buf);
                }
            } else {
                held.put(sum, b.slab, bufs);
            }
            merged_now = Some(b.slab);
        }
    }

    /// First sum, Eq. (5): ρ_k += Σ m W over these blocks' pairs; with `pressure_energy`
    /// also Σ m u W (`physics::pressure_energy`).
    pub fn density<const D: usize>(
        blocks: &[&PairBlock],
        local: &Local<D>,
        pressure_energy: bool,
        work: &mut [Work<D>],
        (pair_stage, held): (&[u8], &mut Held),
    ) {
        let order = (crate::sweep::DENSITY, pair_stage, held);
        let m = &local.mass;
        if pressure_energy {
            let u = &local.u;
            Self::scatter(
                blocks,
                work,
                order,
                |i| (m[i], u[i]),
                Each(|&(m_i, u_i): &(f64, f64), p: &Pair| {
                    let j = p.j as usize;
                    let (mwi, mwj) = (m_i * p.w, m[j] * p.w);
                    (
                        DensitySum {
                            rho: mwj,
                            mu_w: mwj * u[j],
                            n: 1,
                        },
                        DensitySum {
                            rho: mwi,
                            mu_w: mwi * u_i,
                            n: 1,
                        },
                    )
                }),
                |wk, a: &DensitySum| {
                    wk.rho += a.rho;
                    wk.mu_w += a.mu_w;
                    wk.interactions += a.n;
                },
            );
            return;
        }
        Self::scatter(
            blocks,
            work,
            order,
            |i| m[i],
            Each(|&m_i: &f64, p: &Pair| ((m[p.j as usize] * p.w, 1u32), (m_i * p.w, 1u32))),
            |wk, a: &(f64, u32)| {
                wk.rho += a.0;
                wk.interactions += a.1;
            },
        );
    }

    /// Second sum, Eq. (10): the velocity gradient, needing every partner's density.
    pub fn gradient<const D: usize>(
        blocks: &[&PairBlock],
        local: &Local<D>,
        work: &mut [Work<D>],
        (pair_stage, held): (&[u8], &mut Held),
    ) {
        Self::scatter(
            blocks,
            work,
            (crate::sweep::GRADIENT, pair_stage, held),
            |i| {
                let x: [f64; D] = std::array::from_fn(|d| local.pos[d][i]);
                (x, local.velocity(i), local.vol[i])
            },
            Each(|(xi, vi, sj): &([f64; D], [f64; D], f64), p: &Pair| {
                let j = p.j as usize;
                let dx: [f64; D] = std::array::from_fn(|d| xi[d] - local.pos[d][j]);
                let g = gradient_pair(&dx, p.f, vi, &local.velocity(j));
                let (si, sj) = (local.vol[j], *sj);
                let scale = |s: f64| -> [[f64; D]; D] {
                    std::array::from_fn(|a| std::array::from_fn(|b| s * g[a][b]))
                };
                (scale(si), scale(sj))
            }),
            |wk, g: &[[f64; D]; D]| wk.grad.add(g),
        );
    }

    /// Third sum: accelerations (Eq. 7 + viscosity) and du/dt.
    pub fn force<const D: usize>(
        blocks: &[&PairBlock],
        local: &Local<D>,
        phys: &Physics<D>,
        work: &mut [Work<D>],
        order: (&[u8], &mut Held),
    ) {
        let orbital = !local.v_av.is_empty();
        let f = match (phys.pair_terms().viscous, orbital) {
            (true, true) => Self::force_with::<D, true, true>,
            (true, false) => Self::force_with::<D, true, false>,
            (false, true) => Self::force_with::<D, false, true>,
            (false, false) => Self::force_with::<D, false, false>,
        };
        f(blocks, local, phys, work, order)
    }

    /// The force sum compiled with and without the physical viscosity (without it no
    /// partner's stress is loaded and the viscous terms are not there to branch over) and
    /// with and without orbital velocities for the AV (without them v_av is v, and the
    /// compiler computes v_ij·r_ij once for both).
    fn force_with<const D: usize, const VISCOUS: bool, const ORBITAL: bool>(
        blocks: &[&PairBlock],
        local: &Local<D>,
        phys: &Physics<D>,
        work: &mut [Work<D>],
        (pair_stage, held): (&[u8], &mut Held),
    ) {
        let terms = PairTerms {
            viscous: VISCOUS,
            ..phys.pair_terms()
        };
        // u only where the conductivity or the pressure–energy terms read it: one random
        // load fewer per partner.
        let y_factor = phys.pressure_energy_gamma().map_or(0.0, |g| g - 1.0);
        let need_u = phys.av.conductivity > 0.0 || terms.pressure_energy;
        /// What the force sum reads of partner `k`: only the fields the terms use.
        #[inline(always)]
        fn side<const D: usize, const VISCOUS: bool, const ORBITAL: bool>(
            local: &Local<D>,
            k: usize,
            (need_u, pressure_energy, y_factor): (bool, bool, f64),
        ) -> ForceSide<D> {
            let v = local.velocity(k);
            let u = if need_u { local.u[k] } else { 0.0 };
            ForceSide {
                v,
                v_av: if ORBITAL { local.v_av[k] } else { v },
                rho: local.rho[k],
                rho_inv: if VISCOUS { local.rho_inv[k] } else { 0.0 },
                p: local.p[k],
                cs: local.cs[k],
                av_scale: local.av_scale[k],
                stress: if VISCOUS {
                    local.stress[k]
                } else {
                    [[0.0; D]; D]
                },
                u,
                y: if pressure_energy { y_factor * u } else { 0.0 },
            }
        }
        /// A first partner: position, force side (alone and in both lanes), mass.
        type Prepared<const D: usize> = ([f64; D], ForceSide<D>, f64, ForceSide<D, F64x2>);
        let reads = (need_u, terms.pressure_energy, y_factor);
        let side = |k: usize| side::<D, VISCOUS, ORBITAL>(local, k, reads);
        let av = &phys.av;
        let m = &local.mass;
        Self::scatter(
            blocks,
            work,
            (crate::sweep::FORCE, pair_stage, held),
            |i| {
                let x: [f64; D] = std::array::from_fn(|d| local.pos[d][i]);
                let s = side(i);
                (x, s, m[i], ForceSide::zip(&s, &s))
            },
            InTwos(
                |(xi, side_i, mi, _): &Prepared<D>, p: &Pair| {
                    let j = p.j as usize;
                    let dx: [f64; D] = std::array::from_fn(|d| xi[d] - local.pos[d][j]);
                    let pf = force_pair(&dx, p.r, p.f, side_i, &side(j), av, terms);
                    let [ci, cj] = ForceSum::of_pair(&pf, *mi, m[j]);
                    (ci, cj)
                },
                // Two pairs in the lanes of one register: each arithmetic instruction
                // serves both, the same operations as above lane by lane.
                |(xi, _, mi, side_i): &Prepared<D>, p: &Pair, q: &Pair| {
                    let (j, k) = (p.j as usize, q.j as usize);
                    let dx: [F64x2; D] = std::array::from_fn(|d| {
                        F64x2::splat(xi[d]) - F64x2::new(local.pos[d][j], local.pos[d][k])
                    });
                    let (r, f) = (F64x2::new(p.r, q.r), F64x2::new(p.f, q.f));
                    let side_jk = ForceSide::zip(&side(j), &side(k));
                    let pf = force_pair(&dx, r, f, side_i, &side_jk, av, terms);
                    let [ci, cj] =
                        ForceSum::of_pair(&pf, F64x2::splat(*mi), F64x2::new(m[j], m[k]));
                    [(ci.lane(0), cj.lane(0)), (ci.lane(1), cj.lane(1))]
                },
            ),
            |wk, a: &ForceSum<D>| {
                for d in 0..D {
                    wk.acc[d] += a.acc[d];
                }
                wk.du += a.du;
                wk.diss += a.diss;
                wk.vsig = wk.vsig.max(a.vsig);
            },
        );
    }
}

/// What pair finding tests over the whole working set ([`candidates`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tested {
    /// Candidate partners tested for distance.
    pub candidates: u64,
    /// Occupied stencil cells whose box was tested against a particle's reach.
    pub cells: u64,
}

/// What pair finding tests over the whole working set ([`PairBlock::find`]'s loops): for
/// each particle that pairs at all ([`class::excluded`]), the box of every occupied cell of
/// its half stencil, and as candidates the particles below it in its own cell and those of
/// the stencil cells within the support's reach. Over the pairs found, what each pair
/// costs ([`crate::sweep::cost`]).
pub fn candidates<const D: usize>(local: &Local<D>, support: f64) -> Tested {
    let stencil = half_stencil::<D>();
    let mut cells = StencilCells::new(local, &stencil);
    let mut total = Tested::default();
    for i in 0..local.len() {
        if class::excluded(local.class[i]).is_none() {
            continue;
        }
        let c = local.cell[i];
        cells.set_cell(local, c);
        let x = local.position(i);
        total.candidates += (i - cells.own_start) as u64;
        total.cells += cells.ranges.len() as u64;
        for (a, b) in cells.near(x, support * support) {
            total.candidates += (b - a) as u64;
        }
    }
    total
}

/// The cell at offset `o` from cell `ci` of a grid of `n` cells per axis, if it lies inside.
#[inline]
fn offset_cell<const D: usize>(
    n: [usize; D],
    ci: &[usize; D],
    o: &[isize; D],
) -> Option<[usize; D]> {
    let mut nc = [0usize; D];
    for d in 0..D {
        let x = ci[d] as isize + o[d];
        if x < 0 || x >= n[d] as isize {
            return None;
        }
        nc[d] = x as usize;
    }
    Some(nc)
}

/// Integer cell coordinates from an x-major linear index.
#[inline]
fn cell_coords<const D: usize>(n: [usize; D], mut c: u64) -> [usize; D] {
    let mut out = [0; D];
    for d in (0..D).rev() {
        out[d] = (c % n[d] as u64) as usize;
        c /= n[d] as u64;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every partner a task's pairs write lies in that task's span (else the task would
    /// write outside what its buffer clears and merges), for the runs of one, two and many
    /// tasks; on two tasks each span holds well under the whole block (about half of it:
    /// its half of the slab and the part of the previous slab next to that half).
    #[test]
    fn a_tasks_span_holds_every_partner_it_writes() {
        let (p, bx, h) = crate::bench::uniform_box(8000, 50.0, 5).unwrap();
        let kernel = Kernel::<3>::new(h);
        let local = Local::build(&p, &bx, kernel.support());
        for slab in 0..local.num_slabs() {
            let b = PairBlock::find(&local, &kernel, slab);
            let n = b.i_end - b.j_start;
            for tasks in [1, 2, 7] {
                let chunk = b.len.div_ceil(tasks).max(1);
                let runs = b.runs(chunk);
                let mut covered = vec![0usize; n];
                for run in runs.clone() {
                    let span = b.span(run.clone());
                    assert!(span.prev.end <= b.i_start - b.j_start);
                    assert!(span.cur.start >= b.i_start - b.j_start && span.cur.end <= n);
                    for p in b.groups[run].iter().flat_map(|g| &g.pairs) {
                        for k in [p.i, p.j] {
                            assert!(span.covers(k as usize - b.j_start), "slab {slab}: {p:?}");
                        }
                    }
                    for (o, c) in covered.iter_mut().enumerate() {
                        *c += span.covers(o) as usize;
                    }
                }
                if tasks == 2 && slab > 0 && runs.len() == 2 {
                    let mean = covered.iter().sum::<usize>() as f64 / (2 * n) as f64;
                    // A slab one cell thick, cut in two along y: each half reaches its
                    // own half of the previous slab and one row of cells beyond (1/8 of
                    // a slab here): 0.5 + 1/8 on average, 0.59 measured; a span over the
                    // whole block (1.0) fails.
                    assert!(mean < 0.7, "slab {slab}: spans cover {mean} of the block");
                }
            }
        }
    }

    /// The sums' buffers come back from the scratch pool holding what earlier sums left in
    /// them; the entries a task reads are those it cleared. Poisoned with NaN (and then
    /// with 1e300), the pool gives the same evaluation to the bit as freshly zeroed
    /// buffers. (That a span holds every partner is the test above.)
    #[test]
    fn stale_scratch_buffers_change_no_sum() {
        use crate::physics::artificial_viscosity::ArtificialViscosity;
        use crate::physics::eos::Eos;
        let (mut p0, bx, h) = crate::bench::uniform_box(4000, 50.0, 9).unwrap();
        // A converging, shearing flow, so that the gradient and the AV have work to do.
        for i in 0..p0.len() {
            let x: [f64; 3] = std::array::from_fn(|d| p0.pos[d][i]);
            p0.vel[0][i] = (6.0 * x[0]).sin() + x[1];
            p0.vel[1][i] = (5.0 * x[2]).cos();
            p0.vel[2][i] = -x[0] * x[1];
        }
        let phys = crate::sweep::Physics::hydro(
            Kernel::<3>::new(h),
            Eos::Ideal { gamma: 5.0 / 3.0 },
            ArtificialViscosity::for_shocks(),
        );
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let run = || {
            let mut p = p0.clone();
            pool.install(|| {
                crate::sweep::evaluate(&mut p, &bx, &phys, crate::sweep::Window::SWEEP)
            });
            p
        };
        // Fresh buffers, filled with zeros when allocated.
        crate::memory::clear_scratch();
        let clean = run();
        for poison in [f64::NAN, 1e300] {
            crate::memory::clear_scratch();
            let n = 2 * p0.len();
            for _ in 0..8 {
                crate::memory::keep_scratch(vec![(poison, 7u32); n]);
                crate::memory::keep_scratch(vec![[[poison; 3]; 3]; n]);
                crate::memory::keep_scratch(vec![
                    ForceSum::<3> {
                        acc: [poison; 3],
                        du: poison,
                        diss: poison,
                        vsig: poison,
                    };
                    n
                ]);
            }
            let again = run();
            assert_eq!(again.rho, clean.rho, "poison {poison}");
            assert_eq!(again.interactions, clean.interactions);
            assert_eq!(again.acc, clean.acc);
            assert_eq!(again.du, clean.du);
            assert_eq!(again.vsig, clean.vsig);
            assert_eq!(again.vgrad, clean.vgrad);
        }
    }

    /// The partner list holds exactly the candidates a branch per candidate would keep,
    /// in order, with their r², across ranges where none, some and all candidates are
    /// partners (the last writes up to the list's end), after a clear; with some
    /// candidates of an excluded class, and with boundary images (which pair with a real
    /// particle, not with an image).
    #[test]
    fn partner_list_keeps_the_candidates_a_branch_would() {
        let xs: Vec<f64> = (0..40).map(|k| 0.05 * k as f64).collect();
        let pos = [xs.clone(), vec![0.0; 40]];
        let some_no_pair: Vec<u8> = (0..40)
            .map(|k| if k % 7 == 3 { class::NO_PAIR } else { 0 })
            .collect();
        let images: Vec<u8> = (0..40).map(|k| (k % 2) as u8 * class::IMAGE).collect();
        let (xi, support2) = ([0.5, 0.0], 0.3 * 0.3);
        let ranges = [30..40, 0..0, 5..10, 8..13, 0..40, 12..20];
        for (ci, classes) in [(0, &some_no_pair), (0, &images), (class::IMAGE, &images)] {
            let excluded = class::excluded(ci).unwrap();
            let mut hits = Hits::default();
            for round in 0..2 {
                hits.clear();
                let mut want = Vec::new();
                for r in ranges.iter().skip(round) {
                    hits.gather(&pos, classes, xi, excluded, r.clone(), support2);
                    for k in r.clone() {
                        let r2 = (xi[0] - xs[k]).powi(2);
                        if r2 < support2 && class::pairs(ci, classes[k]) {
                            want.push((k as u32, r2));
                        }
                    }
                }
                let got: Vec<(u32, f64)> = (0..hits.n).map(|m| (hits.j[m], hits.r2[m])).collect();
                assert_eq!(got, want);
                assert!(!want.is_empty());
            }
        }
    }

    /// A group's counts cut its pairs into the runs of one first partner each, in order,
    /// as comparing each pair's first partner with the next one's does (both leave out
    /// the first partners without pairs).
    #[test]
    fn counts_cut_the_pairs_where_the_first_partner_changes() {
        let (p, bx, h) = crate::bench::uniform_box(3000, 50.0, 3).unwrap();
        let kernel = Kernel::<3>::new(h);
        let local = Local::build(&p, &bx, kernel.support());
        let mut runs_seen = 0;
        for slab in 0..local.num_slabs() {
            let b = PairBlock::find(&local, &kernel, slab);
            for g in &b.groups {
                let by_count: Vec<(usize, &[Pair])> = g.runs().collect();
                let by_pair: Vec<(usize, &[Pair])> = g
                    .pairs
                    .chunk_by(|a, b| a.i == b.i)
                    .map(|ps| (ps[0].i as usize, ps))
                    .collect();
                assert_eq!(by_count, by_pair, "slab {slab}, group from {}", g.first);
                runs_seen += by_count.len();
            }
        }
        assert!(runs_seen > 1000, "{runs_seen} runs");
    }

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

    #[test]
    fn candidates_bound_the_pairs_found() {
        let (p, bx, h) = crate::bench::uniform_box(4000, 50.0, 3).unwrap();
        let kernel = Kernel::<3>::new(h);
        let local = Local::build(&p, &bx, kernel.support());
        let pairs: u64 = (0..local.num_slabs())
            .map(|s| PairBlock::find(&local, &kernel, s).len() as u64)
            .sum();
        let n = local.len() as u64;
        let tested = candidates(&local, kernel.support());
        let c = tested.candidates;
        // At most the 13 occupied cells of the 3D half stencil per particle, at least one
        // (the box is dense).
        assert!(
            (n..=13 * n).contains(&tested.cells),
            "{} cells for {n}",
            tested.cells
        );
        assert!(
            pairs > 0 && pairs < c && c < n * (n - 1) / 2,
            "{pairs} {c} {n}"
        );
        // Cells of at least the support: the half stencil's 13.5 cells hold several
        // candidates per pair within the sphere.
        let ratio = c as f64 / pairs as f64;
        assert!((3.0..20.0).contains(&ratio), "{ratio}");
    }

    /// Particles that pair with nothing (`class::NO_PAIR`: every pair of theirs is another
    /// rank's) are skipped by pair finding before any candidate or cell box is tested, and
    /// the count of what it tests skips them alike.
    #[test]
    fn particles_pairing_with_nothing_test_no_candidates() {
        let (p, bx, h) = crate::bench::uniform_box(4000, 50.0, 3).unwrap();
        let kernel = Kernel::<3>::new(h);
        let mut local = Local::build(&p, &bx, kernel.support());
        let all = candidates(&local, kernel.support());
        // Every other particle in cell order marked as lying in a lower rank's region.
        for k in (0..local.len()).step_by(2) {
            local.class[k] |= class::NO_PAIR;
        }
        let found: usize = (0..local.num_slabs())
            .map(|s| PairBlock::find(&local, &kernel, s).pairs().count())
            .sum();
        let some = candidates(&local, kernel.support());
        assert!(found > 0);
        assert!(some.cells < all.cells && some.candidates < all.candidates);
        for k in 0..local.len() {
            local.class[k] |= class::NO_PAIR;
        }
        let none = candidates(&local, kernel.support());
        assert_eq!(none, Tested::default());
    }

    /// Skipping the stencil cells beyond the support saves the edge and corner cells'
    /// share: of the 27 cells' volume around a particle, on average 1 + 6 + 12 π/4 + 8 π/6
    /// = 20.6 lie within reach, so the candidates fall to 0.76 of every occupied stencil
    /// cell's (a uniform box; 0.85 allows for its jitter and the box's few thousand
    /// particles) — while every pair is still found (the brute-force tests).
    #[test]
    fn cells_beyond_the_support_are_skipped() {
        let (p, bx, h) = crate::bench::uniform_box(4000, 50.0, 3).unwrap();
        let kernel = Kernel::<3>::new(h);
        let local = Local::build(&p, &bx, kernel.support());
        let tested = candidates(&local, kernel.support()).candidates;
        // Every particle below in its cell and every particle of its occupied stencil
        // cells, from the cell occupancy alone.
        let grid = &local.grid;
        let mut all = 0u64;
        for i in 0..local.len() {
            let c = local.cell[i];
            all += (i - local.cells.range(c).0) as u64;
            let ci = cell_coords(grid.n, c);
            for o in &half_stencil::<3>() {
                if let Some(nc) = offset_cell(grid.n, &ci, o) {
                    let (a, b) = local.cells.range(grid.key(nc));
                    all += (b - a) as u64;
                }
            }
        }
        let share = tested as f64 / all as f64;
        assert!((0.6..0.85).contains(&share), "{tested} of {all}: {share}");
        let pairs = crate::sweep::all_pairs(&local, &kernel);
        let brute = crate::sweep::reference::brute_force_pairs(&local, kernel.support());
        assert_eq!(pairs.len(), brute.len());
    }
}
