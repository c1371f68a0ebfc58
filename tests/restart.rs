//! Guards checkpoints and restarts: a run stopped at step k and resumed ends in exactly the
//! state (every bit of every particle array) of the run that was never stopped; a run killed
//! by SIGKILL three times and stopped by SIGTERM once, resumed after each, ends in the same
//! bits (falling back past a truncated newest checkpoint); SIGTERM checkpoints the step and
//! exits with 143; a snapshot restarts a problem
//! (`--from`); and bad restart input fails with one clear line.

use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use sphdisk::io::checkpoint;
use sphdisk::io::hdf5::read_snapshot;

mod common;
use common::problem_file as problem;
use common::{ok, path_str as s, sphdisk_err as sphdisk};

/// Every array of the newest checkpoint of a run, as bits: the complete state.
fn final_state_bits<const D: usize>(run: &Path) -> Vec<(String, Vec<u64>)> {
    let newest = checkpoint::list(run).unwrap().remove(0);
    let (_, mut p) = checkpoint::read::<D>(&newest).unwrap();
    let mut out = vec![("id".to_string(), p.id.clone())];
    for (name, v) in p.named_arrays_mut() {
        out.push((name, v.iter().map(|x| x.to_bits()).collect()));
    }
    out
}

fn assert_same_state<const D: usize>(a: &Path, b: &Path) {
    let (x, y) = (final_state_bits::<D>(a), final_state_bits::<D>(b));
    assert_eq!(x.len(), y.len());
    for ((na, va), (nb, vb)) in x.iter().zip(&y) {
        assert_eq!(na, nb);
        let differ = va.iter().zip(vb).filter(|(p, q)| p != q).count();
        assert_eq!(
            differ,
            0,
            "array {na}: {differ} of {} values differ",
            va.len()
        );
    }
    assert_eq!(
        std::fs::read(a.join("final.csv")).unwrap(),
        std::fs::read(b.join("final.csv")).unwrap()
    );
    // The global totals' time series: the resumed run's rows after its checkpoint replace
    // those its first part wrote later, so the file is byte for byte the same.
    let stats = |r: &Path| std::fs::read_to_string(r.join("statistics.csv")).unwrap();
    assert_eq!(stats(a), stats(b), "statistics.csv differs");
}

/// Runs `file` with `sets` uninterrupted into `a`, and stopped after `k` steps then resumed
/// into `b`; both must end in the same bits.
fn stop_and_resume<const D: usize>(file: &str, sets: &[&str], k: u64) {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let p = problem(file);
    let with = |out: &Path, extra: &[&str]| -> Vec<String> {
        let mut v = vec![
            "run".into(),
            p.clone(),
            "--quiet".into(),
            "--out".into(),
            s(out),
        ];
        for x in sets {
            v.push("--set".into());
            v.push(x.to_string());
        }
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    let args = with(&a, &[]);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let k_str = k.to_string();
    let args = with(&b, &["--stop-after", &k_str]);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        !b.join("summary.json").exists(),
        "a stopped run has no summary yet"
    );
    ok(&["run", "--quiet", "--resume", &s(&b)]);
    assert_same_state::<D>(&a, &b);
    let log = std::fs::read_to_string(b.join("run.log")).unwrap();
    assert!(log.contains(&format!("stopped after step {k}")), "{log}");
    assert!(log.contains("resume from"), "{log}");
}

#[test]
fn resumed_sedov_blast_is_bit_identical_to_the_uninterrupted_run() {
    stop_and_resume::<2>(
        "sedov2d.toml",
        &["particles.n=40", "output.interval=0.02"],
        7,
    );
}

#[test]
fn resumed_viscous_ring_is_bit_identical_to_the_uninterrupted_run() {
    // Physical viscosity, gravity and accretion: every part of the state matters.
    stop_and_resume::<2>(
        "ring.toml",
        &["particles.n=20", "ring.tau_end=0.03", "output.interval=0"],
        11,
    );
}

/// The step of the newest checkpoint of `run` (0 when it has none).
fn newest_step(run: &Path) -> u64 {
    checkpoint::list(run)
        .ok()
        .and_then(|l| l.into_iter().next())
        .and_then(|p| {
            let name = p.file_stem()?.to_string_lossy().into_owned();
            name.strip_prefix("ckpt_")?.parse().ok()
        })
        .unwrap_or(0)
}

