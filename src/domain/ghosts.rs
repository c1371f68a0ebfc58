//! Ghost regions between ranks (paper, Section 2.3): a region's faces are treated as physical
//! boundaries, realised like the periodic ones of Section 2.2 with ghost particles that are
//! copies of other ranks' particles, and — as there — with every pair evaluated only once.
//!
//! **The one-sided rule.** A particle j owned by rank s is a ghost on rank r if and only if
//! r < s and j lies closer than `support` to r's cuboid. Rank r then evaluates every pair
//! between its own particles and the particles of *higher-ranked* neighbours; the higher rank
//! does not hold r's particles, so a pair that crosses a region boundary is evaluated exactly
//! once, on the lower of the two ranks (what r adds to its ghosts is sent back to their
//! owners, as periodic ghosts' sums are folded into their owners). Why it covers every pair:
//! for |x_i − x_j| < support with owners r < s, x_i lies in r's closed cuboid, so the
//! distance from x_j to that cuboid is at most |x_i − x_j|. The comparison is made on squared
//! distances, per axis monotone in floating point, so it holds exactly. It relies on each
//! particle lying inside its owner's cuboid: positions must be inside the box (periodic
//! images are out of scope here).
//!
//! [`Decomposition::ghost_sources`] gives the neighbour ranks in both directions (symmetric);
//! under the one-sided rule rank r receives ghosts only from those above it.

use super::decomposition::{Decomposition, point};

/// Squared distance between cuboids `a` and `b` along the first `dim` axes (0 if they touch
/// or overlap).
pub fn cuboid_distance2(a: ([f64; 3], [f64; 3]), b: ([f64; 3], [f64; 3]), dim: usize) -> f64 {
    (0..dim)
        .map(|d| {
            let gap = (b.0[d] - a.1[d]).max(a.0[d] - b.1[d]).max(0.0);
            gap * gap
        })
        .sum()
}

/// Squared distance from point `x` to cuboid `c` along the first `dim` axes (0 inside).
#[inline]
pub fn point_cuboid_distance2(x: [f64; 3], c: ([f64; 3], [f64; 3]), dim: usize) -> f64 {
    (0..dim)
        .map(|d| {
            let gap = (c.0[d] - x[d]).max(x[d] - c.1[d]).max(0.0);
            gap * gap
        })
        .sum()
}

impl Decomposition {
    /// The ranks other than `rank` whose regions lie closer than `support` to `rank`'s
    /// region (cuboid–cuboid distance < support): its neighbours for ghost exchange, in either
    /// direction. Symmetric: s is in r's list exactly when r is in s's. Under the one-sided
    /// rule `rank` receives ghosts only from the entries above it, and sends its particles to
    /// those below it.
    pub fn ghost_sources(&self, rank: usize, support: f64) -> Vec<usize> {
        let mine = self.region(rank);
        let s2 = support * support;
        (0..self.n_regions())
            .filter(|&s| s != rank && cuboid_distance2(mine, self.region(s), self.dim()) < s2)
            .collect()
    }

    /// The particles that are one-sided ghosts on `rank`: indices j owned by a higher rank
    /// and closer than `support` to `rank`'s cuboid (module documentation). O(particles);
    /// for every rank at once use [`Decomposition::one_sided_ghost_counts`].
    pub fn one_sided_ghosts(&self, rank: usize, positions: &[&[f64]], support: f64) -> Vec<usize> {
        let mine = self.region(rank);
        let s2 = support * support;
        let dim = self.dim();
        (0..positions[0].len())
            .filter(|&j| {
                let x = point(positions, dim, j);
                self.owner(x) > rank && point_cuboid_distance2(x, mine, dim) < s2
            })
            .collect()
    }

    /// Number of one-sided ghosts on `rank`.
    pub fn one_sided_ghost_count(&self, rank: usize, positions: &[&[f64]], support: f64) -> usize {
        self.one_sided_ghosts(rank, positions, support).len()
    }

