//! Guards `sphdisk analyse lightcurve` as users call it: a run folder with a light curve (no
//! run.toml needed) gives the period with error bars, two pictures and a JSON; a disk that
//! grows is detrended unless `--no-detrend`; a file that is not a light curve fails with one
//! line naming it.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

use sphdisk::rng::Rng;

mod common;

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.len() > 1000 && b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

/// 40 orbits sampled at uneven steps (0.02–0.1 code times), l_total modulated at exactly
/// P_orb = 2π with a 5% semi-amplitude, plus white noise; an initial transient (a rising
/// disk) in the first 3 orbits that `--skip-orbits 3` leaves out.
fn synthetic_csv() -> String {
    light_curve_csv(42, 40.0 * TAU, |t, rng| {
        let rise = 1.0 - (-t / 3.0).exp();
        let disk = 2.0 * rise * (1.0 + 0.05 * (t + 1.0).cos()) + 0.05 * rng.normal();
        (disk, 0.1, 0.3 + 0.02 * rng.normal())
    })
}

/// `lightcurve.csv` text over `span` at uneven steps of 0.02–0.1, each row's (disk, stream,
/// spot) luminosities from `row(t, rng)`.
fn light_curve_csv(
    seed: u64,
    span: f64,
    mut row: impl FnMut(f64, &mut Rng) -> (f64, f64, f64),
) -> String {
    let mut rng = Rng::new(seed);
    let mut csv = String::from("t,orbit,l_total,l_disk,l_stream,l_spot,l_observed\n");
    let mut t = 0.0f64;
    while t < span {
        let (disk, stream, spot) = row(t, &mut rng);
        let total = disk + stream + spot;
        // What the observer sees: an orbital hump of 20% peaking at phase 0.8.
        let observed = 2.0 * (1.0 + 0.2 * (TAU * (t / TAU - 0.8)).cos());
        let _ = writeln!(
            csv,
            "{t:e},{:e},{total:e},{disk:e},{stream:e},{spot:e},{observed:e}",
            t / TAU
        );
        t += 0.02 + 0.08 * rng.uniform();
    }
    csv
}

