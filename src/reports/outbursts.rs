//! `sphdisk analyse outbursts <run>`: the dwarf-nova outbursts of a cataclysmic-variable
//! run with `[outbursts]` (paper, Section 4; Osaki 1989's thermal–tidal instability), from
//! the series the run writes: `lightcurve.csv` (the dissipation light curve), `monitor.csv`
//! (disk mass, R90, the mass on the hot branch) and `modes.csv` (the disk's eccentricity).
//!
//! - **Brightness.** The light curve smoothed over one orbit ([`SMOOTH_ORBITS`]: the
//!   orbital and superhump modulations average out), in magnitudes above quiescence,
//!   Δm = 2.5 log₁₀(L / L_q), with L_q the [`QUIESCENT_QUANTILE`] quantile of the smoothed
//!   light after the first [`START_ORBITS`].
//! - **Outbursts.** The stretches where Δm exceeds [`THRESHOLD_MAG`]; stretches less than
//!   [`MERGE_ORBITS`] apart are one outburst, and one shorter than [`MIN_ORBITS`] is
//!   noise. Each has its start, end, duration, peak Δm, the largest fraction of the disk on
//!   the hot branch, the largest disk radius R90 and the largest (one-orbit mean)
//!   eccentricity.
//! - **Superoutbursts.** An outburst during which the disk turned eccentric — its m = 1
//!   amplitude reached three times the circular disk's own (the 10% quantile of the run's
//!   one-orbit mean, at least [`SUPER_ECCENTRICITY`]: three times what the stream's
//!   lopsided impact alone holds; a coarse disk's particle noise holds more) — is a
//!   superoutburst; its light curve from the time e reached half
//!   its peak to the outburst's end is searched for the superhump (P_sh and ε, as
//!   `analyse superhump` does: `reports::lightcurve`, periods 0.8–1.5 P_orb).
//! - **Recurrence.** The intervals between successive outbursts' starts, in orbits, and in
//!   days: with the run's `binary.period_days`, or scaled to OY Car's P_orb = 0.0631209 d
//!   (exact-solutions.md, section 4) for a run in code units.
//!
//! Writes `outbursts.json` ([`OutburstFigures`]), the same under the key `outbursts` of
//! `summary.json`, and `outbursts.png` (Δm, the hot fraction and e against time).

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use plotters::style::RGBColor;
use serde::Serialize;

use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle, plot_panels};
use crate::reports::lightcurve::{self, LightcurveFigures};
use crate::reports::superhump::{self, ModesRow, running_mean};

/// Width of the running mean of the light curve, in orbits.
pub const SMOOTH_ORBITS: f64 = 1.0;
/// Orbits at the start left out of the quiescent level (the set-up relaxes).
pub const START_ORBITS: f64 = 2.0;
/// The quantile of the smoothed light taken as quiescence: the faint end, robust against
/// the few faintest rows.
pub const QUIESCENT_QUANTILE: f64 = 0.05;
/// An outburst is brighter than quiescence by at least this (magnitudes); dwarf-nova
/// outbursts are 2–5 mag.
pub const THRESHOLD_MAG: f64 = 1.0;
/// Bright stretches closer than this (orbits) are one outburst (a dip of the smoothed
/// light during the decline).
pub const MERGE_ORBITS: f64 = 2.0;
/// Bright stretches shorter than this (orbits) are not outbursts.
pub const MIN_ORBITS: f64 = 1.0;
/// The m = 1 amplitude (one-orbit mean) that makes an outburst a superoutburst: three
/// times the ~0.01 the stream's impact holds in a circular disk
/// (`superhump::ECCENTRIC_MIN` is the same bar).
pub const SUPER_ECCENTRICITY: f64 = superhump::ECCENTRIC_MIN;
/// OY Car's orbital period (days), the scale for runs in code units.
pub const OY_CAR_PERIOD_DAYS: f64 = 0.0631209;

/// One row of `monitor.csv` as the analysis uses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonitorRow {
    pub t: f64,
    pub disk_mass: f64,
    pub r_disk: f64,
    pub hot_mass: f64,
}

/// Parses `monitor.csv` (header `io::timeseries::MONITOR_HEADER`), keeping the rows of the
/// latest pass through each time (a resumed run).
pub fn parse_monitor(text: &str) -> Result<Vec<MonitorRow>> {
    Ok(crate::reports::cv_accretion::parse_ledger(text)?
        .into_iter()
        .map(|r| MonitorRow {
            t: r.t,
            disk_mass: r.disk_mass,
            r_disk: r.r_disk,
            hot_mass: r.hot_mass,
        })
        .collect())
}

