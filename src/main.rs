//! The `sphdisk` command: `run` a problem file, `bench` the sweep, `decompose` (the domain
//! decomposition's balance and ghosts).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};

use sphdisk::config::Config;
use sphdisk::render::image::{RenderOptions, render_png};
use sphdisk::simulation::{Ended, RunOptions, default_out_dir, run};
use sphdisk::sweep::Window;

#[derive(Parser)]
#[command(
    name = "sphdisk",
    version,
    about = "SPH for astrophysical accretion disks"
)]
struct Cli {
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a problem file and write snapshots (HDF5), checkpoints, final.csv, run.log and
    /// summary.json; or continue a run from its checkpoint with --resume.
    Run {
        /// Problem file (TOML), e.g. problems/sod.toml (not with --resume).
        #[arg(required_unless_present = "resume", conflicts_with = "resume")]
        problem: Option<PathBuf>,
        /// Output folder (default: runs/<problem name>).
        #[arg(long, conflicts_with = "resume")]
        out: Option<PathBuf>,
        /// Override a key of the problem file, e.g. --set particles.n=800 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// Start from the particles of this snapshot (HDF5, SWIFT or GADGET names) instead
        /// of the problem's own set-up.
        #[arg(long, value_name = "SNAPSHOT")]
        from: Option<PathBuf>,
        /// Continue the run in this folder from its newest checkpoint (bit for bit).
        #[arg(long, value_name = "RUN_FOLDER")]
        resume: Option<PathBuf>,
        /// Stop after this many steps (counted from the run's start) with a checkpoint.
        #[arg(long, value_name = "STEPS", value_parser = clap::value_parser!(u64).range(1..))]
        stop_after: Option<u64>,
        /// No progress bar and no report on the terminal (run.log has it all).
        #[arg(long)]
        quiet: bool,
        /// Replace the files of an earlier run in the output folder (other files stay).
        #[arg(long, conflicts_with = "resume")]
        force: bool,
    },
    /// Picture of a snapshot (SPH kernel interpolation onto pixels), or with a run folder
    /// every snapshot of the run as movie frames with one colour scale.
    Render {
        /// A snapshot (`runs/X/snap_0003.hdf5`) or a run folder (`runs/X`).
        input: PathBuf,
        /// column-density, density, dissipation, temperature (P/ρ = kT/μm_p) or velocity.
        #[arg(long, default_value = "column-density")]
        quantity: String,
        /// face-on, edge-on or slice.
        #[arg(long, default_value = "face-on")]
        view: String,
        /// The PNG to write (a snapshot) or the folder of frames (a run folder). Default:
        /// beside the input, named after the quantity and view.
        #[arg(long)]
        out: Option<PathBuf>,
        /// log or linear (default: log for densities, linear otherwise).
        #[arg(long)]
        scale: Option<String>,
        /// viridis or magma.
        #[arg(long)]
        colormap: Option<String>,
        /// Largest pixel count along each axis (2 to 16384).
        #[arg(long, default_value_t = 800, value_parser = clap::value_parser!(u32).range(2..=16384))]
        resolution: u32,
        /// Fixed colour range `LO,HI` (default: from the data; one range for a whole movie).
        #[arg(long, value_name = "LO,HI")]
        range: Option<String>,
        /// The horizontal and vertical extent shown, `LO,HI` each (default: the box).
        #[arg(long, value_name = "LO,HI")]
        xlim: Option<String>,
        #[arg(long, value_name = "LO,HI")]
        ylim: Option<String>,
        /// Height of the slice plane (3D `--view slice`; default: the box middle).
        #[arg(long)]
        slice_z: Option<f64>,
        /// Do not draw the Roche lobes and L1 of a binary run (drawn when the snapshot's
        /// problem file has `[binary]`).
        #[arg(long)]
        no_roche: bool,
        /// Frames per second of a run folder's `movie.gif` (1 to 50).
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=50))]
        fps: u32,
    },
    /// Check a problem file (keys, values, initial particles) without running it.
    Check {
        problem: PathBuf,
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
    },
    /// Analyse a finished run against its exact solution (`analyse ring runs/ring`).
    Analyse {
        #[command(subcommand)]
        what: AnalyseCommand,
    },
    /// Throughput of the sweep on a 3D periodic box.
    Bench {
        /// Particle numbers (repeatable).
        #[arg(long = "n", default_values_t = [100_000usize])]
        n: Vec<usize>,
        /// Thread counts to compare (repeatable).
        #[arg(long = "with-threads", default_values_t = [1usize, 2])]
        with_threads: Vec<usize>,
        /// Mean neighbours within the kernel support.
        #[arg(long, default_value_t = 50.0)]
        neighbours: f64,
        #[arg(long, default_value_t = 3)]
        steps: usize,
        /// `sweep` (the paper's window) or `full` (keep the whole pair list).
        #[arg(long, value_enum, default_value_t = WindowArg::Sweep)]
        window: WindowArg,
        /// Particles per thread entering the sweep together (`[sweep] batch_per_thread`):
        /// larger holds more pairs at once and runs fewer parallel regions.
        #[arg(long, default_value_t = sphdisk::sweep::BATCH_PARTICLES_PER_THREAD as u64)]
        batch: u64,
        /// Print JSON lines instead of a table.
        #[arg(long)]
        json: bool,
        /// Also write every row to this CSV file (for plotting).
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Step the thread counts in turn, on a particle set each (a machine whose speed
        /// drifts then slows them alike: the speed-up is measured in one period); each turn
        /// is an untimed step, then the timed one, so that the timed step finds its own
        /// particles in the caches, as in a run.
        #[arg(long)]
        alternate: bool,
    },
    /// Load imbalance and ghost fraction of the k-d domain decomposition on a 2D disk and a
    /// 3D clustered box, without running a simulation.
    Decompose {
        /// Region (rank) counts (repeatable).
        #[arg(long = "regions", default_values_t = [15usize, 32, 64, 1000])]
        regions: Vec<usize>,
        /// Particles in the 2D disk (0: skip).
        #[arg(long, default_value_t = 200_000)]
        disk_particles: usize,
        /// Particles in the 3D clustered box (0: skip).
        #[arg(long, default_value_t = 500_000)]
        cluster_particles: usize,
        /// Print JSON lines instead of a table.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Subcommand)]
enum AnalyseCommand {
    /// The spreading ring: averaged Σ(R) against the exact solution at each snapshot
    /// (ring_profiles.csv, ring_errors.csv, ring.png in the run folder).
    Ring {
        /// The run's output folder.
        run: PathBuf,
    },
    /// A disk: its radii, Σ against the thin-disk diffusion equation, effective α,
    /// thickness and radial velocity at each snapshot (disk_evolution.csv in the run folder).
    Disk {
        /// The run's output folder.
        run: PathBuf,
    },
    /// The shock tube: ρ, v, p, u against the exact Riemann solution at the final time
    /// (sod.png, sod_profile.csv in the run folder).
    Sod {
        /// The run's output folder.
        run: PathBuf,
    },
    /// A light curve: the strongest period of lightcurve.csv between 0.2 and 5 orbits, e.g.
    /// a superhump (lightcurve.png, periodogram.png, lightcurve.json in the run folder).
    Lightcurve {
        /// The run's output folder.
        run: PathBuf,
        /// Orbits at the start of the light curve to leave out as the transient.
        #[arg(long, default_value_t = 0.0)]
        skip_orbits: f64,
        /// Fit a floating mean only, not a cubic trend in time with the sinusoid (a disk
        /// still building up then shows as a long period).
        #[arg(long)]
        no_detrend: bool,
    },
    /// SU UMa superhumps: the disk's eccentricity (growth, saturation), its precession, the
    /// superhump period and excess ε in the light curve beside the dynamical and observed ε(q)
    /// (superhump.json, superhump_*.png in each run folder; with several runs and --out, the
    /// series' table and ε(q) plot).
    Superhump {
        /// The runs' output folders (cv runs with modes.csv and lightcurve.csv).
        #[arg(required = true)]
        runs: Vec<PathBuf>,
        /// Where to write superhump_scan.csv and superhump_scan.png (a q series).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Dwarf-nova outbursts of a run with [outbursts]: each outburst's start, duration and
    /// peak (mag above quiescence), superoutbursts (the disk eccentric) with their superhump,
    /// the recurrence in orbits and days (outbursts.json, outbursts.png in the run folder).
    Outbursts {
        /// The run's output folder (a cv run: lightcurve.csv, monitor.csv, modes.csv).
        run: PathBuf,
    },
    /// A cataclysmic variable: the disk's radii and eccentricity, the bright spot's azimuth
    /// and, in 3D, the stream's overflow at each snapshot (cv_evolution.csv, cv.json).
    Cv {
        /// The run's output folder.
        run: PathBuf,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum WindowArg {
    Sweep,
    Full,
}

/// A line on stderr (a run's terminal report, an error), written best-effort: a reader
/// that has quit (`sphdisk run … 2>&1 | head`) must not turn a finished run, its files
/// written, into a panic.
macro_rules! report {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

fn main() -> ExitCode {
    sphdisk::memory::keep_freed_memory();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            // One line, as every other error: clap's first, without its usage block.
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("bad command line");
            eprintln!("error: {}", first.trim_start_matches("error: ").trim());
            return ExitCode::from(2);
        }
    };
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            report!(
                "error: {}",
                sphdisk::limits::shorten_numbers(&format!("{e:#}"))
            );
            ExitCode::from(2)
        }
    }
}

/// `LO,HI` as two numbers, or an error naming the option.
fn pair(option: &str, text: &str) -> Result<(f64, f64)> {
    let parse = |s: &str| s.trim().parse::<f64>();
    match text.split_once(',') {
        Some((a, b)) => match (parse(a), parse(b)) {
            (Ok(a), Ok(b)) => Ok((a, b)),
            _ => anyhow::bail!("{option}: expected two numbers LO,HI, got `{text}`"),
        },
        None => anyhow::bail!("{option}: expected LO,HI, got `{text}`"),
    }
}

/// The terminal report of a run.
fn report_run(ended: &Ended, out: &std::path::Path) {
    match ended {
        // Other ranks of a distributed run: rank 0 reports.
        Ended::Helped => return,
        Ended::Finished(s) => {
            report!(
                "{}: {} particles, {}D, {} steps to t = {} in {:.2} s ({:.3e} particle updates/s, {} threads)",
                s.problem,
                s.particles,
                s.dimension,
                s.steps,
                s.t_end,
                s.wall_seconds,
                s.particle_updates_per_second,
                s.threads
            );
            for (k, v) in &s.errors {
                report!("  {k} = {v:.6e}");
            }
        }
        Ended::Stopped {
            step,
            time,
            checkpoint,
            signal,
        } => {
            let by = signal.map_or(String::new(), |s| {
                format!(" by {}", sphdisk::signals::name(s))
            });
            report!(
                "stopped{by} after step {step} at t = {time}; checkpoint {}",
                checkpoint.display()
            );
            report!("  continue with: sphdisk run --resume {}", out.display());
        }
    }
    report!("  outputs in {}", out.display());
}

/// What `sphdisk run` was asked to do.
enum Job {
    Fresh(Box<Config>, RunOptions),
    Resume(Vec<String>, RunOptions),
}

/// Runs the job on this process, or, when started by `mpirun` with more than one rank (and
/// built with `--features mpi`), on all ranks together.
fn execute(job: Job) -> Result<Ended> {
    #[cfg(feature = "mpi")]
    if let Some(ended) = execute_mpi(&job) {
        return ended;
    }
    // The step loop runs on one of the pool's threads, so that each parallel loop it starts
    // is split from inside the pool instead of handed to it from outside and waited for.
    rayon::scope(|_| match job {
        Job::Fresh(cfg, opts) => run(&cfg, &opts),
        Job::Resume(sets, opts) => sphdisk::simulation::resume(&sets, &opts),
    })
}

/// The job on the MPI ranks; None when there is only one rank (run as usual). A rank that
/// fails ends the whole job with `MPI_Abort` and its message, so that none waits forever.
#[cfg(feature = "mpi")]
fn execute_mpi(job: &Job) -> Option<Result<Ended>> {
    use sphdisk::domain::comm::Comm;
    use sphdisk::domain::mpi_comm::{MpiComm, install_abort_on_panic};
    let universe = mpi::initialize()?;
    let world = mpi::topology::Communicator::duplicate(&universe.world());
    if mpi::topology::Communicator::size(&world) < 2 {
        return None;
    }
    let mut comm = MpiComm::new(world);
    install_abort_on_panic(comm.rank());
    let ended = match job {
        Job::Fresh(cfg, opts) => sphdisk::simulation::run_distributed(&mut comm, cfg, opts),
        Job::Resume(sets, opts) => sphdisk::simulation::resume_distributed(&mut comm, sets, opts),
    };
    match ended {
        Ok(ended) => {
            comm.flush();
            Some(Ok(ended))
        }
        Err(e) => comm.abort(&format!("{e:#}")),
    }
}

fn real_main(cli: Cli) -> Result<()> {
    if !matches!(cli.command, Command::Run { .. }) {
        sphdisk::signals::end_quietly_when_the_reader_quits();
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if let Some(t) = cli.threads {
        sphdisk::limits::check_threads("--threads", t, cores)?;
    } else if let Some(t) = std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
    {
        // rayon's own setting, bounded as --threads is.
        sphdisk::limits::check_threads("RAYON_NUM_THREADS", t, cores)?;
    }
    // Without --threads rayon's default (RAYON_NUM_THREADS, else one per core). The step loop
    // runs on one of these threads (`execute`), so they get the main thread's 8 MiB stack.
    rayon::ThreadPoolBuilder::new()
        .num_threads(cli.threads.unwrap_or(0))
        .stack_size(8 << 20)
        .build_global()
        .context("cannot start the thread pool")?;
    match cli.command {
        Command::Run {
            problem,
            out,
            sets,
            from,
            resume,
            stop_after,
            quiet,
            force,
        } => {
            let (job, out) = match (resume, problem) {
                (Some(dir), _) => {
                    let opts = RunOptions {
                        out: dir.clone(),
                        progress: !quiet,
                        from: None,
                        stop_after,
                        force: false,
                    };
                    (Job::Resume(sets, opts), dir)
                }
                (None, Some(problem)) => {
                    let cfg = Config::load(&problem, &sets)?;
                    let out = out.unwrap_or_else(|| default_out_dir(&problem));
                    let opts = RunOptions {
                        out: out.clone(),
                        progress: !quiet,
                        from,
                        stop_after,
                        force,
                    };
                    (Job::Fresh(Box::new(cfg), opts), out)
                }
                (None, None) => anyhow::bail!("give a problem file or --resume RUN_FOLDER"),
            };
            sphdisk::signals::install()?;
            let ended = execute(job)?;
            if !quiet {
                report_run(&ended, &out);
            }
            if let Ended::Stopped {
                signal: Some(sig), ..
            } = ended
            {
                // 128 + the signal's number, as a shell reports a process the signal ended.
                std::process::exit(128 + sig);
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Ring { run },
        } => {
            let report = sphdisk::reports::ring::analyse_ring(&run)?;
            for ((tau, l1), (_, empty)) in report.l1.iter().zip(&report.empty_annuli) {
                println!(
                    "tau = {tau:.4}: L1 of the averaged Σ = {:.2}%, empty annuli = {:.1}%",
                    100.0 * l1,
                    100.0 * empty
                );
            }
            for f in &report.files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Disk { run },
        } => {
            let report = sphdisk::reports::disk::analyse_disk(&run)?;
            println!(
                "      t  r10 (pred)       r50 (pred)       r90 (pred)       Σ L1   M(<R) L1  α_eff   v_R/c_s"
            );
            for (t, e) in &report.rows {
                let f = |k: &str| e.get(k).copied().unwrap_or(f64::NAN);
                println!(
                    "{t:7.2}  {:+.3} ({:+.3})  {:+.3} ({:+.3})  {:+.3} ({:+.3})  {:.3}  {:.4}    {:.4}  {:.3}",
                    f("disk_r10_change"),
                    f("disk_r10_predicted"),
                    f("disk_r50_change"),
                    f("disk_r50_predicted"),
                    f("disk_r90_change"),
                    f("disk_r90_predicted"),
                    f("disk_sigma_l1"),
                    f("disk_enclosed_mass_l1"),
                    f("disk_alpha_effective"),
                    f("disk_vr_rms_over_cs"),
                );
            }
            println!("wrote {}", report.file.display());
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Sod { run },
        } => {
            for f in sphdisk::reports::sod::analyse_sod(&run)? {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Analyse {
            what:
                AnalyseCommand::Lightcurve {
                    run,
                    skip_orbits,
                    no_detrend,
                },
        } => {
            let report =
                sphdisk::reports::lightcurve::analyse_lightcurve(&run, skip_orbits, !no_detrend)?;
            print!("{}", report.summary());
            for f in &report.files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Superhump { runs, out },
        } => {
            use sphdisk::reports::superhump as sh;
            let mut reports = Vec::new();
            for run in &runs {
                let report = sh::analyse_superhump(run)?;
                print!("{}", report.summary());
                for f in &report.files {
                    println!("wrote {}", f.display());
                }
                reports.push(report);
            }
            if let Some(out) = out {
                let mut with_q = Vec::new();
                for r in &reports {
                    let Some(p) = &r.figures.predictions else {
                        anyhow::bail!(
                            "{}: run.toml gives no binary q; a q series needs it",
                            r.run.display()
                        );
                    };
                    with_q.push((p.q, &r.figures));
                }
                for f in sh::write_scan(&out, &with_q)? {
                    println!("wrote {}", f.display());
                }
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Outbursts { run },
        } => {
            let report = sphdisk::reports::outbursts::analyse_outbursts(&run)?;
            print!("{}", report.summary());
            for f in &report.files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Cv { run },
        } => {
            let report = sphdisk::reports::cv::analyse_cv(&run)?;
            print!("{}", report.summary());
            for f in &report.files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Render {
            input,
            quantity,
            view,
            out,
            scale,
            colormap,
            resolution,
            range,
            xlim,
            ylim,
            slice_z,
            no_roche,
            fps,
        } => {
            use sphdisk::render::interpolate::Extent;
            let mut opts = RenderOptions::new(quantity.parse()?, view.parse()?);
            if let Some(s) = scale {
                opts.scale = s.parse()?;
            }
            if let Some(c) = colormap {
                opts.colormap = c.parse()?;
            }
            opts.resolution = (resolution, resolution);
            opts.range = range.as_deref().map(|r| pair("--range", r)).transpose()?;
            opts.slice_z = slice_z;
            if !no_roche {
                opts.roche_q = sphdisk::render::overlay::mass_ratio_of(&input)?;
            }
            if let Some(first) = sphdisk::io::snapshot_index::snapshot_of(&input)? {
                opts.units = sphdisk::io::hdf5::read_units(&first)?;
                opts.periodic = sphdisk::io::hdf5::read_periodic(&first)?;
            }
            match (xlim, ylim) {
                (None, None) => {}
                (Some(x), Some(y)) => {
                    opts.frame = Some(Extent::new(pair("--xlim", &x)?, pair("--ylim", &y)?)?);
                }
                _ => anyhow::bail!("--xlim and --ylim go together"),
            }
            let name = format!("{}_{}", opts.quantity.name(), opts.view.name());
            if input.is_dir() {
                let out = out.unwrap_or_else(|| input.join(format!("frames_{name}")));
                let frames = sphdisk::render::movie::render_run(&input, &opts, &out)?;
                let gif = out.join("movie.gif");
                sphdisk::render::movie::write_gif(&frames, &gif, fps)?;
                println!(
                    "wrote {} frames in {} and the movie {}",
                    frames.len(),
                    out.display(),
                    gif.display()
                );
            } else {
                let snap = sphdisk::io::hdf5::read_snapshot_with_h(&input)?.in_run_frame();
                let out = out.unwrap_or_else(|| {
                    let stem = input.file_stem().unwrap_or_default().to_string_lossy();
                    input.with_file_name(format!("{stem}_{name}.png"))
                });
                let img =
                    render_png(&snap, &opts, &out).with_context(|| input.display().to_string())?;
                println!(
                    "wrote {} ({} × {} pixels, colour range {:.4e} .. {:.4e})",
                    out.display(),
                    img.frame.nx,
                    img.frame.ny,
                    img.range_used.0,
                    img.range_used.1
                );
            }
            Ok(())
        }
        Command::Check { problem, sets } => {
            let cfg = Config::load(&problem, &sets)?;
            // The set-up with its checks, and the run's snapshot times (a run checks both
            // before it starts).
            fn checked<const D: usize>(cfg: &Config) -> Result<usize> {
                let s = sphdisk::problems::setup::<D>(cfg)?;
                sphdisk::simulation::snapshot_times(cfg, s.t_end, s.output_times)?;
                Ok(s.particles.len())
            }
            let n = match cfg.dimension() {
                1 => checked::<1>(&cfg)?,
                2 => checked::<2>(&cfg)?,
                _ => checked::<3>(&cfg)?,
            };
            println!(
                "{}: ok ({} particles, {}D)",
                problem.display(),
                n,
                cfg.dimension()
            );
            Ok(())
        }
        Command::Bench {
            n,
            with_threads,
            neighbours,
            steps,
            window,
            batch,
            json,
            csv,
            alternate,
        } => {
            if steps == 0 {
                anyhow::bail!("--steps: at least 1");
            }
            sphdisk::limits::check_batch("--batch", batch)?;
            for &t in &with_threads {
                sphdisk::limits::check_threads("--with-threads", t, cores)?;
            }
            let window = match window {
                WindowArg::Sweep => Window::SWEEP,
                WindowArg::Full => Window::FULL_LIST,
            }
            .with_batch(batch as usize);
            sphdisk::bench::check_options(&n, neighbours, window)?;
            if let Some(path) = &csv {
                // Refuse an unwritable path before the measurements, not after.
                std::fs::write(path, "")
                    .with_context(|| format!("--csv: cannot write {}", path.display()))?;
            }
            let mut rows: Vec<String> = vec![sphdisk::bench::BenchResult::CSV_HEADER.to_string()];
            if !json {
                println!(
                    "{:>9} {:>7} {:>8} {:>6} {:>10} {:>12} {:>12} {:>14} {:>12} {:>12} {:>10}",
                    "particles",
                    "threads",
                    "window",
                    "neigh",
                    "s/step",
                    "updates/s",
                    "pairs/s",
                    "pairs/s/core",
                    "window MiB",
                    "full MiB",
                    "RSS MiB"
                );
            }
            for &np in &n {
                let mut one_thread: Option<sphdisk::bench::BenchResult> = None;
                let pools = with_threads
                    .iter()
                    .map(|&t| rayon::ThreadPoolBuilder::new().num_threads(t).build())
                    .collect::<Result<Vec<_>, _>>()?;
                // Alternating, every run ends before the first row; else each row is
                // printed as its run ends.
                let mut alternated = alternate
                    .then(|| sphdisk::bench::run_alternating(np, neighbours, steps, window, &pools))
                    .transpose()?
                    .map(Vec::into_iter);
                for pool in &pools {
                    let mut r = match alternated.as_mut() {
                        Some(results) => results.next().expect("one result per pool"),
                        None => {
                            pool.install(|| sphdisk::bench::run_one(np, neighbours, steps, window))?
                        }
                    };
                    if r.threads == 1 {
                        one_thread = Some(r.clone());
                    } else if let Some(one) = &one_thread {
                        r.compare_with(one);
                    }
                    rows.push(r.csv_row());
                    if json {
                        println!("{}", serde_json::to_string(&r)?);
                    } else {
                        let mib = |b: f64| b / (1024.0 * 1024.0);
                        println!(
                            "{:>9} {:>7} {:>8} {:>6.1} {:>10.3} {:>12.3e} {:>12.3e} {:>14.3e} {:>12.1} {:>12.1} {:>10.1}",
                            r.particles,
                            r.threads,
                            r.window,
                            r.mean_neighbours,
                            r.seconds_per_step,
                            r.particle_updates_per_second,
                            r.pairs_per_second,
                            r.pairs_per_second_per_core,
                            mib(r.peak_window_bytes as f64),
                            mib(r.full_list_bytes as f64),
                            mib(r.peak_rss_bytes as f64)
                        );
                        let t = &r.times_per_step;
                        println!(
                            "          per step: build {:.3} s, find pairs {:.3} s, density {:.3} s, gradient {:.3} s, force {:.3} s, finish {:.3} s, outside the sweep {:.3} s",
                            t.build,
                            t.find_pairs,
                            t.density,
                            t.gradient,
                            t.force,
                            t.finish,
                            r.outside_sweep_seconds_per_step
                        );
                        let c = &r.cost_per_pair;
                        println!(
                            "          per pair: find pairs {:.1} flops {:.0} B ({:.2} candidates, {:.2} cell boxes), density {:.1} flops {:.0} B, gradient {:.1} flops {:.0} B, force {:.1} flops {:.0} B; flops per pair {:.1}, bytes moved per pair {:.0}",
                            c.find.flops,
                            c.find.bytes,
                            r.candidates_per_pair,
                            r.cells_per_pair,
                            c.density.flops,
                            c.density.bytes,
                            c.gradient.flops,
                            c.gradient.bytes,
                            c.force.flops,
                            c.force.bytes,
                            r.flops_per_pair,
                            r.bytes_per_pair
                        );
                        let per_step = r.pairs_per_second * r.seconds_per_step;
                        let rate = |secs: f64| per_step / secs;
                        println!(
                            "          pairs/s of each loop: find pairs {:.3e}, density {:.3e}, gradient {:.3e}, force {:.3e}",
                            rate(t.find_pairs),
                            rate(t.density),
                            rate(t.gradient),
                            rate(t.force)
                        );
                        if let (Some(s), Some(e)) = (r.speedup, r.parallel_efficiency) {
                            println!(
                                "          speed-up over 1 thread {s:.2}, parallel efficiency {:.0}%",
                                100.0 * e
                            );
                        }
                    }
                }
            }
            if let Some(path) = csv {
                let mut text = rows.join("\n");
                text.push('\n');
                std::fs::write(&path, text)
                    .with_context(|| format!("cannot write {}", path.display()))?;
                if !json {
                    println!("wrote {}", path.display());
                }
            }
            Ok(())
        }
        Command::Decompose {
            regions,
            disk_particles,
            cluster_particles,
            json,
        } => {
            let opts = sphdisk::domain::report::ReportOptions {
                regions,
                disk_particles,
                cluster_particles,
                json,
            };
            sphdisk::domain::report::run_report(&opts).map(|_| ())
        }
    }
}
