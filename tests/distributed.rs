//! The distributed algorithm (k-d regions, one-sided copies, partial sums and finals sent at
//! each change of state, migration, rebalancing) against the single-process run, with the
//! ranks as threads of this process (`ThreadComm`), so that it is checked by a plain
//! `cargo test`. `tests/mpi.rs` runs the same comparisons over real MPI ranks.

mod common;

use std::path::Path;

use common::{assert_same_state, error, problem_file};
use sphdisk::config::Config;
use sphdisk::domain::comm::ThreadComm;
use sphdisk::domain::team::Distributed;
use sphdisk::io::checkpoint;
use sphdisk::io::summary::Summary;
use sphdisk::particles::Particles;
use sphdisk::simulation::{Ended, RunOptions, run_in_team, run_with_state};

fn config(file: &str, sets: &[&str]) -> Config {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Config::load(Path::new(&problem_file(file)), &sets).expect("problem file loads")
}

/// Runs on `ranks` in-process ranks (1: the single-process loop) into `out`; returns rank
/// 0's outcome.
fn run_on<const D: usize>(cfg: &Config, ranks: usize, opts: &RunOptions) -> Ended {
    if ranks == 1 {
        return run_with_state::<D>(cfg, opts).expect("run").ended;
    }
    let mut ended = ThreadComm::run(ranks, |c| {
        let mut team = Distributed::new(c);
        run_in_team::<D>(cfg, opts, &mut team).expect("run").ended
    });
    for e in &ended[1..] {
        // Other ranks stop with rank 0, or leave the outputs to it.
        assert!(matches!(e, Ended::Helped | Ended::Stopped { .. }), "{e:?}");
    }
    ended.swap_remove(0)
}

/// The particles after `steps` steps, read back from the checkpoint `--stop-after` writes
/// (it holds every rank's particles).
fn state_after<const D: usize>(cfg: &Config, ranks: usize, steps: u64) -> Particles<D> {
    let dir = tempfile::tempdir().unwrap();
    let opts = RunOptions {
        stop_after: Some(steps),
        ..RunOptions::quiet(dir.path())
    };
    match run_on::<D>(cfg, ranks, &opts) {
        Ended::Stopped { checkpoint, .. } => checkpoint::read::<D>(&checkpoint).unwrap().1,
        other => panic!("expected a stop, got {other:?}"),
    }
}

fn one_step<const D: usize>(file: &str, sets: &[&str]) {
    let cfg = config(file, sets);
    let one = state_after::<D>(&cfg, 1, 1);
    for ranks in [2, 3, 4] {
        let mut many = state_after::<D>(&cfg, ranks, 1);
        assert_same_state(&one, &mut many, &format!("{file} on {ranks} ranks"));
    }
}

#[test]
fn sod_tube_after_one_step_is_the_same_on_2_3_and_4_ranks() {
    one_step::<1>("sod.toml", &[]);
}

#[test]
fn ring_after_one_step_is_the_same_on_2_3_and_4_ranks() {
    one_step::<2>("ring.toml", &["particles.n=20"]);
}

#[test]
fn disk_with_orbital_artificial_viscosity_after_one_step_is_the_same_on_2_3_and_4_ranks() {
    // Guards the orbital-frame AV velocities of copies from other ranks, with gravity, α
    // viscosity and the balanced set-up.
    one_step::<3>("disk3d.toml", &["particles.n=5"]);
}

#[test]
fn blast_3d_after_one_step_is_the_same_on_2_3_and_4_ranks() {
    one_step::<3>("sedov.toml", &["particles.n=16"]);
}

fn finished(e: Ended) -> Summary {
    match e {
        Ended::Finished(s) => *s,
        other => panic!("expected a finished run, got {other:?}"),
    }
}