/// One outburst.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Outburst {
    /// Start and end (orbits) and their difference.
    pub start_orbit: f64,
    pub end_orbit: f64,
    pub duration_orbits: f64,
    /// Peak brightness above quiescence (mag) and when.
    pub peak_mag: f64,
    pub peak_orbit: f64,
    /// The largest fraction of the disk's mass on the hot branch.
    pub hot_fraction_max: f64,
    /// The largest disk radius R90 (a).
    pub r_disk_max: f64,
    /// The largest one-orbit mean m = 1 amplitude.
    pub eccentricity_max: f64,
    /// Whether the disk turned eccentric ([`OutburstFigures::eccentricity_bar`]).
    pub superoutburst: bool,
    /// A superoutburst's superhump: P_sh (P_orb), ε and its error, amplitude (mag).
    pub superhump_period_orbits: Option<f64>,
    pub epsilon: Option<f64>,
    pub epsilon_err: Option<f64>,
    pub superhump_amplitude_mag: Option<f64>,
}

/// What `analyse outbursts` measures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutburstFigures {
    /// The analysed orbits.
    pub orbits: (f64, f64),
    /// The m = 1 amplitude an outburst's disk must reach to be a superoutburst's.
    pub eccentricity_bar: f64,
    /// Quiescent light L_q (code units).
    pub quiescent_light: f64,
    pub outbursts: Vec<Outburst>,
    pub normal_outbursts: usize,
    pub superoutbursts: usize,
    /// Intervals between successive outbursts' starts (orbits), and their mean.
    pub recurrence_orbits: Vec<f64>,
    pub mean_recurrence_orbits: Option<f64>,
    /// One orbit in days (the run's `binary.period_days`, or OY Car's), and what it is.
    pub days_per_orbit: f64,
    pub days_from: String,
    pub mean_recurrence_days: Option<f64>,
    /// Mean duration and peak of the normal outbursts (orbits, mag) and the superoutbursts.
    pub normal_duration_orbits: Option<f64>,
    pub normal_peak_mag: Option<f64>,
    pub super_duration_orbits: Option<f64>,
    pub super_peak_mag: Option<f64>,
    pub notes: Vec<String>,
}

