//! Load balancing between steps (paper, Section 2.4): per-region load statistics, the
//! sequence of load measures the paper uses to place the cuts, the waiting-time correction,
//! and when to move the cuts.
//!
//! The cuts themselves are moved by [`Decomposition::rebalance`] with per-particle weights;
//! this file says which weights.

use super::decomposition::{Decomposition, point};

/// Statistics of one load per region.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct LoadStats {
    /// Largest load over the mean load (1 is perfect balance).
    pub max_over_mean: f64,
    /// Mean over largest, the fraction of the machine doing useful work when every rank waits
    /// for the slowest (1 is perfect).
    pub efficiency: f64,
    pub per_region: Vec<f64>,
}

impl LoadStats {
    /// Statistics of the given per-region loads. All-zero loads count as balanced.
    pub fn from_loads(per_region: Vec<f64>) -> Self {
        let n = per_region.len().max(1) as f64;
        let mean = per_region.iter().sum::<f64>() / n;
        let max = per_region.iter().cloned().fold(0.0, f64::max);
        let (max_over_mean, efficiency) = if max > 0.0 {
            (max / mean, mean / max)
        } else {
            (1.0, 1.0)
        };
        Self {
            max_over_mean,
            efficiency,
            per_region,
        }
    }

    /// Statistics of the sums of per-particle `weights` (empty: particle counts) over each
    /// region of `decomp`.
    pub fn of(decomp: &Decomposition, positions: &[&[f64]], weights: &[f64]) -> Self {
        Self::from_loads(region_loads(decomp, positions, weights))
    }
}

/// Sum of the per-particle `weights` (empty: 1 each, the particle count) over each region.
pub fn region_loads(decomp: &Decomposition, positions: &[&[f64]], weights: &[f64]) -> Vec<f64> {
    let mut loads = vec![0.0; decomp.n_regions()];
    for i in 0..positions[0].len() {
        let w = if weights.is_empty() { 1.0 } else { weights[i] };
        loads[decomp.owner(point(positions, decomp.dim(), i))] += w;
    }
    loads
}

/// What the cuts balance, in the order the paper uses them (Section 2.4):
///
/// 1. [`LoadMeasure::ParticleCount`] before the first step, when nothing else is known:
///    every particle weighs 1;
/// 2. [`LoadMeasure::Interactions`] once a right-hand side has been evaluated: a particle
///    weighs its number of interactions (neighbours within the support, as counted by the
///    sweep in `Particles::interactions`), since the pair sums dominate the work;
/// 3. [`LoadMeasure::WaitTime`] once an acceptable set of boundaries has been found: the
///    interaction weights are fine-tuned by the time each rank spent waiting for the others.
///    A distributed run (`domain::team`) weighs each rank's interactions by its
///    [`interaction_cost_factors`] (busy time per interaction over the mean), so that the
///    cuts equalise the predicted busy time; [`wait_time_correction`] is the simpler factor
///    (busy time over mean busy time), which a second correction would undo.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadMeasure {
    ParticleCount,
    Interactions,
    WaitTime,
}

impl LoadMeasure {
    /// The measure to balance by next: particle count until a right-hand side has been
    /// evaluated (`rhs_evaluated`), then interactions until the interaction loads `stats` are
    /// within `threshold` of balance, then waiting time from there on.
    pub fn next(self, rhs_evaluated: bool, stats: &LoadStats, threshold: f64) -> Self {
        match self {
            Self::ParticleCount if rhs_evaluated => Self::Interactions,
            Self::Interactions if !needs_rebalance(stats, threshold) => Self::WaitTime,
            other => other,
        }
    }
}

/// Bounds of a [`wait_time_correction`] factor: a rank that measured (almost) no busy time
/// must not have its weight vanish and swallow the domain, nor a stalled one shrink to nothing.
pub const CORRECTION_RANGE: (f64, f64) = (0.25, 4.0);

/// Per-rank multiplicative weight factors from the last step's timing: rank r was busy for
/// `step_time − wait[r]` (the wall time of the step less the time it spent waiting for other
/// ranks); its factor is its busy time over the mean busy time, clamped to
/// [`CORRECTION_RANGE`]. Multiply each particle's weight by its owner's factor (see
/// [`corrected_weights`]) before [`Decomposition::rebalance`]: a region that was busier than
/// its weight said gets heavier weights and so a smaller share of the domain. All ranks idle
/// (or no timing): factors of 1.
pub fn wait_time_correction(step_time: f64, wait: &[f64]) -> Vec<f64> {
    let busy: Vec<f64> = wait.iter().map(|w| (step_time - w).max(0.0)).collect();
    let mean = busy.iter().sum::<f64>() / busy.len().max(1) as f64;
    busy.iter()
        .map(|&b| {
            if mean > 0.0 {
                (b / mean).clamp(CORRECTION_RANGE.0, CORRECTION_RANGE.1)
            } else {
                1.0
            }
        })
        .collect()
}

/// Per-rank factors for the interaction weights from the last step: rank r had
/// `interactions[r]` interactions and was busy (evaluation time less waiting) for
/// `busy[r]` seconds; its factor is its busy time per interaction over the mean, clamped
/// to [`CORRECTION_RANGE`]. It includes what a rank does beyond its own particles' sums
/// (the pairs it evaluates for higher ranks' particles) and its speed, and it stays the
/// same after the cuts move, so repeated corrections do not undo each other. Ranks with no
/// interactions or no timing get 1.
pub fn interaction_cost_factors(interactions: &[f64], busy: &[f64]) -> Vec<f64> {
    let mean_cost = busy.iter().sum::<f64>() / interactions.iter().sum::<f64>().max(1.0);
    interactions
        .iter()
        .zip(busy)
        .map(|(&k, &b)| {
            if k > 0.0 && mean_cost > 0.0 {
                (b / k / mean_cost).clamp(CORRECTION_RANGE.0, CORRECTION_RANGE.1)
            } else {
                1.0
            }
        })
        .collect()
}

