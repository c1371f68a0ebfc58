//! `sphdisk analyse cv <run>`: the disk, the bright spot and the stream's overflow of a
//! cataclysmic-variable run (paper, Section 4; exact-solutions.md 4 and 4b), snapshot by
//! snapshot.
//!
//! Frame and units as the run's (`physics::binary`): the accretor at the origin, the donor at
//! (−1, 0, 0), a = 1, G(M1 + M2) = 1, P_orb = 2π, the frame turning counter-clockwise;
//! velocities in the snapshots are corotating ones. Azimuths are in degrees in [0, 360),
//! measured counter-clockwise from +x in that frame: 0° points from the accretor away from
//! the donor, 180° towards it (L1); the Coriolis force bends the stream from L1 towards −y,
//! so it meets the disk between 180° and 270° (about 220° at q = 0.1). Radii R are
//! cylindrical, in the orbital plane.
//!
//! For every snapshot listed in `snapshots.json` (and `final.hdf5` when it is later than the
//! last of them), [`snapshot_figures`] measures ([`CvFigures`]):
//!
//! - the disk: gas on near-circular orbits about the accretor (osculating eccentricity
//!   below `physics::binary::STREAM_ECCENTRICITY`, as `problems::cv::is_disk`); its mass, the
//!   radii holding 50%, 90% and 99% of it (R50, R90, and R99 for its outer edge) and R90
//!   over r_circ (Hessman & Hopp's fit), the tidal radius 0.60/(1+q) and the 3:1 resonance
//!   radius; its eccentricity twice, as the
//!   m = 1 Fourier amplitude of its mass ([`fourier_mode`], window [0.5, 1.0] R90, see
//!   [`ECCENTRICITY_WINDOW`]) and as the mass-weighted mean osculating eccentricity vector in
//!   the same window ([`mean_eccentricity`]) with its longitude of periastron (in the
//!   turning frame, and in the inertial frame, ϖ + Ω t, where a precessing disk moves
//!   slowly); the m = 2 amplitude (the tidal distortion);
//! - the bright spot: the centroid weighted by m ε̇ (ε̇ the specific dissipation rate) of the
//!   stream gas within R90 + 2h (`Region::Spot` of `Binary::region`) ([`spot_centroid`]);
//!   the 10° sector of the annulus [0.8, 1.2] R90 that dissipates most, all gas counted
//!   ([`sector_peak`]); and the azimuth the ballistic stream from L1 has at R = R90
//!   ([`ballistic_stream`], [`predicted_impact_azimuth`]);
//! - 3D runs only, the overflow ([`overflow_figures`]): the disk's height H at its rim (the
//!   mass-weighted rms z of disk gas with R in [0.9, 1.1] R90), the fraction of the stream
//!   mass in that rim annulus that lies above +H or below −H, and where gas that passes over
//!   or under the rim comes closest to the accretor (the re-impact region of the paper's
//!   Figure 5). This is where stream gas *lies* in one snapshot; how much of the stream
//!   *passes* the rim instead of stopping there — the paper's 10–20% — is a flux, measured
//!   by following the particles' ids through the snapshots (`reports::cv_passage`, in 2D
//!   too: there it is gas going through the rim).
//!
//! What cannot be measured (no disk yet, no stream gas near it) is `None`: null in
//! `cv.json`, an empty cell in `cv_evolution.csv`, with a line in `notes` saying why.
//!
//! Writes into the run folder `cv_evolution.csv` (a row per snapshot, columns as
//! [`CvFigures::columns`]; `days` only if `run.toml` gives `binary.period_days`, the
//! overflow columns only in 3D) and `cv.json` (the run's reference radii and the last
//! snapshot's figures, [`CvJson`], with the passage figures under `passage`),
//! `cv_passage.csv` (the passing fraction per orbit of arrival); and from `monitor.csv`,
//! where the stream's gas went over time and whether the disk has become steady
//! (`reports::cv_accretion`):
//! `cv_accretion.csv`, `cv_accretion.png` and the key `accretion` of `cv.json`.

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::analysis::{roche, weighted_quantile};
use crate::config::ProblemKind;
use crate::io::atomic::write_atomic;
use crate::io::hdf5::read_snapshot_with_h;
use crate::io::snapshot::Snapshot;
use crate::io::snapshot_index::snapshots_with_final;
use crate::physics::binary::{Binary, Region};
use crate::problems::cv::ECCENTRICITY_WINDOW;
use crate::render::plot::plot_panels;
use crate::reports::cv_accretion::{self, AccretionFigures};
use crate::reports::cv_passage::{self, PassageFigures, PassageTracker};
use crate::reports::run_config;

/// The annulus, in units of R90, whose 10° sectors are searched for the brightest one.
pub const SPOT_ANNULUS: (f64, f64) = (0.8, 1.2);

/// Width of the sectors of [`SPOT_ANNULUS`], degrees.
pub const SECTOR_DEG: f64 = 10.0;

/// The disk's rim, in units of R90: where the stream's height is compared with the disk's.
pub const RIM: (f64, f64) = (0.9, 1.1);

/// Fewest disk particles in the rim annulus from which its height H is taken.
pub const MIN_RIM_PARTICLES: usize = 5;

/// Fewer disk particles than this in [`ECCENTRICITY_WINDOW`] get a note: their m = 1
/// amplitude is mostly sampling noise (≈ 0.9/√N ≥ 0.2).
pub const MIN_WINDOW_PARTICLES: usize = 20;

/// Time step of the ballistic test stream (code units; P_orb = 2π).
pub const BALLISTIC_DT: f64 = 1e-4;

/// How far from L1 the ballistic test stream starts, along the saddle's unstable direction.
pub const BALLISTIC_OFFSET: f64 = 1e-6;

/// The figures of one snapshot. Lengths in units of a, angles in degrees (module doc).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CvFigures {
    /// The snapshot's file name in the run folder.
    pub snapshot: String,
    /// Code time, and in orbits (t/2π).
    pub t: f64,
    pub orbit: f64,
    /// Time in days (`binary.period_days`).
    pub days: Option<f64>,
    /// Gas particles and their mass.
    pub particles: usize,
    pub gas_mass: f64,
    /// Disk gas (near-circular orbits).
    pub disk_particles: usize,
    pub disk_mass: f64,
    pub disk_mass_fraction: Option<f64>,
    pub disk_radius_50: Option<f64>,
    pub disk_radius_90: Option<f64>,
    /// The radius holding 99% of the disk's mass: its outer edge, for the comparison with
    /// the tidal truncation radius.
    pub disk_radius_99: Option<f64>,
    pub disk_r90_over_r_circ: Option<f64>,
    pub disk_r90_over_tidal: Option<f64>,
    pub disk_r90_over_r31: Option<f64>,
    /// Disk particles in [`ECCENTRICITY_WINDOW`].
    pub disk_window_particles: usize,
    /// |Σ m e^{iφ}| / Σ m over the window, and its phase (the apoastron side).
    pub disk_m1_amplitude: Option<f64>,
    pub disk_m1_phase_deg: Option<f64>,
    /// |Σ m e^{2iφ}| / Σ m over the window.
    pub disk_m2_amplitude: Option<f64>,
    /// |mass-weighted mean osculating eccentricity vector| over the window, its longitude of
    /// periastron in the turning frame and in the inertial frame (ϖ + Ω t).
    pub disk_eccentricity: Option<f64>,
    pub disk_periastron_deg: Option<f64>,
    pub disk_periastron_inertial_deg: Option<f64>,
    /// Stream gas within R90 + 2h (`Region::Spot`), its Σ m ε̇, and the azimuth and the
    /// distance from the accretor of its m ε̇-weighted centroid.
    pub spot_particles: usize,
    pub spot_luminosity: Option<f64>,
    pub spot_azimuth_deg: Option<f64>,
    pub spot_radius: Option<f64>,
    /// The brightest 10° sector of [`SPOT_ANNULUS`] (centre, refined by a parabola through
    /// it and its neighbours) and its Σ m ε̇ over the mean sector's.
    pub spot_sector_azimuth_deg: Option<f64>,
    pub spot_sector_contrast: Option<f64>,
    /// Where the ballistic stream from L1 crosses R = R90.
    pub spot_predicted_azimuth_deg: Option<f64>,
    /// 3D only (absent in 2D).
    #[serde(flatten)]
    pub overflow: Option<OverflowFigures>,
    /// Why figures are missing, one line each.
    pub notes: Vec<String>,
}

