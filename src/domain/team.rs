//! The ranks of a distributed run as the step loop's [`Team`] (paper, Sections 2.3–2.4):
//! the k-d decomposition built from particle counts before the first step, the distributed
//! evaluation of each step ([`super::exchange`]), and between steps the load measured,
//! the cuts moved when the imbalance exceeds a threshold, and particles moved to their new
//! owners. Rank 0 collects the particles for snapshots, checkpoints and the final outputs.
//!
//! Works over any [`Comm`]: MPI ranks (`mpirun -n N sphdisk run …`, feature `mpi`) or
//! in-process ranks ([`super::comm::ThreadComm`], used by the tests).

use anyhow::{Result, bail};
use serde_json::json;

use super::balance::{LoadMeasure, LoadStats, interaction_cost_factors, needs_rebalance};
use super::comm::Comm;
use super::decomposition::{Decomposition, coords};
use super::exchange::{self, ExchangeStats};
use crate::boundary::SimBox;
use crate::integrate::{add_external, rhs};
use crate::io::log::RunLog;
use crate::particles::Particles;
use crate::sweep::{Physics, SweepStats, Window};

/// Imbalance (max/mean interactions − 1) above which the cuts move between steps.
pub const REBALANCE_THRESHOLD: f64 = 0.03;
/// At most this many particles (over all ranks) are sampled to place the cuts.
const CUT_SAMPLE: usize = 400_000;
/// Imbalance history kept for `summary.json`: every step up to this many, then thinned.
const HISTORY: usize = 2000;

/// The processes a run is spread over, as the step loop sees them: one process ([`Solo`]),
/// or the ranks of a distributed run ([`Distributed`]). Every rank runs the same loop on its
/// own particles; the team evaluates right-hand sides together, reduces figures to global
/// ones, and collects the particles on rank 0 for output. Every call is collective: all
/// ranks make it, in the same order.
pub trait Team<const D: usize> {
    /// Whether this process writes the outputs.
    fn is_root(&self) -> bool;
    fn ranks(&self) -> usize;
    /// Keeps this rank's share of the whole particle set (at the start of a run).
    fn distribute(&mut self, p: &mut Particles<D>, bx: &SimBox<D>);
    /// New accelerations and du/dt of this rank's particles (with external gravity).
    fn evaluate(
        &mut self,
        p: &mut Particles<D>,
        bx: &SimBox<D>,
        phys: &Physics<D>,
        window: Window,
    ) -> SweepStats;
    /// Element-wise sum, min or max over the ranks, in place.
    fn sum(&mut self, x: &mut [f64]);
    fn min(&mut self, x: &mut [f64]);
    fn max(&mut self, x: &mut [f64]);
    /// Particles inserted on this rank since the last step (a binary's L1 stream) go to the
    /// ranks that own their places, by the same path as migration.
    fn adopt(&mut self, p: &mut Particles<D>);
    /// Every particle, on rank 0 (in id order); None on the other ranks.
    fn gather(&mut self, p: &Particles<D>) -> Option<Particles<D>>;
    /// After a step: move particles to their new owners, rebalance the load.
    fn between_steps(&mut self, p: &mut Particles<D>, step: u64, log: &mut RunLog) -> Result<()>;
    /// Figures of the distribution for `summary.json` (collective; None on one process).
    fn record(&mut self) -> Option<serde_json::Value>;
}

/// One process, with threads.
pub struct Solo;

