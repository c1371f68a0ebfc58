//! Guards `sphdisk analyse superhump` on synthetic runs whose answers are known: an
//! eccentric Kepler ring whose eccentricity grows as a logistic and whose periastron
//! precesses at a set rate, measured by the run's own mode sums (`problems::cv`), beside a
//! light curve modulated at the beat of that precession with the orbit plus white noise.
//! The analysis must find the growth rate, the saturated eccentricity, the precession, the
//! superhump period and its excess; a q series gives its table and plot; a folder without
//! the series fails with one line naming the file.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use sphdisk::io::timeseries::{LIGHTCURVE_HEADER, MODES_HEADER};
use sphdisk::physics::binary::{Binary, BinaryParams};
use sphdisk::problems::cv::{DiskModes, kepler_ring, mode_sums};
use sphdisk::rng::Rng;

mod common;

const RATE: f64 = 0.035; // ω_p / Ω_orb
const GAMMA: f64 = 0.15; // growth rate per orbit
const E_SAT: f64 = 0.12;
const E0: f64 = 0.002;
const ORBITS: f64 = 80.0;

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.len() > 1000 && b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

/// A run folder with modes.csv, lightcurve.csv and run.toml for mass ratio `q`.
fn synthetic_run(dir: &Path, q: f64, seed: u64) {
    let b = Binary::new(&BinaryParams::with_q(q));
    let mut modes = format!("{MODES_HEADER}\n");
    let mut light = format!("{LIGHTCURVE_HEADER}\n");
    let mut rng = Rng::new(seed);
    let rows = (ORBITS * 50.0) as usize;
    for k in 0..rows {
        let t = k as f64 * TAU / 50.0;
        let orbit = t / TAU;
        let e = E_SAT / (1.0 + (E_SAT / E0 - 1.0) * (-GAMMA * orbit).exp());
        // The periastron is fixed but for the precession in the inertial frame; the frame
        // turns at Ω = 1.
        let varpi = 0.7 + RATE * t - t;
        let ring = kepler_ring::<2>(&b, 0.4, e, varpi, 300, 1e-6);
        let m = DiskModes::from_sums(&mode_sums(&b, &ring, 0.0, 1.0)).unwrap();
        let inertial = (m.periastron_deg + t.to_degrees()).rem_euclid(360.0);
        let _ = writeln!(
            modes,
            "{t:e},{orbit:e},0.45,{:e},{:e},{:e},{:e},{:e},{:e},{:e},{inertial:e}",
            m.mass, m.m1, m.m1_phase_deg, m.m2, m.m2_phase_deg, m.e, m.periastron_deg
        );
        // Superhumps once the disk is eccentric: 4% of the light at the beat period
        // P_orb/(1 − ω_p), on a rising trend, with 2% white noise.
        let beat = (1.0 - RATE) * t;
        let disk =
            (1.0 + 0.002 * orbit) * (1.0 + 0.04 * (e / E_SAT) * beat.cos()) + 0.02 * rng.normal();
        let _ = writeln!(
            light,
            "{t:e},{orbit:e},{:e},{disk:e},0e0,0.1e0,0e0",
            disk + 0.1
        );
    }
    std::fs::write(dir.join("modes.csv"), modes).unwrap();
    std::fs::write(dir.join("lightcurve.csv"), light).unwrap();
    std::fs::write(dir.join("run.toml"), format!("[binary]\nq = {q}\n")).unwrap();
    std::fs::write(dir.join("summary.json"), "{\"problem\": \"synthetic\"}\n").unwrap();
}

