//! Guards `statistics.csv`, the global totals written during every run: its first and last
//! rows are `summary.json`'s start and end totals, bit for bit (the same sums of the same
//! particles), rows come every `output.statistics_steps` steps, and mass plus what was
//! accreted stays the start's mass in every row; and `summary.json`'s `timing`, the step
//! loop's wall time split between the sweep's stages and the rest.

use std::path::Path;

use sphdisk::io::timeseries::{STATISTICS_HEADER, parse_series};

mod common;
use common::problem_file as problem;
use common::{ok, path_str as s, sphdisk_err};

fn column(name: &str) -> usize {
    STATISTICS_HEADER
        .split(',')
        .position(|c| c == name)
        .unwrap()
}

fn rows(run: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(run.join("statistics.csv")).unwrap();
    parse_series(&text, STATISTICS_HEADER, false).unwrap()
}

/// A short run of the spreading ring (gravity, viscosity; 20 particles per ring, to
/// τ = 0.03) with `sets`, into `dir`/ring: its folder and `summary.json`.
fn ring_run(dir: &Path, sets: &[&str]) -> (std::path::PathBuf, serde_json::Value) {
    let out = dir.join("ring");
    let (file, o) = (problem("ring.toml"), s(&out));
    let mut args = vec![
        "run",
        &file,
        "--quiet",
        "--out",
        &o,
        "--set",
        "particles.n=20",
        "--set",
        "ring.tau_end=0.03",
    ];
    for set in sets {
        args.extend(["--set", set]);
    }
    ok(&args);
    let summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    (out, summary)
}

#[test]
fn statistics_rows_are_the_summary_totals_and_conserve_mass_with_accretion() {
    let dir = tempfile::tempdir().unwrap();
    let (out, summary) = ring_run(
        dir.path(),
        &[
            "output.statistics_steps=7",
            // Inside the ring's inner edge (0.6): particles are accreted from the start.
            "gravity.accretion_radius=0.65",
        ],
    );
    let rows = rows(&out);
    let (first, last) = (&rows[0], rows.last().unwrap());
    let steps = summary["steps"].as_u64().unwrap();
    assert!(steps > 7, "{steps} steps");
    // Step 0, every 7th step, and the last.
    let stepcol: Vec<u64> = rows.iter().map(|r| r[column("step")] as u64).collect();
    let mut expect: Vec<u64> = (0..=steps).step_by(7).collect();
    if !steps.is_multiple_of(7) {
        expect.push(steps);
    }
    assert_eq!(stepcol, expect);
    assert_eq!(last[column("t")], summary["t_end"].as_f64().unwrap());
    assert_eq!(
        last[column("particles")],
        summary["particles"].as_f64().unwrap()
    );
    for (row, key) in [(first, "totals_start"), (last, "totals_end")] {
        let t = &summary[key];
        for (col, field) in [
            ("mass", "mass"),
            ("kinetic_energy", "kinetic_energy"),
            ("internal_energy", "internal_energy"),
            ("potential_energy", "potential_energy"),
            ("total_energy", "energy"),
            ("angular_momentum", "angular_momentum"),
        ] {
            // Written with Rust's shortest round-trip formatting: exact.
            assert_eq!(
                row[column(col)],
                t[field].as_f64().unwrap(),
                "{key}.{field}"
            );
        }
        for (d, col) in ["px", "py"].iter().enumerate() {
            assert_eq!(
                row[column(col)],
                t["momentum"][d].as_f64().unwrap(),
                "{col}"
            );
        }
        assert_eq!(row[column("pz")], 0.0, "2D: no z momentum");
    }
    let accreted = summary["accretion"]["mass"].as_f64().unwrap();
    assert!(accreted > 0.0, "the ring accretes");
    assert_eq!(last[column("accreted_mass")], accreted);
    assert_eq!(first[column("accreted_mass")], 0.0);
    // Mass present plus mass accreted is the start's in every row; the two are sums of
    // ~1600 terms in different orders, so they agree to a few ulps (1e-14 relative).
    let m0 = first[column("mass")];
    for r in &rows {
        let m = r[column("mass")] + r[column("accreted_mass")];
        assert!((m - m0).abs() <= 1e-14 * m0, "t = {}: {m} vs {m0}", r[0]);
    }
}

#[test]
fn statistics_steps_zero_is_an_error_naming_the_key() {
    let (code, err) = sphdisk_err(&[
        "check",
        &problem("sod.toml"),
        "--set",
        "output.statistics_steps=0",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("output.statistics_steps"), "{err}");
}

/// `summary.json`'s `timing` splits the step loop's wall time: the sweep's stages add up to
/// its seconds, and those plus the rest make `wall_seconds` (to round-off); the run log
/// prints the same split.
#[test]
fn the_summary_splits_the_wall_time_between_the_sweep_and_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let (out, summary) = ring_run(dir.path(), &[]);
    let t = &summary["timing"];
    let stage = |k: &str| t["sweep"][k].as_f64().unwrap();
    let stages = [
        "build",
        "find_pairs",
        "density",
        "gradient",
        "force",
        "finish",
        "wait",
    ]
    .iter()
    .map(|k| stage(k))
    .sum::<f64>();
    let sweep = t["sweep_seconds"].as_f64().unwrap();
    let outside = t["outside_sweep_seconds"].as_f64().unwrap();
    let wall = summary["wall_seconds"].as_f64().unwrap();
    assert!(stage("find_pairs") > 0.0 && stage("force") > 0.0, "{t}");
    assert!((stages - sweep).abs() <= 1e-9 * sweep, "{stages} {sweep}");
    // The sweep runs inside the loop: it cannot take longer than the loop.
    assert!(sweep > 0.0 && sweep <= wall, "{sweep} {wall}");
    assert!(
        (sweep + outside - wall).abs() <= 1e-9 * wall,
        "{sweep} {outside} {wall}"
    );
    let share = t["outside_sweep_share"].as_f64().unwrap();
    assert!((share - outside / wall).abs() < 1e-12, "{share}");
    let log = std::fs::read_to_string(out.join("run.log")).unwrap();
    assert!(
        log.lines()
            .any(|l| l.contains("] sweep ") && l.contains("outside it")),
        "{log}"
    );
}
