//! `sphdisk bench`: throughput of the sweep on a 3D periodic box of uniformly spread
//! particles at a chosen neighbour count — particle updates per second, pairs per second
//! per core, the window's peak memory, and the process's peak memory — for each thread count,
//! with the time per stage of the sweep, the time outside it, the speed-up and parallel
//! efficiency over one thread, and the floating-point operations and bytes moved per pair
//! of each loop ([`crate::sweep::cost`]). The thread counts run one after another, or
//! stepped in turn on a particle set each ([`run_alternating`]): on a shared machine whose
//! speed drifts, their ratio is then measured in one period. Stepping in turn, each turn
//! takes an untimed step before its timed one, so that the timed step follows a step on
//! the same particles, as in a run (a step right after the other set's starts with caches
//! that set filled: at 10⁵ particles that cost two threads about 15% and one thread 2%).

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
    /// Steps taken on this run's particles and not timed: one before each timed step when
    /// the thread counts step in turn ([`run_alternating`]), else none.
    pub untimed_steps: usize,
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
    pub const CSV_HEADER: &'static str = "particles,threads,window,mean_neighbours,seconds_per_step,particle_updates_per_second,pairs_per_second,pairs_per_second_per_core,speedup,parallel_efficiency,build,find_pairs,density,gradient,force,finish,outside_sweep,peak_window_bytes,peak_rss_bytes,candidates_per_pair,cells_per_pair,flops_per_pair,bytes_per_pair,untimed_steps";

    /// One CSV row (times in seconds per step; an empty speedup where none was measured).
    pub fn csv_row(&self) -> String {
        let opt = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6}"));
        let t = &self.times_per_step;
        format!(
            "{},{},{},{:.3},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{:.4},{:.4},{:.3},{:.3},{}",
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
            self.bytes_per_pair,
            self.untimed_steps
        )
    }
}

/// Particles along each axis of the lattice [`uniform_box`] builds for about `n`: ∛n
/// rounded, at least 2.
pub fn lattice_side(n: usize) -> u64 {
    (n as f64).cbrt().round().max(2.0) as u64
}

/// Refuses, before anything is allocated, a benchmark that cannot be measured: no particles,
/// or more than a run may hold or this machine's memory holds (`--n`); a mean neighbour
/// count that is not a number of at least one, or so large that the kernel's support
/// would reach beyond half the periodic unit box (each particle would meet its own
/// images: (4π/3)(1/2)³ = π/6 of the particles) or that the pairs the window holds would
/// not fit in memory (`--neighbours`).
pub fn check_options(n: &[usize], neighbours: f64, window: Window) -> Result<()> {
    use crate::limits::{MAX_PARTICLES, check_memory, memory_available};
    if !(neighbours.is_finite() && neighbours >= 1.0) {
        anyhow::bail!("--neighbours: a mean of at least 1 neighbour, got {neighbours}");
    }
    for &np in n {
        if np == 0 {
            anyhow::bail!("--n: at least 1 particle, got 0");
        }
        let k = lattice_side(np);
        let Some(total) = k.checked_pow(3).filter(|&t| t <= MAX_PARTICLES) else {
            anyhow::bail!(
                "--n {np}: a lattice of {k}³ particles is more than the {MAX_PARTICLES} a run can hold"
            );
        };
        check_memory::<3>(total, "--n")?;
        let most = std::f64::consts::PI / 6.0 * total as f64;
        if neighbours > most {
            anyhow::bail!(
                "--neighbours {neighbours}: at most {most:.0} for {total} particles (--n {np}): the kernel's support would reach beyond half the periodic box"
            );
        }
        // The window: every pair with a full list; else about three slabs' pairs (a slab
        // is one support wide), the paper's window.
        let support = (neighbours * 3.0 / (4.0 * std::f64::consts::PI * total as f64)).cbrt();
        let share = if window.full_list {
            1.0
        } else {
            (3.0 * support).min(1.0)
        };
        let bytes =
            total as f64 * neighbours / 2.0 * crate::sweep::pairs::BYTES_PER_PAIR as f64 * share;
        if let Some(available) = memory_available()? {
            let need = bytes + (total * crate::limits::bytes_per_particle::<3>()) as f64;
            crate::limits::check_need(
                need,
                available,
                &format!("--neighbours {neighbours}"),
                &format!("{total} particles and their pairs"),
                "--neighbours or --n",
            )?;
        }
    }
    Ok(())
}