/// Conserved totals at the end agree to round-off, error norms to 3 digits.
fn assert_same_run(a: &Summary, b: &Summary, keys: &[&str]) {
    assert_eq!(a.steps, b.steps, "same number of steps");
    assert_eq!(a.particles, b.particles);
    let (ta, tb) = (&a.totals_end, &b.totals_end);
    let close = |x: f64, y: f64, scale: f64, what: &str| {
        assert!(
            (x - y).abs() <= 1e-10 * scale.abs().max(1e-300),
            "{what}: {x} vs {y}"
        );
    };
    close(ta.mass, tb.mass, ta.mass, "mass");
    close(ta.energy, tb.energy, ta.energy, "energy");
    close(
        ta.angular_momentum,
        tb.angular_momentum,
        ta.angular_momentum.abs().max(ta.mass),
        "angular momentum",
    );
    for k in keys {
        let (x, y) = (error(a, k), error(b, k));
        assert!(
            (x - y).abs() <= 5e-4 * x.abs(),
            "errors.{k}: {x} vs {y} differ in the first 3 digits"
        );
    }
}

#[test]
fn sod_tube_to_the_end_on_3_ranks_has_the_same_totals_and_errors() {
    let cfg = config("sod.toml", &[]);
    let dir = tempfile::tempdir().unwrap();
    let one = finished(run_on::<1>(
        &cfg,
        1,
        &RunOptions::quiet(dir.path().join("1")),
    ));
    let three = finished(run_on::<1>(
        &cfg,
        3,
        &RunOptions::quiet(dir.path().join("3")),
    ));
    assert!(one.steps >= 100, "{} steps", one.steps);
    assert_same_run(&one, &three, &["l1_density", "l1_velocity", "l1_pressure"]);
    let par = three.parallel.expect("parallel record");
    assert_eq!(par["ranks"], 3);
    assert_eq!(par["per_rank"].as_array().unwrap().len(), 3);
}

#[test]
fn blast_3d_for_100_steps_on_4_ranks_has_the_same_totals_and_errors() {
    let cfg = config("sedov.toml", &["particles.n=16", "time.courant=0.08"]);
    let dir = tempfile::tempdir().unwrap();
    let one = finished(run_on::<3>(
        &cfg,
        1,
        &RunOptions::quiet(dir.path().join("1")),
    ));
    let four = finished(run_on::<3>(
        &cfg,
        4,
        &RunOptions::quiet(dir.path().join("4")),
    ));
    assert!(one.steps >= 100, "{} steps", one.steps);
    let keys: Vec<&str> = one.errors.keys().map(String::as_str).collect();
    assert_same_run(&one, &four, &keys);
}

#[test]
fn ring_with_accretion_on_3_ranks_keeps_the_ledger_and_the_totals() {
    let cfg = config("ring.toml", &["particles.n=20", "time.end=6.0"]);
    let dir = tempfile::tempdir().unwrap();
    let one = finished(run_on::<2>(
        &cfg,
        1,
        &RunOptions::quiet(dir.path().join("1")),
    ));
    let three = finished(run_on::<2>(
        &cfg,
        3,
        &RunOptions::quiet(dir.path().join("3")),
    ));
    assert!(one.steps >= 100, "{} steps", one.steps);
    assert_same_run(&one, &three, &[]);
    assert_eq!(
        one.accretion.as_ref().map(|a| a.particles),
        three.accretion.as_ref().map(|a| a.particles)
    );
    // Mass in particles plus the ledger equals the initial mass to round-off.
    assert!(
        three.conservation.mass <= 1e-14,
        "{}",
        three.conservation.mass
    );
}

#[test]
fn a_run_resumes_on_another_number_of_ranks_with_the_same_result() {
    let cfg = config("sedov.toml", &["particles.n=12", "time.end=0.01"]);
    let dir = tempfile::tempdir().unwrap();
    let straight = finished(run_on::<3>(
        &cfg,
        1,
        &RunOptions::quiet(dir.path().join("a")),
    ));
    // Stop on 3 ranks, resume on 2.
    let out = dir.path().join("b");
    let stopped = run_on::<3>(
        &cfg,
        3,
        &RunOptions {
            stop_after: Some(3),
            ..RunOptions::quiet(&out)
        },
    );
    assert!(matches!(stopped, Ended::Stopped { step: 3, .. }));
    let opts = RunOptions::quiet(&out);
    let mut resumed = ThreadComm::run(2, |c| {
        sphdisk::domain::team::resume(c, &[], &opts).expect("resume")
    });
    let resumed = finished(resumed.swap_remove(0));
    assert_same_run(&straight, &resumed, &[]);
}