#[test]
fn a_precessing_eccentric_ring_gives_its_growth_precession_and_superhump() {
    let dir = tempfile::tempdir().unwrap();
    synthetic_run(dir.path(), 0.1, 7);
    let run = dir.path().to_string_lossy().into_owned();
    let (code, out, err) = common::sphdisk_cli(None, &["analyse", "superhump", &run]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("eccentric") && out.contains("P_sh"), "{out}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("superhump.json")).unwrap())
            .unwrap();
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("{v} in {json}"));
    let g = &json["growth"];
    assert_eq!(g["eccentric"], true, "{json}");
    // The ring's m = 1 amplitude is its e to 1e-9 (problems::cv tests); the peak is the
    // logistic's at the end, E_SAT (1 − 1e-3); the median over the active stretch (from
    // 0.8 of the peak on) includes the end of the rise, within 2%.
    assert!((num(&g["e_peak"]) / E_SAT - 1.0).abs() < 0.005, "{g}");
    assert!((num(&g["e_saturated"]) / E_SAT - 1.0).abs() < 0.02, "{g}");
    assert_eq!(g["faded"], false);
    // The logistic's rate, bent by the one-orbit running mean by about 1%.
    assert!(
        (num(&g["growth_rate_per_orbit"]) / GAMMA - 1.0).abs() < 0.02,
        "{g}"
    );
    let onset = (E_SAT / E0 - 1.0f64).ln() / GAMMA;
    assert!((num(&g["onset_orbit"]) - onset).abs() < 0.5, "{g}");
    // The precession of a noise-free ring: exact to round-off in the fit.
    let p = &json["precession"];
    assert!((num(&p["rate"]) - RATE).abs() < 1e-6, "{p}");
    assert!((num(&p["rate_osculating"]) - RATE).abs() < 1e-6, "{p}");
    // The light curve's period against the beat: 4% modulation and 2% noise over ~50
    // cycles give σ_P ≈ 1e-3 P_orb; the issue asks for agreement to 1%.
    let beat = 1.0 / (1.0 - RATE);
    let ps = num(&json["superhump_period_orbits"]);
    let eps_err = num(&json["epsilon_err"]);
    assert!(
        (ps - beat).abs() < 3.0 * eps_err && eps_err < 3e-3,
        "P_sh {ps} ± {eps_err}, beat {beat}"
    );
    assert!(num(&json["beat_mismatch"]).abs() < 0.01, "{json}");
    // A ring on one ellipse: the m = 1 phase follows the periastron, and is the source.
    assert_eq!(json["precession"]["source"], "m1_phase", "{json}");
    assert!((num(&json["epsilon"]) - (beat - 1.0)).abs() < 3.0 * eps_err);
    // The hump is the beat's cosine, locked to the apsidal line: no drift within three of
    // its errors (each 4-orbit window's phase carries ~3° from the noise), and the beat
    // with the drift gives the light curve's ε.
    let h = &json["hump_phase"];
    let (drift, drift_err) = (num(&h["drift_deg_per_orbit"]), num(&h["drift_err"]));
    assert!(drift.abs() < 3.0 * drift_err && drift_err < 0.5, "{h}");
    assert!(
        (num(&h["epsilon_locked"]) - (beat - 1.0)).abs() < 3.0 * num(&h["epsilon_locked_err"]),
        "{h}"
    );
    // The predictions for q = 0.1 (analysis::roche: Patterson 0.18 q + 0.29 q²).
    assert!((num(&json["predictions"]["epsilon_patterson2005"]) - 0.0209).abs() < 1e-12);
    for png in [
        "superhump_eccentricity.png",
        "superhump_precession.png",
        "superhump_lightcurve.png",
        "superhump_periodogram.png",
    ] {
        assert!(is_png(&dir.path().join(png)), "{png}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["problem"], "synthetic");
    assert_eq!(summary["superhump"]["growth"], json["growth"]);
}

#[test]
fn a_q_series_gives_its_table_and_plot() {
    let (a, b, out) = (
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
        tempfile::tempdir().unwrap(),
    );
    synthetic_run(a.path(), 0.2, 1);
    synthetic_run(b.path(), 0.1, 2);
    let args = [
        "analyse",
        "superhump",
        &a.path().to_string_lossy(),
        &b.path().to_string_lossy(),
        "--out",
        &out.path().to_string_lossy(),
    ]
    .map(|s| s.to_string());
    let args: Vec<&str> = args.iter().map(|s| s.as_str()).collect();
    let (code, _, err) = common::sphdisk_cli(None, &args);
    assert_eq!(code, 0, "{err}");
    let table = std::fs::read_to_string(out.path().join("superhump_scan.csv")).unwrap();
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 3, "{table}");
    // Sorted by q.
    assert!(lines[1].starts_with("0.1,true,") && lines[2].starts_with("0.2,true,"));
    let columns = |l: &str| l.split(',').count();
    assert!(
        lines.iter().all(|l| columns(l) == columns(lines[0])),
        "{table}"
    );
    let source = lines[0]
        .split(',')
        .position(|c| c == "precession_source")
        .unwrap();
    assert_eq!(lines[1].split(',').nth(source), Some("m1_phase"), "{table}");
    assert!(is_png(&out.path().join("superhump_scan.png")));
}

#[test]
fn a_folder_without_modes_fails_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().to_string_lossy().into_owned();
    let (code, _, err) = common::sphdisk_cli(None, &["analyse", "superhump", &run]);
    assert_eq!(code, 2);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("modes.csv"), "{err}");
}
