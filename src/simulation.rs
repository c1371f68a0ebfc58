//! One run from a problem file (or a checkpoint) to its outputs: set-up, the first
//! evaluation, the step loop with progress, log, snapshots and checkpoints, the final state,
//! the error norms and `summary.json`.
//!
//! Everything the step loop carries from one step to the next lives in [`LoopState`] and
//! the particles, and both go into each checkpoint: a resumed run continues bit for bit.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::boundary::{BoundaryKind, SimBox};
use crate::config::{Config, WindowKind};
use crate::domain::comm::Comm;
use crate::domain::team::{Distributed, Solo, Team};
use crate::integrate::{StepControl, kdk_step_with, rhs, time_step};
use crate::io::atomic::write_atomic;
use crate::io::checkpoint::{self, CheckpointText};
use crate::io::csv::write_particles;
use crate::io::hdf5::{RunMetadata, read_snapshot, write_snapshot};
use crate::io::log::RunLog;
use crate::io::run_folder::{self, FolderLock};
use crate::io::snapshot::{PointMassRecord, Snapshot};
use crate::io::snapshot_index::{SnapshotEntry, SnapshotIndex};
use crate::io::summary::{
    AccretionLedger, Conservation, Flow, MassBudget, MassBudgetRecord, Summary, Timing,
    TotalsRecord, peak_rss_bytes,
};
use crate::io::timeseries::{
    LIGHTCURVE_HEADER, MODES_HEADER, MONITOR_HEADER, STATISTICS_HEADER, Series,
};
use crate::particles::Particles;
use crate::physics::l1_stream::InjectorState;
use crate::physics::mass_transfer::MassTransfer;
use crate::problems::{self, InitialState};
use crate::sweep::{Physics, StageTimes, Window};

/// Default wall-clock seconds between checkpoints.
const CHECKPOINT_WALL_SECONDS: f64 = 600.0;
/// Wall-clock seconds between progress lines in `run.log`.
const LOG_SECONDS: f64 = 30.0;

/// How to run: where outputs go, whether to show progress, where the particles come from,
/// and when to stop early.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    pub out: PathBuf,
    pub progress: bool,
    /// Start from this snapshot's particles instead of the problem's set-up (`--from`).
    pub from: Option<PathBuf>,
    /// Stop after this step (counted from the start of the run), writing a checkpoint.
    pub stop_after: Option<u64>,
    /// A fresh run into a folder that holds another run's files clears them (`--force`)
    /// instead of refusing.
    pub force: bool,
}

impl RunOptions {
    /// Quiet run into `out`, as tests and scripts want it.
    pub fn quiet(out: impl Into<PathBuf>) -> Self {
        Self {
            out: out.into(),
            ..Self::default()
        }
    }
}

/// How a run ended.
#[derive(Clone, Debug)]
pub enum Ended {
    /// A rank other than 0 of a distributed run: rank 0 wrote the outputs.
    Helped,
    /// Reached the end time: `summary.json` and `final.csv` are written.
    Finished(Box<Summary>),
    /// Stopped at `--stop-after`, or by a signal (`signals`): resume from `checkpoint`.
    Stopped {
        step: u64,
        time: f64,
        checkpoint: PathBuf,
        /// The signal that asked for the stop (SIGTERM, SIGINT), if one did.
        signal: Option<i32>,
    },
}

/// Final state of a run, for callers that want the particles themselves (tests, benchmarks).
pub struct Outcome<const D: usize> {
    pub ended: Ended,
    pub particles: Particles<D>,
}

impl<const D: usize> Outcome<D> {
    /// The summary of a finished run.
    pub fn summary(&self) -> Result<&Summary> {
        match &self.ended {
            Ended::Finished(s) => Ok(s),
            Ended::Stopped { step, .. } => bail!("the run stopped early at step {step}"),
            Ended::Helped => bail!("this rank helped; rank 0 has the summary"),
        }
    }
}

/// Runs the problem in the dimension its file names.
pub fn run(cfg: &Config, opts: &RunOptions) -> Result<Ended> {
    match cfg.dimension() {
        1 => Ok(run_with_state::<1>(cfg, opts)?.ended),
        2 => Ok(run_with_state::<2>(cfg, opts)?.ended),
        3 => Ok(run_with_state::<3>(cfg, opts)?.ended),
        d => bail!("key `problem.dimension`: must be 1, 2 or 3, got {d}"),
    }
}

/// Continues the run in `opts.out` from its newest usable checkpoint; `overrides` may
/// change keys of the problem file as it was run (e.g. `time.end` to extend a run).
pub fn resume(overrides: &[String], opts: &RunOptions) -> Result<Ended> {
    run_folder::refuse_if_held(&opts.out)?;
    match resume_dimension(overrides, opts)? {
        1 => Ok(resume_with_state::<1>(overrides, opts)?.ended),
        2 => Ok(resume_with_state::<2>(overrides, opts)?.ended),
        _ => Ok(resume_with_state::<3>(overrides, opts)?.ended),
    }
}

/// [`run`] on the ranks of `comm` (each rank calls this; rank 0 writes).
pub fn run_distributed(comm: &mut dyn Comm, cfg: &Config, opts: &RunOptions) -> Result<Ended> {
    let mut team = Distributed::new(comm);
    Ok(match cfg.dimension() {
        1 => run_in_team::<1>(cfg, opts, &mut team)?.ended,
        2 => run_in_team::<2>(cfg, opts, &mut team)?.ended,
        3 => run_in_team::<3>(cfg, opts, &mut team)?.ended,
        d => bail!("key `problem.dimension`: must be 1, 2 or 3, got {d}"),
    })
}

/// [`resume`] on the ranks of `comm`
/// (any number of ranks: the checkpoint holds every particle).
pub fn resume_distributed(
    comm: &mut dyn Comm,
    overrides: &[String],
    opts: &RunOptions,
) -> Result<Ended> {
    // Rank 0 takes the folder's lock; the others, in other processes, must not see it.
    if comm.rank() == 0 {
        run_folder::refuse_if_held(&opts.out)?;
    }
    let mut team = Distributed::new(comm);
    Ok(match resume_dimension(overrides, opts)? {
        1 => resume_in_team::<1>(overrides, opts, &mut team)?.ended,
        2 => resume_in_team::<2>(overrides, opts, &mut team)?.ended,
        _ => resume_in_team::<3>(overrides, opts, &mut team)?.ended,
    })
}

