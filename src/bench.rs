//! `sphdisk bench`: throughput of the sweep on a 3D periodic box of uniformly spread
//! particles at a chosen neighbour count — particle updates per second, pairs per second
//! per core, the window's peak memory, and the process's peak memory — for each thread count,
//! with the time per stage of the sweep, the time outside it, the speed-up and parallel
//! efficiency over one thread, and the floating-point operations and bytes moved per pair
//! of each loop ([`crate::sweep::cost`]).

use std::time::Instant;

use anyhow::Result;

use crate::boundary::{BoundaryKind, SimBox};
use crate::integrate::{StepControl, kdk_step, time_step};
use crate::io::summary::peak_rss_bytes;
use crate::kernel::Kernel;
use crate::particles::Particles;
use crate::physics::artificial_viscosity::ArtificialViscosity;
use crate::physics::eos::Eos;
use crate::problems::lattice;
use crate::rng::Rng;
use crate::sweep::cost::{Setting, SweepCost, sweep_cost};
use crate::sweep::local::Local;
use crate::sweep::pairs::candidates;
use crate::sweep::{Physics, Window, evaluate};

/// One benchmark configuration's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BenchResult {
    pub particles: usize,
    pub threads: usize,
    pub window: String,
    pub steps: usize,
    pub mean_neighbours: f64,
    pub seconds_per_step: f64,
    pub particle_updates_per_second: f64,
    pub pairs_per_second: f64,
    pub pairs_per_second_per_core: f64,
    pub peak_window_pairs: usize,
    pub peak_window_bytes: usize,
    pub full_list_bytes: usize,
    pub peak_rss_bytes: u64,
    /// Seconds per step in each part of the sweep.
    pub times_per_step: crate::sweep::StageTimes,
    /// Seconds per step outside the sweep: the kicks and drift, the time step, the
    /// integrator's copies.
    pub outside_sweep_seconds_per_step: f64,
    /// Time per step on one thread over this one (when this call measured one thread at
    /// the same size), and that over the thread count.
    pub speedup: Option<f64>,
    pub parallel_efficiency: Option<f64>,
    /// Candidates pair finding tests per pair found (last step's positions).
    pub candidates_per_pair: f64,
    /// Stencil-cell boxes pair finding tests per pair found (same).
    pub cells_per_pair: f64,
    /// Flops and bytes moved per pair of each loop, counted from the code.
    pub cost_per_pair: SweepCost,
    /// All four loops together.
    pub flops_per_pair: f64,
    pub bytes_per_pair: f64,
}

impl BenchResult {
    /// Fills `speedup` and `parallel_efficiency` against `one_thread`'s time per step.
    pub fn compare_with(&mut self, one_thread: &BenchResult) {
        let s = one_thread.seconds_per_step / self.seconds_per_step;
        self.speedup = Some(s);
        self.parallel_efficiency = Some(s / self.threads as f64);
    }

    /// The header of [`BenchResult::csv_row`].
    pub const CSV_HEADER: &'static str = "particles,threads,window,mean_neighbours,seconds_per_step,particle_updates_per_second,pairs_per_second,pairs_per_second_per_core,speedup,parallel_efficiency,build,find_pairs,density,gradient,force,finish,outside_sweep,peak_window_bytes,peak_rss_bytes,candidates_per_pair,cells_per_pair,flops_per_pair,bytes_per_pair";

    /// One CSV row (times in seconds per step; an empty speedup where none was measured).
    pub fn csv_row(&self) -> String {
        let opt = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6}"));
        let t = &self.times_per_step;
        format!(
            "{},{},{},{:.3},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{:.4},{:.4},{:.3},{:.3}",
            self.particles,
            self.threads,
            self.window,
            self.mean_neighbours,
            self.seconds_per_step,
            self.particle_updates_per_second,
            self.pairs_per_second,
            self.pairs_per_second_per_core,
            opt(self.speedup),
            opt(self.parallel_efficiency),
            t.build,
            t.find_pairs,
            t.density,
            t.gradient,
            t.force,
            t.finish,
            self.outside_sweep_seconds_per_step,
            self.peak_window_bytes,
            self.peak_rss_bytes,
            self.candidates_per_pair,
            self.cells_per_pair,
            self.flops_per_pair,
            self.bytes_per_pair
        )
    }
}