/// Three times the circular disk's m = 1 amplitude — the 10% quantile of `e_smooth` (a
/// run spends more than a tenth of its time circular before any superoutburst) — and at
/// least [`SUPER_ECCENTRICITY`].
pub fn eccentricity_bar(e_smooth: &[f64]) -> f64 {
    let mut e: Vec<f64> = e_smooth.iter().copied().filter(|v| v.is_finite()).collect();
    if e.is_empty() {
        return SUPER_ECCENTRICITY;
    }
    e.sort_by(f64::total_cmp);
    let floor = e[(0.1 * (e.len() - 1) as f64).round() as usize];
    SUPER_ECCENTRICITY.max(3.0 * floor)
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// The brightness above quiescence (t in orbits, Δm) of the smoothed light curve, and L_q.
pub fn brightness(light: &[lightcurve::Row]) -> Result<(Vec<f64>, Vec<f64>, f64)> {
    let t: Vec<f64> = light.iter().map(|r| r.t / TAU).collect();
    let l: Vec<f64> = light.iter().map(|r| r.l_total).collect();
    let smooth = running_mean(&t, &l, 0.5 * SMOOTH_ORBITS);
    let t0 = t.first().copied().unwrap_or(0.0) + START_ORBITS;
    let mut late: Vec<f64> = t
        .iter()
        .zip(&smooth)
        .filter(|(ti, _)| **ti >= t0)
        .map(|(_, l)| *l)
        .collect();
    if late.len() < 20 {
        bail!(
            "lightcurve.csv: {} rows after the first {START_ORBITS} orbits; need at least 20",
            late.len()
        );
    }
    late.sort_by(f64::total_cmp);
    let lq = late[((late.len() - 1) as f64 * QUIESCENT_QUANTILE).round() as usize];
    if !(lq > 0.0) {
        bail!("lightcurve.csv: the quiescent light is {lq}; need a positive light curve");
    }
    let dm = smooth.iter().map(|l| 2.5 * (l / lq).log10()).collect();
    Ok((t, dm, lq))
}

/// The stretches (start, end) in orbits where `dm` exceeds [`THRESHOLD_MAG`], merged and
/// filtered as the module doc says.
pub fn bright_stretches(t: &[f64], dm: &[f64]) -> Vec<(f64, f64)> {
    let mut raw: Vec<(f64, f64)> = Vec::new();
    let mut open: Option<f64> = None;
    for (i, (&ti, &m)) in t.iter().zip(dm).enumerate() {
        match (open, m > THRESHOLD_MAG) {
            (None, true) => open = Some(ti),
            (Some(s), false) => {
                raw.push((s, t[i - 1]));
                open = None;
            }
            _ => {}
        }
    }
    if let (Some(s), Some(&end)) = (open, t.last()) {
        raw.push((s, end));
    }
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (s, e) in raw {
        match merged.last_mut() {
            Some(last) if s - last.1 < MERGE_ORBITS => last.1 = e,
            _ => merged.push((s, e)),
        }
    }
    merged.retain(|(s, e)| e - s >= MIN_ORBITS);
    merged
}

/// The whole analysis from the three series (module doc); `days_per_orbit` with what it
/// is.
pub fn analyse(
    light: &[lightcurve::Row],
    monitor: &[MonitorRow],
    modes: &[ModesRow],
    (days_per_orbit, days_from): (f64, String),
) -> Result<OutburstFigures> {
    let (t, dm, lq) = brightness(light)?;
    let stretches = bright_stretches(&t, &dm);
    let modes: Vec<&ModesRow> = modes.iter().filter(|r| r.m1.is_finite()).collect();
    let mt: Vec<f64> = modes.iter().map(|r| r.t / TAU).collect();
    let e_smooth = running_mean(
        &mt,
        &modes.iter().map(|r| r.m1).collect::<Vec<_>>(),
        0.5 * SMOOTH_ORBITS,
    );
    let eccentricity_bar = eccentricity_bar(&e_smooth);
    let mut notes = Vec::new();
    let mut outbursts = Vec::new();
    for &(s, e) in &stretches {
        let within = |x: f64| x >= s && x <= e;
        let (mut peak_mag, mut peak_orbit) = (f64::NEG_INFINITY, s);
        for (ti, m) in t.iter().zip(&dm) {
            if within(*ti) && *m > peak_mag {
                (peak_mag, peak_orbit) = (*m, *ti);
            }
        }
        let mon: Vec<&MonitorRow> = monitor.iter().filter(|r| within(r.t / TAU)).collect();
        let hot_fraction_max = mon
            .iter()
            .filter(|r| r.disk_mass > 0.0)
            .map(|r| r.hot_mass / r.disk_mass)
            .fold(0.0, f64::max);
        let r_disk_max = mon.iter().map(|r| r.r_disk).fold(0.0, f64::max);
        let e_in: Vec<(f64, f64)> = mt
            .iter()
            .zip(&e_smooth)
            .filter(|(ti, _)| within(**ti))
            .map(|(a, b)| (*a, *b))
            .collect();
        let eccentricity_max = e_in.iter().map(|p| p.1).fold(0.0, f64::max);
        let superoutburst = eccentricity_max >= eccentricity_bar;
        let mut ob = Outburst {
            start_orbit: s,
            end_orbit: e,
            duration_orbits: e - s,
            peak_mag,
            peak_orbit,
            hot_fraction_max,
            r_disk_max,
            eccentricity_max,
            superoutburst,
            superhump_period_orbits: None,
            epsilon: None,
            epsilon_err: None,
            superhump_amplitude_mag: None,
        };
        if superoutburst {
            let from = e_in
                .iter()
                .find(|p| p.1 >= 0.5 * eccentricity_max)
                .map_or(s, |p| p.0);
            let rows: Vec<lightcurve::Row> = light
                .iter()
                .filter(|r| r.t / TAU >= from && r.t / TAU <= e)
                .copied()
                .collect();
            match lightcurve::analyse_range(&rows, 0.0, true, superhump::PERIOD_RANGE) {
                Ok(LightcurveFigures {
                    period_orbits,
                    period_excess,
                    period_excess_err,
                    amplitude_mag,
                    ..
                }) => {
                    ob.superhump_period_orbits = Some(period_orbits);
                    ob.epsilon = Some(period_excess);
                    ob.epsilon_err = Some(period_excess_err);
                    ob.superhump_amplitude_mag = amplitude_mag;
                }
                Err(err) => notes.push(format!(
                    "superoutburst at orbit {s:.1}: no superhump period ({err:#})"
                )),
            }
        }
        outbursts.push(ob);
    }
    if let Some(first) = outbursts.first()
        && first.start_orbit <= t[0]
    {
        notes.push(format!(
            "an outburst is under way at the first row (orbit {:.1}): its start and duration are bounds",
            t[0]
        ));
    }
    if let Some(last) = outbursts.last()
        && t.last().is_some_and(|&end| last.end_orbit >= end)
    {
        notes.push(format!(
            "the outburst from orbit {:.1} lasts to the end of the run: its duration is a lower bound",
            last.start_orbit
        ));
    }
    let recurrence_orbits: Vec<f64> = outbursts
        .windows(2)
        .map(|w| w[1].start_orbit - w[0].start_orbit)
        .collect();
    let mean_recurrence_orbits = mean(&recurrence_orbits);
    let pick = |sup: bool, f: fn(&Outburst) -> f64| -> Option<f64> {
        mean(
            &outbursts
                .iter()
                .filter(|o| o.superoutburst == sup)
                .map(f)
                .collect::<Vec<_>>(),
        )
    };
    if outbursts.is_empty() {
        notes.push(format!(
            "no outburst: the one-orbit mean light never rose {THRESHOLD_MAG} mag above quiescence"
        ));
    }
    Ok(OutburstFigures {
        eccentricity_bar,
        orbits: (t[0], t[t.len() - 1]),
        quiescent_light: lq,
        normal_outbursts: outbursts.iter().filter(|o| !o.superoutburst).count(),
        superoutbursts: outbursts.iter().filter(|o| o.superoutburst).count(),
        mean_recurrence_days: mean_recurrence_orbits.map(|r| r * days_per_orbit),
        recurrence_orbits,
        mean_recurrence_orbits,
        days_per_orbit,
        days_from,
        normal_duration_orbits: pick(false, |o| o.duration_orbits),
        normal_peak_mag: pick(false, |o| o.peak_mag),
        super_duration_orbits: pick(true, |o| o.duration_orbits),
        super_peak_mag: pick(true, |o| o.peak_mag),
        outbursts,
        notes,
    })
}

/// What `analyse outbursts` found and wrote.
pub struct OutburstReport {
    pub run: PathBuf,
    pub figures: OutburstFigures,
    pub files: Vec<PathBuf>,
}

fn read(run: &Path, name: &str, what: &str) -> Result<String> {
    let path = run.join(name);
    std::fs::read_to_string(&path).with_context(|| {
        format!(
            "{}: cannot read {what} (written by cv runs)",
            path.display()
        )
    })
}

/// Reads a run's series and `run.toml`, analyses them, writes `outbursts.json`,
/// `outbursts.png` and the `outbursts` key of `summary.json`.
pub fn analyse_outbursts(run: &Path) -> Result<OutburstReport> {
    let light = lightcurve::parse_lightcurve(&read(run, "lightcurve.csv", "the light curve")?)
        .with_context(|| run.join("lightcurve.csv").display().to_string())?;
    let (light, _) = lightcurve::supersede(&light);
    let monitor = parse_monitor(&read(run, "monitor.csv", "the disk's monitor")?)
        .with_context(|| run.join("monitor.csv").display().to_string())?;
    let modes = superhump::parse_modes(&read(run, "modes.csv", "the disk's modes")?)
        .with_context(|| run.join("modes.csv").display().to_string())?;
    let lightcurve::RunBinary {
        period_days: days,
        note,
        ..
    } = lightcurve::binary_of(run);
    let scale = match days {
        Some(d) => (d, "binary.period_days of run.toml".to_string()),
        None => (
            OY_CAR_PERIOD_DAYS,
            "OY Car's orbital period (the run is in code units)".to_string(),
        ),
    };
    let mut f =
        analyse(&light, &monitor, &modes, scale).with_context(|| run.display().to_string())?;
    f.notes.extend(note);
    let png = run.join("outbursts.png");
    plot_panels(&png, (1800, 1000), &panels(&light, &monitor, &modes, &f)?)?;
    let json = crate::io::summary::write_analysis(run, "outbursts", "outbursts", &f)?;
    Ok(OutburstReport {
        run: run.to_path_buf(),
        figures: f,
        files: vec![png, json],
    })
}

impl OutburstReport {
    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let f = &self.figures;
        let mut s = format!(
            "{}: orbits {:.1} to {:.1}, {} normal outburst(s), {} superoutburst(s)\n",
            self.run.display(),
            f.orbits.0,
            f.orbits.1,
            f.normal_outbursts,
            f.superoutbursts
        );
        for o in &f.outbursts {
            s += &format!(
                "  {} orbits {:.1}–{:.1} ({:.1} orbits, {:.2} d): peak {:.2} mag at {:.1}, hot ≤ {:.0}%, R90 ≤ {:.3}, e ≤ {:.3}{}\n",
                if o.superoutburst {
                    "superoutburst"
                } else {
                    "outburst     "
                },
                o.start_orbit,
                o.end_orbit,
                o.duration_orbits,
                o.duration_orbits * f.days_per_orbit,
                o.peak_mag,
                o.peak_orbit,
                100.0 * o.hot_fraction_max,
                o.r_disk_max,
                o.eccentricity_max,
                match (o.superhump_period_orbits, o.epsilon, o.epsilon_err) {
                    (Some(p), Some(e), Some(err)) => format!(
                        "; superhump P_sh = {p:.4} P_orb, ε = {}",
                        lightcurve::plus_minus(e, err)
                    ),
                    _ => String::new(),
                }
            );
        }
        if let (Some(r), Some(d)) = (f.mean_recurrence_orbits, f.mean_recurrence_days) {
            s += &format!(
                "  mean recurrence {r:.1} orbits = {d:.2} d ({} d per orbit: {})\n",
                f.days_per_orbit, f.days_from
            );
        }
        for n in &f.notes {
            s += &format!("  note: {n}\n");
        }
        s
    }
}