impl<const D: usize> Team<D> for Solo {
    fn is_root(&self) -> bool {
        true
    }
    fn ranks(&self) -> usize {
        1
    }
    fn distribute(&mut self, _: &mut Particles<D>, _: &SimBox<D>) {}
    fn evaluate(
        &mut self,
        p: &mut Particles<D>,
        bx: &SimBox<D>,
        phys: &Physics<D>,
        window: Window,
    ) -> SweepStats {
        rhs(p, bx, phys, window)
    }
    fn sum(&mut self, _: &mut [f64]) {}
    fn min(&mut self, _: &mut [f64]) {}
    fn max(&mut self, _: &mut [f64]) {}
    fn adopt(&mut self, _: &mut Particles<D>) {}
    fn gather(&mut self, p: &Particles<D>) -> Option<Particles<D>> {
        Some(p.clone())
    }
    fn between_steps(&mut self, _: &mut Particles<D>, _: u64, _: &mut RunLog) -> Result<()> {
        Ok(())
    }
    fn record(&mut self) -> Option<serde_json::Value> {
        None
    }
}

/// A distributed run's ranks.
pub struct Distributed<'c> {
    comm: &'c mut dyn Comm,
    decomp: Option<Decomposition>,
    measure: LoadMeasure,
    /// Per step: max/mean over ranks of the interactions and of the busy time.
    imbalance: Vec<(u64, f64, f64)>,
    rebalances: u64,
    migrated: u64,
    evaluations: u64,
    /// This rank's totals over the run.
    totals: ExchangeStats,
    last: ExchangeStats,
    /// Test hooks: return an error (`SPHDISK_FAIL_AT=rank:step`) or panic
    /// (`SPHDISK_PANIC_AT=rank:step`) on that rank after that step, to exercise the abort.
    fail_at: Option<(usize, u64)>,
    panic_at: Option<(usize, u64)>,
}

impl<'c> Distributed<'c> {
    pub fn new(comm: &'c mut dyn Comm) -> Self {
        let hook = |var: &str| {
            std::env::var(var).ok().and_then(|s| {
                let (r, k) = s.split_once(':')?;
                Some((r.trim().parse().ok()?, k.trim().parse().ok()?))
            })
        };
        Self {
            comm,
            decomp: None,
            measure: LoadMeasure::ParticleCount,
            imbalance: Vec::new(),
            rebalances: 0,
            migrated: 0,
            evaluations: 0,
            totals: ExchangeStats::default(),
            last: ExchangeStats::default(),
            fail_at: hook("SPHDISK_FAIL_AT"),
            panic_at: hook("SPHDISK_PANIC_AT"),
        }
    }

    fn decomp(&self) -> &Decomposition {
        self.decomp
            .as_ref()
            .expect("distribute() before the first step")
    }

    /// Moves the cuts to balance `weights` (one per particle of this rank), from a sample
    /// of every rank's particles gathered on every rank (so that all place the same cuts).
    fn rebalance<const D: usize>(&mut self, p: &Particles<D>, weights: &[f64]) {
        let mut n = [p.len() as f64];
        self.comm.sum(&mut n);
        let stride = (n[0] as usize).div_ceil(CUT_SAMPLE).max(1);
        let mut mine = Vec::new();
        for i in (0..p.len()).step_by(stride) {
            mine.extend((0..D).map(|d| p.pos[d][i]));
            mine.push(weights[i] * stride as f64);
        }
        let all = self.comm.all_gather(mine);
        let mut pos: [Vec<f64>; D] = std::array::from_fn(|_| Vec::new());
        let mut w = Vec::new();
        for part in &all {
            for c in part.chunks_exact(D + 1) {
                for d in 0..D {
                    pos[d].push(c[d]);
                }
                w.push(c[D]);
            }
        }
        let coords: Vec<&[f64]> = pos.iter().map(Vec::as_slice).collect();
        self.decomp
            .as_mut()
            .expect("decomposition")
            .rebalance(&coords, &w, 1.0);
        self.rebalances += 1;
    }
}

