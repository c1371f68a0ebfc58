//! One run from a problem file to its outputs: set-up, the first evaluation, the step loop
//! with progress and snapshots, the final state, the error norms and `summary.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::config::{Config, WindowKind};
use crate::integrate::{StepControl, kdk_step, time_step};
use crate::io::csv::write_particles;
use crate::io::summary::{Conservation, Summary, TotalsRecord, peak_rss_bytes};
use crate::kernel::{KERNEL_NAME, Kernel};
use crate::particles::Particles;
use crate::problems::{self, InitialState};
use crate::sweep::{Physics, Window, evaluate};

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
    } = problems::setup::<D>(cfg)?;
    let phys = Physics {
        kernel: Kernel::<D>::new(h),
        eos: cfg.eos,
        av: cfg.artificial_viscosity,
    };
    let window = match cfg.sweep.window {
        WindowKind::Sweep => Window::Sweep,
        WindowKind::Full => Window::FullList,
    };
    let ctl = StepControl {
        courant: cfg.time.courant,
        force: cfg.time.force,
        energy: cfg.time.energy,
    };
    let evolve_u = cfg.eos.evolves_energy();

    let start = Instant::now();
    let mut stats = evaluate(&mut p, &bx, &phys, window);
    if let Some(p0) = pressure_equilibrium {
        for i in 0..p.len() {
            p.u[i] = cfg.eos.internal_energy(p.rho[i], p0);
        }
        stats = evaluate(&mut p, &bx, &phys, window);
    }
    let totals_start = p.totals();
    let mut peak_pairs = stats.peak_pairs;
    let mut peak_bytes = stats.peak_window_bytes;
    let mut pairs_total: u64 = 0;
    let mut interactions_sum: u64 = p.interactions.iter().map(|&k| k as u64).sum();

    let t_end = cfg.time.end;
    let interval = cfg.output.interval.filter(|&i| i > 0.0);
    let mut snap = 0usize;
    let snap_path = |k: usize| opts.out.join(format!("snap_{k:04}.csv"));
    if interval.is_some() {
        write_particles(&snap_path(snap), &p, h)?;
        snap += 1;
    }

    let bar = progress_bar(opts.progress, t_end);
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
        let next_out = interval.map_or(t_end, |i| (snap as f64 * i).min(t_end));
        let target = if next_out > t { next_out } else { t_end };
        if t + dt >= target * (1.0 - 1e-12) {
            dt = target - t;
        }
        let s = kdk_step(&mut p, &bx, &phys, window, dt);
        t = if t + dt >= target * (1.0 - 1e-12) {
            target
        } else {
            t + dt
        };
        steps += 1;
        pairs_total += s.pairs;
        peak_pairs = peak_pairs.max(s.peak_pairs);
        peak_bytes = peak_bytes.max(s.peak_window_bytes);
        interactions_sum += p.interactions.iter().map(|&k| k as u64).sum::<u64>();
        let now = p.totals();
        let (_, dp, _) = now.drift_from(&prev);
        max_dp_step = max_dp_step.max(dp);
        prev = now;
        if let Some(i) = p.u.iter().position(|u| !u.is_finite() || *u < 0.0) {
            bail!(
                "particle {} has internal energy {} at t = {t:.6} (step {steps}): reduce time.courant or time.energy",
                p.id[i],
                p.u[i]
            );
        }
        if let Some(iv) = interval
            && t >= snap as f64 * iv * (1.0 - 1e-12)
        {
            write_particles(&snap_path(snap), &p, h)?;
            snap += 1;
        }
        bar.set_position((t / t_end * 1000.0) as u64);
        bar.set_message(format!("t = {t:.4}  step {steps}  dt = {dt:.2e}"));
    }
    bar.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();

    write_particles(&opts.out.join("final.csv"), &p, h)?;
    let totals_end = p.totals();
    let (dm, dp, de) = totals_end.drift_from(&totals_start);
    let errors = problems::errors(cfg, &p, &bx, h, t)?;
    let n = p.len();
    let summary = Summary {
        problem: cfg.name().to_string(),
        dimension: D,
        particles: n,
        steps,
        t_end: t,
        wall_seconds: wall,
        particle_updates_per_second: if wall > 0.0 {
            (n as f64 * steps as f64) / wall
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
        },
        errors,
        smoothing_length: h,
        kernel: KERNEL_NAME.to_string(),
        mean_neighbours: interactions_sum as f64 / ((steps + 1) as f64 * n as f64),
        ghosts: stats.ghosts,
        peak_window_bytes: peak_bytes,
        peak_rss_bytes: peak_rss_bytes(),
        totals_start: TotalsRecord::from(&totals_start),
        totals_end: TotalsRecord::from(&totals_end),
    };
    summary.write(&opts.out.join("summary.json"))?;
    Ok(Outcome {
        summary,
        particles: p,
    })
}

fn progress_bar(show: bool, t_end: f64) -> ProgressBar {
    let _ = t_end;
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