/// Per-particle `weights` (empty: 1 each) times the factor of each particle's owner.
pub fn corrected_weights(
    decomp: &Decomposition,
    positions: &[&[f64]],
    weights: &[f64],
    factors: &[f64],
) -> Vec<f64> {
    (0..positions[0].len())
        .map(|i| {
            let w = if weights.is_empty() { 1.0 } else { weights[i] };
            w * factors[decomp.owner(point(positions, decomp.dim(), i))]
        })
        .collect()
}

/// Whether the loads are out of balance by more than `threshold` (max/mean > 1 + threshold):
/// the cuts should move before the next step.
pub fn needs_rebalance(stats: &LoadStats, threshold: f64) -> bool {
    stats.max_over_mean > 1.0 + threshold
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::decomposition::TreeShape;

    #[test]
    fn interaction_cost_factors_weigh_slower_interactions_more() {
        // Rank 1 needs twice the time per interaction of rank 0; rank 2 measured nothing.
        let f = interaction_cost_factors(&[100.0, 100.0, 0.0], &[1.0, 2.0, 0.0]);
        let mean = 3.0 / 200.0;
        assert!((f[0] - 0.01 / mean).abs() < 1e-12);
        assert!((f[1] - 0.02 / mean).abs() < 1e-12);
        assert_eq!(f[2], 1.0);
    }

    #[test]
    fn load_stats_measure_max_over_mean_and_efficiency() {
        let s = LoadStats::from_loads(vec![1.0, 2.0, 3.0]);
        assert_eq!(s.max_over_mean, 1.5);
        assert!((s.efficiency - 2.0 / 3.0).abs() < 1e-15);
        assert_eq!(LoadStats::from_loads(vec![0.0; 4]).max_over_mean, 1.0);
        assert!(needs_rebalance(&s, 0.03));
        assert!(!needs_rebalance(
            &LoadStats::from_loads(vec![1.0, 1.02]),
            0.03
        ));
    }

    #[test]
    fn region_loads_sum_weights_by_owner() {
        let d = Decomposition::new(&TreeShape::uniform([2, 1, 1]), 2, [0.0; 3], [1.0; 3]);
        let pos = [vec![0.1, 0.6, 0.7], vec![0.5, 0.5, 0.5]];
        let v: Vec<&[f64]> = pos.iter().map(|p| p.as_slice()).collect();
        assert_eq!(region_loads(&d, &v, &[]), vec![1.0, 2.0]);
        assert_eq!(region_loads(&d, &v, &[5.0, 1.0, 2.0]), vec![5.0, 3.0]);
    }

    #[test]
    fn load_measure_follows_the_papers_sequence() {
        let balanced = LoadStats::from_loads(vec![1.0, 1.01]);
        let off = LoadStats::from_loads(vec![1.0, 2.0]);
        let m = LoadMeasure::ParticleCount;
        assert_eq!(m.next(false, &balanced, 0.03), LoadMeasure::ParticleCount);
        let m = m.next(true, &off, 0.03);
        assert_eq!(m, LoadMeasure::Interactions);
        assert_eq!(m.next(true, &off, 0.03), LoadMeasure::Interactions);
        let m = m.next(true, &balanced, 0.03);
        assert_eq!(m, LoadMeasure::WaitTime);
        assert_eq!(m.next(true, &off, 0.03), LoadMeasure::WaitTime);
    }

    #[test]
    fn wait_time_correction_makes_busy_ranks_heavier() {
        // Step of 10 s: rank 0 waited 6 s (busy 4), rank 1 waited 2 s (busy 8), rank 2 none.
        let f = wait_time_correction(10.0, &[6.0, 2.0, 0.0]);
        let mean = (4.0 + 8.0 + 10.0) / 3.0;
        assert!((f[0] - 4.0 / mean).abs() < 1e-12);
        assert!((f[2] - 10.0 / mean).abs() < 1e-12);
        assert_eq!(wait_time_correction(1.0, &[1.0, 1.0]), vec![1.0, 1.0]);
        // A rank that did nothing is clamped, not zeroed.
        assert_eq!(
            wait_time_correction(1.0, &[1.0, 0.0])[0],
            CORRECTION_RANGE.0
        );
    }

    #[test]
    fn wait_time_correction_moves_cuts_away_from_the_slow_rank() {
        let n = 2000;
        let pos = [
            (0..n)
                .map(|i| (i as f64 + 0.5) / n as f64)
                .collect::<Vec<_>>(),
            vec![0.5; n],
        ];
        let v: Vec<&[f64]> = pos.iter().map(|p| p.as_slice()).collect();
        let mut d = Decomposition::build(2, 2, [0.0; 3], [1.0; 3], &v, &[]);
        assert!((d.tree().x[1] - 0.5).abs() < 1e-3);
        // Rank 0 was busy 3 s, rank 1 1 s, for equal weights: factors 1.5 and 0.5, and the
        // cut moves to where 1.5 x = 1.5 (0.5 − x) + 0.5 · 0.5, x = 1/3 (one step towards
        // the 1/4 that would equalise the times if a particle's cost stayed with its side).
        let f = wait_time_correction(4.0, &[1.0, 3.0]);
        assert_eq!(f, vec![1.5, 0.5]);
        let w = corrected_weights(&d, &v, &[], &f);
        d.rebalance(&v, &w, 1.0);
        assert!((d.tree().x[1] - 1.0 / 3.0).abs() < 1e-3, "{:?}", d.tree().x);
    }
}