/// The stream's overflow over and under the disk's rim (3D runs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OverflowFigures {
    /// Mass-weighted rms z of disk gas with R in [`RIM`] × R90.
    pub disk_rim_height: Option<f64>,
    /// H/R at R90.
    pub disk_rim_aspect: Option<f64>,
    /// Stream (non-disk) mass with R in the rim annulus.
    pub overflow_rim_stream_mass: Option<f64>,
    /// Fraction of that mass with |z| > H, with z > H, with z < −H.
    pub overflow_fraction: Option<f64>,
    pub overflow_fraction_above: Option<f64>,
    pub overflow_fraction_below: Option<f64>,
    /// Non-disk gas with |z| > H at R ≤ 1.1 R90 (over or under the disk, or at its rim).
    pub overflow_mass: Option<f64>,
    /// Mass-weighted medians of that gas's osculating periastron distance and azimuth.
    pub overflow_reimpact_radius: Option<f64>,
    pub overflow_reimpact_azimuth_deg: Option<f64>,
}

/// What `cv.json` holds: the run's reference radii and the last snapshot's figures.
#[derive(Clone, Debug, Serialize)]
pub struct CvJson {
    pub run: String,
    pub dimension: usize,
    pub q: f64,
    pub period_days: Option<f64>,
    /// Snapshots analysed (rows of `cv_evolution.csv`).
    pub snapshots: usize,
    pub l1_distance: f64,
    /// Volume-equivalent radius of the accretor's Roche lobe (Eggleton 1983).
    pub roche_lobe_radius: f64,
    /// Hessman & Hopp's fits, and the ballistic stream's own closest approach.
    pub r_circ: f64,
    pub r_min: f64,
    pub r_min_ballistic: f64,
    /// The azimuth of the ballistic stream's closest approach (where overflowing gas would
    /// come down if it kept to the stream's path).
    pub r_min_ballistic_azimuth_deg: f64,
    pub tidal_radius: f64,
    pub r_31: f64,
    /// Where the stream's gas went, window by window, from `monitor.csv`
    /// (`reports::cv_accretion`); `None` without that file or a stream.
    pub accretion: Option<AccretionFigures>,
    /// The stream's passage through the rim, particle by particle (`reports::cv_passage`);
    /// None when no stream gas reached the rim early enough to be counted.
    pub passage: Option<PassageFigures>,
    /// Why the passage figures are missing or how far to trust them.
    pub passage_notes: Vec<String>,
    #[serde(flatten)]
    pub last: CvFigures,
}

/// What `analyse cv` measured and wrote.
pub struct CvReport {
    pub json: CvJson,
    pub rows: Vec<CvFigures>,
    pub files: Vec<PathBuf>,
}

/// Reads `run.toml` and the snapshots of a cv run, writes `cv_evolution.csv` and `cv.json`.
pub fn analyse_cv(run: &Path) -> Result<CvReport> {
    let cfg = run_config(run, ProblemKind::Cv, "a cataclysmic-variable run")?;
    let Some(params) = cfg.binary else {
        bail!(
            "{}: run.toml has no `[binary]` table",
            run.join("run.toml").display()
        );
    };
    let b = Binary::new(&params);
    let period_days = params.period_days;
    let dimension = cfg.problem.dimension;
    let files = snapshots_with_final(run)?;
    if files.is_empty() {
        bail!(
            "{}: lists no snapshots (set `output.interval` to write some)",
            run.join("snapshots.json").display()
        );
    }
    let mut rows = Vec::with_capacity(files.len());
    let mut samples = Vec::with_capacity(files.len());
    let mut passage = PassageTracker::new();
    for (name, _) in &files {
        let path = run.join(name);
        let snap = read_snapshot_with_h(&path)?.in_run_frame();
        if snap.dimension != dimension {
            bail!(
                "{}: the snapshot is {}D but run.toml's problem is {dimension}D",
                path.display(),
                snap.dimension
            );
        }
        let disk = disk_mask(&b, &snap);
        let mut f = snapshot_figures_of_disk(&b, &snap, period_days, &disk);
        f.snapshot.clone_from(name);
        passage.feed(&snap, &disk, f.disk_radius_90);
        samples.push(cv_accretion::DiskSample {
            orbit: f.orbit,
            radius_mass: (0..snap.len())
                .filter(|&i| disk[i])
                .map(|i| (cylindrical_radius(&snap, i), snap.mass[i]))
                .collect(),
        });
        rows.push(f);
    }
    let csv = evolution_csv(&rows, period_days.is_some(), dimension == 3);
    let csv_path = run.join("cv_evolution.csv");
    write_atomic(&csv_path, csv.as_bytes())?;
    let q = b.q;
    let mut files = vec![csv_path];
    let monitor = run.join("monitor.csv");
    let accretion = if monitor.is_file() {
        let text = std::fs::read_to_string(&monitor)
            .with_context(|| format!("cannot read {}", monitor.display()))?;
        let ledger =
            cv_accretion::parse_ledger(&text).with_context(|| monitor.display().to_string())?;
        cv_accretion::accretion_figures(&ledger, q).map(|mut a| {
            a.viscosity = steady_viscosity(&b, &cfg.eos, &ledger, &mut samples);
            a
        })
    } else {
        None
    };
    if let Some(a) = &accretion {
        let path = run.join("cv_accretion.csv");
        write_atomic(&path, cv_accretion::windows_csv(&a.windows).as_bytes())?;
        files.push(path);
        let png = run.join("cv_accretion.png");
        plot_panels(&png, (1000, 900), &cv_accretion::panels(a))?;
        files.push(png);
    }
    let mut passage_notes = Vec::new();
    let passage = passage.finish(&mut passage_notes);
    if let Some(p) = &passage {
        let path = run.join("cv_passage.csv");
        write_atomic(&path, cv_passage::windows_csv(&p.windows).as_bytes())?;
        files.push(path);
    }
    let r_min_point = *ballistic_stream(q, 0.0).last().expect("starts at L1");
    let json = CvJson {
        run: run.display().to_string(),
        dimension,
        q,
        period_days,
        snapshots: rows.len(),
        l1_distance: roche::l1_distance(q),
        roche_lobe_radius: roche::eggleton_radius(1.0 / q),
        r_circ: roche::r_circ_fit(q),
        r_min: roche::r_min_fit(q),
        r_min_ballistic: r_min_point[0].hypot(r_min_point[1]),
        r_min_ballistic_azimuth_deg: azimuth_deg(r_min_point[0], r_min_point[1]),
        tidal_radius: roche::tidal_radius(q),
        r_31: roche::r_31(q),
        accretion,
        passage,
        passage_notes,
        last: rows.last().cloned().expect("at least one snapshot"),
    };
    let json_path = run.join("cv.json");
    let text = serde_json::to_string_pretty(&json).context("cv.json")?;
    write_atomic(&json_path, format!("{text}\n").as_bytes())?;
    files.push(json_path);
    Ok(CvReport { json, rows, files })
}

/// Radial annuli of the steady disk's ν(R) between 1.5 R_in and r_circ.
pub const VISCOSITY_BINS: usize = 8;

/// The steady disk's viscosity (`reports::cv_accretion::steady_viscosity`) from the
/// snapshots of the run's last quarter, where the white dwarf then accretes at least half
/// the transfer rate.
fn steady_viscosity(
    b: &Binary,
    eos: &crate::physics::eos::Eos,
    ledger: &[cv_accretion::LedgerRow],
    samples: &mut Vec<cv_accretion::DiskSample>,
) -> Option<cv_accretion::SteadyViscosity> {
    let end = samples.last()?.orbit;
    let start = samples.first()?.orbit;
    let from = end - 0.25 * (end - start);
    samples.retain(|s| s.orbit >= from && s.orbit > start);
    let (first, last) = (samples.first()?.orbit, samples.last()?.orbit);
    let (mdot, share) = cv_accretion::accretion_rate(ledger, first, last)?;
    if share < 0.5 {
        return None;
    }
    let cs = match eos {
        crate::physics::eos::Eos::Isothermal { cs } => Some(*cs),
        _ => None,
    };
    cv_accretion::steady_viscosity(
        samples,
        mdot,
        share,
        b.accretor_radius,
        (1.5 * b.accretor_radius, roche::r_circ_fit(b.q)),
        VISCOSITY_BINS,
        1.0 - b.mu,
        cs,
    )
}

