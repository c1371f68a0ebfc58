//! `sphdisk analyse ring <run>`: the spreading ring's azimuthally averaged Σ(R) against the
//! exact solution at each snapshot (paper, Figure 4c), the scatter of the particles' own Σ
//! (Figure 4b), the L1 error and the share of the ring's annuli left without particles, as
//! CSV files and a PNG.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::analysis::annulus_stats;
use crate::io::atomic::write_atomic;
use crate::io::hdf5::read_snapshot_with_h;
use crate::io::snapshot_index::SnapshotIndex;
use crate::io::summary::Summary;
use crate::problems::ring::{exact, ring_empty_annuli, ring_l1, tau_at};
use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle, plot_panels};

/// What the analysis wrote, and at each τ the L1 error and the empty-annulus fraction
/// ([`ring_empty_annuli`]).
pub struct RingReport {
    pub files: Vec<PathBuf>,
    pub l1: Vec<(f64, f64)>,
    pub empty_annuli: Vec<(f64, f64)>,
}

pub fn analyse_ring(run: &Path) -> Result<RingReport> {
    let summary = Summary::read(&run.join("summary.json"))
        .with_context(|| format!("{} has no readable summary.json", run.display()))?;
    let rec = summary.ring.clone().with_context(|| {
        format!(
            "{}: summary.json has no `ring` entry: not a ring run",
            run.display()
        )
    })?;
    rec.check()
        .with_context(|| format!("{}", run.join("summary.json").display()))?;
    let sol = exact(&rec);
    let index = SnapshotIndex::read(run)?;
    let scale = std::f64::consts::PI * rec.r0 * rec.r0 / rec.mass;
    let mut profiles = String::from(
        "tau,r,count,sigma_mean,sigma_exact,sigma_min,sigma_max,sigma_p10,sigma_p90\n",
    );
    let mut errors = String::from("tau,l1,empty_annuli\n");
    let mut l1s = Vec::new();
    let mut empties = Vec::new();
    let mut averaged = Vec::new();
    let mut exact_curves = Vec::new();
    let mut band = Vec::new();
    let mut scatter = Vec::new();
    let mut last_tau = rec.tau_start;
    // Each snapshot at its own time (the index's may have been edited).
    let mut snaps = Vec::new();
    for entry in &index.snapshots {
        let path = run.join(&entry.file);
        let snap = read_snapshot_with_h(&path)?;
        if snap.time > 0.0 {
            let p = snap
                .to_particles::<2>()
                .with_context(|| path.display().to_string())?;
            snaps.push((path, snap.time, p));
        }
    }
    if snaps.is_empty() {
        bail!(
            "{}: no snapshot after t = 0 to compare (snapshots.json lists {})",
            run.display(),
            index.snapshots.len()
        );
    }
    for (k, (path, time, p)) in snaps.iter().enumerate() {
        let time = *time;
        // One annulus of `spacing` out to the farthest particle: a bounded number.
        let rmax = (0..p.len())
            .map(|i| p.pos[0][i].hypot(p.pos[1][i]))
            .fold(0.0, f64::max);
        if rmax / rec.spacing > MAX_ANNULI {
            bail!(
                "{}: a particle lies at R = {rmax:e}, more than {MAX_ANNULI:e} annuli of \
                 `ring.spacing` = {} out: too far to average",
                path.display(),
                rec.spacing
            );
        }
        let tau = tau_at(&rec, time);
        let stats = annulus_stats(p, rec.spacing);
        let l1 = ring_l1(&rec, p, time);
        if !l1.is_finite() {
            bail!(
                "{}: the particles fill fewer than two annuli of `ring.spacing` = {}: no \
                 Σ(R) to compare",
                path.display(),
                rec.spacing
            );
        }
        let empty = ring_empty_annuli(&rec, p, time);
        let _ = writeln!(errors, "{tau},{l1},{empty}");
        l1s.push((tau, l1));
        empties.push((tau, empty));
        let mut avg = Vec::new();
        for b in stats.iter().filter(|b| b.count > 0) {
            let ex = sol.sigma(b.r, tau);
            let _ = writeln!(
                profiles,
                "{tau},{},{},{},{ex},{},{},{},{}",
                b.r, b.count, b.mean, b.min, b.max, b.p10, b.p90
            );
            avg.push((b.r / rec.r0, b.mean * scale));
            if k + 1 == snaps.len() {
                band.push((b.r / rec.r0, b.p10 * scale, b.p90 * scale));
            }
        }
        let curve: Vec<(f64, f64)> = (1..400)
            .map(|i| {
                let r = i as f64 * 0.005 * rec.r0;
                (r / rec.r0, sol.sigma(r, tau) * scale)
            })
            .collect();
        averaged.push((tau, avg));
        exact_curves.push(curve);
        if k + 1 == snaps.len() {
            last_tau = tau;
            scatter = (0..p.len())
                .map(|i| (p.pos[0][i].hypot(p.pos[1][i]) / rec.r0, p.rho[i] * scale))
                .collect();
        }
    }
    let prof_path = run.join("ring_profiles.csv");
    let err_path = run.join("ring_errors.csv");
    write_atomic(&prof_path, profiles.as_bytes())?;
    write_atomic(&err_path, errors.as_bytes())?;

    let ymax = averaged
        .iter()
        .flat_map(|(_, a)| a.iter().map(|p| p.1))
        .chain(exact_curves.iter().flat_map(|c| c.iter().map(|p| p.1)))
        .fold(0.0, f64::max)
        * 1.1;
    let mut left = Vec::new();
    for (k, ((tau, avg), curve)) in averaged.iter().zip(&exact_curves).enumerate() {
        let color = PALETTE[k % (PALETTE.len() - 1)];
        left.push(Series {
            label: Some(format!("SPH, τ = {tau:.3}")),
            points: avg.clone(),
            color,
            style: SeriesStyle::Line,
        });
        left.push(Series {
            label: None,
            points: curve.clone(),
            color,
            style: SeriesStyle::Dashed,
        });
    }
    let mut right = vec![Series {
        label: Some("particles".into()),
        points: scatter,
        color: PALETTE[1],
        style: SeriesStyle::Dots,
    }];
    right.push(Series {
        label: Some("10–90% band".into()),
        points: band.iter().map(|b| (b.0, b.1)).collect(),
        color: PALETTE[2],
        style: SeriesStyle::Line,
    });
    right.push(Series {
        label: None,
        points: band.iter().map(|b| (b.0, b.2)).collect(),
        color: PALETTE[2],
        style: SeriesStyle::Line,
    });
    right.push(Series {
        label: Some("exact".into()),
        points: exact_curves.last().cloned().unwrap_or_default(),
        color: RGB_BLACK,
        style: SeriesStyle::Dashed,
    });
    let png = run.join("ring.png");
    plot_panels(
        &png,
        (1400, 600),
        &[
            Panel {
                title: "azimuthally averaged Σ (solid) vs exact (dashed)".into(),
                x_label: "R / R0".into(),
                y_label: "Σ πR0²/M".into(),
                x_range: (0.0, 2.0),
                y_range: (0.0, ymax),
                series: left,
            },
            Panel {
                title: format!("particles' Σ at τ = {last_tau:.3}"),
                x_label: "R / R0".into(),
                y_label: "Σ πR0²/M".into(),
                x_range: (0.0, 2.0),
                y_range: (0.0, ymax),
                series: right,
            },
        ],
    )?;
    Ok(RingReport {
        files: vec![prof_path, err_path, png],
        l1: l1s,
        empty_annuli: empties,
    })
}

/// Most averaging annuli out to the farthest particle (10⁷: 10⁶ per R0 out to 10 R0).
const MAX_ANNULI: f64 = 1e7;

const RGB_BLACK: plotters::style::RGBColor = plotters::style::RGBColor(0, 0, 0);