/// Starts `args`, waits until `run` has a checkpoint `ahead` steps past its newest one
/// when this was called, lets it go on for `after_ms`, then sends `signal`; returns the
/// exit status, or None if the run finished before the signal landed.
fn interrupt(
    args: &[&str],
    run: &Path,
    ahead: u64,
    after_ms: u64,
    signal: &str,
) -> Option<std::process::ExitStatus> {
    let from = newest_step(run);
    let mut child = Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(args)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while newest_step(run) < from + ahead {
        if let Some(st) = child.try_wait().unwrap() {
            assert!(st.success(), "{args:?}: {st}");
            return None;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "no checkpoints written"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    std::thread::sleep(Duration::from_millis(after_ms));
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    (!status.success()).then_some(status)
}

#[test]
fn a_run_killed_several_times_and_stopped_by_sigterm_resumes_bit_identically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let p = problem("sedov2d.toml");
    let sets = [
        "--set",
        "particles.n=48",
        "--set",
        "output.checkpoint_steps=1",
        "--set",
        "time.end=0.08",
    ];
    let (a_s, b_s) = (s(&a), s(&b));
    ok(&[&["run", &p, "--quiet", "--out", &a_s][..], &sets[..]].concat());
    let fresh = [&["run", &p, "--quiet", "--out", &b_s][..], &sets[..]].concat();
    let resume = ["run", "--quiet", "--resume", &b_s];
    // SIGKILL at three moments (a few checkpoints in, at varying offsets into a step), each
    // followed by a resume; then a scheduler's SIGTERM; then the resume to the end.
    let mut kills = 0;
    for (k, (ahead, after_ms)) in [(3, 0), (4, 7), (5, 13)].into_iter().enumerate() {
        let args: &[&str] = if k == 0 { &fresh } else { &resume };
        let Some(status) = interrupt(args, &b, ahead, after_ms, "-KILL") else {
            break;
        };
        assert_eq!(status.signal(), Some(9), "killed: {status}");
        kills += 1;
        if k == 0 {
            // The worst a kill during a write could leave if rename were not atomic: a
            // truncated newest checkpoint. The resume must fall back to the previous one.
            let newest: PathBuf = checkpoint::list(&b).unwrap().remove(0);
            let bytes = std::fs::read(&newest).unwrap();
            std::fs::write(&newest, &bytes[..bytes.len() / 2]).unwrap();
        }
    }
    let mut terms = 0;
    if kills == 3
        && let Some(status) = interrupt(&resume, &b, 3, 3, "-TERM")
    {
        // 128 + 15, after writing a checkpoint of the step it was in.
        assert_eq!(status.code(), Some(143), "{status}");
        assert!(!b.join("summary.json").exists());
        assert!(!b.join(".sphdisk.lock").exists(), "the lock is released");
        terms += 1;
    }
    if !b.join("summary.json").exists() {
        ok(&resume);
    }
    eprintln!("{kills} SIGKILLs and {terms} SIGTERM before the end");
    // On any machine the first kills land: the run has far more steps than they need.
    assert_eq!((kills, terms), (3, 1), "the run ended before every signal");
    let log = std::fs::read_to_string(b.join("run.log")).unwrap();
    assert!(log.contains("skip checkpoint"), "{log}");
    assert_eq!(log.matches("resume from").count(), 4, "{log}");
    assert_same_state::<2>(&a, &b);
}

#[test]
fn sigterm_finishes_the_step_checkpoints_and_resumes_bit_identically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let p = problem("sedov2d.toml");
    let sets = [
        "--set",
        "particles.n=64",
        "--set",
        "time.end=0.15",
        "--set",
        "output.interval=0.0075",
    ];
    let (a_s, b_s) = (s(&a), s(&b));
    ok(&[&["run", &p, "--quiet", "--out", &a_s][..], &sets[..]].concat());
    let child = Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args([&["run", &p, "--out", &b_s][..], &sets[..]].concat())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Once the first snapshot is out the run is stepping: a scheduler's SIGTERM.
    let t0 = Instant::now();
    while !b.join("snap_0001.hdf5").exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no snapshot written"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    if out.status.success() {
        // Finished before the signal landed: nothing to show on this machine.
        eprintln!("run finished before SIGTERM; the stop was not exercised");
        return;
    }
    // 128 + 15, after writing a checkpoint of the step it was in.
    assert_eq!(out.status.code(), Some(143), "{err}");
    assert!(err.contains("stopped by SIGTERM"), "{err}");
    assert!(!b.join("summary.json").exists());
    assert!(!checkpoint::list(&b).unwrap().is_empty());
    assert!(!b.join(".sphdisk.lock").exists(), "the lock is released");
    ok(&["run", "--quiet", "--resume", &b_s]);
    assert_same_state::<2>(&a, &b);
}