/// `cv_evolution.csv`: a header and a row per snapshot, empty cells for missing figures.
pub fn evolution_csv(rows: &[CvFigures], days: bool, three_d: bool) -> String {
    let mut csv = String::new();
    let Some(first) = rows.first() else {
        return csv;
    };
    let names: Vec<&str> = first.columns(days, three_d).iter().map(|c| c.0).collect();
    csv.push_str("snapshot,");
    csv.push_str(&names.join(","));
    csv.push('\n');
    for r in rows {
        csv.push_str(&r.snapshot);
        for (_, v) in r.columns(days, three_d) {
            csv.push(',');
            if let Some(v) = v {
                let _ = write!(csv, "{v}");
            }
        }
        csv.push('\n');
    }
    csv
}

impl CvFigures {
    /// The numeric figures in the order of `cv_evolution.csv`; `days` and the overflow
    /// columns only when asked for (a run with `binary.period_days`; a 3D run).
    pub fn columns(&self, days: bool, three_d: bool) -> Vec<(&'static str, Option<f64>)> {
        let n = |k: usize| Some(k as f64);
        let mut c = vec![("t", Some(self.t)), ("orbit", Some(self.orbit))];
        if days {
            c.push(("days", self.days));
        }
        c.extend([
            ("particles", n(self.particles)),
            ("gas_mass", Some(self.gas_mass)),
            ("disk_particles", n(self.disk_particles)),
            ("disk_mass", Some(self.disk_mass)),
            ("disk_mass_fraction", self.disk_mass_fraction),
            ("disk_radius_50", self.disk_radius_50),
            ("disk_radius_90", self.disk_radius_90),
            ("disk_radius_99", self.disk_radius_99),
            ("disk_r90_over_r_circ", self.disk_r90_over_r_circ),
            ("disk_r90_over_tidal", self.disk_r90_over_tidal),
            ("disk_r90_over_r31", self.disk_r90_over_r31),
            ("disk_window_particles", n(self.disk_window_particles)),
            ("disk_m1_amplitude", self.disk_m1_amplitude),
            ("disk_m1_phase_deg", self.disk_m1_phase_deg),
            ("disk_m2_amplitude", self.disk_m2_amplitude),
            ("disk_eccentricity", self.disk_eccentricity),
            ("disk_periastron_deg", self.disk_periastron_deg),
            (
                "disk_periastron_inertial_deg",
                self.disk_periastron_inertial_deg,
            ),
            ("spot_particles", n(self.spot_particles)),
            ("spot_luminosity", self.spot_luminosity),
            ("spot_azimuth_deg", self.spot_azimuth_deg),
            ("spot_radius", self.spot_radius),
            ("spot_sector_azimuth_deg", self.spot_sector_azimuth_deg),
            ("spot_sector_contrast", self.spot_sector_contrast),
            (
                "spot_predicted_azimuth_deg",
                self.spot_predicted_azimuth_deg,
            ),
        ]);
        if three_d {
            let o = self.overflow.unwrap_or_default();
            c.extend([
                ("disk_rim_height", o.disk_rim_height),
                ("disk_rim_aspect", o.disk_rim_aspect),
                ("overflow_rim_stream_mass", o.overflow_rim_stream_mass),
                ("overflow_fraction", o.overflow_fraction),
                ("overflow_fraction_above", o.overflow_fraction_above),
                ("overflow_fraction_below", o.overflow_fraction_below),
                ("overflow_mass", o.overflow_mass),
                ("overflow_reimpact_radius", o.overflow_reimpact_radius),
                (
                    "overflow_reimpact_azimuth_deg",
                    o.overflow_reimpact_azimuth_deg,
                ),
            ]);
        }
        c
    }
}

impl CvReport {
    /// The terminal table: a line per snapshot, then the snapshots' notes.
    pub fn summary(&self) -> String {
        let three_d = self.json.dimension == 3;
        let j = &self.json;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "q = {}: r_circ = {:.4}, r_min = {:.4} (ballistic {:.4} at {:.1}°), r_3:1 = {:.4}, tidal radius = {:.4}, Roche lobe = {:.4} (a)",
            j.q,
            j.r_circ,
            j.r_min,
            j.r_min_ballistic,
            j.r_min_ballistic_azimuth_deg,
            j.r_31,
            j.tidal_radius,
            j.roche_lobe_radius
        );
        let _ = write!(
            s,
            " orbit  disk N      R90      R99  R90/rc  R90/rt  R90/r31   e(m=1)   e(osc)  ϖ(°)  spot(°)  R_spot  sector(°)  ballistic(°)"
        );
        if three_d {
            let _ = write!(s, "    H/R  overflow  R_re-impact  az_re-impact(°)");
        }
        s.push('\n');
        let f3 = |v: Option<f64>, w: usize| match v {
            Some(v) => format!("{v:>w$.3}"),
            None => format!("{:>w$}", "–"),
        };
        let f1 = |v: Option<f64>, w: usize| match v {
            Some(v) => format!("{v:>w$.1}"),
            None => format!("{:>w$}", "–"),
        };
        for r in &self.rows {
            let _ = write!(
                s,
                "{:6.2}  {:6}  {}  {}  {}  {}  {}  {}  {}  {}  {}  {}  {}  {}",
                r.orbit,
                r.disk_particles,
                f3(r.disk_radius_90, 7),
                f3(r.disk_radius_99, 7),
                f3(r.disk_r90_over_r_circ, 6),
                f3(r.disk_r90_over_tidal, 6),
                f3(r.disk_r90_over_r31, 7),
                f3(r.disk_m1_amplitude, 7),
                f3(r.disk_eccentricity, 7),
                f1(r.disk_periastron_deg, 5),
                f1(r.spot_azimuth_deg, 7),
                f3(r.spot_radius, 6),
                f1(r.spot_sector_azimuth_deg, 9),
                f1(r.spot_predicted_azimuth_deg, 12),
            );
            if three_d {
                let o = r.overflow.unwrap_or_default();
                let _ = write!(
                    s,
                    "  {}  {}  {}  {}",
                    f3(o.disk_rim_aspect, 5),
                    f3(o.overflow_fraction, 8),
                    f3(o.overflow_reimpact_radius, 11),
                    f1(o.overflow_reimpact_azimuth_deg, 15),
                );
            }
            s.push('\n');
        }
        if let Some(days) = j.last.days {
            let _ = writeln!(s, "last snapshot at {days:.4} d");
        }
        if let Some(a) = &j.accretion {
            let l = &a.last;
            let at =
                |o: Option<f64>| o.map_or("not reached".to_string(), |o| format!("orbit {o:.1}"));
            let _ = writeln!(
                s,
                "the stream's gas over orbits {:.1}–{:.1}: accreted {:.3}, returned {:.3}, escaped {:.3}, kept {:.3} (the disk {:.3}) of the {:.4e} injected per orbit; R90 {:.4} = {:.3} of the tidal radius (0.9 R_L {:.4}, r_3:1 {:.4})",
                l.orbit_start,
                l.orbit_end,
                l.accreted,
                l.returned,
                l.escaped,
                l.kept,
                l.disk_growth,
                l.injected_per_orbit,
                l.r_disk_90,
                a.r_disk_over_tidal,
                a.roche_lobe_09,
                a.r_31
            );
            let _ = writeln!(
                s,
                "accretion onto the white dwarf ({:.1}-orbit windows): half the transfer rate {}, 90% {}",
                a.window_orbits,
                at(a.accretion_half_orbit),
                at(a.accretion_ninety_orbit)
            );
            if let Some(v) = &a.viscosity {
                let _ = writeln!(s, "{}", v.summary_line());
            }
        }
        if let Some(p) = &j.passage {
            let _ = writeln!(s, "{}", p.summary_line());
        }
        for n in &j.passage_notes {
            let _ = writeln!(s, "note (passage): {n}");
        }
        for r in &self.rows {
            for n in &r.notes {
                let _ = writeln!(s, "note ({}): {n}", r.snapshot);
            }
        }
        s
    }
}

