//! One run from a problem file to its outputs: set-up, the first evaluation, the step loop
//! with progress and snapshots, the final state, the error norms and `summary.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::config::{Config, WindowKind};
use crate::integrate::{StepControl, kdk_step, rhs, time_step};
use crate::io::atomic::write_atomic;
use crate::io::csv::write_particles;
use crate::io::summary::{AccretionLedger, Conservation, Summary, TotalsRecord, peak_rss_bytes};
use crate::kernel::{KERNEL_NAME, Kernel};
use crate::particles::Particles;
use crate::problems::{self, InitialState};
use crate::sweep::{Physics, Window};

/// How to run: where outputs go, and whether to show progress.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub out: PathBuf,
    pub progress: bool,
}

/// Runs the problem in the dimension its file names.
pub fn run(cfg: &Config, opts: &RunOptions) -> Result<Summary> {
    match cfg.dimension() {
        1 => run_dim::<1>(cfg, opts),
        2 => run_dim::<2>(cfg, opts),
        3 => run_dim::<3>(cfg, opts),
        d => bail!("key `problem.dimension`: must be 1, 2 or 3, got {d}"),
    }
}

/// Final state of a run, for callers that want the particles themselves (tests, benchmarks).
pub struct Outcome<const D: usize> {
    pub summary: Summary,
    pub particles: Particles<D>,
}

fn run_dim<const D: usize>(cfg: &Config, opts: &RunOptions) -> Result<Summary> {
    Ok(run_with_state::<D>(cfg, opts)?.summary)
}

/// Runs a problem of dimension `D` and returns the summary with the final particles.
pub fn run_with_state<const D: usize>(cfg: &Config, opts: &RunOptions) -> Result<Outcome<D>> {
    std::fs::create_dir_all(&opts.out)
        .with_context(|| format!("cannot create output folder {}", opts.out.display()))?;
    let InitialState {
        particles: mut p,
        bx,
        h,
        pressure_equilibrium,
        t_end: problem_t_end,
        output_times,
    } = problems::setup::<D>(cfg)?;
    let phys = Physics {
        kernel: Kernel::<D>::new(h),
        eos: cfg.eos,
        av: cfg.artificial_viscosity,
        viscosity: cfg.viscosity,
        gravity: cfg.gravity,
    };
    let gravity = phys.gravity.as_ref();
    let window = match cfg.sweep.window {
        WindowKind::Sweep => Window::Sweep,
        WindowKind::Full => Window::FullList,
    };
    let ctl = StepControl {
        courant: cfg.time.courant,
        force: cfg.time.force,
        energy: cfg.time.energy,
        viscous: cfg.time.viscous,
    };
    let evolve_u = cfg.eos.evolves_energy();
    let t_end = cfg
        .time
        .end
        .or(problem_t_end)
        .context("key `time.end`: missing")?;

    let start = Instant::now();
    let mut stats = rhs(&mut p, &bx, &phys, window);
    if let Some(p0) = pressure_equilibrium {
        for i in 0..p.len() {
            p.u[i] = cfg.eos.internal_energy(p.rho[i], p0);
        }
        stats = rhs(&mut p, &bx, &phys, window);
    }
    let totals_start = p.totals(gravity);
    let mut peak_pairs = stats.peak_pairs;
    let mut peak_bytes = stats.peak_window_bytes;
    let mut pairs_total: u64 = 0;
    let mut updates: u64 = 0;
    let mut interactions_sum: u64 = p.interactions.iter().map(|&k| k as u64).sum();
    let mut evaluations: u64 = 1;
    let mut accreted = AccretionLedger::default();

    // Snapshot times: multiples of output.interval and the problem's own times.
    let mut out_times: Vec<f64> = output_times
        .into_iter()
        .filter(|&x| x > 0.0 && x <= t_end)
        .collect();
    if let Some(iv) = cfg.output.interval.filter(|&i| i > 0.0) {
        let k_max = (t_end / iv * (1.0 + 1e-12)).floor() as usize;
        out_times.extend((1..=k_max).map(|k| k as f64 * iv));
    }
    out_times.sort_by(f64::total_cmp);
    out_times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t_end);
    let mut snapshots = SnapshotIndex::default();
    if !out_times.is_empty() {
        snapshots.write(&opts.out, &p, h, 0.0, 0)?;
    }
    let mut next_snap = 0usize;

    let bar = progress_bar(opts.progress);
    let mut t = 0.0;
    let mut steps: u64 = 0;
    let mut max_dp_step: f64 = 0.0;
    let mut prev = totals_start;
    while t < t_end * (1.0 - 1e-12) {
        if steps >= cfg.time.max_steps {
            bail!(
                "reached time.max_steps = {} at t = {t:.6} before time.end = {t_end}",
                cfg.time.max_steps
            );
        }
        let mut dt = time_step(&p, h, &ctl, evolve_u);
        if !(dt > 0.0 && dt.is_finite()) {
            bail!("time step is {dt} at t = {t}: the state is not physical (check the set-up)");
        }
        let target = out_times
            .get(next_snap)
            .copied()
            .unwrap_or(t_end)
            .min(t_end);
        let lands = t + dt >= target * (1.0 - 1e-12);
        if lands {
            dt = target - t;
        }
        updates += p.len() as u64;
        let s = kdk_step(&mut p, &bx, &phys, window, dt);
        t = if lands { target } else { t + dt };
        steps += 1;
        evaluations += 1;
        pairs_total += s.pairs;
        peak_pairs = peak_pairs.max(s.peak_pairs);
        peak_bytes = peak_bytes.max(s.peak_window_bytes);
        interactions_sum += p.interactions.iter().map(|&k| k as u64).sum::<u64>();
        let now = p.totals(gravity);
        let (_, dp, _) = now.drift_from(&prev);
        max_dp_step = max_dp_step.max(dp);
        prev = now;
        if let Some(g) = gravity
            && let Some(r_acc) = g.accretion_radius
            && accreted.accrete(&mut p, r_acc, g) > 0
        {
            if p.is_empty() {
                bail!("every particle was accreted by t = {t:.6}");
            }
            prev = p.totals(gravity);
        }
        if let Some(i) = p.u.iter().position(|u| !u.is_finite() || *u < 0.0) {
            bail!(
                "particle {} has internal energy {} at t = {t:.6} (step {steps}): reduce time.courant or time.energy",
                p.id[i],
                p.u[i]
            );
        }
        if lands && next_snap < out_times.len() {
            next_snap += 1;
            snapshots.write(&opts.out, &p, h, t, steps)?;
        }
        bar.set_position((t / t_end * 1000.0) as u64);
        bar.set_message(format!(
            "t = {t:.4}  step {steps}  N = {}  dt = {dt:.2e}",
            p.len()
        ));
    }
    bar.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();

    write_particles(&opts.out.join("final.csv"), &p, h)?;
    let totals_end = p.totals(gravity);
    // Conservation counts what was accreted as still present.
    let mut with_accreted = totals_end;
    accreted.add_to(&mut with_accreted);
    let (dm, dp, de) = with_accreted.drift_from(&totals_start);
    let l0 = totals_start.angular_momentum;
    let dl = (with_accreted.angular_momentum - l0).abs() / l0.abs().max(f64::MIN_POSITIVE);
    let errors = problems::errors(cfg, &p, &bx, h, t)?;
    let n = p.len();
    let ring = match cfg.problem.kind {
        crate::config::ProblemKind::Ring => Some(problems::ring::record(cfg)?),
        _ => None,
    };
    let summary = Summary {
        problem: cfg.name().to_string(),
        dimension: D,
        particles: n,
        steps,
        t_end: t,
        wall_seconds: wall,
        particle_updates_per_second: if wall > 0.0 {
            updates as f64 / wall
        } else {
            0.0
        },
        pairs_per_second: if wall > 0.0 {
            pairs_total as f64 / wall
        } else {
            0.0
        },
        peak_pair_window: peak_pairs,
        threads: rayon::current_num_threads(),
        ranks: 1,
        conservation: Conservation {
            mass: dm,
            momentum: dp,
            energy: evolve_u.then_some(de),
            momentum_max_per_step: max_dp_step,
            angular_momentum: (D >= 2 && l0 != 0.0).then_some(dl),
        },
        errors,
        smoothing_length: h,
        kernel: KERNEL_NAME.to_string(),
        mean_neighbours: interactions_sum as f64 / (evaluations as f64 * n as f64),
        ghosts: stats.ghosts,
        peak_window_bytes: peak_bytes,
        peak_rss_bytes: peak_rss_bytes(),
        totals_start: TotalsRecord::from(&totals_start),
        totals_end: TotalsRecord::from(&totals_end),
        accretion: gravity
            .and_then(|g| g.accretion_radius)
            .map(|_| accreted.clone()),
        ring,
    };
    summary.write(&opts.out.join("summary.json"))?;
    Ok(Outcome {
        summary,
        particles: p,
    })
}