impl<const D: usize> Team<D> for Distributed<'_> {
    fn is_root(&self) -> bool {
        self.comm.rank() == 0
    }

    fn ranks(&self) -> usize {
        self.comm.size()
    }

    fn distribute(&mut self, p: &mut Particles<D>, bx: &SimBox<D>) {
        // Every rank holds the same whole set here: the same cuts everywhere.
        let decomp = Decomposition::for_particles(self.comm.size(), bx, p, &[]);
        let me = self.comm.rank();
        let keep: Vec<bool> = decomp
            .owners(&coords(p))
            .into_iter()
            .map(|o| o == me)
            .collect();
        p.retain(&keep);
        self.decomp = Some(decomp);
    }

    fn evaluate(
        &mut self,
        p: &mut Particles<D>,
        bx: &SimBox<D>,
        phys: &Physics<D>,
        window: Window,
    ) -> SweepStats {
        let decomp = self
            .decomp
            .take()
            .expect("distribute() before the first step");
        let s = exchange::evaluate(self.comm, &decomp, p, bx, phys, window);
        self.decomp = Some(decomp);
        add_external(p, phys);
        self.evaluations += 1;
        let t = &mut self.totals;
        t.copies_sent += s.copies_sent;
        t.copies_received += s.copies_received;
        t.values_sent += s.values_sent;
        t.messages_sent += s.messages_sent;
        t.wait += s.wait;
        t.total += s.total;
        t.sweep.pairs += s.sweep.pairs;
        t.sweep.times.add(&s.sweep.times);
        self.last = s;
        s.sweep
    }

    fn sum(&mut self, x: &mut [f64]) {
        self.comm.sum(x);
    }

    fn min(&mut self, x: &mut [f64]) {
        self.comm.min(x);
    }

    fn max(&mut self, x: &mut [f64]) {
        self.comm.max(x);
    }

    fn adopt(&mut self, p: &mut Particles<D>) {
        let decomp = self.decomp.take().expect("decomposition");
        self.migrated += exchange::migrate(self.comm, &decomp, p) as u64;
        self.decomp = Some(decomp);
    }

    fn gather(&mut self, p: &Particles<D>) -> Option<Particles<D>> {
        let mut buf = Vec::with_capacity(p.len() * Particles::<D>::STATE_LEN);
        for i in 0..p.len() {
            p.state_of(i, &mut buf);
        }
        let parts = self.comm.gather(buf)?;
        let mut rows: Vec<&[f64]> = parts
            .iter()
            .flat_map(|b| b.chunks_exact(Particles::<D>::STATE_LEN))
            .collect();
        rows.sort_by_key(|r| r[0].to_bits());
        let flat: Vec<f64> = rows.concat();
        let mut all = Particles::new();
        all.push_states(&flat);
        Some(all)
    }

    fn between_steps(&mut self, p: &mut Particles<D>, step: u64, log: &mut RunLog) -> Result<()> {
        if let Some((r, k)) = self.fail_at
            && r == self.comm.rank()
            && k == step
        {
            bail!("failure injected by SPHDISK_FAIL_AT={r}:{k} (test of the abort path)");
        }
        if let Some((r, k)) = self.panic_at
            && r == self.comm.rank()
            && k == step
        {
            panic!("panic injected by SPHDISK_PANIC_AT={r}:{k} (test of the abort path)");
        }
        // Load of the step just taken, per rank: interactions, and the busy time (the
        // evaluation's time less the time spent waiting for other ranks).
        let my_interactions: f64 = p.interactions.iter().map(|&k| k as f64).sum();
        let my_busy = (self.last.total - self.last.wait).max(0.0);
        let per_rank = self.comm.all_gather(vec![my_interactions, my_busy]);
        let interactions: Vec<f64> = per_rank.iter().map(|v| v[0]).collect();
        let busy: Vec<f64> = per_rank.iter().map(|v| v[1]).collect();
        let stats = LoadStats::from_loads(interactions.clone());
        let busy_stats = LoadStats::from_loads(busy.clone());
        if self.imbalance.len() >= HISTORY {
            // Keep every other entry: the history stays bounded and spans the whole run.
            let kept: Vec<_> = self.imbalance.iter().copied().step_by(2).collect();
            self.imbalance = kept;
        }
        self.imbalance
            .push((step, stats.max_over_mean, busy_stats.max_over_mean));
        self.measure = self.measure.next(true, &stats, REBALANCE_THRESHOLD);
        // Paper 2.4: balance the interactions; once they are balanced, fine-tune by the time
        // each rank was busy. A rank's time per interaction (it includes the pairs it
        // evaluates for higher ranks' particles, and its speed) weighs its particles, so
        // the cuts equalise the predicted busy time.
        let (trigger, weight_per_interaction) = match self.measure {
            LoadMeasure::WaitTime => {
                let cost = interaction_cost_factors(&interactions, &busy)[self.comm.rank()];
                (&busy_stats, cost)
            }
            _ => (&stats, 1.0),
        };
        if needs_rebalance(trigger, REBALANCE_THRESHOLD) {
            let w: Vec<f64> = p
                .interactions
                .iter()
                .map(|&k| weight_per_interaction * (k as f64).max(1.0))
                .collect();
            self.rebalance(p, &w);
            log.line(&format!(
                "step {step}: load max/mean {:.4} > {:.2} ({:?}): cuts moved",
                trigger.max_over_mean,
                1.0 + REBALANCE_THRESHOLD,
                self.measure
            ));
        }
        let decomp = self.decomp.take().expect("decomposition");
        self.migrated += exchange::migrate(self.comm, &decomp, p) as u64;
        self.decomp = Some(decomp);
        Ok(())
    }

    fn record(&mut self) -> Option<serde_json::Value> {
        let t = &self.totals;
        let mine = vec![
            t.wait,
            t.total,
            t.copies_sent as f64,
            t.copies_received as f64,
            t.values_sent as f64,
            t.messages_sent as f64,
            self.migrated as f64,
            t.sweep.pairs as f64,
        ];
        let all = self.comm.gather(mine)?;
        let evals = self.evaluations.max(1) as f64;
        let per_rank: Vec<serde_json::Value> = all
            .iter()
            .enumerate()
            .map(|(r, v)| {
                json!({
                    "rank": r,
                    "wait_seconds": v[0],
                    "evaluate_seconds": v[1],
                    "wait_fraction": if v[1] > 0.0 { v[0] / v[1] } else { 0.0 },
                    "copies_sent_per_step": v[2] / evals,
                    "copies_received_per_step": v[3] / evals,
                    "bytes_sent_per_step": 8.0 * v[4] / evals,
                    "messages_per_step": v[5] / evals,
                    "particles_migrated": v[6],
                    "pairs_per_step": v[7] / evals,
                })
            })
            .collect();
        let stat = |f: fn(&(u64, f64, f64)) -> f64| {
            let h: Vec<f64> = self.imbalance.iter().map(f).collect();
            let max = h.iter().copied().fold(1.0, f64::max);
            (max, h.iter().sum::<f64>() / h.len().max(1) as f64)
        };
        let (max, mean) = stat(|x| x.1);
        let (busy_max, busy_mean) = stat(|x| x.2);
        let d = self.decomp();
        Some(json!({
            "ranks": self.comm.size(),
            "tree": d.shape().describe(d.dim()),
            "rebalance_threshold": REBALANCE_THRESHOLD,
            "rebalances": self.rebalances,
            "load_measure": format!("{:?}", self.measure),
            // max/mean over ranks of the interactions (the balanced load)…
            "imbalance_max": max,
            "imbalance_mean": mean,
            // …and of the busy time (what the wait-time tuning balances).
            "busy_imbalance_max": busy_max,
            "busy_imbalance_mean": busy_mean,
            // [step, interactions max/mean, busy time max/mean]
            "imbalance_history": self.imbalance.iter().map(|&(s, x, b)| json!([s, x, b])).collect::<Vec<_>>(),
            "per_rank": per_rank,
        }))
    }
}