// ---------------------------------------------------------------------------------------
// Per-particle helpers (a snapshot in the run's frame; 2D snapshots have z = 0)

fn position(s: &Snapshot, i: usize) -> [f64; 3] {
    [s.pos[0][i], s.pos[1][i], s.pos[2][i]]
}

fn velocity(s: &Snapshot, i: usize) -> [f64; 3] {
    [s.vel[0][i], s.vel[1][i], s.vel[2][i]]
}

fn cylindrical_radius(s: &Snapshot, i: usize) -> f64 {
    s.pos[0][i].hypot(s.pos[1][i])
}

/// Azimuth of (x, y) in degrees, in [0, 360), counter-clockwise from +x.
pub fn azimuth_deg(x: f64, y: f64) -> f64 {
    let a = y.atan2(x).to_degrees().rem_euclid(360.0);
    // rem_euclid of a tiny negative angle rounds to 360 itself.
    if a >= 360.0 { 0.0 } else { a }
}

/// The osculating Kepler orbit about the accretor of gas at `x` with corotating velocity
/// `v`: its eccentricity vector (pointing to periastron) and its periastron distance.
/// `Binary::eccentricity` is this vector's length.
pub fn osculating_orbit(b: &Binary, x: [f64; 3], v: [f64; 3]) -> ([f64; 3], f64) {
    let e = b.eccentricity_vector(&x, &v);
    // The velocity relative to the accretor in the inertial frame: v + Ω × x.
    let u = [v[0] - b.omega * x[1], v[1] + b.omega * x[0], v[2]];
    let gm = 1.0 - b.mu;
    let l = [
        x[1] * u[2] - x[2] * u[1],
        x[2] * u[0] - x[0] * u[2],
        x[0] * u[1] - x[1] * u[0],
    ];
    let l2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
    let en = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
    (e, l2 / (gm * (1.0 + en)))
}

/// Whether each particle is disk gas (`problems::cv::is_disk`).
pub fn disk_mask(b: &Binary, s: &Snapshot) -> Vec<bool> {
    (0..s.len())
        .map(|i| b.region(&position(s, i), &velocity(s, i), 0.0, 0.0) == Region::Disk)
        .collect()
}

/// The radius R holding `fraction` of the mass of the particles `pick` selects (None if
/// they have no mass): the R of the particle at which the mass sorted by R reaches it.
pub fn mass_radius(s: &Snapshot, fraction: f64, pick: impl Fn(usize) -> bool) -> Option<f64> {
    let rm: Vec<(f64, f64)> = (0..s.len())
        .filter(|&i| pick(i))
        .map(|i| (cylindrical_radius(s, i), s.mass[i]))
        .collect();
    weighted_quantile(rm, fraction)
}

/// The mass-weighted median of azimuths (degrees): offsets from the weighted circular mean
/// direction, wrapped to (−180, 180], have their median added back to it.
pub(crate) fn circular_median_deg(am: &[(f64, f64)]) -> Option<f64> {
    let (mut c, mut sn) = (0.0, 0.0);
    for &(a, m) in am {
        let (s, co) = a.to_radians().sin_cos();
        c += m * co;
        sn += m * s;
    }
    if c == 0.0 && sn == 0.0 {
        return None;
    }
    let mean = azimuth_deg(c, sn);
    let offsets: Vec<(f64, f64)> = am
        .iter()
        .map(|&(a, m)| {
            let d = (a - mean).rem_euclid(360.0);
            (if d > 180.0 { d - 360.0 } else { d }, m)
        })
        .collect();
    let med = weighted_quantile(offsets, 0.5)?;
    Some((mean + med).rem_euclid(360.0))
}

/// The m-th Fourier mode of the mass of the particles `pick` selects, about the accretor:
/// (|Σ m e^{imφ}| / Σ m, the phase of Σ m e^{imφ} over m in degrees), or None without mass.
/// For m = 1 and a Kepler ellipse sampled uniformly in mean anomaly the amplitude is the
/// ellipse's eccentricity and the phase points to apoastron ([`ECCENTRICITY_WINDOW`]).
pub fn fourier_mode(s: &Snapshot, m: u32, pick: impl Fn(usize) -> bool) -> Option<(f64, f64)> {
    let (mut c, mut sn, mut total) = (0.0, 0.0, 0.0);
    for i in (0..s.len()).filter(|&i| pick(i)) {
        let phi = s.pos[1][i].atan2(s.pos[0][i]);
        let (si, co) = (m as f64 * phi).sin_cos();
        c += s.mass[i] * co;
        sn += s.mass[i] * si;
        total += s.mass[i];
    }
    if !(total > 0.0) {
        return None;
    }
    let phase = (sn.atan2(c).to_degrees() / m as f64).rem_euclid(360.0 / m as f64);
    Some((c.hypot(sn) / total, phase))
}

/// The mass-weighted mean osculating eccentricity vector of the particles `pick` selects:
/// (its length, the azimuth of its projection on the orbital plane — the longitude of
/// periastron — in degrees), or None without mass. For particles on one Kepler ellipse,
/// each with its Kepler velocity, every vector is the ellipse's: the mean is e itself.
pub fn mean_eccentricity(
    b: &Binary,
    s: &Snapshot,
    pick: impl Fn(usize) -> bool,
) -> Option<(f64, f64)> {
    let mut e = [0.0; 3];
    let mut total = 0.0;
    for i in (0..s.len()).filter(|&i| pick(i)) {
        let (ev, _) = osculating_orbit(b, position(s, i), velocity(s, i));
        for d in 0..3 {
            e[d] += s.mass[i] * ev[d];
        }
        total += s.mass[i];
    }
    if !(total > 0.0) {
        return None;
    }
    let len = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt() / total;
    Some((len, azimuth_deg(e[0], e[1])))
}

/// The bright spot as its m ε̇-weighted centroid: over the stream gas within `r_disk` + 2h
/// (`Region::Spot`), (particles, Σ m ε̇, the centroid's azimuth in degrees and its distance
/// from the accretor). Azimuth and distance are None when that gas dissipates nothing.
pub fn spot_centroid(b: &Binary, s: &Snapshot, r_disk: f64) -> (usize, f64, Option<(f64, f64)>) {
    let (mut n, mut l, mut wx, mut wy) = (0, 0.0, 0.0, 0.0);
    for i in 0..s.len() {
        let (x, v) = (position(s, i), velocity(s, i));
        if b.region(&x, &v, r_disk, 2.0 * s.h[i]) != Region::Spot {
            continue;
        }
        n += 1;
        let w = s.mass[i] * s.diss[i].max(0.0);
        l += w;
        wx += w * x[0];
        wy += w * x[1];
    }
    let c = (l > 0.0).then(|| (azimuth_deg(wx, wy), (wx / l).hypot(wy / l)));
    (n, l, c)
}