/// The dimension of the run in `opts.out`: that of its newest checkpoint that passes every
/// check of [`load_checkpoint`].
pub fn resume_dimension(overrides: &[String], opts: &RunOptions) -> Result<usize> {
    let mut first_err = None;
    let expected = run_folder::read_run_id(&opts.out)?;
    let expected = expected.as_deref();
    for (k, path) in checkpoint::list(&opts.out)?.into_iter().enumerate() {
        let usable = checkpoint::dimension(&path).and_then(|d| match d {
            1 => load_checkpoint::<1>(&path, overrides, expected).map(|_| 1),
            2 => load_checkpoint::<2>(&path, overrides, expected).map(|_| 2),
            _ => load_checkpoint::<3>(&path, overrides, expected).map(|_| 3),
        });
        match usable {
            Ok(d) => return Ok(d),
            Err(e) if Final::ends_search(&e, k) => return Err(e),
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    Err(no_checkpoint(opts, overrides, first_err))
}

/// The error of a run folder none of whose checkpoints can be resumed from: the newest
/// one's reason, under the override it names where one of `overrides` set that key
/// (`--set time.end=…: key `time.end`: … before the checkpoint's time`).
fn no_checkpoint(
    opts: &RunOptions,
    overrides: &[String],
    newest_err: Option<anyhow::Error>,
) -> anyhow::Error {
    match newest_err {
        Some(e) => {
            let head =
                crate::config::blamed_override(&format!("{e:#}"), overrides).unwrap_or_else(|| {
                    format!(
                        "no usable checkpoint to resume from in {}",
                        checkpoint::folder(&opts.out).display()
                    )
                });
            e.context(head)
        }
        None => anyhow::anyhow!(
            "{} has no checkpoint to resume from (looked in {})",
            opts.out.display(),
            checkpoint::folder(&opts.out).display()
        ),
    }
}

/// A refusal no older checkpoint can cure, so the search for a usable one stops at it.
#[derive(Debug)]
enum Final {
    /// A checkpoint of another run than the one whose folder it lies in (its run id differs
    /// from the folder's `run.id`): never resumed from, and not fallen back from where it
    /// is the newest.
    ForeignRun(String),
    /// An override of `--resume --set` that no checkpoint can take (a key a resume may not
    /// change, or a value its checks refuse): reported as the override's fault, not as "no
    /// usable checkpoint", and without trying the older checkpoints.
    BadOverride(String),
}

impl Final {
    /// Whether `e`, met at the `k`-th newest checkpoint, ends the search.
    fn ends_search(e: &anyhow::Error, k: usize) -> bool {
        match e.downcast_ref::<Final>() {
            Some(Final::ForeignRun(_)) => k == 0,
            Some(Final::BadOverride(_)) => true,
            None => false,
        }
    }
}

impl std::fmt::Display for Final {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Final::ForeignRun(m) | Final::BadOverride(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Final {}

/// Keys `--resume --set` may change: when and what the run writes, how far it goes.
const RESUMABLE_KEYS: [&str; 3] = ["time.", "output.", "sweep."];

/// A checkpoint read back and checked: its configuration (with `overrides`), loop state,
/// particles and box.
struct Resumable<const D: usize> {
    cfg: Config,
    st: LoopState,
    p: Particles<D>,
    bx: SimBox<D>,
}

/// Reads the checkpoint at `path` (dimension `D`; checksums verified) and refuses what no
/// run can have written: a configuration of another dimension, a state that does not
/// parse, a time outside [0, t_end], a box that is not `D`-dimensional or too small for
/// the kernel, h not a positive number, a particle with a mass or u out of range, a
/// position or velocity not finite, a position outside the box, an id twice.
fn load_checkpoint<const D: usize>(
    path: &Path,
    overrides: &[String],
    run_id: Option<&str>,
) -> Result<Resumable<D>> {
    let what = path.display();
    let (text, p) = checkpoint::read::<D>(path)?;
    let mut table: toml::Table = text
        .config_toml
        .parse()
        .with_context(|| format!("{what}: stored configuration"))?;
    let stored = table.clone();
    for o in overrides {
        let key = o.split_once('=').map_or(o.as_str(), |(k, _)| k.trim());
        if !RESUMABLE_KEYS.iter().any(|p| key.starts_with(p)) {
            return Err(Final::BadOverride(format!(
                "--set {key}: cannot change when a run is resumed (only time.*, output.* and sweep.* can); start a new run instead"
            ))
            .into());
        }
        crate::config::apply_override(&mut table, o)
            .map_err(|e| Final::BadOverride(format!("{e:#}")))?;
    }
    let cfg = match Config::from_table(table) {
        Ok(cfg) => cfg,
        // The stored configuration is sound and an override is not: the override's fault,
        // the same at every checkpoint.
        Err(e) if !overrides.is_empty() && Config::from_table(stored).is_ok() => {
            let msg = format!("{e:#}");
            let blamed = crate::config::blamed_override(&msg, overrides)
                .unwrap_or_else(|| format!("--set {}", overrides.join(" --set ")));
            return Err(Final::BadOverride(format!("{blamed}: {msg}")).into());
        }
        Err(e) => return Err(e.context(format!("{what}: configuration"))),
    };
    if cfg.dimension() != D {
        bail!(
            "{what}: the configuration is {}D, the particles {D}D",
            cfg.dimension()
        );
    }
    let mut st: LoopState = serde_json::from_str(&text.state_json)
        .with_context(|| format!("{what}: stored run state"))?;
    if let Some(id) = run_id
        && st.run_id != id
    {
        let theirs = if st.run_id.is_empty() {
            "none".to_string()
        } else {
            st.run_id.clone()
        };
        return Err(Final::ForeignRun(format!(
            "{what} belongs to another run (run id {theirs}) than the one in its folder ({} says {id}): remove it, or resume the folder it came from",
            run_folder::RUN_ID_FILE
        ))
        .into());
    }
    if !(st.t_end > 0.0 && st.t_end.is_finite()) {
        bail!(
            "{what}: end time t_end = {} is not a positive number",
            st.t_end
        );
    }
    if !(st.t >= 0.0 && st.t <= st.t_end) {
        bail!(
            "{what}: time t = {} outside [0, t_end = {}]",
            st.t,
            st.t_end
        );
    }
    let bx = st.sim_box::<D>().with_context(|| format!("{what}"))?;
    (|| -> Result<()> {
        if p.is_empty() {
            bail!("no particles");
        }
        problems::check_particles(&p, st.h)?;
        bx.validate(cfg.particles.kernel.support_factor() * st.h)?;
        bx.check_inside_closed(&p.pos, &p.id)?;
        crate::limits::check_grid(&cfg, &bx, st.h, &p.pos)
    })()
    .with_context(|| format!("{what}"))?;
    if !overrides.is_empty() {
        // A new end or interval: the snapshots written stay; those to come follow the
        // new settings.
        let future = match &st.problem_times {
            Some(times) => times.clone(),
            None => st.out_times[st.next_snap.min(st.out_times.len())..].to_vec(),
        };
        let (end, times) = snapshot_times(&cfg, Some(st.t_end), future)?;
        if !(st.t <= end) {
            bail!(
                "key `time.end`: {end} is before the checkpoint's time t = {} ({what})",
                st.t
            );
        }
        st.t_end = end;
        st.out_times.truncate(st.next_snap);
        let t = st.t;
        st.out_times
            .extend(times.into_iter().filter(|&x| x > t * (1.0 + 1e-12)));
    }
    Ok(Resumable { cfg, st, p, bx })
}

/// Global totals of the particles of every rank.
fn global_totals<const D: usize>(
    team: &mut dyn Team<D>,
    p: &Particles<D>,
    gravity: Option<&crate::physics::gravity::PointMass>,
) -> crate::particles::Totals<D> {
    let mut t = p.totals(gravity);
    if team.ranks() > 1 {
        let mut v = vec![
            t.mass,
            t.momentum_scale,
            t.angular_momentum,
            t.kinetic,
            t.internal,
            t.potential,
        ];
        v.extend(t.momentum);
        team.sum(&mut v);
        (
            t.mass,
            t.momentum_scale,
            t.angular_momentum,
            t.kinetic,
            t.internal,
            t.potential,
        ) = (v[0], v[1], v[2], v[3], v[4], v[5]);
        t.momentum = std::array::from_fn(|d| v[6 + d]);
    }
    t
}

/// What the step loop carries between steps, besides the particles: saved in checkpoints.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct LoopState {
    t: f64,
    steps: u64,
    t_end: f64,
    h: f64,
    box_min: Vec<f64>,
    box_max: Vec<f64>,
    box_kinds: Vec<BoundaryKind>,
    out_times: Vec<f64>,
    next_snap: usize,
    snapshots: SnapshotIndex,
    accreted: AccretionLedger,
    totals_start: TotalsRecord,
    prev: TotalsRecord,
    max_dp_step: f64,
    peak_pairs: usize,
    peak_bytes: usize,
    pairs_total: u64,
    updates: u64,
    interactions_sum: u64,
    evaluations: u64,
    ghosts: usize,
    /// Wall seconds spent before this process started (earlier parts of a resumed run).
    wall_before: f64,
    /// Largest neighbour grid of the run: cells, and bytes of its cell index.
    #[serde(default)]
    peak_grid_cells: u64,
    #[serde(default)]
    peak_grid_index_bytes: usize,
    /// The run's identity (also in the folder's `run.id`): a resumed run takes only its own
    /// checkpoints. Empty in checkpoints written before runs had one.
    #[serde(default)]
    run_id: String,
    /// The problem's own output times (a ring's τ), kept so that `--resume --set` can
    /// recompute the snapshot times for a new end or interval.
    #[serde(default)]
    problem_times: Option<Vec<f64>>,
    /// A binary's L1 injector.
    #[serde(default)]
    injector: Option<InjectorState>,
    /// A binary's mass budget.
    #[serde(default)]
    budget: MassBudget,
    /// Time of the next row of the binary's time series.
    #[serde(default)]
    next_series: f64,
    /// Largest share of the internal energy held by particles without a neighbour, over
    /// the steps (a Sedov blast's trapped core).
    #[serde(default)]
    max_isolated_energy_fraction: f64,
    /// Seconds in each part of the sweep, summed over the steps (this rank's).
    #[serde(default)]
    sweep_times: StageTimes,
}

impl LoopState {
    fn sim_box<const D: usize>(&self) -> Result<SimBox<D>> {
        if self.box_min.len() != D || self.box_max.len() != D || self.box_kinds.len() != D {
            bail!("checkpoint box is not {D}-dimensional");
        }
        Ok(SimBox {
            min: std::array::from_fn(|d| self.box_min[d]),
            max: std::array::from_fn(|d| self.box_max[d]),
            kinds: std::array::from_fn(|d| self.box_kinds[d]),
        })
    }
}

/// A run in progress: configuration, physics, particles and loop state.
struct Run<const D: usize> {
    cfg: Config,
    phys: Physics<D>,
    bx: SimBox<D>,
    p: Particles<D>,
    st: LoopState,
    window: Window,
    ctl: StepControl,
    evolve_u: bool,
    meta: RunMetadata,
    /// A binary's sources and sinks (cv problems).
    mt: Option<MassTransfer>,
}

impl<const D: usize> Run<D> {
    fn new(cfg: Config, p: Particles<D>, st: LoopState, bx: SimBox<D>) -> Self {
        let phys = Physics::from_config(&cfg, st.h);
        let window = match cfg.sweep.window {
            WindowKind::Sweep => Window::SWEEP,
            WindowKind::Full => Window::FULL_LIST,
        }
        .with_batch(cfg.sweep.batch_per_thread as usize);
        let ctl = StepControl {
            courant: cfg.time.courant,
            force: cfg.time.force,
            energy: cfg.time.energy,
            viscous: cfg.time.viscous,
        };
        let meta = RunMetadata {
            parameters: cfg.flattened(),
            units: cfg.units(),
            periodic: bx.kinds.iter().all(|k| *k == BoundaryKind::Periodic),
            physical: cfg.physical_units().is_some(),
        };
        Self {
            evolve_u: cfg.eos.evolves_energy(),
            mt: MassTransfer::from_config(&cfg),
            cfg,
            phys,
            bx,
            p,
            st,
            window,
            ctl,
            meta,
        }
    }

    fn snapshot(&self, p: &Particles<D>) -> Snapshot {
        let mut s = Snapshot::from_particles(
            p,
            self.st.h,
            self.bx.min,
            self.bx.max,
            self.st.t,
            self.st.steps,
        );
        s.kernel = self.cfg.particles.kernel;
        if self.phys.av.switch().is_some() {
            s.alpha.clone_from(&p.alpha);
        }
        if let Some(g) = &self.phys.gravity {
            // At the origin of the run's frame, in the file's frame like the gas.
            s.point_masses.push(PointMassRecord {
                id: u64::MAX,
                pos: s.shift,
                vel: [0.0; 3],
                mass: g.gm,
            });
        }
        s
    }

    /// Writes the next snapshot from `all` (every particle; None on ranks other than 0,
    /// which only keep the index in step).
    fn write_snapshot(
        &mut self,
        dir: &Path,
        all: Option<&Particles<D>>,
        log: &mut RunLog,
    ) -> Result<()> {
        let file = format!("snap_{:04}.hdf5", self.st.snapshots.snapshots.len());
        let files = self.cfg.output.files_per_snapshot.unwrap_or(1);
        let Some(all) = all else {
            self.st.snapshots.snapshots.push(SnapshotEntry {
                file,
                time: self.st.t,
                step: self.st.steps,
                files,
            });
            return Ok(());
        };
        write_snapshot(&dir.join(&file), &self.snapshot(all), &self.meta, files)?;
        log.line(&format!(
            "snapshot {file} at t = {} (step {})",
            self.st.t, self.st.steps
        ));
        self.st.snapshots.snapshots.push(SnapshotEntry {
            file,
            time: self.st.t,
            step: self.st.steps,
            files,
        });
        let text = serde_json::to_string_pretty(&self.st.snapshots)?;
        write_atomic(&dir.join("snapshots.json"), text.as_bytes())
    }

    fn write_checkpoint(
        &self,
        dir: &Path,
        all: &mut Particles<D>,
        wall: f64,
        log: &mut RunLog,
    ) -> Result<PathBuf> {
        let mut st = self.st.clone();
        st.wall_before = wall;
        let text = CheckpointText {
            config_toml: toml::to_string(&self.cfg).context("cannot write the configuration")?,
            state_json: serde_json::to_string(&st)?,
        };
        let path = checkpoint::write(dir, self.st.steps, &text, all)?;
        log.line(&format!(
            "checkpoint {} at t = {} (step {})",
            path.display(),
            self.st.t,
            self.st.steps
        ));
        Ok(path)
    }
}

/// Runs a problem of dimension `D` and returns how it ended with the final particles.
pub fn run_with_state<const D: usize>(cfg: &Config, opts: &RunOptions) -> Result<Outcome<D>> {
    run_in_team(cfg, opts, &mut Solo)
}

/// [`run_with_state`] on the ranks of `team` (each rank calls it; rank 0 writes).
pub fn run_in_team<const D: usize>(
    cfg: &Config,
    opts: &RunOptions,
    team: &mut dyn Team<D>,
) -> Result<Outcome<D>> {
    // The folder is this run's alone while it runs; a fresh run does not mix its files
    // with another run's.
    let _lock = if team.is_root() {
        std::fs::create_dir_all(&opts.out)
            .with_context(|| format!("cannot create output folder {}", opts.out.display()))?;
        let lock = FolderLock::acquire(&opts.out)?;
        run_folder::remove_stale_temporaries(&opts.out)?;
        if !opts.force {
            run_folder::refuse_if_used(&opts.out)?;
        }
        Some(lock)
    } else {
        None
    };
    let (mut run, notes) = start_fresh::<D>(cfg, opts)?;
    let mut log = if team.is_root() {
        // Only now that the set-up stands: a failed one loses nothing.
        if opts.force {
            run_folder::clear(&opts.out)?;
        }
        // The problem file as run (overrides applied), for analyses and for reproducing it.
        let text = toml::to_string(cfg).context("cannot write the configuration")?;
        write_atomic(&opts.out.join("run.toml"), text.as_bytes())?;
        run.st.run_id = run_folder::new_run_id(&text);
        write_atomic(
            &opts.out.join(run_folder::RUN_ID_FILE),
            format!("{}\n", run.st.run_id).as_bytes(),
        )?;
        RunLog::open(&opts.out)?
    } else {
        RunLog::silent()
    };
    log.line(&format!(
        "start {}: {} particles, {D}D, t = {}, t_end = {}, {} ranks × {} threads",
        cfg.name(),
        run.p.len(),
        run.st.t,
        run.st.t_end,
        team.ranks(),
        rayon::current_num_threads()
    ));
    for note in &notes {
        log.line(note);
    }
    if !run.st.out_times.is_empty() {
        let all = team.is_root().then(|| run.p.clone());
        run.write_snapshot(&opts.out, all.as_ref(), &mut log)?;
    }
    team.distribute(&mut run.p, &run.bx);
    advance(run, opts, log, team)
}

/// Continues the run in `opts.out` (dimension `D`) from its newest readable checkpoint.
pub fn resume_with_state<const D: usize>(
    overrides: &[String],
    opts: &RunOptions,
) -> Result<Outcome<D>> {
    resume_in_team(overrides, opts, &mut Solo)
}

/// [`resume_with_state`] on the ranks of `team`: every rank reads the checkpoint (which
/// holds every particle, so the number of ranks may differ from the run that wrote it) and
/// keeps its share.
pub fn resume_in_team<const D: usize>(
    overrides: &[String],
    opts: &RunOptions,
    team: &mut dyn Team<D>,
) -> Result<Outcome<D>> {
    let (_lock, mut log) = if team.is_root() {
        let lock = FolderLock::acquire(&opts.out)?;
        let stale = run_folder::remove_stale_temporaries(&opts.out)?;
        let mut log = RunLog::open(&opts.out)?;
        if stale > 0 {
            log.line(&format!("removed {stale} temporary files of killed writes"));
        }
        (Some(lock), log)
    } else {
        (None, RunLog::silent())
    };
    let expected = run_folder::read_run_id(&opts.out)?;
    let mut first_err = None;
    for (k, path) in checkpoint::list(&opts.out)?.into_iter().enumerate() {
        match load_checkpoint::<D>(&path, overrides, expected.as_deref()) {
            Ok(Resumable { cfg, st, p, bx }) => {
                log.line(&format!(
                    "resume from {} at t = {} (step {})",
                    path.display(),
                    st.t,
                    st.steps
                ));
                if team.is_root() && !overrides.is_empty() {
                    // The problem as it now runs.
                    let text = toml::to_string(&cfg).context("cannot write the configuration")?;
                    write_atomic(&opts.out.join("run.toml"), text.as_bytes())?;
                }
                let mut run = Run::new(cfg, p, st, bx);
                team.distribute(&mut run.p, &run.bx);
                return advance(run, opts, log, team);
            }
            Err(e) if Final::ends_search(&e, k) => return Err(e),
            Err(e) => {
                log.line(&format!("skip checkpoint: {e:#}"));
                first_err.get_or_insert(e);
            }
        }
    }
    Err(no_checkpoint(opts, overrides, first_err))
}

/// The end time of a run (`time.end`, or the problem's own `problem_t_end`) and its
/// snapshot times: multiples of `output.interval` and the problem's own `times`, at most
/// [`MAX_SNAPSHOTS`](crate::limits::MAX_SNAPSHOTS) of them (refused before any is made).
pub fn snapshot_times(
    cfg: &Config,
    problem_t_end: Option<f64>,
    times: Vec<f64>,
) -> Result<(f64, Vec<f64>)> {
    let t_end = cfg
        .time
        .end
        .or(problem_t_end)
        .context("key `time.end`: missing")?;
    let mut out_times: Vec<f64> = times
        .into_iter()
        .filter(|&x| x > 0.0 && x <= t_end)
        .collect();
    if let Some(iv) = cfg.output.interval.filter(|&i| i > 0.0) {
        let k_max = crate::limits::check_snapshot_count(iv, t_end)?;
        out_times.extend((1..=k_max).map(|k| k as f64 * iv));
    }
    out_times.sort_by(f64::total_cmp);
    out_times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t_end);
    Ok((t_end, out_times))
}

/// Set-up, the first evaluation, and the snapshot times of a new run.
/// Also returns lines for `run.log` on where a `--from` run's h and start time came from.
fn start_fresh<const D: usize>(cfg: &Config, opts: &RunOptions) -> Result<(Run<D>, Vec<String>)> {
    let InitialState {
        particles,
        bx,
        h,
        pressure_equilibrium,
        t_end: problem_t_end,
        output_times,
        injector,
    } = problems::setup::<D>(cfg)?;
    let mut injector = injector;
    let mut notes = Vec::new();
    let (particles, h, t0) = match &opts.from {
        None => (particles, h, 0.0),
        Some(path) => {
            let what = || format!("--from {}", path.display());
            let snap = read_snapshot(path)?;
            let p = snap.to_particles::<D>().with_context(what)?;
            let t0 = snap.time;
            if t0 < 0.0 {
                bail!("{}: Header/Time = {t0} is before 0", what());
            }
            let (h, note) = initial_h_from_file(cfg, h, &snap.h);
            notes.push(format!("{}: {note}", what()));
            let state = InitialState::new(p, bx, h);
            problems::check_initial_state(&state, cfg.particles.kernel)
                .and_then(|_| crate::limits::check_grid(cfg, &bx, h, &state.particles.pos))
                .with_context(what)?;
            if let Some(inj) = &mut injector {
                // New stream particles take ids after the file's.
                inj.next_id = inj
                    .next_id
                    .max(state.particles.id.iter().max().map_or(0, |m| m + 1));
            }
            if t0 > 0.0 {
                notes.push(format!(
                    "{}: the run starts at the file's time t = {t0}",
                    what()
                ));
            }
            (state.particles, h, t0)
        }
    };
    let mut particles = particles;
    if let Some(sw) = cfg.artificial_viscosity.switch() {
        sw.initialise(&mut particles);
    }
    let problem_times = output_times.clone();
    let (t_end, mut out_times) = snapshot_times(cfg, problem_t_end, output_times)?;
    if t0 > 0.0 {
        if !(t_end > t0) {
            bail!(
                "key `time.end`: {t_end} is not after t = {t0}, the time of {} where the run starts (give a later time.end, e.g. --set time.end={})",
                opts.from
                    .as_ref()
                    .map_or(String::new(), |p| p.display().to_string()),
                2.0 * t0
            );
        }
        out_times.retain(|&x| x > t0 + 1e-12 * t_end);
    }

    let zero = TotalsRecord::from(&particles.totals(None));
    let st = LoopState {
        t: t0,
        steps: 0,
        t_end,
        h,
        box_min: bx.min.to_vec(),
        box_max: bx.max.to_vec(),
        box_kinds: bx.kinds.to_vec(),
        out_times,
        next_snap: 0,
        snapshots: SnapshotIndex::default(),
        accreted: AccretionLedger::default(),
        totals_start: zero.clone(),
        prev: zero,
        max_dp_step: 0.0,
        peak_pairs: 0,
        peak_bytes: 0,
        pairs_total: 0,
        updates: 0,
        interactions_sum: 0,
        evaluations: 1,
        ghosts: 0,
        wall_before: 0.0,
        peak_grid_cells: 0,
        peak_grid_index_bytes: 0,
        run_id: String::new(),
        problem_times: Some(problem_times),
        injector,
        budget: MassBudget::default(),
        next_series: 0.0,
        max_isolated_energy_fraction: 0.0,
        sweep_times: StageTimes::default(),
    };
    let mut run = Run::new(cfg.clone(), particles, st, bx);
    if let (Some(mt), Some(inj)) = (&run.mt, &mut run.st.injector) {
        // A stream continued from a file's time: releases before it are not made up.
        mt.skip_releases_before(inj, t0);
    }
    let mut stats = rhs(&mut run.p, &run.bx, &run.phys, run.window);
    if let Some(p0) = pressure_equilibrium {
        for i in 0..run.p.len() {
            run.p.u[i] = cfg.eos.internal_energy(run.p.rho[i], p0);
        }
        stats = rhs(&mut run.p, &run.bx, &run.phys, run.window);
    }
    let now = run.p.totals(run.phys.gravity.as_ref());
    let energies = [
        now.kinetic,
        now.internal,
        now.potential,
        now.mass,
        now.momentum_scale,
        now.angular_momentum,
    ];
    if !energies.iter().all(|e| e.is_finite()) || !run.p.rho.iter().all(|r| r.is_finite()) {
        let culprit = cfg.largest_value().map_or(String::new(), |(k, v)| {
            format!("key `{k}` = {v:e}, the largest value in the problem: ")
        });
        bail!(
            "{culprit}the set-up's totals overflow (mass {:e}, kinetic {:e}, internal {:e}, potential {:e} energy): lower the values that scale them",
            now.mass,
            now.kinetic,
            now.internal,
            now.potential
        );
    }
    let totals = TotalsRecord::from(&now);
    run.st.totals_start = totals.clone();
    run.st.prev = totals;
    run.st.peak_pairs = stats.peak_pairs;
    run.st.peak_bytes = stats.peak_window_bytes;
    run.st.ghosts = stats.ghosts;
    run.st.interactions_sum = run.p.interactions.iter().map(|&k| k as u64).sum();
    Ok((run, notes))
}

/// The constant smoothing length of a run from a file (`--from`) whose particles carry
/// `file_h`, with a line saying where it came from. `particles.h`, when the problem file
/// (or `--set`) gives it, wins; otherwise the file's h: its value when every particle has
/// the same, else the median (sphdisk runs at one h); a file without smoothing lengths
/// (GADGET initial conditions: 0) leaves the problem's `problem_h` (`h_factor` × spacing).
pub fn initial_h_from_file(cfg: &Config, problem_h: f64, file_h: &[f64]) -> (f64, String) {
    let has_h = !file_h.is_empty() && file_h.iter().all(|&x| x > 0.0 && x.is_finite());
    if !has_h {
        return (
            problem_h,
            format!("h = {problem_h} from the problem (the file has no smoothing lengths)"),
        );
    }
    let mut sorted = file_h.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    let range = if hi > lo {
        format!("from {lo} to {hi}")
    } else {
        format!("{lo}")
    };
    if let Some(h) = cfg.particles.h {
        return (
            h,
            format!("h = {h} from particles.h; the file's SmoothingLengths ({range}) are not used"),
        );
    }
    if hi == lo {
        return (lo, format!("h = {lo} from the file's SmoothingLengths"));
    }
    let median = sorted[sorted.len() / 2];
    (
        median,
        format!(
            "h = {median}, the median of the file's SmoothingLengths ({range}): sphdisk runs at one h (set particles.h to choose it)"
        ),
    )
}

/// The step loop, from wherever `run` stands to the end time (or `opts.stop_after`).
fn advance<const D: usize>(
    mut run: Run<D>,
    opts: &RunOptions,
    mut log: RunLog,
    team: &mut dyn Team<D>,
) -> Result<Outcome<D>> {
    let root = team.is_root();
    let start = Instant::now();
    let wall = |st: &LoopState| st.wall_before + start.elapsed().as_secs_f64();
    let gravity = run.phys.gravity;
    let gravity = gravity.as_ref();
    let t_end = run.st.t_end;
    let ckpt_steps = run.cfg.output.checkpoint_steps;
    let ckpt_wall = run
        .cfg
        .output
        .checkpoint_wall_seconds
        .unwrap_or(CHECKPOINT_WALL_SECONDS);
    let mut last_ckpt = Instant::now();
    let mut last_log = Instant::now();
    let updates_at_start = run.st.updates;
    // The step a checkpoint was last written at (by this process).
    let mut ckpt_at: Option<u64> = None;

    let mut series = match (&run.mt, root) {
        (Some(_), true) => {
            let fresh = run.st.steps == 0;
            [
                Series::open(
                    &opts.out,
                    "lightcurve.csv",
                    LIGHTCURVE_HEADER,
                    fresh,
                    run.st.t,
                )?,
                Series::open(&opts.out, "monitor.csv", MONITOR_HEADER, fresh, run.st.t)?,
                Series::open(&opts.out, "modes.csv", MODES_HEADER, fresh, run.st.t)?,
            ]
        }
        _ => [Series::silent(), Series::silent(), Series::silent()],
    };
    let stats_every = run
        .cfg
        .output
        .statistics_steps
        .unwrap_or(crate::config::DEFAULT_STATISTICS_STEPS);
    let mut stats = if root {
        let fresh = run.st.steps == 0;
        Series::open(
            &opts.out,
            "statistics.csv",
            STATISTICS_HEADER,
            fresh,
            run.st.t,
        )?
    } else {
        Series::silent()
    };
    if run.st.steps == 0 {
        statistics_row(team, &run.p, gravity, &run.st, 0.0, &mut stats)?;
    }
    let bar = progress_bar(opts.progress && root);
    let first_step = run.st.steps;
    while run.st.t < t_end * (1.0 - 1e-12) {
        if let Some(mt) = &run.mt {
            inject_stream(mt, &mut run.p, &mut run.st, &run.phys, team);
        }
        let st = &mut run.st;
        if st.steps >= run.cfg.time.max_steps {
            bail!(
                "reached time.max_steps = {} at t = {:.6} before time.end = {t_end}",
                run.cfg.time.max_steps,
                st.t
            );
        }
        let mut dt = [time_step(&run.p, st.h, &run.ctl, run.evolve_u).min(
            run.mt
                .as_ref()
                .map_or(f64::INFINITY, MassTransfer::max_step),
        )];
        team.min(&mut dt);
        let [mut dt] = dt;
        if !(dt > 0.0 && dt.is_finite()) {
            let culprit = run.cfg.largest_value().map_or(String::new(), |(k, v)| {
                format!(" (the largest value in the problem: key `{k}` = {v:e})")
            });
            bail!(
                "time step is {dt} at t = {}: the state is not physical; check the set-up{culprit}",
                st.t
            );
        }
        // A run that would spin for hours at a vanishing step says so at once.
        let budget = run.cfg.time.max_steps.saturating_sub(st.steps);
        if st.steps == first_step && (t_end - st.t) / dt > budget as f64 {
            bail!(
                "key `time.max_steps`: the first time step, dt = {dt:e} at t = {}, would take about {:.1e} steps to reach time.end = {t_end}, more than the {budget} left: check time.courant, time.force, time.energy, time.viscous, particles.h or particles.h_factor and the set-up's speeds, or raise time.max_steps",
                st.t,
                (t_end - st.t) / dt
            );
        }
        let target = st
            .out_times
            .get(st.next_snap)
            .copied()
            .unwrap_or(t_end)
            .min(t_end);
        let lands = st.t + dt >= target * (1.0 - 1e-12);
        if lands {
            dt = target - st.t;
        }
        let mut n = [run.p.len() as f64];
        team.sum(&mut n);
        st.updates += n[0] as u64;
        // Particles over all ranks (at the step's start), for the progress lines.
        let n_all = n[0] as usize;
        let (bx, phys, window) = (run.bx, run.phys, run.window);
        let s = kdk_step_with(&mut run.p, &bx, &phys, dt, |p| {
            team.evaluate(p, &bx, &phys, window)
        });
        let own = &run.p;
        let isolated: f64 = (0..own.len())
            .filter(|&i| own.interactions[i] == 0)
            .map(|i| own.mass[i] * own.u[i])
            .sum();
        let mut sums = [
            s.pairs as f64,
            s.ghosts as f64,
            own.interactions.iter().map(|&k| k as f64).sum::<f64>(),
            isolated,
        ];
        team.sum(&mut sums);
        let mut maxes = [
            s.peak_pairs as f64,
            s.peak_window_bytes as f64,
            s.grid_cells as f64,
            s.grid_index_bytes as f64,
        ];
        team.max(&mut maxes);
        st.peak_grid_cells = st.peak_grid_cells.max(maxes[2] as u64);
        st.peak_grid_index_bytes = st.peak_grid_index_bytes.max(maxes[3] as usize);
        st.t = if lands { target } else { st.t + dt };
        st.steps += 1;
        st.evaluations += 1;
        st.sweep_times.add(&s.times);
        st.pairs_total += sums[0] as u64;
        st.peak_pairs = st.peak_pairs.max(maxes[0] as usize);
        st.peak_bytes = st.peak_bytes.max(maxes[1] as usize);
        st.ghosts = sums[1] as usize;
        st.interactions_sum += sums[2] as u64;
        let now = global_totals(team, &run.p, gravity);
        if now.internal > 0.0 {
            st.max_isolated_energy_fraction =
                st.max_isolated_energy_fraction.max(sums[3] / now.internal);
        }
        let (_, dp, _) = now.drift_from(&st.prev.to_totals::<D>());
        st.max_dp_step = st.max_dp_step.max(dp);
        st.prev = TotalsRecord::from(&now);
        if let Some(g) = gravity
            && let Some(r_acc) = g.accretion_radius
        {
            let gone = if team.ranks() == 1 {
                st.accreted.accrete(&mut run.p, r_acc, g)
            } else {
                // This step's accretion on every rank, added to the (global) ledger.
                let mut delta = AccretionLedger::default();
                delta.accrete(&mut run.p, r_acc, g);
                let mut v = delta.to_values::<D>();
                team.sum(&mut v);
                st.accreted.add_values::<D>(&v);
                v[0] as usize
            };
            if gone > 0 {
                let mut n = [run.p.len() as f64];
                team.sum(&mut n);
                if n[0] == 0.0 {
                    bail!("every particle was accreted by t = {:.6}", st.t);
                }
                st.prev = TotalsRecord::from(&global_totals(team, &run.p, gravity));
            }
        }
        if let Some(mt) = &run.mt {
            remove_at_sinks(mt, &mut run.p, &mut run.st, &run.phys, team);
        }
        let st = &mut run.st;
        if let Some(i) = run.p.u.iter().position(|u| !u.is_finite() || *u < 0.0) {
            bail!(
                "particle {} has internal energy {} at t = {:.6} (step {}): reduce time.courant or time.energy",
                run.p.id[i],
                run.p.u[i],
                st.t,
                st.steps
            );
        }
        let (t, steps) = (st.t, st.steps);
        if steps % stats_every == 0 || t >= t_end * (1.0 - 1e-12) {
            statistics_row(team, &run.p, gravity, &run.st, dt, &mut stats)?;
        }
        if let Some(mt) = &run.mt
            && t >= run.st.next_series
        {
            let support = run.phys.kernel.support();
            let every = run
                .cfg
                .output
                .lightcurve_interval
                .unwrap_or(std::f64::consts::TAU / 50.0);
            write_series(
                mt,
                &run.phys,
                &run.p,
                &mut run.st,
                support,
                every,
                team,
                &mut series,
            )?;
        }
        team.between_steps(&mut run.p, steps, &mut log)?;
        let snap_due = lands && run.st.next_snap < run.st.out_times.len();
        // Rank 0's clock decides, so that every rank agrees; a signal on any rank stops all.
        let mut due = [
            (last_ckpt.elapsed().as_secs_f64() >= ckpt_wall) as u8 as f64,
            crate::signals::requested().unwrap_or(0) as f64,
        ];
        if team.ranks() > 1 {
            due[0] = if root { due[0] } else { 0.0 };
            team.max(&mut due);
        }
        let signal = (due[1] > 0.0).then_some(due[1] as i32);
        let stop = (opts.stop_after.is_some_and(|k| steps >= k) || signal.is_some())
            && t < t_end * (1.0 - 1e-12);
        let ckpt_due = snap_due || ckpt_steps.is_some_and(|k| steps % k == 0) || due[0] > 0.0;
        let mut all = if snap_due || ckpt_due || stop {
            team.gather(&run.p)
        } else {
            None
        };
        if snap_due {
            run.st.next_snap += 1;
            run.write_snapshot(&opts.out, all.as_ref(), &mut log)?;
        }
        if ckpt_due || stop {
            let w = wall(&run.st);
            let path = match &mut all {
                Some(all) => run.write_checkpoint(&opts.out, all, w, &mut log)?,
                None => checkpoint::folder(&opts.out).join(format!("ckpt_{steps:010}.hdf5")),
            };
            ckpt_at = Some(steps);
            last_ckpt = Instant::now();
            if stop {
                bar.finish_and_clear();
                log.line(&match signal {
                    Some(sig) => format!(
                        "stopped by {} after step {steps} at t = {t}",
                        crate::signals::name(sig)
                    ),
                    None => format!("stopped after step {steps} at t = {t}"),
                });
                return Ok(Outcome {
                    ended: Ended::Stopped {
                        step: steps,
                        time: t,
                        checkpoint: path,
                        signal,
                    },
                    particles: run.p,
                });
            }
        }
        let rate = (run.st.updates - updates_at_start) as f64 / start.elapsed().as_secs_f64();
        if root && last_log.elapsed().as_secs_f64() >= LOG_SECONDS {
            last_log = Instant::now();
            log.line(&format!(
                "t = {t:.6} step {steps} N = {n_all} dt = {dt:.3e} {rate:.3e} updates/s"
            ));
        }
        bar.set_position((t / t_end * 1000.0) as u64);
        bar.set_message(format!(
            "t = {t:.4}  step {steps}  N = {n_all}  dt = {dt:.2e}  {rate:.2e} updates/s"
        ));
    }
    bar.finish_and_clear();
    // The loop's wall time: the final outputs below are not part of it.
    let wall_loop = wall(&run.st);
    let parallel = team.record();
    let all = team.gather(&run.p);
    let Some(mut all) = all else {
        return Ok(Outcome {
            ended: Ended::Helped,
            particles: run.p,
        });
    };
    // A checkpoint of the end state lets `--resume --set time.end=…` extend the run.
    if ckpt_at != Some(run.st.steps)
        && checkpoint::list(&opts.out)?
            .first()
            .is_none_or(|c| !c.ends_with(format!("ckpt_{:010}.hdf5", run.st.steps)))
    {
        run.write_checkpoint(&opts.out, &mut all, wall_loop, &mut log)?;
    }
    let ranks = team.ranks();
    let summary = finish(&run, &all, wall_loop, &opts.out, ranks, parallel)?;
    log.line(&format!(
        "end at t = {} after {} steps, {:.2} s, {:.3e} updates/s",
        summary.t_end, summary.steps, summary.wall_seconds, summary.particle_updates_per_second
    ));
    if let Some(t) = &summary.timing {
        log.line(&format!(
            "sweep {:.2} s (find pairs {:.2}, density {:.2}, gradient {:.2}, force {:.2}, build {:.2}, finish {:.2}, wait {:.2}), outside it {:.2} s ({:.1}%)",
            t.sweep_seconds,
            t.sweep.find_pairs,
            t.sweep.density,
            t.sweep.gradient,
            t.sweep.force,
            t.sweep.build,
            t.sweep.finish,
            t.sweep.wait,
            t.outside_sweep_seconds,
            100.0 * t.outside_sweep_share
        ));
    }
    Ok(Outcome {
        ended: Ended::Finished(Box::new(summary)),
        particles: all,
    })
}

/// After a step in a binary: the sinks on every rank, the outflows summed over ranks.
fn remove_at_sinks<const D: usize>(
    mt: &MassTransfer,
    p: &mut Particles<D>,
    st: &mut LoopState,
    phys: &crate::sweep::Physics<D>,
    team: &mut dyn Team<D>,
) {
    let mut delta = MassBudget::default();
    mt.remove(p, &mut delta);
    let mut v = delta.outflow_values();
    team.sum(&mut v);
    st.budget.add_outflow_values(&v);
    st.prev = TotalsRecord::from(&global_totals(team, p, phys.gravity.as_ref()));
}

/// Before a step in a binary: the L1 stream's releases due by now. Every rank runs the
/// injector (its state stays the same everywhere); rank 0 keeps the particles and the
/// team hands them to the ranks that own their places. They start with the binary's
/// gravity as their acceleration; the step's evaluation gives them the SPH forces.
fn inject_stream<const D: usize>(
    mt: &MassTransfer,
    p: &mut Particles<D>,
    st: &mut LoopState,
    phys: &crate::sweep::Physics<D>,
    team: &mut dyn Team<D>,
) {
    let Some(inj) = &mut st.injector else { return };
    let gravity = |x: &[f64; D]| crate::integrate::external_acceleration(phys, x);
    let n = if team.is_root() {
        mt.inject(inj, p, st.t, &mut st.budget, gravity)
    } else {
        let mut scratch = Particles::<D>::new();
        let mut budget = MassBudget::default();
        mt.inject(inj, &mut scratch, st.t, &mut budget, gravity)
    };
    if n > 0 {
        if team.ranks() > 1 {
            team.adopt(p);
        }
        st.prev = TotalsRecord::from(&global_totals(team, p, phys.gravity.as_ref()));
    }
}

/// A row of `statistics.csv` after a step of `dt` (collective: totals over ranks; rank 0
/// writes).
fn statistics_row<const D: usize>(
    team: &mut dyn Team<D>,
    p: &Particles<D>,
    gravity: Option<&crate::physics::gravity::PointMass>,
    st: &LoopState,
    dt: f64,
    out: &mut Series,
) -> Result<()> {
    let tot = global_totals(team, p, gravity);
    let mut n = [p.len() as f64];
    team.sum(&mut n);
    let momentum = |d: usize| tot.momentum.get(d).copied().unwrap_or(0.0);
    out.row(&[
        st.t,
        st.steps as f64,
        dt,
        n[0],
        tot.mass,
        st.accreted.mass + st.budget.accreted.mass,
        tot.kinetic,
        tot.internal,
        tot.potential,
        tot.energy(),
        momentum(0),
        momentum(1),
        momentum(2),
        tot.angular_momentum,
    ])
}

/// A row of `lightcurve.csv`, `monitor.csv` and `modes.csv` (collective: sums over ranks; rank 0
/// writes), and the time of the next.
#[allow(clippy::too_many_arguments)]
fn write_series<const D: usize>(
    mt: &MassTransfer,
    phys: &Physics<D>,
    p: &Particles<D>,
    st: &mut LoopState,
    support: f64,
    every: f64,
    team: &mut dyn Team<D>,
    series: &mut [Series; 3],
) -> Result<()> {
    let b = &mt.binary;
    let mut hist = problems::cv::disk_histogram(b, p);
    team.sum(&mut hist);
    let r_disk = problems::cv::histogram_radius(&hist, 0.9);
    let disk_mass: f64 = hist.iter().sum();
    let rim = problems::cv::histogram_radius(&hist, 0.99);
    let l = problems::cv::luminosities(b, p, r_disk, rim, support, st.t);
    let hot = phys.outbursts.map_or(0.0, |o| o.hot_mass(p, &phys.eos).0);
    let mut v = vec![
        l[0],
        l[1],
        l[2],
        p.len() as f64,
        p.mass.iter().sum(),
        hot,
        l[3],
    ];
    team.sum(&mut v);
    let orbit = st.t / std::f64::consts::TAU;
    series[0].row(&[st.t, orbit, v[0] + v[1] + v[2], v[0], v[1], v[2], v[6]])?;
    let f = &st.budget;
    series[1].row(&[
        st.t,
        orbit,
        v[3],
        v[4],
        disk_mass,
        r_disk,
        f.injected.mass,
        f.accreted.mass,
        f.returned.mass,
        f.escaped.mass,
        v[5],
    ])?;
    let (w_lo, w_hi) = problems::cv::ECCENTRICITY_WINDOW;
    let mut sums = problems::cv::mode_sums(b, p, w_lo * r_disk, w_hi * r_disk);
    team.sum(&mut sums);
    let modes = problems::cv::DiskModes::from_sums(&sums);
    let nan = f64::NAN;
    let m = |f: fn(&problems::cv::DiskModes) -> f64| modes.as_ref().map_or(nan, f);
    // The turning frame has turned by Ω t since t = 0: the inertial longitude adds it.
    let inertial = m(|d| d.periastron_deg) + (b.omega * st.t).to_degrees();
    series[2].row(&[
        st.t,
        orbit,
        r_disk,
        m(|d| d.mass),
        m(|d| d.m1),
        m(|d| d.m1_phase_deg),
        m(|d| d.m2),
        m(|d| d.m2_phase_deg),
        m(|d| d.e),
        m(|d| d.periastron_deg),
        inertial.rem_euclid(360.0),
    ])?;
    st.next_series = ((st.t / every).floor() + 1.0) * every;
    Ok(())
}

/// The final state, error norms and `summary.json` of a run that reached its end time.
fn finish<const D: usize>(
    run: &Run<D>,
    p: &Particles<D>,
    wall: f64,
    out: &Path,
    ranks: usize,
    parallel: Option<serde_json::Value>,
) -> Result<Summary> {
    let (st, cfg) = (&run.st, &run.cfg);
    let gravity = run.phys.gravity.as_ref();
    write_particles(&out.join("final.csv"), p, st.h)?;
    write_snapshot(&out.join("final.hdf5"), &run.snapshot(p), &run.meta, 1)?;
    let totals_start = st.totals_start.to_totals::<D>();
    let totals_end = p.totals(gravity);
    // Conservation counts what was accreted as still present.
    let mut with_accreted = totals_end;
    st.accreted.add_to(&mut with_accreted);
    // A binary: what entered through L1 counts with the start, what left with the end.
    let mut totals_start = totals_start;
    totals_start.mass += st.budget.injected.mass;
    with_accreted.mass += st.budget.mass_out();
    let (dm, dp, de) = with_accreted.drift_from(&totals_start);
    let l0 = totals_start.angular_momentum;
    // Relative to |L_z| at the start, or where that is 0 (a blast from rest) to the largest
    // |L_z| the particles could hold now, Σ m |x||v| in the plane.
    let l_scale = if l0 != 0.0 {
        l0.abs()
    } else {
        (0..p.len())
            .map(|i| {
                let r = (0..D.min(2)).map(|d| p.pos[d][i].powi(2)).sum::<f64>();
                let v = (0..D.min(2)).map(|d| p.vel[d][i].powi(2)).sum::<f64>();
                p.mass[i] * (r * v).sqrt()
            })
            .sum()
    };
    let dl = (with_accreted.angular_momentum - l0).abs() / l_scale.max(f64::MIN_POSITIVE);
    let mut errors = problems::errors(cfg, p, &run.bx, st.h, st.t)?;
    if let Some(f) = errors.get_mut("isolated_energy_fraction") {
        *f = f.max(st.max_isolated_energy_fraction);
    }
    let n = p.len();
    let ring = match cfg.problem.kind {
        crate::config::ProblemKind::Ring => Some(problems::ring::record(cfg)?),
        _ => None,
    };
    let per_second = |x: u64| if wall > 0.0 { x as f64 / wall } else { 0.0 };
    let summary = Summary {
        problem: cfg.name().to_string(),
        dimension: D,
        particles: n,
        steps: st.steps,
        t_end: st.t,
        wall_seconds: wall,
        particle_updates_per_second: per_second(st.updates),
        pairs_per_second: per_second(st.pairs_total),
        peak_pair_window: st.peak_pairs,
        threads: rayon::current_num_threads(),
        ranks,
        conservation: Conservation {
            mass: dm,
            momentum: dp,
            energy: run.evolve_u.then_some(de),
            momentum_max_per_step: st.max_dp_step,
            angular_momentum: (D >= 2 && l_scale > 0.0).then_some(dl),
        },
        errors,
        smoothing_length: st.h,
        kernel: cfg.particles.kernel.description().to_string(),
        mean_neighbours: st.interactions_sum as f64 / (st.evaluations as f64 * n as f64),
        ghosts: st.ghosts,
        peak_window_bytes: st.peak_bytes,
        peak_grid_cells: st.peak_grid_cells,
        peak_grid_index_bytes: st.peak_grid_index_bytes,
        peak_rss_bytes: peak_rss_bytes(),
        totals_start: st.totals_start.clone(),
        totals_end: TotalsRecord::from(&totals_end),
        accretion: gravity
            .and_then(|g| g.accretion_radius)
            .map(|_| st.accreted.clone()),
        mass_budget: run.mt.map(|_| {
            let b = &st.budget;
            let start = st.totals_start.mass + b.injected.mass;
            let present = Flow {
                particles: n as u64,
                mass: totals_end.mass,
                angular_momentum: 0.0,
            };
            MassBudgetRecord {
                flows: b.clone(),
                present,
                residual: (start - totals_end.mass - b.mass_out()) / start,
            }
        }),
        binary: run.mt.map(|mt| binary_record(&mt, cfg)),
        ring,
        parallel,
        timing: Some(Timing::of(st.sweep_times, wall)),
    };
    summary.write(&out.join("summary.json"))?;
    Ok(summary)
}

/// A binary's geometry for `summary.json`: q, L1, the lobes, the stream's nozzle, the
/// units, and the run's length in orbits (and days where physical).
fn binary_record(mt: &MassTransfer, cfg: &Config) -> serde_json::Value {
    use crate::analysis::roche;
    let q = mt.binary.q;
    let u = cfg.units();
    let period_days = cfg.binary.and_then(|b| b.period_days);
    let mut v = serde_json::json!({
        "q": q,
        "mu": mt.binary.mu,
        "l1_distance": roche::l1_distance(q),
        "r_circ_fit": roche::r_circ_fit(q),
        "r_31": roche::r_31(q),
        "tidal_radius": roche::tidal_radius(q),
        "accretor_radius": mt.binary.accretor_radius,
        "escape_radius": mt.binary.escape_radius,
        "units_cgs": {"mass": u.mass_cgs, "length": u.length_cgs, "time": u.time_cgs},
    });
    if let Some(s) = &mt.stream {
        let (sy, sz) = s.nozzle();
        v["stream"] = serde_json::json!({
            "particles_per_orbit": s.rate * std::f64::consts::TAU,
            "particle_mass": s.particle_mass,
            "cs": s.cs,
            "nozzle_sigma_orbital_plane": sy,
            "nozzle_sigma_vertical": sz,
        });
    }
    if let Some(p) = period_days {
        v["period_days"] = serde_json::json!(p);
    }
    v
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_h_of_a_run_from_a_file() {
        let sod = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/sod.toml");
        let cfg = Config::load(&sod, &[]).unwrap();
        // One h in the file (sphdisk's snapshots): taken.
        let (h, note) = initial_h_from_file(&cfg, 0.5, &[0.02; 4]);
        assert_eq!(h, 0.02);
        assert!(note.contains("from the file's SmoothingLengths"), "{note}");
        // Varying h (SWIFT, Phantom): their median, the range in the note.
        let (h, note) = initial_h_from_file(&cfg, 0.5, &[0.04, 0.01, 0.03, 0.02, 0.05]);
        assert_eq!(h, 0.03);
        assert!(
            note.contains("median") && note.contains("from 0.01 to 0.05"),
            "{note}"
        );
        // None (GADGET initial conditions read as 0): the problem's.
        let (h, note) = initial_h_from_file(&cfg, 0.5, &[0.0; 3]);
        assert_eq!(h, 0.5);
        assert!(note.contains("no smoothing lengths"), "{note}");
        // particles.h given: it wins, and the note says the file's are not used.
        let cfg = Config::load(&sod, &["particles.h=0.007".into()]).unwrap();
        let (h, note) = initial_h_from_file(&cfg, 0.5, &[0.02; 4]);
        assert_eq!(h, 0.007);
        assert!(note.contains("not used"), "{note}");
    }
}
