//! Guards `sphdisk analyse cv` as users call it: a short cataclysmic-variable run (the
//! problem file `cv2d.toml`, 1.5 orbits at a quarter of its stream rate) gives, per
//! snapshot, a row of `cv_evolution.csv`, and `cv.json` with a disk between half the
//! circularisation radius and the Roche lobe and a bright spot, and from `monitor.csv` where
//! the stream's gas went (`cv_accretion.csv`, `.png`), and how much of the stream passes
//! the disk's rim (`cv_passage.csv`); a folder that is not a run
//! fails with one line naming the file.

mod common;

/// Runs the problem file `problem` through the CLI with `sets` (each `KEY=VALUE`) into a
/// temporary folder, then `analyse cv` on it: the folder (kept alive), the run's path,
/// the analysis's output and its `cv.json`.
fn run_and_analyse(
    problem: &str,
    sets: &[&str],
) -> (
    tempfile::TempDir,
    std::path::PathBuf,
    String,
    serde_json::Value,
) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.to_string_lossy().into_owned();
    let problem = common::problem_file(problem);
    let mut args = vec!["run", problem.as_str(), "--out", &out_s, "--quiet"];
    for s in sets {
        args.extend(["--set", s]);
    }
    let (code, _, err) = common::sphdisk_cli(None, &args);
    assert_eq!(code, 0, "run: {err}");
    let (code, stdout, err) = common::sphdisk_cli(None, &["analyse", "cv", &out_s]);
    assert_eq!(code, 0, "analyse: {err}");
    let json =
        serde_json::from_str(&std::fs::read_to_string(out.join("cv.json")).unwrap()).unwrap();
    (dir, out, stdout, json)
}

#[test]
fn a_short_cv_run_gives_its_disk_and_bright_spot() {
    let (_dir, out, stdout, json) = run_and_analyse(
        "cv2d.toml",
        &[
            "stream.particles_per_orbit=500",
            "time.end=9.42",
            "output.interval=3.14",
        ],
    );
    assert!(
        stdout.contains("R90") && stdout.contains("cv.json"),
        "{stdout}"
    );
    let num = |k: &str| {
        json[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number in {json:#}"))
    };
    let (r90, r_circ, lobe) = (
        num("disk_radius_90"),
        num("r_circ"),
        num("roche_lobe_radius"),
    );
    assert!(
        r90 > 0.5 * r_circ && r90 < lobe,
        "R90 = {r90}: not between r_circ/2 = {} and the Roche lobe {lobe}",
        0.5 * r_circ
    );
    let spot = num("spot_azimuth_deg");
    assert!((0.0..360.0).contains(&spot), "{spot}");
    // 2D: no overflow figures.
    assert!(json.get("overflow_fraction").is_none(), "{json:#}");
    // The stream's passage through the rim, followed particle by particle
    // (reports::cv_passage): a share of the arrived mass; no over/under split in 2D; the
    // snapshots, half an orbit apart, are too coarse to trust it blindly, and a note says so.
    let p = &json["passage"];
    let f = p["passed_fraction"]
        .as_f64()
        .unwrap_or_else(|| panic!("no passage figures: {json:#}"));
    assert!((0.0..=1.0).contains(&f), "{p:#}");
    assert!(p["arrived_particles"].as_u64().unwrap() > 0, "{p:#}");
    assert!(p["over_under_fraction"].is_null(), "{p:#}");
    assert!(p["stream_to_rim_height"].is_null(), "{p:#}");
    assert!(
        json["passage_notes"]
            .as_array()
            .unwrap()
            .iter()
            .any(|n| n.as_str().unwrap().contains("orbit apart")),
        "{json:#}"
    );
    assert!(
        stdout.contains("the stream's passage through the rim"),
        "{stdout}"
    );
    assert!(out.join("cv_passage.csv").is_file());
    // A row per snapshot (t = 0, 1, 2 × 3.14 and the end state), each with its time.
    let csv = std::fs::read_to_string(out.join("cv_evolution.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert!(rows[0].starts_with("snapshot,t,orbit,"), "{}", rows[0]);
    assert_eq!(rows.len(), 1 + num("snapshots") as usize, "{csv}");
    assert!(rows.len() >= 4, "{csv}");
    // Where the stream's gas went, from monitor.csv: the shares of each window add up to
    // the mass injected in it (the ledger closes to round-off; 1e-5 for the CSV's six
    // digits).
    let a = &json["accretion"];
    let share = |k: &str| {
        a["last"][k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {a:#}"))
    };
    let sum = share("accreted") + share("returned") + share("escaped") + share("kept");
    assert!((sum - 1.0).abs() < 1e-9, "{a:#}");
    assert!(share("injected_per_orbit") > 0.0);
    let windows = std::fs::read_to_string(out.join("cv_accretion.csv")).unwrap();
    assert_eq!(windows.lines().count(), 1 + 4, "{windows}");
    for line in windows.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert!((v[3] + v[4] + v[5] + v[6] - 1.0).abs() < 1e-5, "{line}");
    }
    let png = std::fs::read(out.join("cv_accretion.png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    assert!(
        stdout.contains("accretion onto the white dwarf"),
        "{stdout}"
    );
}

#[test]
fn a_folder_without_a_run_is_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().to_string_lossy().into_owned();
    let (code, _, err) = common::sphdisk_cli(None, &["analyse", "cv", &path]);
    assert_eq!(code, 2);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("run.toml"), "{err}");
}

/// `problems/overflow3d.toml` for half an orbit with a snapshot every 0.05 orbit: the
/// stream's passage through the rim is measured with its over/under and through parts,
/// which add up to at most the passed fraction (the rest was found where the disk was too
/// thin in particles to give a height); the re-impact lies inside the passing radius and
/// outside the accretor; no note about coarse snapshots.
#[test]
fn a_short_overflow_run_gives_the_streams_passage_through_the_rim() {
    let (_dir, _, stdout, json) = run_and_analyse("overflow3d.toml", &["time.end=3.1416"]);
    let p = &json["passage"];
    let num = |k: &str| {
        p[k].as_f64()
            .unwrap_or_else(|| panic!("{k} is not a number in {json:#}"))
    };
    let (passed, over, through) = (
        num("passed_fraction"),
        num("over_under_fraction"),
        num("through_fraction"),
    );
    assert!(passed > 0.0 && passed <= 1.0, "{p:#}");
    assert!(over >= 0.0 && through >= 0.0, "{p:#}");
    assert!(over + through <= passed + 1e-12, "{p:#}");
    // The stream's height as it comes to the rim, against the rim's (3D only).
    let (stream, rim) = (num("stream_height"), num("rim_height"));
    assert!(stream > 0.0 && rim > 0.0, "{p:#}");
    assert!(
        (num("stream_to_rim_height") - stream / rim).abs() < 1e-12,
        "{p:#}"
    );
    assert!(stdout.contains("of its height"), "{stdout}");
    let (r, r90) = (num("reimpact_radius"), num("reimpact_radius_over_r90"));
    assert!(
        r > 0.1 && r90 < 0.75,
        "re-impact at {r} a = {r90} R90: {p:#}"
    );
    assert!(
        json["passage_notes"].as_array().unwrap().is_empty(),
        "{json:#}"
    );
    assert!(
        stdout.contains("passes the rim instead of stopping there"),
        "{stdout}"
    );
}
