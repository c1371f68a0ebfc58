//! A reader that quits (`sphdisk bench | head -1`, `sphdisk run … 2>&1 | head -1`): the
//! commands that only print end quietly, as `cat` does (killed by SIGPIPE, the status a
//! shell shows as 141), and a run finishes and writes its files, its report lost — never a
//! panic with a backtrace (status 101).

#![cfg(unix)]

use std::os::unix::process::ExitStatusExt;
use std::process::{Command, Stdio};

mod common;
use common::path_str as s;
use common::problem_file as problem;

/// `sphdisk args…` with the read end of `stream` ("stdout" or "stderr") closed as soon as
/// the process starts; the other stream discarded. Its exit status.
fn with_reader_gone(args: &[&str], stream: &str) -> std::process::ExitStatus {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_sphdisk"));
    cmd.args(args).stdin(Stdio::null());
    if stream == "stdout" {
        cmd.stdout(Stdio::piped()).stderr(Stdio::null());
    } else {
        cmd.stderr(Stdio::piped()).stdout(Stdio::null());
    }
    let mut child = cmd.spawn().unwrap();
    // The reader quits before the command has measured or run anything: every line it
    // prints after its set-up meets a pipe without a reader.
    drop(child.stdout.take());
    drop(child.stderr.take());
    child.wait().unwrap()
}

#[test]
fn a_bench_whose_reader_quits_ends_quietly() {
    let status = with_reader_gone(&["bench", "--n", "4000", "--steps", "1"], "stdout");
    // Before: `println!` panicked on the closed pipe (status 101).
    assert_eq!(status.signal(), Some(libc::SIGPIPE), "{status:?}");
}

#[test]
fn a_run_whose_reader_quits_finishes_and_writes_its_files() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("sod");
    let args = [
        "run",
        &problem("sod.toml"),
        "--out",
        &s(&out),
        "--set",
        "time.end=0.02",
    ];
    let status = with_reader_gone(&args, "stderr");
    // Before: the report on stderr panicked after the run (status 101).
    assert_eq!(status.code(), Some(0), "{status:?}");
    for f in ["summary.json", "final.csv", "final.hdf5", "run.log"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
}