/// A jittered cubic lattice of about `n` particles in the unit periodic box, with h set for
/// about `neighbours` partners within the support: (4π/3)(2h)³ n = neighbours.
pub fn uniform_box(
    n: usize,
    neighbours: f64,
    seed: u64,
) -> anyhow::Result<(Particles<3>, SimBox<3>, f64)> {
    let k = (n as f64).cbrt().round().max(2.0) as usize;
    let dx = 1.0 / k as f64;
    let mut rng = Rng::new(seed);
    let mut p = Particles::new();
    let total = (k * k * k) as f64;
    for x in lattice::cuboid([0.0; 3], [dx; 3], [k; 3])? {
        let jitter: [f64; 3] =
            std::array::from_fn(|d| (x[d] + 0.2 * dx * (rng.uniform() - 0.5)).rem_euclid(1.0));
        let v: [f64; 3] = std::array::from_fn(|_| 0.01 * rng.normal());
        let id = p.len() as u64;
        p.push(id, jitter, v, 1.0 / total, 1.0);
    }
    let support = (neighbours * 3.0 / (4.0 * std::f64::consts::PI * total)).cbrt();
    let bx = SimBox {
        min: [0.0; 3],
        max: [1.0; 3],
        kinds: [BoundaryKind::Periodic; 3],
    };
    Ok((p, bx, 0.5 * support))
}

/// Runs `steps` KDK steps (after one warm-up evaluation) with the current rayon pool.
pub fn run_one(n: usize, neighbours: f64, steps: usize, window: Window) -> Result<BenchResult> {
    let (mut p, bx, h) = uniform_box(n, neighbours, 7)?;
    let phys = Physics::hydro(
        Kernel::<3>::new(h),
        Eos::Ideal { gamma: 5.0 / 3.0 },
        ArtificialViscosity::for_shocks(),
    );
    let ctl = StepControl::default();
    let warm = evaluate(&mut p, &bx, &phys, window);
    let start = Instant::now();
    let mut pairs = 0u64;
    let mut peak = warm.peak_pairs;
    let mut times = crate::sweep::StageTimes::default();
    let mut last_pairs = warm.pairs;
    for _ in 0..steps {
        let dt = time_step(&p, h, &ctl, true);
        let s = kdk_step(&mut p, &bx, &phys, window, dt);
        pairs += s.pairs;
        last_pairs = s.pairs;
        peak = peak.max(s.peak_pairs);
        times.add(&s.times);
    }
    let times_per_step = times.scaled(1.0 / steps as f64);
    let secs = start.elapsed().as_secs_f64();
    let in_sweep = times_per_step.total();
    let threads = rayon::current_num_threads();
    let per_step_pairs = pairs as f64 / steps as f64;
    // The peak memory of the steps, before the count below builds a working set of its own.
    let peak_rss = peak_rss_bytes();
    // The last evaluation's positions are the particles' (the final kick moves none).
    let support = phys.kernel.support();
    let tested = candidates(&Local::build(&p, &bx, support), support);
    let setting = Setting::of(&phys, tested, last_pairs);
    let cost = sweep_cost::<3>(&setting);
    Ok(BenchResult {
        particles: p.len(),
        threads,
        window: format!("{window:?}"),
        steps,
        mean_neighbours: 2.0 * per_step_pairs / p.len() as f64,
        seconds_per_step: secs / steps as f64,
        particle_updates_per_second: p.len() as f64 * steps as f64 / secs,
        pairs_per_second: pairs as f64 / secs,
        pairs_per_second_per_core: pairs as f64 / secs / threads as f64,
        peak_window_pairs: peak,
        peak_window_bytes: peak * crate::sweep::pairs::BYTES_PER_PAIR,
        full_list_bytes: per_step_pairs as usize * crate::sweep::pairs::BYTES_PER_PAIR,
        peak_rss_bytes: peak_rss,
        outside_sweep_seconds_per_step: (secs / steps as f64 - in_sweep).max(0.0),
        times_per_step,
        speedup: None,
        parallel_efficiency: None,
        candidates_per_pair: setting.candidates_per_pair,
        cells_per_pair: setting.cells_per_pair,
        cost_per_pair: cost,
        flops_per_pair: cost.total().flops,
        bytes_per_pair: cost.total().bytes,
    })
}
