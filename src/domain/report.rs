//! `sphdisk decompose`: how well the k-d decomposition balances the load and how many ghosts
//! it costs (paper, Section 2.4: "more than 92 %" processor usage with 275 000 particles on
//! 64 processors), computed in one process without running a simulation.
//!
//! Two particle sets, from fixed seeds:
//! * a 2D Keplerian-like disk: surface density Σ ∝ R⁻¹ between R = 0.2 and 2.0 (so R is
//!   uniform: dN = 2πR Σ dR ∝ dR), uniform azimuth, in the box [−2.2, 2.2]²;
//! * a 3D clustered box: a uniform background plus two Plummer spheres and two Gaussian
//!   clumps, in the unit cube.
//!
//! For each region count it follows the paper's sequence: the tree is built balanced by
//! particle count, then its cuts are moved to balance interactions, then moved a few more
//! times by the pairs each rank evaluated under the one-sided ghost rule (measured on the
//! previous tree, as a run would between steps). It reports max/mean of each load, the
//! efficiency mean/max, and the one-sided ghost fraction (ghosts / owned particles per
//! region) of the final tree.
//!
//! Interactions are exact: each particle's neighbours within the support 2h, counted on the
//! crate's neighbour grid ([`crate::grid`]). The smoothing length is one global h, as in the
//! rest of the crate, chosen so that the mean neighbour count over the particles is about 20
//! (2D) or 50 (3D); in the dense parts particles have many more neighbours, which is what
//! makes balancing by interactions differ from balancing by count. Balancing each particle's
//! neighbour count is not yet balancing the work: under the one-sided rule a pair across a
//! boundary is evaluated by the lower rank alone, so small regions with many boundary pairs
//! (and the first ranks, whose neighbours are all above them) carry more than their
//! particles' share; the moves by measured pairs correct that.

use std::time::Instant;

use anyhow::{Result, bail};
use rayon::prelude::*;
use serde::Serialize;

use super::balance::LoadStats;
use super::decomposition::Decomposition;
use crate::boundary::{BoundaryKind, SimBox};
use crate::grid::Grid;
use crate::rng::Rng;

/// What `sphdisk decompose` computes.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Region (rank) counts.
    pub regions: Vec<usize>,
    /// Particles in the 2D disk (0: skip it).
    pub disk_particles: usize,
    /// Particles in the 3D clustered box (0: skip it).
    pub cluster_particles: usize,
    /// JSON lines instead of a table.
    pub json: bool,
}

/// One particle set decomposed into one number of regions.
#[derive(Clone, Debug, Serialize)]
pub struct ReportRow {
    pub distribution: String,
    pub dim: usize,
    pub particles: usize,
    pub regions: usize,
    /// The tree's shape ([`super::TreeShape::describe`]).
    pub tree: String,
    pub particles_per_region: f64,
    /// Kernel support 2h.
    pub support: f64,
    pub mean_neighbours: f64,
    /// Balanced by particle count: particles max/mean and mean/max.
    pub count_max_over_mean: f64,
    pub count_efficiency: f64,
    /// Interactions max/mean of the count-balanced tree (what balancing by count leaves).
    pub interactions_max_over_mean_count_balanced: f64,
    /// Rebalanced by interactions (each particle weighing its neighbour count):
    /// interactions max/mean and mean/max.
    pub interactions_max_over_mean: f64,
    pub interactions_efficiency: f64,
    /// Pairs each rank evaluates under the one-sided ghost rule, max/mean, on that tree.
    pub pairs_max_over_mean_interaction_balanced: f64,
    /// After `pair_rebalances` more moves of the cuts, each by the pairs measured on the
    /// previous tree ([`one_sided_pair_weights`]): pairs max/mean and mean/max. This is the
    /// final tree; the rest of the row describes it.
    pub pair_rebalances: usize,
    pub pairs_max_over_mean: f64,
    pub pairs_efficiency: f64,
    /// Particles max/mean of the final tree.
    pub particles_max_over_mean_final: f64,
    /// One-sided ghosts over owned particles per region of the final tree: mean and max over
    /// regions, and all ghosts over all particles.
    pub ghost_fraction_mean: f64,
    pub ghost_fraction_max: f64,
    pub ghost_fraction_total: f64,
    /// Wall time of the builds, the rebalances and the ghost count.
    pub seconds: f64,
}