const BLACK: RGBColor = RGBColor(0, 0, 0);
const GREY: RGBColor = RGBColor(140, 140, 140);
const RED: RGBColor = RGBColor(200, 30, 30);

fn panels(
    light: &[lightcurve::Row],
    monitor: &[MonitorRow],
    modes: &[ModesRow],
    f: &OutburstFigures,
) -> Result<Vec<Panel>> {
    let (t, dm, _) = brightness(light)?;
    let (a, b) = f.orbits;
    let raw: Vec<(f64, f64)> = light
        .iter()
        .map(|r| (r.t / TAU, 2.5 * (r.l_total / f.quiescent_light).log10()))
        .filter(|p| p.1.is_finite())
        .collect();
    let top = raw.iter().map(|p| p.1).fold(THRESHOLD_MAG, f64::max) + 0.3;
    let bottom = raw.iter().map(|p| p.1).fold(0.0, f64::min).max(-2.0) - 0.2;
    let mut light_series = vec![
        Series {
            label: Some("dissipation light".into()),
            points: raw,
            color: GREY,
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("one-orbit mean".into()),
            points: t.iter().copied().zip(dm).collect(),
            color: BLACK,
            style: SeriesStyle::Line,
        },
        Series {
            label: Some(format!("outburst threshold {THRESHOLD_MAG} mag")),
            points: vec![(a, THRESHOLD_MAG), (b, THRESHOLD_MAG)],
            color: PALETTE[2],
            style: SeriesStyle::Dashed,
        },
    ];
    let peaks: Vec<(f64, f64)> = f
        .outbursts
        .iter()
        .filter(|o| o.superoutburst)
        .map(|o| (o.peak_orbit, o.peak_mag))
        .collect();
    if !peaks.is_empty() {
        light_series.push(Series {
            label: Some("superoutburst peak".into()),
            points: peaks,
            color: RED,
            style: SeriesStyle::Markers,
        });
    }
    let hot: Vec<(f64, f64)> = monitor
        .iter()
        .filter(|r| r.disk_mass > 0.0)
        .map(|r| (r.t / TAU, r.hot_mass / r.disk_mass))
        .collect();
    let rows: Vec<&ModesRow> = modes.iter().filter(|r| r.m1.is_finite()).collect();
    let mt: Vec<f64> = rows.iter().map(|r| r.t / TAU).collect();
    let e: Vec<f64> = running_mean(
        &mt,
        &rows.iter().map(|r| r.m1).collect::<Vec<_>>(),
        0.5 * SMOOTH_ORBITS,
    );
    let r_disk: Vec<(f64, f64)> = monitor.iter().map(|r| (r.t / TAU, r.r_disk)).collect();
    Ok(vec![
        Panel {
            title: format!(
                "light curve: {} outburst(s), {} superoutburst(s); 1 orbit = {:.4} d",
                f.normal_outbursts, f.superoutbursts, f.days_per_orbit
            ),
            x_label: "orbit (t / P_orb)".into(),
            y_label: "brightness above quiescence (mag)".into(),
            x_range: (a, b.max(a + 1e-9)),
            y_range: (bottom, top),
            series: light_series,
        },
        Panel {
            title: "the disk: hot-branch mass fraction, eccentricity (m = 1), radius R90 (a)"
                .into(),
            x_label: "orbit (t / P_orb)".into(),
            y_label: "fraction / e / R90".into(),
            x_range: (a, b.max(a + 1e-9)),
            y_range: (0.0, 1.0),
            series: vec![
                Series {
                    label: Some("hot fraction".into()),
                    points: hot,
                    color: RED,
                    style: SeriesStyle::Line,
                },
                Series {
                    label: Some("e (one-orbit mean)".into()),
                    points: mt.into_iter().zip(e).collect(),
                    color: PALETTE[1],
                    style: SeriesStyle::Line,
                },
                Series {
                    label: Some("R90 (a)".into()),
                    points: r_disk,
                    color: PALETTE[3],
                    style: SeriesStyle::Line,
                },
            ],
        },
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A light curve (one row per P_orb/50) of quiescence L = 1 with outbursts given as
    /// (start, rise, plateau, decline, peak L) in orbits, and a superhump modulation of
    /// relative amplitude `sh` at period `p_sh` during the ones marked super.
    fn synthetic(
        orbits: f64,
        bursts: &[(f64, f64, f64, f64, f64, bool)],
        p_sh: f64,
        sh: f64,
    ) -> (Vec<lightcurve::Row>, Vec<MonitorRow>, Vec<ModesRow>) {
        let n = (orbits * 50.0) as usize;
        let mut light = Vec::new();
        let mut monitor = Vec::new();
        let mut modes = Vec::new();
        for k in 0..n {
            let o = k as f64 / 50.0;
            let mut l = 1.0;
            let mut e = 0.01;
            let mut hot = 0.0;
            for &(s, rise, plateau, decline, peak, sup) in bursts {
                let x = o - s;
                let f = if x < 0.0 {
                    0.0
                } else if x < rise {
                    x / rise
                } else if x < rise + plateau {
                    1.0
                } else if x < rise + plateau + decline {
                    1.0 - (x - rise - plateau) / decline
                } else {
                    0.0
                };
                l += (peak - 1.0) * f;
                hot += f;
                if sup && f > 0.0 {
                    e += 0.15 * f;
                    l *= 1.0 + sh * f * (TAU * o / p_sh).sin();
                }
            }
            let t = o * TAU;
            light.push(lightcurve::Row {
                t,
                orbit: o,
                l_total: l,
                l_disk: l,
                l_stream: 0.0,
                l_spot: 0.0,
                l_observed: 0.0,
            });
            monitor.push(MonitorRow {
                t,
                disk_mass: 1.0,
                r_disk: 0.4,
                hot_mass: hot,
            });
            modes.push(ModesRow {
                t,
                r_disk: 0.4,
                m1: e,
                m1_phase_deg: 0.0,
                m2: 0.0,
                e,
                periastron_inertial_deg: 0.0,
            });
        }
        (light, monitor, modes)
    }

    #[test]
    fn finds_normal_outbursts_and_a_superoutburst_with_its_superhump() {
        // Two normal outbursts of 3 mag (L = 10^1.2 = 15.85) every 40 orbits, then a
        // superoutburst of 3.5 mag lasting 30 orbits with a 3% superhump at P_sh = 1.03.
        let peak = 10f64.powf(0.4 * 3.0);
        let sup = 10f64.powf(0.4 * 3.5);
        let bursts = [
            (10.0, 1.0, 4.0, 3.0, peak, false),
            (50.0, 1.0, 4.0, 3.0, peak, false),
            (90.0, 1.0, 25.0, 4.0, sup, true),
        ];
        let (light, monitor, modes) = synthetic(140.0, &bursts, 1.03, 0.1);
        let f = analyse(&light, &monitor, &modes, (0.0631209, "test".into())).unwrap();
        assert_eq!((f.normal_outbursts, f.superoutbursts), (2, 1), "{f:#?}");
        // Quiescence is L = 1: the 5% quantile of the smoothed light is exactly 1.
        assert!((f.quiescent_light - 1.0).abs() < 1e-12);
        // Peaks: the one-orbit mean of a 4-orbit plateau reaches the plateau, 3.0 mag.
        for o in &f.outbursts[..2] {
            assert!((o.peak_mag - 3.0).abs() < 1e-9, "{o:?}");
        }
        // The threshold (1 mag, L = 2.51) is crossed on the linear rise and decline of the
        // smoothed light: starts within one orbit of the set start.
        let starts: Vec<f64> = f.outbursts.iter().map(|o| o.start_orbit).collect();
        for (s, b) in starts.iter().zip(&bursts) {
            assert!((s - b.0).abs() < 1.0, "{starts:?}");
        }
        // Recurrence 40 orbits (to the threshold's sampling, 1/50 orbit).
        assert!((f.recurrence_orbits[0] - 40.0).abs() < 0.05, "{f:#?}");
        assert!((f.mean_recurrence_days.unwrap() - 40.0 * 0.0631209).abs() < 0.01);
        // The superoutburst lasts ~27 orbits above 1 mag, the normal ones ~6.
        let s = &f.outbursts[2];
        assert!(
            s.duration_orbits > 25.0 && s.duration_orbits < 31.0,
            "{s:?}"
        );
        assert!(f.normal_duration_orbits.unwrap() < 8.0);
        // Its superhump: ε = 0.03 recovered within 3σ, with σ below 0.005.
        let (e, err) = (s.epsilon.unwrap(), s.epsilon_err.unwrap());
        assert!(
            err < 5e-3 && (e - 0.03).abs() < 3.0 * err.max(1e-4),
            "{e} ± {err}"
        );
    }

    #[test]
    fn a_coarse_disks_noise_does_not_make_a_normal_outburst_super() {
        // A coarse disk: the circular disk's m = 1 noise is 0.02 (not 0.01) and a normal
        // outburst lifts it to 0.04 — past SUPER_ECCENTRICITY = 0.03, not past three times
        // the run's own floor (0.06); the superoutburst's eccentric disk (0.17) is.
        let peak = 10f64.powf(0.4 * 3.0);
        let bursts = [
            (10.0, 1.0, 4.0, 3.0, peak, false),
            (50.0, 1.0, 4.0, 3.0, peak, false),
            (90.0, 1.0, 25.0, 4.0, 10f64.powf(0.4 * 3.5), true),
        ];
        let (light, monitor, mut modes) = synthetic(140.0, &bursts, 1.03, 0.1);
        for (m, r) in modes.iter_mut().zip(&monitor) {
            let in_super = m.m1 > 0.01 + 1e-12;
            m.m1 += 0.01;
            if !in_super {
                m.m1 += 0.02 * r.hot_mass;
            }
        }
        let f = analyse(&light, &monitor, &modes, (0.0631209, "test".into())).unwrap();
        assert!(
            (f.eccentricity_bar - 0.06).abs() < 1e-9,
            "{}",
            f.eccentricity_bar
        );
        assert_eq!((f.normal_outbursts, f.superoutbursts), (2, 1), "{f:#?}");
        assert!(f.outbursts[..2].iter().all(|o| o.eccentricity_max > 0.039));
    }

    #[test]
    fn a_quiet_light_curve_has_no_outbursts() {
        let (light, monitor, modes) =
            synthetic(60.0, &[(20.0, 1.0, 2.0, 1.0, 2.0, false)], 1.0, 0.0);
        // 2× quiescence is 0.75 mag: below the 1-mag bar.
        let f = analyse(&light, &monitor, &modes, (1.0, "test".into())).unwrap();
        assert!(f.outbursts.is_empty(), "{f:#?}");
        assert!(f.notes.iter().any(|n| n.contains("no outburst")));
    }

    #[test]
    fn close_bright_stretches_merge_and_short_ones_drop() {
        let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.1).collect();
        let dm: Vec<f64> = t
            .iter()
            .map(|&x| {
                if (10.0..20.0).contains(&x)
                    || (21.0..25.0).contains(&x)
                    || (50.0..50.5).contains(&x)
                {
                    2.0
                } else {
                    0.0
                }
            })
            .collect();
        let s = bright_stretches(&t, &dm);
        assert_eq!(s.len(), 1, "{s:?}");
        assert!((s[0].0 - 10.0).abs() < 1e-9 && (s[0].1 - 24.9).abs() < 1e-9);
    }
}