    /// Number of one-sided ghosts on every rank, in one pass over the particles: each
    /// particle is tested only against the lower-ranked neighbours of its owner.
    pub fn one_sided_ghost_counts(&self, positions: &[&[f64]], support: f64) -> Vec<usize> {
        let n = self.n_regions();
        let dim = self.dim();
        let s2 = support * support;
        let regions: Vec<_> = (0..n).map(|r| self.region(r)).collect();
        let lower: Vec<Vec<usize>> = (0..n)
            .map(|s| {
                (0..s)
                    .filter(|&r| cuboid_distance2(regions[r], regions[s], dim) < s2)
                    .collect()
            })
            .collect();
        let mut counts = vec![0; n];
        for j in 0..positions[0].len() {
            let x = point(positions, dim, j);
            for &r in &lower[self.owner(x)] {
                if point_cuboid_distance2(x, regions[r], dim) < s2 {
                    counts[r] += 1;
                }
            }
        }
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use std::collections::HashMap;

    fn points(n: usize, dim: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = Rng::new(seed);
        (0..dim)
            .map(|_| (0..n).map(|_| rng.uniform().powi(2)).collect())
            .collect()
    }

    fn view(pos: &[Vec<f64>]) -> Vec<&[f64]> {
        pos.iter().map(|p| p.as_slice()).collect()
    }

    #[test]
    fn one_sided_ghosts_cover_each_cross_pair_once() {
        for (n, dim, support) in [(7, 2, 0.08), (15, 2, 0.05), (12, 3, 0.12), (5, 1, 0.01)] {
            let mut pos = points(1500, dim, 41);
            let d = Decomposition::build(n, dim, [0.0; 3], [1.0; 3], &view(&pos), &[]);
            // Add particles exactly on the cuts, and pairs straddling them.
            let mut rng = Rng::new(2);
            for &xc in &d.tree().x[1..d.tree().x.len() - 1] {
                for dx in [0.0, -0.3 * support, 0.3 * support] {
                    pos[0].push(xc + dx);
                    for p in pos.iter_mut().skip(1) {
                        p.push(rng.uniform());
                    }
                }
            }
            let v = view(&pos);
            let owners = d.owners(&v);
            // Every (owned, ghost) pair within support on every rank.
            let mut seen: HashMap<(usize, usize), usize> = HashMap::new();
            for r in 0..n {
                let ghosts = d.one_sided_ghosts(r, &v, support);
                for i in (0..owners.len()).filter(|&i| owners[i] == r) {
                    for &j in &ghosts {
                        assert_ne!(owners[j], r);
                        if dist2(&v, dim, i, j) < support * support {
                            *seen.entry((i.min(j), i.max(j))).or_default() += 1;
                        }
                    }
                }
            }
            // Brute force: every cross pair within support, exactly once.
            let mut expected = 0;
            for i in 0..owners.len() {
                for j in i + 1..owners.len() {
                    if owners[i] != owners[j] && dist2(&v, dim, i, j) < support * support {
                        expected += 1;
                        assert_eq!(seen.get(&(i, j)), Some(&1), "{dim}D {n}: pair ({i}, {j})");
                    }
                }
            }
            assert_eq!(seen.len(), expected);
            assert!(
                expected > 100,
                "{dim}D {n}: only {expected} cross pairs tested"
            );
        }
    }

    fn dist2(v: &[&[f64]], dim: usize, i: usize, j: usize) -> f64 {
        (0..dim).map(|d| (v[d][i] - v[d][j]).powi(2)).sum()
    }

    #[test]
    fn ghost_counts_in_one_pass_match_per_rank() {
        let pos = points(3000, 3, 43);
        let v = view(&pos);
        let d = Decomposition::build(20, 3, [0.0; 3], [1.0; 3], &v, &[]);
        let all = d.one_sided_ghost_counts(&v, 0.07);
        for (r, &count) in all.iter().enumerate() {
            assert_eq!(count, d.one_sided_ghost_count(r, &v, 0.07));
        }
        // The highest rank has no one above it to take ghosts from.
        assert_eq!(all[19], 0);
        assert!(all[0] > 0);
    }

    #[test]
    fn ghost_sources_are_symmetric_neighbours() {
        for (n, dim) in [(15, 2), (32, 2), (64, 3), (6, 1)] {
            let pos = points(5000, dim, 47);
            let d = Decomposition::build(n, dim, [0.0; 3], [1.0; 3], &view(&pos), &[]);
            for support in [0.0, 0.03, 0.2] {
                let lists: Vec<Vec<usize>> = (0..n).map(|r| d.ghost_sources(r, support)).collect();
                for r in 0..n {
                    assert!(!lists[r].contains(&r));
                    for &s in &lists[r] {
                        assert!(lists[s].contains(&r), "{dim}D {n}: {s} lists not {r}");
                    }
                }
                // With a positive support, face neighbours (touching cuboids) are included.
                if support > 0.0 {
                    for r in 0..n {
                        for s in 0..n {
                            let touch =
                                s != r && cuboid_distance2(d.region(r), d.region(s), dim) == 0.0;
                            assert!(!touch || lists[r].contains(&s));
                        }
                    }
                }
                // Zero support: nobody.
                if support == 0.0 {
                    assert!(lists.iter().all(|l| l.is_empty()));
                }
            }
            // A support as wide as the box: everyone.
            assert_eq!(d.ghost_sources(0, 2.0).len(), n - 1);
        }
    }

    #[test]
    fn distances_between_cuboids_and_points() {
        let a = ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        let b = ([2.0, 1.0, 0.0], [3.0, 2.0, 1.0]);
        assert_eq!(cuboid_distance2(a, b, 2), 1.0);
        assert_eq!(cuboid_distance2(b, a, 3), 1.0);
        assert_eq!(point_cuboid_distance2([0.5, 0.5, 9.0], a, 2), 0.0);
        assert_eq!(point_cuboid_distance2([-1.0, 3.0, 0.0], a, 2), 5.0);
    }
}