/// Snapshots written so far, listed in `snapshots.json` (file, time, step) so that tools
/// can find each snapshot's time.
#[derive(Default, serde::Serialize, serde::Deserialize)]
pub struct SnapshotIndex {
    pub snapshots: Vec<SnapshotEntry>,
}

#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct SnapshotEntry {
    pub file: String,
    pub time: f64,
    pub step: u64,
}

impl SnapshotIndex {
    fn write<const D: usize>(
        &mut self,
        dir: &Path,
        p: &Particles<D>,
        h: f64,
        time: f64,
        step: u64,
    ) -> Result<()> {
        let file = format!("snap_{:04}.csv", self.snapshots.len());
        write_particles(&dir.join(&file), p, h)?;
        self.snapshots.push(SnapshotEntry { file, time, step });
        let text = serde_json::to_string_pretty(self)?;
        write_atomic(&dir.join("snapshots.json"), text.as_bytes())
    }

    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("snapshots.json");
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "cannot read {} (a run folder lists its snapshots there)",
                path.display()
            )
        })?;
        serde_json::from_str(&text)
            .with_context(|| format!("{} is not a snapshot index", path.display()))
    }
}

fn progress_bar(show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40.cyan/blue} {percent:>3}%  {msg}  elapsed {elapsed}  ETA {eta}",
        )
        .expect("valid template"),
    );
    bar
}

/// The default output folder for a problem file: `runs/<stem>`.
pub fn default_out_dir(problem: &Path) -> PathBuf {
    let stem = problem
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("runs").join(stem)
}