/// A jittered cubic lattice of about `n` particles in the unit periodic box, with h set for
/// about `neighbours` partners within the support: (4π/3)(2h)³ n = neighbours.
pub fn uniform_box(
    n: usize,
    neighbours: f64,
    seed: u64,
) -> anyhow::Result<(Particles<3>, SimBox<3>, f64)> {
    let k = lattice_side(n) as usize;
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

/// A benchmark in progress: the box after its warm-up evaluation, and what its steps have
/// added up. [`run_one`] steps one to the end; [`run_alternating`] steps several in turn.
pub struct BenchRun {
    p: Particles<3>,
    bx: SimBox<3>,
    h: f64,
    phys: Physics<3>,
    ctl: StepControl,
    window: Window,
    /// The pool's threads (set-up, steps and the closing count run on one pool).
    threads: usize,
    steps: usize,
    /// Steps taken and not counted ([`BenchRun::untimed_step`]).
    untimed: usize,
    /// Seconds of the steps (their own time: another run's steps in between not counted).
    secs: f64,
    pairs: u64,
    peak: usize,
    times: crate::sweep::StageTimes,
    last_pairs: u64,
}

impl BenchRun {
    /// Sets up the box of about `n` particles and evaluates it once (the warm-up), on the
    /// current rayon pool.
    pub fn new(n: usize, neighbours: f64, window: Window) -> Result<Self> {
        let (mut p, bx, h) = uniform_box(n, neighbours, 7)?;
        let phys = Physics::hydro(
            Kernel::<3>::new(h),
            Eos::Ideal { gamma: 5.0 / 3.0 },
            ArtificialViscosity::for_shocks(),
        );
        let warm = evaluate(&mut p, &bx, &phys, window);
        Ok(Self {
            p,
            bx,
            h,
            phys,
            ctl: StepControl::default(),
            window,
            threads: rayon::current_num_threads(),
            steps: 0,
            untimed: 0,
            secs: 0.0,
            pairs: 0,
            peak: warm.peak_pairs,
            times: crate::sweep::StageTimes::default(),
            last_pairs: warm.pairs,
        })
    }

    /// One KDK step, timed.
    pub fn step(&mut self) {
        let start = Instant::now();
        let s = self.advance();
        self.secs += start.elapsed().as_secs_f64();
        self.steps += 1;
        self.pairs += s.pairs;
        self.last_pairs = s.pairs;
        self.peak = self.peak.max(s.peak_pairs);
        self.times.add(&s.times);
    }

    /// One KDK step, neither timed nor counted: it brings this run's particles back into
    /// the caches after another run's steps.
    pub fn untimed_step(&mut self) {
        self.advance();
        self.untimed += 1;
    }

    fn advance(&mut self) -> crate::sweep::SweepStats {
        let dt = time_step(&self.p, self.h, &self.ctl, true);
        kdk_step(&mut self.p, &self.bx, &self.phys, self.window, dt)
    }

    /// The figures of the steps taken (at least one). The peak resident memory is the
    /// process's: with runs alternating it holds every run's particles.
    pub fn result(&self) -> BenchResult {
        let (steps, secs, pairs, p) = (self.steps.max(1), self.secs, self.pairs, &self.p);
        let times_per_step = self.times.scaled(1.0 / steps as f64);
        let in_sweep = times_per_step.total();
        let threads = self.threads;
        let per_step_pairs = pairs as f64 / steps as f64;
        // The peak memory of the steps, before the count below builds a working set of its
        // own.
        let peak_rss = peak_rss_bytes();
        // The last evaluation's positions are the particles' (the final kick moves none).
        let support = self.phys.kernel.support();
        let tested = candidates(&Local::build(p, &self.bx, support), support);
        let setting = Setting::of(&self.phys, tested, self.last_pairs);
        let cost = sweep_cost::<3>(&setting);
        BenchResult {
            particles: p.len(),
            threads,
            window: self.window.label(),
            steps,
            untimed_steps: self.untimed,
            mean_neighbours: 2.0 * per_step_pairs / p.len() as f64,
            seconds_per_step: secs / steps as f64,
            particle_updates_per_second: p.len() as f64 * steps as f64 / secs,
            pairs_per_second: pairs as f64 / secs,
            pairs_per_second_per_core: pairs as f64 / secs / threads as f64,
            peak_window_pairs: self.peak,
            peak_window_bytes: self.peak * crate::sweep::pairs::BYTES_PER_PAIR,
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
        }
    }
}

/// Runs `steps` KDK steps (after one warm-up evaluation) with the current rayon pool.
pub fn run_one(n: usize, neighbours: f64, steps: usize, window: Window) -> Result<BenchResult> {
    let mut run = BenchRun::new(n, neighbours, window)?;
    for _ in 0..steps {
        run.step();
    }
    Ok(run.result())
}

/// One run per pool, on a particle set of its own, stepped in turn — a step on each pool,
/// then the next step on each —, so that a machine whose speed drifts (a shared one) slows
/// them alike and their ratio is measured in one period. Each turn is an untimed step, then
/// the timed one: the timed step follows a step on its own particles, as in a run, not the
/// other runs' steps, whose particles fill the caches. The results come in the pools'
/// order.
pub fn run_alternating(
    n: usize,
    neighbours: f64,
    steps: usize,
    window: Window,
    pools: &[rayon::ThreadPool],
) -> Result<Vec<BenchResult>> {
    let mut runs = pools
        .iter()
        .map(|pool| pool.install(|| BenchRun::new(n, neighbours, window)))
        .collect::<Result<Vec<_>>>()?;
    for _ in 0..steps {
        for (pool, run) in pools.iter().zip(&mut runs) {
            pool.install(|| {
                run.untimed_step();
                run.step();
            });
        }
    }
    Ok(pools
        .iter()
        .zip(&runs)
        .map(|(pool, run)| pool.install(|| run.result()))
        .collect())
}