#[test]
fn a_run_from_its_own_first_snapshot_repeats_it() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let p = problem("sedov2d.toml");
    // n = 32: the lattice coordinates are dyadic, so the shift into the file's [0, L] frame
    // and back is exact and the repeat can be compared bit for bit.
    let common = [
        "--quiet",
        "--set",
        "particles.n=32",
        "--set",
        "output.interval=0.04",
    ];
    ok(&[&["run", &p, "--out", &s(&a)], &common[..]].concat());
    let first = s(&a.join("snap_0000.hdf5"));
    ok(&[&["run", &p, "--out", &s(&b), "--from", &first], &common[..]].concat());
    assert_eq!(
        std::fs::read(a.join("final.csv")).unwrap(),
        std::fs::read(b.join("final.csv")).unwrap()
    );
    let snap = read_snapshot(&b.join("final.hdf5")).unwrap();
    assert_eq!(snap.dimension, 2);
    assert_eq!(snap.len(), 32 * 32);
}

#[test]
fn bad_restart_input_fails_with_one_clear_line() {
    let dir = tempfile::tempdir().unwrap();
    let empty = s(dir.path());
    let (code, err) = sphdisk(&["run", "--resume", &empty]);
    assert_ne!(code, 0);
    assert!(err.contains("no checkpoint to resume from"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    // A 2D snapshot given to a 1D problem.
    let a = dir.path().join("a");
    ok(&[
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &s(&a),
        "--set",
        "particles.n=16",
        "--set",
        "time.end=0.001",
    ]);
    let (code, err) = sphdisk(&[
        "run",
        &problem("sod.toml"),
        "--quiet",
        "--out",
        &s(&dir.path().join("c")),
        "--from",
        &s(&a.join("final.hdf5")),
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("snapshot is 2D but the problem is 1D"),
        "{err}"
    );

    // A truncated snapshot.
    let bytes = std::fs::read(a.join("final.hdf5")).unwrap();
    let cut = dir.path().join("cut.hdf5");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let (code, err) = sphdisk(&[
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &s(&dir.path().join("d")),
        "--from",
        &s(&cut),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("cut.hdf5"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// The rows of a time series (`lightcurve.csv`, `monitor.csv`, `modes.csv`) of a run: header, rows.
fn series(run: &Path, name: &str) -> (String, Vec<String>) {
    let text = std::fs::read_to_string(run.join(name)).unwrap();
    let mut lines = text.lines().map(String::from);
    let header = lines.next().expect("a header");
    (header, lines.collect())
}

#[test]
fn resumed_l1_stream_is_bit_identical_with_the_same_time_series_and_budget() {
    // The gas disk problem made small: the stream (injected between steps, with ids and
    // the nozzle's random numbers from the checkpointed injector), pressure, ν and
    // artificial viscosity; an accretor radius of 0.2 a (beyond the stream's closest
    // approach) makes it strike the accretor from about step 110, and gas returns into
    // the donor's lobe from about step 85. Stopped at step 150 of about 270: particles
    // were inserted, accreted and returned before the stop and are after it.
    let sets = [
        "time.end=2.0",
        "stream.particles_per_orbit=600",
        "binary.accretor_radius=0.2",
        "output.interval=0",
        "output.lightcurve_interval=0.05",
    ];
    let k = 150;
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let p = problem("cv2d.toml");
    let args = |out: &Path, extra: &[&str]| -> Vec<String> {
        let mut v: Vec<String> = ["run", &p, "--quiet", "--out", &s(out)]
            .iter()
            .map(|x| x.to_string())
            .collect();
        for x in sets {
            v.extend(["--set".to_string(), x.to_string()]);
        }
        v.extend(extra.iter().map(|x| x.to_string()));
        v
    };
    ok(&strs(&args(&a, &[])));
    ok(&strs(&args(&b, &["--stop-after", &k.to_string()])));
    let (_, before) = series(&b, "lightcurve.csv");
    let (_, monitor_before) = series(&b, "monitor.csv");
    let (_, modes_before) = series(&b, "modes.csv");
    ok(&["run", "--quiet", "--resume", &s(&b)]);
    assert_same_state::<2>(&a, &b);
    let log = std::fs::read_to_string(b.join("run.log")).unwrap();
    assert!(log.contains(&format!("stopped after step {k}")), "{log}");
    assert!(log.contains("resume from"), "{log}");

    let summary = |run: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(run.join("summary.json")).unwrap()).unwrap()
    };
    let (sa, sb) = (summary(&a), summary(&b));
    let budget = &sa["mass_budget"];
    assert_eq!(budget, &sb["mass_budget"], "mass budget");
    for (flow, least) in [("injected", 100), ("accreted", 10), ("returned", 3)] {
        assert!(
            budget[flow]["particles"].as_u64().unwrap() >= least,
            "{flow}: {budget}"
        );
    }
    assert_eq!(sa["steps"], sb["steps"]);
    assert_eq!(sa["particles"], sb["particles"]);
    assert_eq!(sa["totals_end"], sb["totals_end"]);
    // The stop came after the first accretion and before the last insertion.
    let accreted_at_stop = |rows: &[String]| -> f64 {
        rows.last()
            .unwrap()
            .split(',')
            .nth(7)
            .unwrap()
            .parse()
            .unwrap()
    };
    assert!(
        accreted_at_stop(&monitor_before) > 0.0,
        "accretion before the stop"
    );
    for name in ["lightcurve.csv", "monitor.csv", "modes.csv"] {
        let (ha, ra) = series(&a, name);
        let (hb, rb) = series(&b, name);
        assert_eq!(ha, hb, "{name}: header");
        let times = |rows: &[String]| -> Vec<f64> {
            rows.iter()
                .map(|r| r.split(',').next().unwrap().parse().unwrap())
                .collect()
        };
        let tb = times(&rb);
        assert!(
            tb.windows(2).all(|w| w[0] < w[1]),
            "{name}: the resumed run's rows are in order without repeats"
        );
        assert_eq!(ra.len(), rb.len(), "{name}: no row missing or repeated");
        for (i, (x, y)) in ra.iter().zip(&rb).enumerate() {
            assert_eq!(x, y, "{name}: row {}", i + 1);
        }
        // Rows were written before the stop and after the resume.
        let stopped = match name {
            "lightcurve.csv" => &before,
            "monitor.csv" => &monitor_before,
            _ => &modes_before,
        };
        assert!(!stopped.is_empty() && stopped.len() < rb.len(), "{name}");
        assert_eq!(
            &rb[..stopped.len()],
            &stopped[..],
            "{name}: rows before the stop kept"
        );
    }
}

#[test]
fn a_run_from_a_snapshot_starts_at_its_time_with_its_h() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("a"),
        dir.path().join("b"),
        dir.path().join("c"),
    );
    let p = problem("sedov2d.toml");
    let small = ["--quiet", "--set", "particles.n=16"];
    // A snapshot at t = 0.1, h = 1.6 × spacing.
    ok(&[
        &["run", &p, "--out", &s(&a), "--set", "time.end=0.1"][..],
        &small[..],
    ]
    .concat());
    let file = s(&a.join("final.hdf5"));
    let from = read_snapshot(&a.join("final.hdf5")).unwrap();
    assert_eq!(from.time, 0.1);
    let file_h = from.h[0];

    // From it with another h_factor: the run starts at 0.1 with the file's h.
    ok(&[
        &["run", &p, "--out", &s(&b), "--from", &file][..],
        &["--set", "time.end=0.14", "--set", "particles.h_factor=1.3"][..],
        &small[..],
    ]
    .concat());
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(b.join("snapshots.json")).unwrap()).unwrap();
    let times: Vec<f64> = index["snapshots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["time"].as_f64().unwrap())
        .collect();
    // The start (0.1) and the interval's multiples after it (0.12); none before.
    assert_eq!(times.len(), 2, "{times:?}");
    assert_eq!(times[0], 0.1);
    assert!((times[1] - 0.12).abs() < 1e-12, "{times:?}");
    let first = read_snapshot(&b.join("snap_0000.hdf5")).unwrap();
    assert_eq!(first.time, 0.1);
    assert_eq!(first.h[0], file_h);
    let end = read_snapshot(&b.join("final.hdf5")).unwrap();
    assert!((end.time - 0.14).abs() < 1e-12, "{}", end.time);
    assert!(end.h.iter().all(|&h| h == file_h));
    let log = std::fs::read_to_string(b.join("run.log")).unwrap();
    assert!(log.contains("from the file's SmoothingLengths"), "{log}");
    assert!(log.contains("starts at the file's time t = 0.1"), "{log}");

    // particles.h given by the user wins over the file, and run.log says so.
    ok(&[
        &["run", &p, "--out", &s(&c), "--from", &file][..],
        &["--set", "time.end=0.11", "--set", "particles.h=0.11"][..],
        &small[..],
    ]
    .concat());
    assert!(
        read_snapshot(&c.join("final.hdf5"))
            .unwrap()
            .h
            .iter()
            .all(|&h| h == 0.11)
    );
    let log = std::fs::read_to_string(c.join("run.log")).unwrap();
    assert!(log.contains("h = 0.11 from particles.h"), "{log}");

    // An end time not after the file's time is refused, naming time.end.
    let (code, err) = sphdisk(&[
        "run",
        &p,
        "--quiet",
        "--out",
        &s(&dir.path().join("d")),
        "--from",
        &file,
        "--set",
        "particles.n=16",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("time.end") && err.contains("0.1"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}
