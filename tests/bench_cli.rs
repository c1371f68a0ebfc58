//! `sphdisk bench --csv`: one row per thread count, the speed-up and parallel efficiency
//! against the one-thread row, and the time per step split into the sweep's stages and
//! the rest. (The figures themselves are timings and belong in BENCHMARKS.md; this checks
//! that the report is consistent with itself.)

mod common;
use common::sphdisk_cli;

/// A small benchmark on 1 and 2 threads, two steps, with `extra` arguments.
fn scaling_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "bench",
        "--n",
        "4000",
        "--steps",
        "2",
        "--with-threads",
        "1",
        "--with-threads",
        "2",
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn bench_writes_a_consistent_csv_of_thread_scaling() {
    let d = tempfile::tempdir().unwrap();
    let csv = d.path().join("scaling.csv");
    let (code, out, err) = sphdisk_cli(
        Some(d.path()),
        &scaling_args(&["--csv", csv.to_str().unwrap()]),
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("parallel efficiency"), "{out}");
    assert!(out.contains("bytes moved per pair"), "{out}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = |row: &str, name: &str| -> String {
        let k = header.iter().position(|h| *h == name).unwrap();
        row.split(',').nth(k).unwrap().to_string()
    };
    for row in &lines[1..] {
        assert_eq!(row.split(',').count(), header.len(), "{row}");
        let f = |name: &str| col(row, name).parse::<f64>().unwrap();
        // The stages and the rest add up to the step (the rest is what is left over).
        let parts: f64 = [
            "build",
            "find_pairs",
            "density",
            "gradient",
            "force",
            "finish",
            "outside_sweep",
        ]
        .iter()
        .map(|n| f(n))
        .sum();
        let step = f("seconds_per_step");
        assert!((parts - step).abs() <= 1e-5 * step, "{parts} vs {step}");
        // Run one after another, every step is timed.
        assert_eq!(col(row, "untimed_steps"), "0");
        assert!(f("pairs_per_second_per_core") * f("threads") <= f("pairs_per_second") * 1.000001);
        // Bytes moved per pair (sphdisk::sweep::cost): the three sums' fixed 520 B (72 + 232
        // + 216: the record, the second partner's fields and accumulator), and pair
        // finding's 60 B per pair (the partner list's index and r² read back, r written and
        // read, the record stored) plus 53 B per candidate tested (x and class read, r²
        // written and read back between the two loops, index and r² listed) and 64 B per
        // stencil-cell box tested.
        let bytes = 580.0 + 53.0 * f("candidates_per_pair") + 64.0 * f("cells_per_pair");
        assert!((f("bytes_per_pair") - bytes).abs() < 0.01, "{row}");
        assert!(
            f("flops_per_pair") > 0.0
                && f("candidates_per_pair") > 1.0
                && f("cells_per_pair") > 0.0,
            "{row}"
        );
    }
    assert_eq!(col(lines[1], "threads"), "1");
    assert_eq!(
        col(lines[1], "speedup"),
        "",
        "no speed-up of one thread over itself"
    );
    let s: f64 = col(lines[2], "speedup").parse().unwrap();
    let e: f64 = col(lines[2], "parallel_efficiency").parse().unwrap();
    let t1: f64 = col(lines[1], "seconds_per_step").parse().unwrap();
    let t2: f64 = col(lines[2], "seconds_per_step").parse().unwrap();
    // Six significant digits in the file.
    assert!((s - t1 / t2).abs() <= 1e-5 * s, "{s} vs {}", t1 / t2);
    assert!((e - s / 2.0).abs() <= 1e-5, "{e} vs {s}/2");

    // An unwritable path is refused before anything is measured, naming --csv.
    let (code, _, err) = sphdisk_cli(
        Some(d.path()),
        &["bench", "--n", "4000", "--csv", "/nonexistent/dir/x.csv"],
    );
    assert_ne!(code, 0);
    assert!(err.contains("--csv") && err.lines().count() <= 2, "{err}");
}