#[test]
fn a_light_curve_gives_its_period_pictures_and_json() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lightcurve.csv"), synthetic_csv()).unwrap();
    let run = dir.path().to_string_lossy().into_owned();
    let (code, out, err) =
        common::sphdisk_cli(None, &["analyse", "lightcurve", &run, "--skip-orbits", "3"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("P_orb") && out.contains("mag peak to peak"),
        "{out}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("lightcurve.json")).unwrap())
            .unwrap();
    let num = |k: &str| json[k].as_f64().unwrap_or_else(|| panic!("{k} in {json}"));
    let (p, e) = (num("period"), num("period_err"));
    // Within 3 of its stated σ (the seed is fixed; 3σ fails 0.3% of seeds), and σ small
    // enough that the check means something: σ_f ≈ √6·0.05/(π·232·0.1·√4000) ≈ 2.7e-5,
    // σ_P = σ_f·(2π)² ≈ 1e-3, under 2e-4 of the period.
    assert!((p - TAU).abs() < 3.0 * e, "period {p} ± {e}");
    assert!(e > 0.0 && e < 1e-3 * TAU, "period_err {e}");
    assert!((num("period_orbits") - 1.0).abs() < 3.0 * num("period_orbits_err"));
    // Semi-amplitude 0.1 on a mean of 2.4: 4.2% (the stated σ is ~1% of that).
    assert!((num("amplitude_rel") - 0.1 / 2.4).abs() < 0.003, "{json}");
    assert!(
        num("orbit_start") >= 3.0 && num("orbit_start") < 3.1,
        "{json}"
    );
    assert!(json["binary"].is_null(), "no run.toml: {json}");
    // Detrended by default; the keys added beside the old ones.
    assert_eq!(json["detrended"], true, "{json}");
    assert_eq!(json["trend_degree"], 3, "{json}");
    assert!(num("amplitude_rel_err") > 0.0 && num("amplitude_rel_err") < 0.003);
    assert!((num("trend_start") - 2.4).abs() < 0.1 && (num("trend_end") - 2.4).abs() < 0.1);
    assert!(out.contains("trend: polynomial of degree 3"), "{out}");
    for png in ["lightcurve.png", "periodogram.png", "orbital.png"] {
        assert!(is_png(&dir.path().join(png)), "{png}");
    }
    // The observed column's orbital hump: period P_orb (a noiseless sinusoid: the error is
    // round-off), maximum at phase 0.8 to half a bin (bins of 0.02), height over the median
    // 2.5 log10(1.2) = 0.198 mag and the minimum at 0.3, 2.5 log10(1/0.8) = 0.242 mag under
    // it (the median of 1 + 0.2 cos over the bins is 1 to 1e-3: 0.002 mag).
    let o = &json["orbital"];
    let onum = |k: &str| o[k].as_f64().unwrap_or_else(|| panic!("{k} in {o}"));
    assert!((onum("period_orbits") - 1.0).abs() < 1e-4, "{o}");
    assert!((onum("hump_phase") - 0.8).abs() <= 0.011, "{o}");
    assert!((onum("minimum_phase") - 0.3).abs() <= 0.011, "{o}");
    assert!((onum("hump_mag") - 0.198).abs() < 0.004, "{o}");
    assert!((onum("minimum_depth_mag") - 0.242).abs() < 0.004, "{o}");
    assert!(o["inclination_deg"].is_null(), "no run.toml: {o}");
    assert!(
        out.contains("orbital hump at phase 0.79") || out.contains("orbital hump at phase 0.81"),
        "{out}"
    );
}

/// 10 orbits of a disk that doubles linearly, modulated at 1.05 P_orb with a 3% semi-amplitude
/// of its light, plus white noise; no transient.
fn growing_csv() -> String {
    let span = 10.0 * TAU;
    light_curve_csv(43, span, |t, rng| {
        let disk =
            1e-13 * (1.0 + t / span) * (1.0 + 0.03 * (t / 1.05).cos()) + 1e-15 * rng.normal();
        (disk, 0.0, 1e-14)
    })
}

#[test]
fn a_growing_disk_is_detrended_unless_told_not_to() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lightcurve.csv"), growing_csv()).unwrap();
    let run = dir.path().to_string_lossy().into_owned();
    let json = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("lightcurve.json")).unwrap())
            .unwrap()
    };
    let num =
        |j: &serde_json::Value, k: &str| j[k].as_f64().unwrap_or_else(|| panic!("{k} in {j}"));

    let (code, out, err) = common::sphdisk_cli(None, &["analyse", "lightcurve", &run]);
    assert_eq!(code, 0, "{err}");
    let j = json();
    let (p, e) = (num(&j, "period_orbits"), num(&j, "period_orbits_err"));
    // ~1000 rows over 10 orbits: σ_P ≈ 1e-3 P_orb; 3σ, seed fixed.
    assert!((p - 1.05).abs() < 3.0 * e && e < 5e-3, "{p} ± {e}\n{out}");
    // 3% of the disk; l_total carries a constant 1e-14 more (mean 1.6e-13): 2.8%.
    let rel = num(&j, "amplitude_rel");
    assert!((rel - 0.028).abs() < 0.1 * 0.028, "{rel}\n{out}");
    assert!(out.contains("% of the mean trend"), "{out}");
    for png in ["lightcurve.png", "periodogram.png"] {
        assert!(is_png(&dir.path().join(png)), "{png}");
    }

    let (code, out, err) =
        common::sphdisk_cli(None, &["analyse", "lightcurve", &run, "--no-detrend"]);
    assert_eq!(code, 0, "{err}");
    let j = json();
    assert_eq!(j["detrended"], false, "{j}");
    assert_eq!(j["trend_degree"], 0, "{j}");
    // The rise wins: the peak lies at the long end of the range, far from 1.05 P_orb.
    assert!(num(&j, "period_orbits") > 3.0, "{out}");
    assert!(out.contains("trend: none (--no-detrend)"), "{out}");
}

#[test]
fn a_wrong_header_fails_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("lightcurve.csv");
    std::fs::write(&csv, "t,l_total\n0,1\n1,2\n").unwrap();
    let (code, out, err) = common::sphdisk_cli(
        None,
        &["analyse", "lightcurve", &dir.path().to_string_lossy()],
    );
    assert_ne!(code, 0, "{out}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(&*csv.to_string_lossy()) && err.contains("header"),
        "{err}"
    );
    assert!(!dir.path().join("lightcurve.json").exists());

    // Skipping more than the curve holds: one short line saying how long the curve is
    // (before, 1e300 was written out in its 301 digits).
    let long = tempfile::tempdir().unwrap();
    std::fs::write(long.path().join("lightcurve.csv"), synthetic_csv()).unwrap();
    let run = long.path().to_string_lossy().into_owned();
    for (skip, shown) in [("50", "first 50 orbits"), ("1e300", "first 1e300 orbits")] {
        let (code, _, err) = common::sphdisk_cli(
            None,
            &["analyse", "lightcurve", &run, "--skip-orbits", skip],
        );
        assert_eq!(code, 2, "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(
            err.contains(shown) && err.contains("rows over 39.9"),
            "{err}"
        );
        assert!(err.len() < 300, "{err}");
    }

    // No light curve at all: also one line naming the file.
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = common::sphdisk_cli(
        None,
        &["analyse", "lightcurve", &empty.path().to_string_lossy()],
    );
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("lightcurve.csv"), "{err}");
}
