//! The `sphdisk` command: `run` a problem file, `bench` the sweep, `decompose` (the domain
//! decomposition's balance and ghosts).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand, ValueEnum};

use sphdisk::config::Config;
use sphdisk::simulation::{RunOptions, default_out_dir, run};
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
    /// Run a problem file and write final.csv, snapshots and summary.json.
    Run {
        /// Problem file (TOML), e.g. problems/sod.toml.
        problem: PathBuf,
        /// Output folder (default: runs/<problem name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a key of the problem file, e.g. --set particles.n=800 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        sets: Vec<String>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
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
        /// Print JSON lines instead of a table.
        #[arg(long)]
        json: bool,
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
}

#[derive(Clone, Copy, ValueEnum)]
enum WindowArg {
    Sweep,
    Full,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match real_main(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn real_main(cli: Cli) -> Result<()> {
    if let Some(t) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global()
            .context("cannot start the thread pool")?;
    }
    match cli.command {
        Command::Run {
            problem,
            out,
            sets,
            quiet,
        } => {
            let cfg = Config::load(&problem, &sets)?;
            let out = out.unwrap_or_else(|| default_out_dir(&problem));
            let opts = RunOptions {
                out: out.clone(),
                progress: !quiet,
            };
            let s = run(&cfg, &opts)?;
            if !quiet {
                eprintln!(
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
                    eprintln!("  {k} = {v:.6e}");
                }
                eprintln!("  outputs in {}", out.display());
            }
            Ok(())
        }
        Command::Analyse {
            what: AnalyseCommand::Ring { run },
        } => {
            let report = sphdisk::analysis::ring_report::analyse_ring(&run)?;
            for (tau, l1) in &report.l1 {
                println!("tau = {tau:.4}: L1 of the averaged Σ = {:.2}%", 100.0 * l1);
            }
            for f in &report.files {
                println!("wrote {}", f.display());
            }
            Ok(())
        }
        Command::Check { problem, sets } => {
            let cfg = Config::load(&problem, &sets)?;
            let n = match cfg.dimension() {
                1 => sphdisk::problems::setup::<1>(&cfg)?.particles.len(),
                2 => sphdisk::problems::setup::<2>(&cfg)?.particles.len(),
                _ => sphdisk::problems::setup::<3>(&cfg)?.particles.len(),
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
            json,
        } => {
            let window = match window {
                WindowArg::Sweep => Window::Sweep,
                WindowArg::Full => Window::FullList,
            };
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
                for &t in &with_threads {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build()?;
                    let r =
                        pool.install(|| sphdisk::bench::run_one(np, neighbours, steps, window))?;
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
                            "          per step: build {:.3} s, find pairs {:.3} s, density {:.3} s, gradient {:.3} s, force {:.3} s, finish {:.3} s",
                            t.build, t.find_pairs, t.density, t.gradient, t.force, t.finish
                        );
                    }
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