/// `--alternate`: the thread counts step in turn, a particle set each — one row per thread
/// count as without it, each over the same particles and steps (the same pairs, to the
/// last bits of the positions), the speed-up the ratio of their own step times.
#[test]
fn bench_alternate_steps_the_thread_counts_in_turn() {
    let (code, out, err) = sphdisk_cli(None, &scaling_args(&["--alternate", "--json"]));
    assert_eq!(code, 0, "{err}");
    let rows: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(rows.len(), 2, "{out}");
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap();
    assert_eq!(f(&rows[0], "threads"), 1.0);
    assert_eq!(f(&rows[1], "threads"), 2.0);
    for r in &rows {
        assert_eq!(f(r, "steps"), 2.0);
        // Each turn an untimed step first, on the run's own particles, so that the timed
        // one does not start with caches the other set filled.
        assert_eq!(f(r, "untimed_steps"), 2.0);
        assert_eq!(f(r, "particles"), f(&rows[0], "particles"));
    }
    // The two sets start alike and differ after two steps only in the last bits of the
    // sums' order on two threads: a pair at the support's edge at most.
    let (n1, n2) = (
        f(&rows[0], "mean_neighbours"),
        f(&rows[1], "mean_neighbours"),
    );
    assert!(
        (n1 - n2).abs() <= 2.0 / f(&rows[0], "particles"),
        "{n1} vs {n2}"
    );
    let s = f(&rows[1], "speedup");
    let want = f(&rows[0], "seconds_per_step") / f(&rows[1], "seconds_per_step");
    assert!((s - want).abs() <= 1e-12 * want, "{s} vs {want}");
    assert!(rows[0]["speedup"].is_null());

    // No steps to time, or an absurd thread count: refused before anything is measured,
    // naming the option.
    let (code, _, err) = sphdisk_cli(None, &["bench", "--n", "4000", "--steps", "0"]);
    assert_ne!(code, 0);
    assert!(err.contains("--steps") && err.lines().count() <= 2, "{err}");
    let (code, _, err) = sphdisk_cli(None, &["bench", "--n", "4000", "--with-threads", "100000"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("--with-threads") && err.contains("100000") && err.lines().count() <= 2,
        "{err}"
    );
}

/// A size or neighbour count the benchmark cannot measure is refused in one line naming the
/// option, before anything is allocated or printed: no particles; more than a run holds, or
/// than this machine's memory; not a number of at least one neighbour; a support reaching
/// beyond half the periodic box (π/6 of the particles: 524 of 1 000); pairs beyond memory.
/// Before, `--n 0` measured 8 particles, `--neighbours 0` spent seconds finding no pairs,
/// `nan` and `inf` ran, `1e9` counted every particle's 27 images, and a lattice too large
/// was refused naming the problem files' key `particles.n`.
#[test]
fn absurd_sizes_and_neighbour_counts_are_refused_naming_the_option() {
    let cases: [(&[&str], &str); 10] = [
        (&["--n", "0"], "--n"),
        (&["--n", "5000000000"], "--n"),
        (&["--n", "3000000000"], "--n"),
        (&["--neighbours", "0"], "--neighbours"),
        (&["--neighbours=-5"], "--neighbours"),
        (&["--neighbours", "nan"], "--neighbours"),
        (&["--neighbours", "inf"], "--neighbours"),
        (&["--n", "1000", "--neighbours", "1e9"], "--neighbours"),
        (&["--n", "1000", "--neighbours", "525"], "--neighbours"),
        (
            &["--n", "1000000", "--neighbours", "500000"],
            "--neighbours",
        ),
    ];
    for (args, option) in cases {
        let mut all = vec!["bench"];
        all.extend_from_slice(args);
        // Memory measured against a fixed limit, whatever this machine has free.
        let (code, out, err) = sphdisk_cli_with_memory(&all, "16G");
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(out.is_empty(), "{args:?} printed before refusing: {out}");
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
        assert!(
            lines[0].starts_with(&format!("error: {option}")),
            "{args:?}: {err}"
        );
        assert!(!err.contains("particles.n"), "{args:?}: {err}");
    }
    // The largest support that stays within half the box is measured.
    let (code, out, err) = sphdisk_cli_with_memory(
        &[
            "bench",
            "--n",
            "1000",
            "--neighbours",
            "500",
            "--steps",
            "1",
            "--with-threads",
            "1",
            "--json",
        ],
        "16G",
    );
    assert_eq!(code, 0, "{err}");
    let row: serde_json::Value = serde_json::from_str(out.lines().next().unwrap()).unwrap();
    assert_eq!(row["particles"].as_f64(), Some(1000.0));
}

/// `sphdisk args…` with `SPHDISK_MEMORY_LIMIT` set: (status, stdout, stderr).
fn sphdisk_cli_with_memory(args: &[&str], limit: &str) -> (i32, String, String) {
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(args)
        .env("SPHDISK_MEMORY_LIMIT", limit)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}