/// The brightest sector of the annulus `r_lo` ≤ R ≤ `r_hi`, all gas counted: Σ m ε̇ in
/// sectors `sector_deg` wide from 0°; the largest, its centre moved by the vertex of the
/// parabola through it and its two neighbours (at most half a sector). Returns (azimuth in
/// degrees, the sector's Σ m ε̇ over the mean sector's), or None if the annulus dissipates
/// nothing.
pub fn sector_peak(s: &Snapshot, r_lo: f64, r_hi: f64, sector_deg: f64) -> Option<(f64, f64)> {
    let n = (360.0 / sector_deg).round().max(3.0) as usize;
    let width = 360.0 / n as f64;
    let mut sum = vec![0.0; n];
    for i in 0..s.len() {
        let r = cylindrical_radius(s, i);
        if r < r_lo || r > r_hi {
            continue;
        }
        let k = ((azimuth_deg(s.pos[0][i], s.pos[1][i]) / width) as usize).min(n - 1);
        sum[k] += s.mass[i] * s.diss[i].max(0.0);
    }
    let total: f64 = sum.iter().sum();
    if !(total > 0.0) {
        return None;
    }
    let k = (0..n).max_by(|&a, &c| sum[a].total_cmp(&sum[c]))?;
    let (y0, y1, y2) = (sum[(k + n - 1) % n], sum[k], sum[(k + 1) % n]);
    let curv = y0 - 2.0 * y1 + y2;
    let shift = if curv < 0.0 {
        (0.5 * (y0 - y2) / curv).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    let az = ((k as f64 + 0.5 + shift) * width).rem_euclid(360.0);
    Some((az, y1 / (total / n as f64)))
}

/// The overflow figures of a 3D snapshot (module doc), given the disk mask and R90.
///
/// The re-impact region: a snapshot catches each overflowing particle at one point of its
/// path; its osculating Kepler orbit about the accretor ([`osculating_orbit`]) says where
/// that path comes closest to the accretor — accurate inside the disk's radius, where the
/// accretor's gravity dominates the donor's tide. The gas counted is the non-disk gas with
/// |z| > H at R ≤ 1.1 R90 (over or under the disk, or at its rim): gas that has passed
/// above or below the rim instead of striking it, and that falls back onto the disk's faces
/// near its periastron (exact-solutions.md 4b: near r_circ). The mass-weighted medians of
/// the periastron distances and azimuths (about their mean direction) are reported.
pub fn overflow_figures(
    b: &Binary,
    s: &Snapshot,
    disk: &[bool],
    r90: f64,
    notes: &mut Vec<String>,
) -> OverflowFigures {
    let mut o = OverflowFigures::default();
    let (lo, hi) = (RIM.0 * r90, RIM.1 * r90);
    let in_rim = |i: usize| (lo..=hi).contains(&cylindrical_radius(s, i));
    let (mut mz2, mut m, mut count) = (0.0, 0.0, 0);
    for i in (0..s.len()).filter(|&i| disk[i] && in_rim(i)) {
        mz2 += s.mass[i] * s.pos[2][i].powi(2);
        m += s.mass[i];
        count += 1;
    }
    if count < MIN_RIM_PARTICLES || !(m > 0.0) {
        notes.push(format!(
            "{count} disk particle(s) at the rim ({lo:.3}–{hi:.3} a), fewer than {MIN_RIM_PARTICLES}: no disk height H, no overflow figures"
        ));
        return o;
    }
    let h = (mz2 / m).sqrt();
    o.disk_rim_height = Some(h);
    o.disk_rim_aspect = Some(h / r90);
    let (mut rim_mass, mut above, mut below) = (0.0, 0.0, 0.0);
    for i in (0..s.len()).filter(|&i| !disk[i] && in_rim(i)) {
        rim_mass += s.mass[i];
        let z = s.pos[2][i];
        if z > h {
            above += s.mass[i];
        } else if z < -h {
            below += s.mass[i];
        }
    }
    if rim_mass > 0.0 {
        o.overflow_rim_stream_mass = Some(rim_mass);
        o.overflow_fraction = Some((above + below) / rim_mass);
        o.overflow_fraction_above = Some(above / rim_mass);
        o.overflow_fraction_below = Some(below / rim_mass);
    } else {
        notes.push(format!(
            "no stream gas at the rim ({lo:.3}–{hi:.3} a): no overflow fraction"
        ));
    }
    let (mut over, mut radii, mut azimuths) = (0.0, Vec::new(), Vec::new());
    for i in 0..s.len() {
        if disk[i] || s.pos[2][i].abs() <= h || cylindrical_radius(s, i) > hi {
            continue;
        }
        let (e, rp) = osculating_orbit(b, position(s, i), velocity(s, i));
        over += s.mass[i];
        radii.push((rp, s.mass[i]));
        azimuths.push((azimuth_deg(e[0], e[1]), s.mass[i]));
    }
    if over > 0.0 {
        o.overflow_mass = Some(over);
        o.overflow_reimpact_radius = weighted_quantile(radii, 0.5);
        o.overflow_reimpact_azimuth_deg = circular_median_deg(&azimuths);
    } else {
        notes.push(format!(
            "no stream gas with |z| > H = {h:.4} at R ≤ {hi:.3}: no re-impact region"
        ));
    }
    o
}

/// Everything [`CvFigures`] holds for one snapshot `s` in the run's frame (its `snapshot`
/// name left empty).
pub fn snapshot_figures(b: &Binary, s: &Snapshot, period_days: Option<f64>) -> CvFigures {
    snapshot_figures_of_disk(b, s, period_days, &disk_mask(b, s))
}

/// [`snapshot_figures`] with the disk's mask ([`disk_mask`]) given.
fn snapshot_figures_of_disk(
    b: &Binary,
    s: &Snapshot,
    period_days: Option<f64>,
    disk: &[bool],
) -> CvFigures {
    let q = b.q;
    let mut f = CvFigures {
        t: s.time,
        orbit: s.time / TAU,
        days: period_days.map(|p| p * s.time / TAU),
        particles: s.len(),
        gas_mass: s.mass.iter().fold(0.0, |acc, m| acc + m),
        ..CvFigures::default()
    };
    f.disk_particles = disk.iter().filter(|&&d| d).count();
    // fold from +0 (an empty f64 sum is −0).
    f.disk_mass = (0..s.len())
        .filter(|&i| disk[i])
        .fold(0.0, |acc, i| acc + s.mass[i]);
    if f.gas_mass > 0.0 {
        f.disk_mass_fraction = Some(f.disk_mass / f.gas_mass);
    }
    let r90 = mass_radius(s, 0.9, |i| disk[i]).filter(|&r| r > 0.0);
    let Some(r90) = r90 else {
        f.notes.push(format!(
            "no disk yet: no gas on a near-circular orbit (osculating e < {})",
            crate::physics::binary::STREAM_ECCENTRICITY
        ));
        if s.dimension == 3 {
            f.overflow = Some(OverflowFigures::default());
        }
        return f;
    };
    f.disk_radius_50 = mass_radius(s, 0.5, |i| disk[i]);
    f.disk_radius_90 = Some(r90);
    f.disk_radius_99 = mass_radius(s, 0.99, |i| disk[i]);
    f.disk_r90_over_r_circ = Some(r90 / roche::r_circ_fit(q));
    f.disk_r90_over_tidal = Some(r90 / roche::tidal_radius(q));
    f.disk_r90_over_r31 = Some(r90 / roche::r_31(q));

    let (w_lo, w_hi) = (ECCENTRICITY_WINDOW.0 * r90, ECCENTRICITY_WINDOW.1 * r90);
    let window = |i: usize| disk[i] && (w_lo..=w_hi).contains(&cylindrical_radius(s, i));
    f.disk_window_particles = (0..s.len()).filter(|&i| window(i)).count();
    if (1..MIN_WINDOW_PARTICLES).contains(&f.disk_window_particles) {
        f.notes.push(format!(
            "only {} disk particle(s) between 0.5 and 1.0 R90: the eccentricities are noise (≈ 0.9/√N)",
            f.disk_window_particles
        ));
    }
    if let Some((a, phase)) = fourier_mode(s, 1, window) {
        f.disk_m1_amplitude = Some(a);
        f.disk_m1_phase_deg = Some(phase);
        f.disk_m2_amplitude = fourier_mode(s, 2, window).map(|x| x.0);
    } else {
        f.notes.push(format!(
            "no disk gas between {w_lo:.4} and {w_hi:.4} (0.5–1.0 R90): no eccentricity"
        ));
    }
    if let Some((e, w)) = mean_eccentricity(b, s, window) {
        f.disk_eccentricity = Some(e);
        f.disk_periastron_deg = Some(w);
        f.disk_periastron_inertial_deg =
            Some((w + (b.omega * s.time).to_degrees()).rem_euclid(360.0));
    }

    let (n_spot, l_spot, centroid) = spot_centroid(b, s, r90);
    f.spot_particles = n_spot;
    if n_spot == 0 {
        f.notes.push(format!(
            "no stream gas within R90 + 2h = {:.4}: no bright-spot centroid",
            r90 + 2.0 * s.h.iter().copied().fold(0.0, f64::max)
        ));
    } else {
        f.spot_luminosity = Some(l_spot);
        match centroid {
            Some((az, r)) => {
                f.spot_azimuth_deg = Some(az);
                f.spot_radius = Some(r);
            }
            None => f
                .notes
                .push("the stream gas within R90 + 2h dissipates nothing: no centroid".into()),
        }
    }
    match sector_peak(s, SPOT_ANNULUS.0 * r90, SPOT_ANNULUS.1 * r90, SECTOR_DEG) {
        Some((az, contrast)) => {
            f.spot_sector_azimuth_deg = Some(az);
            f.spot_sector_contrast = Some(contrast);
        }
        None => f
            .notes
            .push("the annulus 0.8–1.2 R90 dissipates nothing: no brightest sector".into()),
    }
    match predicted_impact_azimuth(q, r90) {
        Some(az) => f.spot_predicted_azimuth_deg = Some(az),
        None => f.notes.push(format!(
            "the ballistic stream does not reach R90 = {r90:.4} (its closest approach is {:.4}): no predicted impact",
            ballistic_r_min(q)
        )),
    }
    if s.dimension == 3 {
        f.overflow = Some(overflow_figures(b, s, disk, r90, &mut f.notes));
    }
    f
}

// ---------------------------------------------------------------------------------------
// The ballistic stream

/// Right-hand side of a test particle in the turning frame (Ω = 1 along +z, orbital plane):
/// d(x, y, vx, vy)/dt = (vx, vy, −∇Φ_Roche + (2 vy, −2 vx)), the last term the Coriolis
/// force −2 Ω × v.
fn stream_rhs(mu: f64, s: &[f64; 4]) -> [f64; 4] {
    let (x, y, vx, vy) = (s[0], s[1], s[2], s[3]);
    let r1 = x.hypot(y);
    let r2 = (x + 1.0).hypot(y);
    let k1 = (1.0 - mu) / (r1 * r1 * r1);
    let k2 = mu / (r2 * r2 * r2);
    [
        vx,
        vy,
        -k1 * x - k2 * (x + 1.0) + (x + mu) + 2.0 * vy,
        -k1 * y - k2 * y + y - 2.0 * vx,
    ]
}

/// One classical Runge–Kutta step of length `dt`.
fn rk4(mu: f64, s: &[f64; 4], dt: f64) -> [f64; 4] {
    let add = |a: &[f64; 4], k: &[f64; 4], f: f64| -> [f64; 4] {
        std::array::from_fn(|d| a[d] + f * k[d])
    };
    let k1 = stream_rhs(mu, s);
    let k2 = stream_rhs(mu, &add(s, &k1, 0.5 * dt));
    let k3 = stream_rhs(mu, &add(s, &k2, 0.5 * dt));
    let k4 = stream_rhs(mu, &add(s, &k3, dt));
    std::array::from_fn(|d| s[d] + dt / 6.0 * (k1[d] + 2.0 * k2[d] + 2.0 * k3[d] + k4[d]))
}

/// The unstable direction of the saddle at L1 in phase space: near L1 (ξ, η the offsets
/// along and across the line of centres) ξ'' − 2η' = (2A+1) ξ, η'' + 2ξ' = −(A−1) η, whose
/// growing solution e^{λt} has λ⁴ + (2 − A) λ² − (2A+1)(A−1) = 0 and η/ξ = (λ² − 2A − 1)/(2λ).
/// Returns (λ, the unit vector (ξ, η) with ξ > 0, towards the accretor); its angle below the
/// line of centres is Lubow & Shu's `roche::stream_angle`.
pub fn l1_unstable_direction(q: f64) -> (f64, [f64; 2]) {
    let a = roche::l1_a(q);
    let b = a - 2.0;
    let lambda2 = 0.5 * (b + (b * b + 4.0 * (2.0 * a + 1.0) * (a - 1.0)).sqrt());
    let lambda = lambda2.sqrt();
    let eta = (lambda2 - 2.0 * a - 1.0) / (2.0 * lambda);
    let n = 1.0f64.hypot(eta);
    (lambda, [1.0 / n, eta / n])
}

/// A cold ballistic test particle leaving L1 towards the accretor, in the turning frame:
/// (x, y, vx, vy) at every step (corotating velocities), from L1 + ε n with velocity λ ε n
/// (n, λ of [`l1_unstable_direction`], ε = [`BALLISTIC_OFFSET`]: on the saddle's unstable
/// manifold, the limit of a stream launched at vanishing speed) by classical RK4 with the
/// Coriolis force, step [`BALLISTIC_DT`]. It stops where it first reaches R = `r_stop`
/// (that last point found by bisection on the step length: its R is `r_stop` to round-off)
/// or at its first closest approach to the accretor if that comes first (bisection on
/// x·v = 0); `r_stop` = 0 therefore gives the closest approach r_min as the last point. It
/// also stops after two orbital periods. The Jacobi constant ½ v² + Φ_Roche is kept to
/// about 1e-12.
pub fn ballistic_stream(q: f64, r_stop: f64) -> Vec<[f64; 4]> {
    let mu = roche::mu(q);
    let (lambda, n) = l1_unstable_direction(q);
    let l1 = roche::l1_point(q);
    let e = BALLISTIC_OFFSET;
    let mut s = [
        l1[0] + e * n[0],
        l1[1] + e * n[1],
        lambda * e * n[0],
        lambda * e * n[1],
    ];
    let radius = |s: &[f64; 4]| s[0].hypot(s[1]);
    let radial = |s: &[f64; 4]| s[0] * s[2] + s[1] * s[3];
    let mut out = vec![s];
    if radius(&s) <= r_stop {
        return out;
    }
    let steps = (2.0 * TAU / BALLISTIC_DT).ceil() as usize;
    let bisect = |s: &[f64; 4], below: &dyn Fn(&[f64; 4]) -> bool| -> [f64; 4] {
        let (mut lo, mut hi) = (0.0, BALLISTIC_DT);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if below(&rk4(mu, s, mid)) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        rk4(mu, s, hi)
    };
    for _ in 0..steps {
        let next = rk4(mu, &s, BALLISTIC_DT);
        if radius(&next) <= r_stop {
            out.push(bisect(&s, &|x| radius(x) <= r_stop));
            return out;
        }
        if radial(&s) < 0.0 && radial(&next) >= 0.0 {
            out.push(bisect(&s, &|x| radial(x) >= 0.0));
            return out;
        }
        out.push(next);
        s = next;
    }
    out
}

/// The ballistic stream's closest approach to the accretor (the last point of
/// [`ballistic_stream`] with `r_stop` = 0).
pub fn ballistic_r_min(q: f64) -> f64 {
    let last = *ballistic_stream(q, 0.0).last().expect("starts at L1");
    last[0].hypot(last[1])
}

/// The azimuth (degrees) at which the ballistic stream from L1 first reaches R = `r`, or
/// None if it never comes that close (r below its closest approach).
pub fn predicted_impact_azimuth(q: f64, r: f64) -> Option<f64> {
    let path = ballistic_stream(q, r);
    let last = path.last()?;
    let reached = (last[0].hypot(last[1]) - r).abs() <= 1e-9 * r.max(1.0);
    reached.then(|| azimuth_deg(last[0], last[1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::binary::BinaryParams;

    fn binary(q: f64) -> Binary {
        Binary::new(&BinaryParams::with_q(q))
    }

    /// Gas at `x` (orbital plane) moving with the inertial velocity `u` relative to the
    /// accretor, written as a corotating velocity.
    fn corotating(b: &Binary, x: [f64; 2], u: [f64; 2]) -> [f64; 2] {
        [u[0] + b.omega * x[1], u[1] - b.omega * x[0]]
    }

    /// A 2D snapshot of particles (x, y, corotating v, mass, ε̇), h = 0.01.
    fn snapshot(parts: &[([f64; 2], [f64; 2], f64, f64)]) -> Snapshot {
        let n = parts.len();
        let mut s = Snapshot {
            dimension: 2,
            id: (0..n as u64).collect(),
            h: vec![0.01; n],
            rho: vec![1.0; n],
            u: vec![0.0; n],
            p: vec![0.0; n],
            pos: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            vel: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            ..Snapshot::default()
        };
        for (i, (x, v, m, d)) in parts.iter().enumerate() {
            for k in 0..2 {
                s.pos[k][i] = x[k];
                s.vel[k][i] = v[k];
            }
            s.mass.push(*m);
            s.diss.push(*d);
        }
        s
    }

    /// A uniform circular disk of rings at R = k dR (k = 1..=K), ~2πk particles on ring k,
    /// equal masses, on circular Kepler orbits, dissipating `diss` each.
    fn circular_disk(
        b: &Binary,
        k_max: usize,
        dr: f64,
        diss: f64,
    ) -> Vec<([f64; 2], [f64; 2], f64, f64)> {
        let gm = 1.0 - b.mu;
        let mut parts = Vec::new();
        for k in 1..=k_max {
            let r = k as f64 * dr;
            let n = (TAU * k as f64).round() as usize;
            let vk = (gm / r).sqrt();
            for j in 0..n {
                let phi = TAU * (j as f64 + 0.5 * (k % 2) as f64) / n as f64;
                let (s, c) = phi.sin_cos();
                let x = [r * c, r * s];
                parts.push((x, corotating(b, x, [-vk * s, vk * c]), 1e-6, diss));
            }
        }
        parts
    }

    /// `n` particles uniform in mean anomaly on a Kepler ellipse about the accretor
    /// (semi-major axis `a`, eccentricity `e`, periastron at `varpi` radians), each with its
    /// Kepler velocity.
    fn eccentric_ring(
        b: &Binary,
        n: usize,
        a: f64,
        e: f64,
        varpi: f64,
    ) -> Vec<([f64; 2], [f64; 2], f64, f64)> {
        (0..n)
            .map(|j| {
                let m_anom = TAU * j as f64 / n as f64;
                let (x, u) = crate::analysis::kepler_point(1.0 - b.mu, a, e, varpi, m_anom);
                (x, corotating(b, x, u), 1e-6, 0.0)
            })
            .collect()
    }

    #[test]
    fn azimuths_follow_the_frame_convention() {
        assert_eq!(azimuth_deg(1.0, 0.0), 0.0);
        assert!((azimuth_deg(-1.0, 0.0) - 180.0).abs() < 1e-12);
        assert!((azimuth_deg(0.0, -1.0) - 270.0).abs() < 1e-12);
        assert_eq!(azimuth_deg(1.0, -1e-300), 0.0);
        let m = circular_median_deg(&[(350.0, 1.0), (5.0, 1.0), (10.0, 1.0)]).unwrap();
        assert!((m - 5.0).abs() < 1e-9, "{m}");
    }

    /// Uniform surface density out to R_out: the mass within R is (R/R_out)², so R90 =
    /// √0.9 R_out and R50 = √0.5 R_out, to within one ring spacing.
    #[test]
    fn a_circular_disk_gives_its_radii_and_no_eccentricity() {
        let b = binary(0.1);
        let (k, dr) = (40, 0.0075);
        let s = snapshot(&circular_disk(&b, k, dr, 1.0));
        let f = snapshot_figures(&b, &s, Some(0.07));
        let r_out = (k as f64 + 0.5) * dr;
        assert_eq!(f.disk_particles, s.len());
        let r90 = f.disk_radius_90.unwrap();
        assert!((r90 - 0.9f64.sqrt() * r_out).abs() < dr, "{r90}");
        let r50 = f.disk_radius_50.unwrap();
        assert!((r50 - 0.5f64.sqrt() * r_out).abs() < dr, "{r50}");
        let r99 = f.disk_radius_99.unwrap();
        assert!((r99 - 0.99f64.sqrt() * r_out).abs() < dr, "{r99}");
        assert!(
            f.disk_m1_amplitude.unwrap() < 1e-3,
            "{:?}",
            f.disk_m1_amplitude
        );
        assert!(f.disk_eccentricity.unwrap() < 1e-12);
        let r = f.disk_r90_over_r_circ.unwrap() * roche::r_circ_fit(0.1);
        assert!((r - r90).abs() < 1e-15);
        assert_eq!(f.days, Some(0.0));
        // No stream: no spot centroid; an evenly lit annulus has no bright sector.
        assert_eq!(f.spot_particles, 0);
        assert_eq!(f.spot_azimuth_deg, None);
        assert!(
            f.notes.iter().any(|n| n.contains("no stream gas")),
            "{:?}",
            f.notes
        );
        assert!(f.spot_sector_contrast.unwrap() < 1.2);
        assert!(f.overflow.is_none());
    }

    /// For particles uniform in mean anomaly on one ellipse, ⟨cos f⟩ = −e: the m = 1
    /// amplitude is e and points to apoastron; each osculating vector is the ellipse's, so
    /// their mean is e and points to periastron (both to 1e-3).
    #[test]
    fn an_eccentric_ring_gives_its_eccentricity() {
        let b = binary(0.1);
        let (e, varpi) = (0.2, 40f64.to_radians());
        let s = snapshot(&eccentric_ring(&b, 2000, 0.3, e, varpi));
        let (a1, phase) = fourier_mode(&s, 1, |_| true).unwrap();
        assert!((a1 - e).abs() < 1e-3, "{a1}");
        assert!((phase - 220.0).abs() < 0.5, "{phase}");
        let (em, w) = mean_eccentricity(&b, &s, |_| true).unwrap();
        assert!((em - e).abs() < 1e-3, "{em}");
        assert!((w - 40.0).abs() < 0.1, "{w}");
        // Through the whole analysis: all of it is disk gas (e < 0.3); the window
        // [0.5, 1.0] R90 cuts the ring's outermost 10% of mass near apoastron, which lowers
        // the m = 1 amplitude but leaves every osculating vector e.
        let f = snapshot_figures(&b, &s, None);
        assert_eq!(f.disk_particles, s.len());
        assert!((f.disk_eccentricity.unwrap() - e).abs() < 1e-3);
        assert!((f.disk_periastron_deg.unwrap() - 40.0).abs() < 0.1);
        let a = f.disk_m1_amplitude.unwrap();
        assert!(a > 0.5 * e && a < e, "{a}");
    }

    /// A hot blob of stream gas (at rest in the turning frame: a nearly radial orbit) at the
    /// rim of a faintly dissipating disk, at azimuth 230°: found within 5° by the centroid
    /// and by the brightest sector.
    #[test]
    fn a_spot_blob_is_found_at_its_azimuth() {
        let b = binary(0.1);
        let mut parts = circular_disk(&b, 40, 0.0075, 1e-3);
        let r90 = 0.9f64.sqrt() * 40.5 * 0.0075;
        let az = 230f64.to_radians();
        let mut rng = crate::rng::Rng::new(7);
        for _ in 0..200 {
            let r = 0.97 * r90 * (1.0 + 0.01 * rng.normal());
            let th = az + 0.04 * rng.normal();
            parts.push(([r * th.cos(), r * th.sin()], [0.0, 0.0], 1e-6, 1.0));
        }
        let s = snapshot(&parts);
        let f = snapshot_figures(&b, &s, None);
        assert_eq!(f.spot_particles, 200);
        let c = f.spot_azimuth_deg.unwrap();
        assert!((c - 230.0).abs() < 5.0, "centroid {c}");
        assert!((f.spot_radius.unwrap() - 0.97 * r90).abs() < 0.05 * r90);
        let k = f.spot_sector_azimuth_deg.unwrap();
        assert!((k - 230.0).abs() < 5.0, "sector {k}");
        assert!(f.spot_sector_contrast.unwrap() > 5.0);
        // The blob is not disk gas, so R90 is still the disk's.
        assert!((f.disk_radius_90.unwrap() - r90).abs() < 0.0075);
        assert!(f.spot_predicted_azimuth_deg.is_some());
    }

    #[test]
    fn an_empty_snapshot_has_notes_not_figures() {
        let b = binary(0.1);
        let mut s = snapshot(&[([-0.7, 0.0], [0.05, 0.0], 1e-6, 0.0)]);
        let f = snapshot_figures(&b, &s, None);
        assert_eq!(f.disk_radius_90, None);
        assert_eq!(f.spot_azimuth_deg, None);
        assert!(f.notes[0].contains("no disk yet"));
        // 3D: the overflow figures are there, null.
        s.dimension = 3;
        let f = snapshot_figures(&b, &s, None);
        assert_eq!(f.overflow, Some(OverflowFigures::default()));
        let v = serde_json::to_value(&f).unwrap();
        assert!(v["overflow_fraction"].is_null());
        assert!(v["disk_radius_90"].is_null());
        let csv = evolution_csv(&[f], false, true);
        let row = csv.lines().nth(1).unwrap();
        assert!(row.contains(",,"), "{row}");
    }

    /// Every numeric figure of the JSON is a column of the CSV, and 2D has no overflow.
    #[test]
    fn csv_columns_match_the_json_figures() {
        let b = binary(0.1);
        let mut s = snapshot(&circular_disk(&b, 20, 0.01, 1.0));
        s.dimension = 3;
        let f = snapshot_figures(&b, &s, Some(0.06));
        let cols: Vec<&str> = f.columns(true, true).iter().map(|c| c.0).collect();
        let v = serde_json::to_value(&f).unwrap();
        for (k, _) in v.as_object().unwrap() {
            if k != "snapshot" && k != "notes" {
                assert!(cols.contains(&k.as_str()), "{k} is not a column");
            }
        }
        assert_eq!(cols.len() + 2, v.as_object().unwrap().len());
        let f2 = CvFigures {
            overflow: None,
            ..f
        };
        let v2 = serde_json::to_value(&f2).unwrap();
        assert!(v2.get("overflow_fraction").is_none());
        let header = evolution_csv(&[f2], false, false);
        assert!(!header.contains("overflow") && !header.contains("days"));
    }

    /// A disk with a thin layer and stream gas at the rim, half of it above H: the overflow
    /// fraction is a half, and its re-impact lies at the gas's periastron.
    #[test]
    fn overflow_of_a_synthetic_3d_rim() {
        let b = binary(0.1);
        let parts = circular_disk(&b, 30, 0.01, 0.0);
        let mut s = snapshot(&parts);
        s.dimension = 3;
        // Disk particles at z = ±0.002: H = 0.002.
        for i in 0..s.len() {
            s.pos[2][i] = if i % 2 == 0 { 0.002 } else { -0.002 };
        }
        let disk = disk_mask(&b, &s);
        let r90 = mass_radius(&s, 0.9, |i| disk[i]).unwrap();
        // Stream gas at R90, azimuth 200°, at rest in the turning frame; half at z = 0.03.
        let n0 = s.len();
        for k in 0..10 {
            let th = 200f64.to_radians();
            s.pos[0].push(r90 * th.cos());
            s.pos[1].push(r90 * th.sin());
            s.pos[2].push(if k < 5 { 0.03 } else { 0.0 });
            for d in 0..3 {
                s.vel[d].push(0.0);
            }
            s.mass.push(1e-6);
            s.h.push(0.01);
            s.diss.push(1.0);
            s.id.push((n0 + k) as u64);
        }
        let disk = disk_mask(&b, &s);
        let mut notes = Vec::new();
        let o = overflow_figures(&b, &s, &disk, r90, &mut notes);
        assert!((o.disk_rim_height.unwrap() - 0.002).abs() < 1e-12);
        assert!((o.overflow_fraction.unwrap() - 0.5).abs() < 1e-12, "{o:?}");
        assert_eq!(o.overflow_fraction_below, Some(0.0));
        // At rest in the turning frame: inertial speed R Ω, much below Kepler's, so the gas
        // is at apoastron and its periastron lies opposite (20°), far inside.
        let (_, rp) = osculating_orbit(
            &b,
            [
                r90 * 200f64.to_radians().cos(),
                r90 * 200f64.to_radians().sin(),
                0.03,
            ],
            [0.0; 3],
        );
        assert!((o.overflow_reimpact_radius.unwrap() - rp).abs() < 1e-12);
        assert!(rp < 0.1 * r90);
        let az = o.overflow_reimpact_azimuth_deg.unwrap();
        assert!((az - 20.0).abs() < 1.0, "{az}");
        assert!(notes.is_empty(), "{notes:?}");
    }

    /// The unstable direction of the linearised saddle is Lubow & Shu's launch angle.
    #[test]
    fn the_test_stream_leaves_l1_at_the_lubow_shu_angle() {
        for q in [0.05, 0.1, 0.2, 0.5] {
            let (lambda, n) = l1_unstable_direction(q);
            assert!(lambda > 0.0 && n[0] > 0.0 && n[1] < 0.0);
            let angle = (-n[1]).atan2(n[0]);
            assert!(
                (angle - roche::stream_angle(q)).abs() < 1e-10,
                "q {q}: {angle}"
            );
        }
    }

    /// The closest approach against Hessman & Hopp's power-law fit, and the stream's
    /// circularisation radius j²/GM1 at that point against the ballistic values of
    /// exact-solutions.md 4b (0.2295, 0.1935, 0.1707 at q = 0.10, 0.15, 0.20; to 2e-4: the
    /// table's four digits and the 1.3e-4 by which this stream lies above it at each q —
    /// the table does not say how its stream was launched).
    ///
    /// The fit is within 1% at q = 0.1 (0.142217 against 0.142043, +0.12%) but not at
    /// q = 0.2: the converged cold stream comes to 0.101728, 1.21% inside the fit's 0.102977
    /// (a quarter of the step and a thousandth of the offset change r_min by < 1e-11, so it
    /// is the fit's error — a two-parameter power law over 0.05 ≤ q ≤ 1 —, not the
    /// integration's). Hence 1% at q = 0.1 and 1.5% at q = 0.2.
    #[test]
    fn the_ballistic_stream_comes_as_close_as_hessman_and_hopp_say() {
        for (q, tol, r_circ) in [
            (0.1, 0.01, 0.2295),
            (0.15, 0.01, 0.1935),
            (0.2, 0.015, 0.1707),
        ] {
            let path = ballistic_stream(q, 0.0);
            let last = *path.last().unwrap();
            let r = last[0].hypot(last[1]);
            assert_eq!(r, ballistic_r_min(q));
            let fit = roche::r_min_fit(q);
            assert!((r / fit - 1.0).abs() < tol, "q {q}: {r} against {fit}");
            // At closest approach the velocity is tangential.
            assert!((last[0] * last[2] + last[1] * last[3]).abs() < 1e-12);
            let j = last[0] * (last[3] + last[0]) - last[1] * (last[2] - last[1]);
            let rc = j * j / (1.0 - roche::mu(q));
            assert!(
                (rc - r_circ).abs() < 2e-4,
                "q {q}: r_circ {rc} against {r_circ}"
            );
        }
    }

    #[test]
    fn the_ballistic_stream_keeps_its_jacobi_constant_and_stops_at_r_stop() {
        let q = 0.1;
        let path = ballistic_stream(q, 0.0);
        let c = |s: &[f64; 4]| {
            0.5 * (s[2] * s[2] + s[3] * s[3]) + roche::potential(q, [s[0], s[1], 0.0])
        };
        let c0 = c(&path[0]);
        let worst = path.iter().map(|s| (c(s) - c0).abs()).fold(0.0, f64::max);
        assert!(worst < 1e-8, "{worst}");
        // Starts at the L1 potential.
        assert!((c0 - roche::l1_potential(q)).abs() < 1e-10);
        // Stopping at a radius: the last point lies on it, below the stream's path (−y).
        let r_stop = 0.3;
        let path = ballistic_stream(q, r_stop);
        let last = path.last().unwrap();
        assert!((last[0].hypot(last[1]) - r_stop).abs() < 1e-12);
        let az = predicted_impact_azimuth(q, r_stop).unwrap();
        assert!(az > 180.0 && az < 360.0, "{az}");
        // Inside r_min the stream never arrives.
        assert_eq!(predicted_impact_azimuth(q, 0.5 * roche::r_min_fit(q)), None);
    }
}