/// A particle set to decompose, with its box and interaction counts.
struct Sample {
    name: &'static str,
    dim: usize,
    lo: [f64; 3],
    hi: [f64; 3],
    pos: Vec<Vec<f64>>,
    support: f64,
    interactions: Vec<f64>,
}

/// Computes and prints (table or JSON lines) the report; returns its rows.
pub fn run_report(opts: &ReportOptions) -> Result<Vec<ReportRow>> {
    if opts.regions.is_empty() || opts.regions.contains(&0) {
        bail!("decompose: region counts must be at least 1");
    }
    check_sizes(opts)?;
    let mut samples = Vec::new();
    if opts.disk_particles > 0 {
        let pos = keplerian_disk(opts.disk_particles, 1);
        let support = support_for_neighbours(&pos, 20.0);
        let interactions = neighbour_counts(&pos, support);
        samples.push(Sample {
            name: "disk Σ∝1/R",
            dim: 2,
            lo: [-2.2, -2.2, 0.0],
            hi: [2.2, 2.2, 0.0],
            pos: Vec::from(pos),
            support,
            interactions: interactions.iter().map(|&k| k as f64).collect(),
        });
    }
    if opts.cluster_particles > 0 {
        let pos = clustered_cube(opts.cluster_particles, 2);
        let support = support_for_neighbours(&pos, 50.0);
        let interactions = neighbour_counts(&pos, support);
        samples.push(Sample {
            name: "clumps 3D",
            dim: 3,
            lo: [0.0; 3],
            hi: [1.0; 3],
            pos: Vec::from(pos),
            support,
            interactions: interactions.iter().map(|&k| k as f64).collect(),
        });
    }
    if !opts.json {
        print_legend();
        print_header();
    }
    let mut rows = Vec::new();
    for s in &samples {
        for &n in &opts.regions {
            let row = analyse(s, n);
            if opts.json {
                println!("{}", serde_json::to_string(&row)?);
            } else {
                print_row(&row);
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

/// Refuses, before anything is allocated, a sample of more particles than a run may hold or
/// this machine's memory holds, and more regions than a sample has particles (a region
/// would hold none), naming the option.
fn check_sizes(opts: &ReportOptions) -> Result<()> {
    use crate::limits::{MAX_PARTICLES, check_memory};
    let samples = [
        ("--disk-particles", opts.disk_particles, 2),
        ("--cluster-particles", opts.cluster_particles, 3),
    ];
    for (option, n, dim) in samples {
        if n == 0 {
            continue;
        }
        if n as u64 > MAX_PARTICLES {
            bail!("{option}: {n} is more than the {MAX_PARTICLES} particles a run can hold");
        }
        if dim == 2 {
            check_memory::<2>(n as u64, option)?;
        } else {
            check_memory::<3>(n as u64, option)?;
        }
        if let Some(&r) = opts.regions.iter().find(|&&r| r > n) {
            bail!(
                "--regions {r}: more regions than the {n} particles of {option} (a region would hold none)"
            );
        }
    }
    Ok(())
}

/// Moves of the cuts by measured one-sided pair counts after the interaction balance.
const PAIR_REBALANCES: usize = 6;

fn analyse(s: &Sample, n: usize) -> ReportRow {
    let start = Instant::now();
    let v: Vec<&[f64]> = s.pos.iter().map(|p| p.as_slice()).collect();
    let w = &s.interactions;
    let np = v[0].len();

    // Before the first step: balance by particle count.
    let mut d = Decomposition::build(n, s.dim, s.lo, s.hi, &v, &[]);
    let count = LoadStats::of(&d, &v, &[]);
    let inter_by_count = LoadStats::of(&d, &v, w);
    // After the first right-hand side: move the cuts to balance interactions.
    d.rebalance(&v, w, 1.0);
    let inter = LoadStats::of(&d, &v, w);
    // Then step after step: the pairs each rank evaluated under the one-sided rule, per
    // particle, move the cuts; measured again on the moved tree.
    let mut pw = pair_weights(s, &d.owners(&v));
    let pairs_first = LoadStats::of(&d, &v, &pw);
    for _ in 0..PAIR_REBALANCES {
        d.rebalance(&v, &pw, 1.0);
        pw = pair_weights(s, &d.owners(&v));
    }
    let pairs = LoadStats::of(&d, &v, &pw);
    let owned = LoadStats::of(&d, &v, &[]);
    let ghosts = d.one_sided_ghost_counts(&v, s.support);
    let fractions: Vec<f64> = ghosts
        .iter()
        .zip(&owned.per_region)
        .filter(|(_, o)| **o > 0.0)
        .map(|(&g, &o)| g as f64 / o)
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    ReportRow {
        distribution: s.name.to_string(),
        dim: s.dim,
        particles: np,
        regions: n,
        tree: d.shape().describe(s.dim),
        particles_per_region: np as f64 / n as f64,
        support: s.support,
        mean_neighbours: w.iter().sum::<f64>() / np.max(1) as f64,
        count_max_over_mean: count.max_over_mean,
        count_efficiency: count.efficiency,
        interactions_max_over_mean_count_balanced: inter_by_count.max_over_mean,
        interactions_max_over_mean: inter.max_over_mean,
        interactions_efficiency: inter.efficiency,
        pairs_max_over_mean_interaction_balanced: pairs_first.max_over_mean,
        pair_rebalances: PAIR_REBALANCES,
        pairs_max_over_mean: pairs.max_over_mean,
        pairs_efficiency: pairs.efficiency,
        particles_max_over_mean_final: owned.max_over_mean,
        ghost_fraction_mean: fractions.iter().sum::<f64>() / fractions.len().max(1) as f64,
        ghost_fraction_max: fractions.iter().cloned().fold(0.0, f64::max),
        ghost_fraction_total: ghosts.iter().sum::<usize>() as f64 / np.max(1) as f64,
        seconds,
    }
}

fn print_header() {
    println!(
        "{:<10} {:>6} {:>4} {:>5} {:>5} | {:>8} {:>6} | {:>8} | {:>8} {:>6} | {:>8} | {:>8} {:>6} | {:>8} | {:>7} {:>7} {:>6} | {:>5} | tree",
        "set",
        "parts",
        "regs",
        "p/reg",
        "neigh",
        "count",
        "eff",
        "inter¹",
        "inter",
        "eff",
        "pairs²",
        "pairs³",
        "eff",
        "count⁴",
        "ghosts",
        "max",
        "total",
        "s",
    );
}

fn print_row(r: &ReportRow) {
    let pct = |x: f64| format!("{:+.2}%", 100.0 * (x - 1.0));
    println!(
        "{:<10} {:>6} {:>4} {:>5.0} {:>5.1} | {:>8} {:>5.1}% | {:>8} | {:>8} {:>5.1}% | {:>8} | {:>8} {:>5.1}% | {:>8} | {:>6.1}% {:>6.1}% {:>5.1}% | {:>5.1} | {}",
        r.distribution,
        r.particles,
        r.regions,
        r.particles_per_region,
        r.mean_neighbours,
        pct(r.count_max_over_mean),
        100.0 * r.count_efficiency,
        pct(r.interactions_max_over_mean_count_balanced),
        pct(r.interactions_max_over_mean),
        100.0 * r.interactions_efficiency,
        pct(r.pairs_max_over_mean_interaction_balanced),
        pct(r.pairs_max_over_mean),
        100.0 * r.pairs_efficiency,
        pct(r.particles_max_over_mean_final),
        100.0 * r.ghost_fraction_mean,
        100.0 * r.ghost_fraction_max,
        100.0 * r.ghost_fraction_total,
        r.seconds,
        r.tree,
    );
}

/// What the table's columns mean.
fn print_legend() {
    println!(
        "Imbalance as max/mean − 1 over regions; eff = mean/max.\n\
         count: particles, tree balanced by count. inter¹: neighbour interactions on that tree.\n\
         inter: interactions after rebalancing by them (weight = neighbour count).\n\
         pairs²: pairs each rank evaluates under the one-sided ghost rule, on that tree;\n\
         pairs³: after {PAIR_REBALANCES} more moves of the cuts by the measured pairs (the final tree).\n\
         count⁴: particles on the final tree. ghosts: one-sided ghosts / owned particles per\n\
         region of the final tree, mean and max over regions; total: all ghosts / all particles.\n\
         s: seconds for the builds, moves and ghost count."
    );
}

/// `n` particles of a 2D disk with Σ ∝ R⁻¹ between R = 0.2 and 2.0: R uniform, azimuth
/// uniform.
pub fn keplerian_disk(n: usize, seed: u64) -> [Vec<f64>; 2] {
    let mut rng = Rng::new(seed);
    let mut pos = [Vec::with_capacity(n), Vec::with_capacity(n)];
    for _ in 0..n {
        let r = 0.2 + 1.8 * rng.uniform();
        let phi = std::f64::consts::TAU * rng.uniform();
        pos[0].push(r * phi.cos());
        pos[1].push(r * phi.sin());
    }
    pos
}

/// `n` particles in the unit cube: 40 % uniform background, and 15 % in each of two Plummer
/// spheres (scale radii 0.08 and 0.12) and two Gaussian clumps (σ 0.06 and 0.1); clump
/// particles falling outside the cube are drawn again.
pub fn clustered_cube(n: usize, seed: u64) -> [Vec<f64>; 3] {
    enum Clump {
        Plummer(f64),
        Gauss(f64),
    }
    let clumps = [
        ([0.3, 0.3, 0.3], Clump::Plummer(0.08)),
        ([0.7, 0.6, 0.4], Clump::Plummer(0.12)),
        ([0.25, 0.75, 0.7], Clump::Gauss(0.06)),
        ([0.65, 0.3, 0.75], Clump::Gauss(0.1)),
    ];
    let mut rng = Rng::new(seed);
    let mut pos = [
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
    ];
    for _ in 0..n {
        // Membership is drawn, not cycled: a cycle would alias with the strided sample that
        // `support_for_neighbours` measures on.
        let u = rng.uniform();
        let x: [f64; 3] = if u < 0.4 {
            std::array::from_fn(|_| rng.uniform())
        } else {
            let (centre, clump) = &clumps[(((u - 0.4) / 0.15) as usize).min(3)];
            loop {
                let off: [f64; 3] = match clump {
                    Clump::Gauss(sigma) => std::array::from_fn(|_| sigma * rng.normal()),
                    Clump::Plummer(a) => {
                        // Inverse of the enclosed mass M(<r)/M = r³/(r² + a²)^{3/2}.
                        let u = rng.uniform().max(1e-12);
                        let r = a / (u.powf(-2.0 / 3.0) - 1.0).max(1e-300).sqrt();
                        let cz = 2.0 * rng.uniform() - 1.0;
                        let phi = std::f64::consts::TAU * rng.uniform();
                        let sz = (1.0 - cz * cz).sqrt();
                        [r * sz * phi.cos(), r * sz * phi.sin(), r * cz]
                    }
                };
                let x: [f64; 3] = std::array::from_fn(|d| centre[d] + off[d]);
                if x.iter().all(|c| (0.0..=1.0).contains(c)) {
                    break x;
                }
            }
        };
        for d in 0..3 {
            pos[d].push(x[d]);
        }
    }
    pos
}

/// [`one_sided_pair_weights`] for a sample of either dimension.
fn pair_weights(s: &Sample, owners: &[usize]) -> Vec<f64> {
    if s.dim == 2 {
        let pos: [Vec<f64>; 2] = std::array::from_fn(|d| s.pos[d].clone());
        one_sided_pair_weights(&pos, s.support, owners)
    } else {
        let pos: [Vec<f64>; 3] = std::array::from_fn(|d| s.pos[d].clone());
        one_sided_pair_weights(&pos, s.support, owners)
    }
}

/// Particles sorted into the crate's neighbour grid (cells ≥ the support), positions copied
/// in cell order so that a cell's particles are contiguous.
struct CellList<const D: usize> {
    grid: Grid<D>,
    start: Vec<u32>,
    order: Vec<u32>,
    sorted: [Vec<f64>; D],
}

impl<const D: usize> CellList<D> {
    fn new(pos: &[Vec<f64>; D], support: f64) -> Self {
        let bx = SimBox {
            min: [0.0; D],
            max: [1.0; D],
            kinds: [BoundaryKind::Open; D],
        };
        let grid = Grid::new(&bx, support, pos);
        let (order, start) = grid.sort(pos);
        let sorted = std::array::from_fn(|d| order.iter().map(|&i| pos[d][i as usize]).collect());
        Self {
            grid,
            start,
            order,
            sorted,
        }
    }

    /// Calls `f` with the cell-order index of every particle closer than √`s2` to `x` (a
    /// particle at `x` itself included). The cells adjacent along the last axis are
    /// contiguous, so each of the 3^(D−1) rows of the stencil is one range.
    fn visit(&self, x: [f64; D], s2: f64, mut f: impl FnMut(usize)) {
        let c = self.grid.coords(x);
        let n = self.grid.n;
        for row in 0..3usize.pow(D as u32 - 1) {
            let mut cc = c;
            let mut rest = row;
            let mut inside = true;
            for d in 0..D - 1 {
                let v = c[d] as isize + (rest % 3) as isize - 1;
                rest /= 3;
                if v < 0 || v >= n[d] as isize {
                    inside = false;
                    break;
                }
                cc[d] = v as usize;
            }
            if !inside {
                continue;
            }
            let last = D - 1;
            cc[last] = c[last].saturating_sub(1);
            let a = self.start[self.grid.index(cc)] as usize;
            cc[last] = (c[last] + 1).min(n[last] - 1);
            let b = self.start[self.grid.index(cc) + 1] as usize;
            for k in a..b {
                let r2: f64 = (0..D).map(|d| (self.sorted[d][k] - x[d]).powi(2)).sum();
                if r2 < s2 {
                    f(k);
                }
            }
        }
    }

    /// Number of particles [`CellList::visit`] visits.
    fn count(&self, x: [f64; D], s2: f64) -> u32 {
        let mut total = 0;
        self.visit(x, s2, |_| total += 1);
        total
    }

    /// Position of the particle at cell-order index `k`.
    fn at(&self, k: usize) -> [f64; D] {
        std::array::from_fn(|d| self.sorted[d][k])
    }

    /// Per-particle values computed in cell order, put back in source order.
    fn unsort<T: Copy + Default>(&self, in_cell_order: Vec<T>) -> Vec<T> {
        let mut out = vec![T::default(); in_cell_order.len()];
        for (k, &i) in self.order.iter().enumerate() {
            out[i as usize] = in_cell_order[k];
        }
        out
    }
}

/// The pairs evaluated on each particle's behalf under the one-sided ghost rule
/// ([`super::ghosts`]): a pair within one rank counts ½ to each partner; a pair across two
/// ranks counts 1 to the partner on the lower rank, which evaluates it, and 0 to the other.
/// Summed over a rank's particles: the pairs that rank evaluates. Depends on the cuts.
pub fn one_sided_pair_weights<const D: usize>(
    pos: &[Vec<f64>; D],
    support: f64,
    owners: &[usize],
) -> Vec<f64> {
    let cells = CellList::new(pos, support);
    let s2 = support * support;
    let own: Vec<usize> = cells.order.iter().map(|&i| owners[i as usize]).collect();
    let in_cell_order: Vec<f64> = (0..own.len())
        .into_par_iter()
        .map(|k| {
            let mut w = 0.0;
            cells.visit(cells.at(k), s2, |m| {
                if m != k {
                    w += match own[m].cmp(&own[k]) {
                        std::cmp::Ordering::Equal => 0.5,
                        std::cmp::Ordering::Greater => 1.0,
                        std::cmp::Ordering::Less => 0.0,
                    };
                }
            });
            w
        })
        .collect();
    cells.unsort(in_cell_order)
}

/// Each particle's number of neighbours closer than `support` (itself excluded), exact, on
/// the neighbour grid.
pub fn neighbour_counts<const D: usize>(pos: &[Vec<f64>; D], support: f64) -> Vec<u32> {
    let cells = CellList::new(pos, support);
    let s2 = support * support;
    let in_cell_order: Vec<u32> = (0..cells.order.len())
        .into_par_iter()
        .map(|k| cells.count(cells.at(k), s2) - 1)
        .collect();
    cells.unsort(in_cell_order)
}

/// A support for which the particles' mean neighbour count is about `target`: a first guess
/// from the mean density over the particles' bounding box, then a few corrections by
/// (target / measured)^(1/D), measured on up to 20 000 particles.
pub fn support_for_neighbours<const D: usize>(pos: &[Vec<f64>; D], target: f64) -> f64 {
    let n = pos[0].len();
    if n < 2 {
        return 1.0;
    }
    let volume: f64 = (0..D)
        .map(|d| {
            let (a, b) = pos[d]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            (b - a).max(f64::MIN_POSITIVE)
        })
        .product();
    let ball = [2.0, std::f64::consts::PI, 4.0 * std::f64::consts::PI / 3.0][D - 1];
    let mut support = (target * volume / (n as f64 * ball)).powf(1.0 / D as f64);
    let step = (n / 20_000).max(1);
    for _ in 0..4 {
        let cells = CellList::new(pos, support);
        let s2 = support * support;
        let sample: Vec<usize> = (0..n).step_by(step).collect();
        let total: u64 = sample
            .par_iter()
            .map(|&i| (cells.count(std::array::from_fn(|d| pos[d][i]), s2) - 1) as u64)
            .sum();
        let mean = total as f64 / sample.len() as f64;
        support *= if mean > 0.0 {
            (target / mean).powf(1.0 / D as f64)
        } else {
            2.0
        };
    }
    support
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbour_counts_match_brute_force() {
        let mut rng = Rng::new(5);
        let pos: [Vec<f64>; 3] = std::array::from_fn(|_| (0..600).map(|_| rng.uniform()).collect());
        let counts = neighbour_counts(&pos, 0.15);
        for i in 0..600 {
            let brute = (0..600)
                .filter(|&j| {
                    j != i && (0..3).map(|d| (pos[d][i] - pos[d][j]).powi(2)).sum::<f64>() < 0.0225
                })
                .count();
            assert_eq!(counts[i] as usize, brute, "particle {i}");
        }
        let disk = keplerian_disk(800, 3);
        let c2 = neighbour_counts(&disk, 0.2);
        let brute: usize = (0..800)
            .map(|i| {
                (0..800)
                    .filter(|&j| {
                        j != i
                            && (disk[0][i] - disk[0][j]).powi(2) + (disk[1][i] - disk[1][j]).powi(2)
                                < 0.04
                    })
                    .count()
            })
            .sum();
        assert_eq!(c2.iter().map(|&c| c as usize).sum::<usize>(), brute);
    }

    #[test]
    fn pair_weights_sum_to_the_pairs_each_rank_evaluates() {
        let mut rng = Rng::new(9);
        let pos: [Vec<f64>; 2] = std::array::from_fn(|_| (0..700).map(|_| rng.uniform()).collect());
        let v: Vec<&[f64]> = pos.iter().map(|p| p.as_slice()).collect();
        let d = Decomposition::build(6, 2, [0.0; 3], [1.0; 3], &v, &[]);
        let owners = d.owners(&v);
        let support = 0.08;
        let w = one_sided_pair_weights(&pos, support, &owners);
        let loads = super::super::balance::region_loads(&d, &v, &w);
        // Brute force: each pair on the lower of its two owners.
        let mut pairs = [0.0; 6];
        for i in 0..700 {
            for j in i + 1..700 {
                if (pos[0][i] - pos[0][j]).powi(2) + (pos[1][i] - pos[1][j]).powi(2)
                    < support * support
                {
                    pairs[owners[i].min(owners[j])] += 1.0;
                }
            }
        }
        assert_eq!(loads, pairs.to_vec());
    }

    #[test]
    fn disk_has_sigma_inverse_r_and_clumps_stay_in_the_cube() {
        let disk = keplerian_disk(20_000, 1);
        let r: Vec<f64> = (0..20_000).map(|i| disk[0][i].hypot(disk[1][i])).collect();
        assert!(r.iter().all(|&r| (0.2..=2.0).contains(&r)));
        // Σ ∝ 1/R: R is uniform, so half the particles lie inside R = 1.1.
        let inner = r.iter().filter(|&&r| r < 1.1).count() as f64 / 20_000.0;
        assert!((inner - 0.5).abs() < 0.02, "{inner}");
        let cube = clustered_cube(10_000, 2);
        assert!(cube.iter().flatten().all(|x| (0.0..=1.0).contains(x)));
    }

    #[test]
    fn support_gives_the_asked_mean_neighbour_count() {
        let disk = keplerian_disk(5000, 4);
        let s = support_for_neighbours(&disk, 20.0);
        let c = neighbour_counts(&disk, s);
        let mean = c.iter().map(|&c| c as f64).sum::<f64>() / 5000.0;
        assert!((mean - 20.0).abs() < 2.0, "{mean}");
    }

    #[test]
    fn support_calibration_is_unbiased_on_the_clustered_box() {
        // 100 000 particles: the calibration samples every 5th one.
        let cube = clustered_cube(100_000, 2);
        let s = support_for_neighbours(&cube, 50.0);
        let c = neighbour_counts(&cube, s);
        let mean = c.iter().map(|&c| c as f64).sum::<f64>() / 100_000.0;
        assert!((mean - 50.0).abs() < 5.0, "{mean}");
    }

    #[test]
    fn report_balances_small_sets() {
        let rows = run_report(&ReportOptions {
            regions: vec![7, 16],
            disk_particles: 4000,
            cluster_particles: 6000,
            json: true,
        })
        .unwrap();
        assert_eq!(rows.len(), 4);
        for r in &rows {
            // Count balance within a few particles per region.
            assert!(
                r.count_max_over_mean < 1.0 + 4.0 / r.particles_per_region,
                "{r:?}"
            );
            assert!(r.interactions_max_over_mean < 1.15, "{r:?}");
            assert!(r.pairs_max_over_mean < 1.15, "{r:?}");
            assert!(r.ghost_fraction_max > 0.0 && r.ghost_fraction_total > 0.0);
        }
        assert!(
            run_report(&ReportOptions {
                regions: vec![0],
                disk_particles: 10,
                cluster_particles: 0,
                json: true
            })
            .is_err()
        );
    }

    /// Sizes that cannot be decomposed are refused naming the option, before a particle is
    /// placed (before, 10¹¹ disk particles aborted on a failed allocation, and 10⁸ regions
    /// of 200 000 particles ran for minutes).
    #[test]
    fn absurd_sizes_are_refused_naming_the_option() {
        let refused = |regions: Vec<usize>, disk: usize, cluster: usize, option: &str| {
            let e = run_report(&ReportOptions {
                regions,
                disk_particles: disk,
                cluster_particles: cluster,
                json: true,
            })
            .unwrap_err()
            .to_string();
            assert!(e.starts_with(option), "{e}");
        };
        refused(vec![4], 100_000_000_000, 0, "--disk-particles");
        refused(vec![4], 0, 100_000_000_000, "--cluster-particles");
        refused(vec![100_000_000], 200_000, 0, "--regions");
        refused(vec![15, 1000], 0, 500, "--regions");
    }
}
