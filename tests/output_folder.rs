//! Output-folder ownership: a fresh run does not write into a folder holding another run's
//! files (it says how to go on, and loses nothing), `--force` replaces them and leaves
//! only the new run's files beside the user's own, and one run at a time holds a folder.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::problem_file as problem;
use common::{ok, path_str as s, sphdisk_err as sphdisk};

const LOCK: &str = ".sphdisk.lock";

/// Asserts a failure with one `error:` line holding every word of `expect`.
fn fails(args: &[&str], expect: &[&str]) {
    let (code, err) = sphdisk(args);
    assert_ne!(code, 0, "{args:?} should fail");
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: one line expected: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for e in expect {
        assert!(err.contains(e), "`{e}` not in: {err}");
    }
}

/// Every file under `dir` (relative name → bytes).
fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let name = s(p.strip_prefix(dir).unwrap());
                out.insert(name, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}

/// A finished 2D blast of 16² particles with checkpoints every 5 steps, into `out`.
fn old_run(out: &Path) {
    ok(&[
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &s(out),
        "--set",
        "particles.n=16",
        "--set",
        "time.end=0.02",
        "--set",
        "output.interval=0.01",
        "--set",
        "output.checkpoint_steps=5",
    ]);
}

/// A fresh 8² blast into `out`, stopped after 2 steps (before its first snapshot time after
/// t = 0: the 4 central particles hold the energy and keep the steps short), with `extra`
/// arguments.
fn new_run_args(out: &str, extra: &[&'static str]) -> Vec<String> {
    let mut v: Vec<String> = [
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        out,
        "--set",
        "particles.n=8",
        "--set",
        "output.checkpoint_steps=1",
        "--stop-after",
        "2",
    ]
    .iter()
    .map(|x| x.to_string())
    .collect();
    v.extend(extra.iter().map(|x| x.to_string()));
    v
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn a_fresh_run_into_a_used_folder_is_refused_and_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("blast");
    old_run(&out);
    let before = contents(&out);
    assert!(before.contains_key("summary.json"), "{:?}", before.keys());
    let o = s(&out);
    fails(
        &strs(&new_run_args(&o, &[])),
        &[&o, "another run's files", "--resume", "--out", "--force"],
    );
    assert_eq!(contents(&out), before, "the old run's files are untouched");
    // The old run still resumes as itself (nothing left to do: it ends at once).
    ok(&["run", "--quiet", "--resume", &o]);
}

#[test]
fn force_leaves_only_the_new_runs_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("blast");
    old_run(&out);
    std::fs::write(out.join("notes.txt"), "my notes").unwrap();
    let o = s(&out);
    let (code, err) = sphdisk(&strs(&new_run_args(&o, &["--force"])));
    assert_eq!(code, 0, "{err}");
    let after = contents(&out);
    let names: Vec<&str> = after.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "checkpoints/ckpt_0000000001.hdf5",
            "checkpoints/ckpt_0000000002.hdf5",
            "notes.txt",
            "run.id",
            "run.log",
            "run.toml",
            "snap_0000.hdf5",
            "snapshots.json",
            "statistics.csv",
        ]
    );
    assert_eq!(after["notes.txt"], b"my notes");
    let toml = String::from_utf8(after["run.toml"].clone()).unwrap();
    assert!(toml.contains("n = 8"), "{toml}");
    let log = String::from_utf8(after["run.log"].clone()).unwrap();
    assert!(!log.contains("end at"), "the old run's log is gone: {log}");
    // Resuming continues the new run: 8² particles, not the old 16².
    ok(&["run", "--quiet", "--resume", &o]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["particles"], 64, "{summary}");
    assert!(!out.join(LOCK).exists(), "the lock goes with the run");
}

/// A child process killed when this goes, also when an assertion fails first.
struct Child(std::process::Child);

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits until `path` exists (at most a minute).
fn wait_for(path: &Path) {
    let start = Instant::now();
    while !path.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "{path:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_second_run_into_a_held_folder_fails_naming_the_lock() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("blast");
    let o = s(&out);
    // A run that lasts: 64² particles to t = 10.
    let first = Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args([
            "run",
            &problem("sedov2d.toml"),
            "--quiet",
            "--out",
            &o,
            "--set",
            "particles.n=64",
            "--set",
            "time.end=10",
        ])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let first = Child(first);
    wait_for(&out.join(LOCK));
    let pid = first.0.id().to_string();
    fails(&strs(&new_run_args(&o, &["--force"])), &[&o, &pid, LOCK]);
    fails(&["run", "--quiet", "--resume", &o], &[&o, &pid, LOCK]);
    drop(first);
    // The killed run's lock is stale: a new run takes the folder over.
    assert!(out.join(LOCK).exists());
    let (code, err) = sphdisk(&strs(&new_run_args(&o, &["--force"])));
    assert_eq!(code, 0, "{err}");
    assert!(!out.join(LOCK).exists());
}

#[test]
fn a_run_that_fails_releases_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tube");
    let (code, err) = sphdisk(&[
        "run",
        &problem("sod.toml"),
        "--quiet",
        "--out",
        &s(&out),
        "--set",
        "time.max_steps=3",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("time.max_steps"), "{err}");
    assert!(out.join("run.toml").is_file());
    assert!(!out.join(LOCK).exists(), "lock left behind");
}

#[test]
fn temporaries_of_killed_writes_are_removed_when_a_run_starts() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("out");
    std::fs::create_dir_all(o.join("checkpoints")).unwrap();
    // A process that has ended left them.
    let mut child = std::process::Command::new("true").spawn().unwrap();
    let dead = child.id();
    child.wait().unwrap();
    let stale = [
        format!(".summary.json.tmp-{dead}"),
        format!("checkpoints/.ckpt_0000000004.hdf5.tmp-{dead}"),
    ];
    for f in &stale {
        std::fs::write(o.join(f), "half").unwrap();
    }
    let o_s = o.to_string_lossy().into_owned();
    // A fresh run: the folder holds no run's files once they are gone.
    ok(&[
        "run",
        &problem("sod.toml"),
        "--quiet",
        "--out",
        &o_s,
        "--set",
        "particles.n=40",
        "--set",
        "time.end=0.01",
    ]);
    for f in &stale {
        assert!(!o.join(f).exists(), "{f} left");
    }
    // And on resume.
    for f in &stale {
        std::fs::write(o.join(f), "half").unwrap();
    }
    ok(&["run", "--quiet", "--resume", &o_s, "--set", "time.end=0.02"]);
    for f in &stale {
        assert!(!o.join(f).exists(), "{f} left after resume");
    }
}
