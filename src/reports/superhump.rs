//! `sphdisk analyse superhump <run>...`: the SU UMa superhump of a cataclysmic-variable run
//! (paper, Section 4, Figure 6; exact-solutions.md 4b) from the two time series the run
//! writes, `modes.csv` (the disk's m = 1 and m = 2 modes) and `lightcurve.csv`.
//!
//! - **Eccentricity.** e(t) is the m = 1 amplitude of the disk mass in the window
//!   [0.5, 1.0) R90 (`problems::cv::ECCENTRICITY_WINDOW`: for a ring on a Kepler
//!   ellipse it is the ellipse's e), smoothed over one orbit ([`SMOOTH_ORBITS`]). Its peak
//!   is its largest value after the first [`START_ORBITS`]; the onset the first time it
//!   reaches half the peak; its floor the least value before the onset. The disk counts as
//!   eccentric when the peak is at least [`ECCENTRIC_MIN`] and three times the floor, and e
//!   stays above half the peak for [`MIN_ACTIVE_ORBITS`] or more. The active stretch runs
//!   from the first time e reaches 0.8 of the peak to the last time it is above half of it:
//!   a disk fed steadily stays eccentric to the end of the run, one that shrinks inside
//!   r_3:1 (the stream too weak to hold it there, or the tides of a heavier donor) loses
//!   the mode again, and its superhump fades as at the end of a superoutburst. The
//!   saturated e is the median over the active stretch. The growth rate γ is that of a
//!   logistic, de/dt = γ e (1 − e/e_peak) — exponential growth at γ while e ≪ e_peak,
//!   saturating at e_peak — whose ln(e/(e_peak − e)) is exactly γ t + const: the slope of
//!   that against time between the last time e was below max(e_peak/8, 1.5 floor) and the
//!   first time it reached 0.7 e_peak (a plain slope of ln e there would read 0.6 γ, bent by
//!   the saturation).
//! - **Precession.** The longitude of periastron in the inertial frame, ϖ = (the m = 1
//!   phase, which points to apoastron) + 180° + Ω t, unwrapped over the active stretch; a
//!   straight-line fit gives ω_p in units of Ω_orb. Its error is the scatter of the slopes
//!   of four equal blocks over √4 — the phase noise is correlated from row to row, so the
//!   formal least-squares error would be
//!   optimistic. The beat of the precession with the orbit has the period
//!   P_beat = P_orb/(1 − ω_p), ε_beat = ω_p/(1 − ω_p). The osculating eccentricity vector's
//!   longitude (`modes.csv` `periastron_inertial_deg`) gives a second rate, reported beside
//!   it. In a strongly distorted disk (e ≳ 0.4 with a large m = 2) the m = 1 phase of the
//!   mass in the window stops following the periastron and flips with the binary's tide;
//!   a longitude more than 1% of whose row-to-row steps exceed 45° ([`JUMP_DEG`],
//!   [`MAX_JUMP_FRACTION`]) is not a periastron, and the rate is then the osculating one
//!   (`source` says which; a note says why). So is one whose longitude wanders more than
//!   [`MAX_SLIP_DEG`] from the osculating one's: where the disk is strongly distorted for a
//!   while, the m = 1 pattern can turn with the binary in steps smaller than a jump and
//!   slip whole turns. Where both follow the periastron but
//!   disagree by more than 10% and three errors, a note says so.
//! - **Light curve.** The dissipation light curve of the same active stretch, its
//!   periodogram searched between [`PERIOD_RANGE`] P_orb with a floating cubic trend
//!   (`reports::lightcurve`): the superhump period P_sh with its error,
//!   ε = (P_sh − P_orb)/P_orb, the modulation's semi-amplitude relative to the trend and its
//!   peak-to-peak amplitude in magnitudes.
//! - **The hump against the apsidal line** (`reports::hump_phase`): the phase of the light
//!   curve's modulation against the turning-frame longitude of periastron, in windows of a
//!   few orbits; its drift per orbit and the ε that the beat and the drift predict together
//!   (a hump that moves along the beat cycle makes P_sh differ from the beat; a note says so
//!   where they differ by more than three errors).
//! - **Beside them:** the dynamical ε of the precession at r_3:1 and at the disk's radius
//!   (R90) at the onset (Hirose & Osaki 1990, `analysis::roche::precession_rate`), and the
//!   observed relations ε(q) of Patterson et al. (2005) and Kato et al. (2009).
//!
//! Writes into the run folder `superhump.json` ([`SuperhumpFigures`]), the same under the key
//! `superhump` of `summary.json` where the run has one, and `superhump_eccentricity.png`,
//! `superhump_precession.png`, `superhump_lightcurve.png`, `superhump_periodogram.png`.
//! Given several runs and `--out DIR`, it also writes the series' table
//! (`superhump_scan.csv`) and ε against q (`superhump_scan.png`) with the observed
//! relations and the dynamical ε at r_3:1.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use plotters::style::RGBColor;
use serde::Serialize;

use crate::analysis::roche;
use crate::io::atomic::write_atomic;
use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle, plot_panels};
use crate::reports::hump_phase::{HumpPhase, hump_phase};
use crate::reports::lightcurve::{self, LightcurveFigures};

/// Header of `modes.csv`.
pub const HEADER: &str = crate::io::timeseries::MODES_HEADER;
/// Width of the running mean of e, in orbits.
pub const SMOOTH_ORBITS: f64 = 1.0;
/// The least saturated m = 1 amplitude called eccentric. A disk of N particles placed at
/// random has an m = 1 amplitude of about 0.9/√N (0.02 for 2000 in the window); the ring
/// lattice of `[initial_disk]` starts at round-off, and the stream's lopsided impact
/// alone holds the amplitude near 0.01 (measured in the first orbits of
/// `problems/superhump.toml`).
pub const ECCENTRIC_MIN: f64 = 0.03;
/// Orbits at the start of a run left out of the search for the peak, the onset and the
/// floor: the set-up relaxes
/// (the stream's first impact, the edges of an initial disk) and lifts the m = 1 amplitude
/// for about an orbit.
pub const START_ORBITS: f64 = 2.0;
/// The shortest stretch (orbits, onset to the last time above half the peak) called an
/// eccentric disk: enough superhump cycles to measure.
pub const MIN_ACTIVE_ORBITS: f64 = 5.0;
/// Periods searched in the light curve, in P_orb: superhumps lie within a few tens of per
/// cent of the orbit (observed ε from −(negative superhumps) to +10%).
pub const PERIOD_RANGE: (f64, f64) = (0.8, 1.5);

/// One line of `modes.csv` (NaN where the window held no disk gas).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModesRow {
    pub t: f64,
    pub r_disk: f64,
    pub m1: f64,
    pub m1_phase_deg: f64,
    pub m2: f64,
    pub e: f64,
    pub periastron_inertial_deg: f64,
}

/// Parses `modes.csv`: the header must be [`HEADER`]; an unfinished last line (a run still
/// writing) is ignored; rows whose time does not increase replace the earlier rows from
/// that time on (a resumed run).
pub fn parse_modes(text: &str) -> Result<Vec<ModesRow>> {
    let rows = crate::io::timeseries::parse_series(text, HEADER, true)?
        .into_iter()
        .map(|v| ModesRow {
            t: v[0],
            r_disk: v[2],
            m1: v[4],
            m1_phase_deg: v[5],
            m2: v[6],
            e: v[8],
            periastron_inertial_deg: v[10],
        });
    Ok(crate::io::timeseries::supersede(rows, |r| r.t))
}

/// The eccentricity's growth, saturation and (where the disk shrinks) decay.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Growth {
    /// The m = 1 amplitude (smoothed) before the onset, at its least.
    pub e_floor: f64,
    /// Its largest value after the first [`START_ORBITS`] orbits, and when.
    pub e_peak: f64,
    pub peak_orbit: f64,
    /// Its median over the active stretch ([`Growth::active_orbits`]).
    pub e_saturated: f64,
    /// The mean osculating eccentricity over the same stretch (a second measure).
    pub e_osculating_saturated: f64,
    /// The m = 2 amplitude over the same stretch (the tidal response).
    pub m2_saturated: f64,
    /// The m = 1 amplitude's median over the last quarter of the run.
    pub e_end: f64,
    pub eccentric: bool,
    /// The mode had faded by the end: e_end below half the peak.
    pub faded: bool,
    /// First time (orbits) e reached half its peak.
    pub onset_orbit: Option<f64>,
    /// The disk's radius R90 at the onset.
    pub r_disk_at_onset: Option<f64>,
    /// The logistic growth rate per orbit, and its e-folding time.
    pub growth_rate_per_orbit: Option<f64>,
    pub e_folding_orbits: Option<f64>,
    /// The stretch fitted, in orbits.
    pub growth_fit_orbits: Option<(f64, f64)>,
    /// The stretch (orbits) over which the precession and the superhump are measured: from
    /// the first time e reached 0.8 of its peak to the last time it was above half of it
    /// (the second half of the run if the disk did not turn eccentric).
    pub active_orbits: (f64, f64),
}

/// The precession of the eccentric disk.
#[derive(Clone, Debug, Serialize)]
pub struct Precession {
    /// ω_p / Ω_orb, and its error (four blocks), from the longitude named by `source`.
    pub rate: f64,
    pub rate_err: f64,
    pub source: PrecessionSource,
    /// The slope of the m = 1 phase's longitude, its error, and the share of its
    /// row-to-row steps that jump by more than [`JUMP_DEG`].
    pub rate_m1_phase: f64,
    pub rate_m1_phase_err: f64,
    pub m1_phase_jumps: f64,
    /// How far the m = 1 phase's longitude wanders from the osculating one's over the
    /// stretch (2%–98% range of their difference, degrees; NaN where the osculating one
    /// does not follow the periastron).
    pub m1_phase_slip_deg: f64,
    /// The same from the osculating eccentricity vector's longitude.
    pub rate_osculating: f64,
    pub rate_osculating_err: f64,
    pub osculating_jumps: f64,
    /// P_beat / P_orb = 1/(1 − ω_p) and ε_beat = ω_p/(1 − ω_p), with errors.
    pub beat_period_orbits: f64,
    pub epsilon_beat: f64,
    pub epsilon_beat_err: f64,
    /// Prograde turns of the periastron over the stretch.
    pub turns: f64,
    pub orbits: (f64, f64),
    /// (orbit, unwrapped longitude of periastron in degrees) of the rows fitted, for the
    /// picture.
    #[serde(skip)]
    pub points: Vec<(f64, f64)>,
}

/// The expected period excesses for the run's q.
#[derive(Clone, Debug, Serialize)]
pub struct Predictions {
    pub q: f64,
    pub r_31: f64,
    pub tidal_radius: f64,
    /// ε of the dynamical precession at r_3:1 and at R90 at the onset.
    pub epsilon_dynamical_r31: f64,
    pub epsilon_dynamical_r_disk: Option<f64>,
    /// Observed ε(q): Patterson et al. (2005), Kato et al. (2009).
    pub epsilon_patterson2005: f64,
    pub epsilon_kato2009: f64,
}

/// What `analyse superhump` measured.
#[derive(Clone, Debug, Serialize)]
pub struct SuperhumpFigures {
    pub orbits: (f64, f64),
    pub growth: Growth,
    pub precession: Option<Precession>,
    /// The light curve over the saturated stretch.
    pub lightcurve: Option<LightcurveFigures>,
    /// P_sh/P_orb, ε = P_sh/P_orb − 1 and their error; the modulation (relative
    /// semi-amplitude, peak-to-peak magnitudes).
    pub superhump_period_orbits: Option<f64>,
    pub epsilon: Option<f64>,
    pub epsilon_err: Option<f64>,
    pub amplitude_rel: Option<f64>,
    pub amplitude_mag: Option<f64>,
    /// (P_sh − P_beat)/P_sh: the light curve's period against the beat of the measured
    /// precession with the orbit.
    pub beat_mismatch: Option<f64>,
    /// The hump's phase against the apsidal line, its drift, and the ε the beat and the
    /// drift predict together (`reports::hump_phase`).
    pub hump_phase: Option<HumpPhase>,
    pub predictions: Option<Predictions>,
    pub notes: Vec<String>,
}

/// Running mean of `y` over ±`half` in `t` (both sorted by t; NaN values skipped).
pub(crate) fn running_mean(t: &[f64], y: &[f64], half: f64) -> Vec<f64> {
    let (mut lo, mut hi) = (0, 0);
    let (mut sum, mut n) = (0.0, 0usize);
    let mut out = Vec::with_capacity(t.len());
    for i in 0..t.len() {
        while hi < t.len() && t[hi] <= t[i] + half {
            if y[hi].is_finite() {
                sum += y[hi];
                n += 1;
            }
            hi += 1;
        }
        while t[lo] < t[i] - half {
            if y[lo].is_finite() {
                sum -= y[lo];
                n -= 1;
            }
            lo += 1;
        }
        out.push(if n > 0 { sum / n as f64 } else { f64::NAN });
    }
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Least-squares line y = a + b x: (a, b).
pub(crate) fn line_fit(x: &[f64], y: &[f64]) -> Option<(f64, f64)> {
    let n = x.len() as f64;
    if x.len() < 2 {
        return None;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    (sxx > 0.0).then(|| (my - sxy / sxx * mx, sxy / sxx))
}

/// Unwraps angles in degrees (steps below 180° in size are taken as the path).
pub(crate) fn unwrap_deg(a: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(a.len());
    let mut offset = 0.0;
    for (k, &x) in a.iter().enumerate() {
        if k > 0 {
            let prev = a[k - 1];
            let d = x - prev;
            if d > 180.0 {
                offset -= 360.0;
            } else if d < -180.0 {
                offset += 360.0;
            }
        }
        out.push(x + offset);
    }
    out
}

/// The growth of e (module doc). `t` in orbits.
pub fn growth(t: &[f64], m1: &[f64], osc: &[f64], m2: &[f64], r_disk: &[f64]) -> Growth {
    let es = running_mean(t, m1, 0.5 * SMOOTH_ORBITS);
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let median_over = |y: &[f64], lo: f64, hi: f64| {
        median(
            t.iter()
                .zip(y)
                .filter(|(tt, _)| (lo..=hi).contains(*tt))
                .map(|(_, v)| *v)
                .collect(),
        )
    };
    let e_end = median_over(&es, t1 - 0.25 * (t1 - t0), t1);
    let mut g = Growth {
        e_end,
        active_orbits: (t0 + 0.5 * (t1 - t0), t1),
        ..Growth::default()
    };
    let from = t.partition_point(|x| *x < t0 + START_ORBITS);
    let Some(peak) = (from..es.len())
        .filter(|&k| es[k].is_finite())
        .max_by(|&a, &b| es[a].total_cmp(&es[b]))
    else {
        return g;
    };
    let e_peak = es[peak];
    (g.e_peak, g.peak_orbit) = (e_peak, t[peak]);
    // The onset, floor and fit are searched after the set-up's relaxation as the peak is:
    // a transient in the first orbits must not stand for the floor. The first row there at
    // `share` of the peak (the peak itself qualifies).
    let first_at = |share: f64| {
        from + es[from..=peak]
            .iter()
            .position(|e| *e >= share * e_peak)
            .unwrap_or(peak - from)
    };
    let onset = first_at(0.5);
    g.e_floor = es[from..onset.max(from + 1)]
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(f64::INFINITY, f64::min);
    let start = first_at(0.8);
    let end = es.iter().rposition(|e| *e >= 0.5 * e_peak).unwrap_or(peak);
    g.eccentric = e_peak >= ECCENTRIC_MIN
        && e_peak >= 3.0 * g.e_floor
        && t[end] - t[onset] >= MIN_ACTIVE_ORBITS;
    g.faded = e_end < 0.5 * e_peak;
    let stretch = |y: &[f64]| median_over(y, t[start], t[end]);
    if !g.eccentric {
        return g;
    }
    g.active_orbits = (t[start], t[end]);
    g.e_saturated = stretch(&es);
    g.e_osculating_saturated = stretch(&running_mean(t, osc, 0.5 * SMOOTH_ORBITS));
    g.m2_saturated = stretch(&running_mean(t, m2, 0.5 * SMOOTH_ORBITS));
    g.onset_orbit = Some(t[onset]);
    g.r_disk_at_onset = r_disk[onset].is_finite().then_some(r_disk[onset]);
    let low = (e_peak / 8.0).max(1.5 * g.e_floor);
    let a = from + es[from..onset].iter().rposition(|e| *e <= low).unwrap_or(0);
    let b = first_at(0.7);
    // The logistic de/dt = γ e (1 − e/e_peak) has ln(e/(e_peak − e)) = γ t + const exactly.
    let (x, y): (Vec<f64>, Vec<f64>) = (a..=b)
        .filter(|&k| es[k] > 0.0 && es[k] < e_peak)
        .map(|k| (t[k], (es[k] / (e_peak - es[k])).ln()))
        .unzip();
    if x.len() >= 5
        && let Some((_, rate)) = line_fit(&x, &y)
        && rate > 0.0
    {
        g.growth_rate_per_orbit = Some(rate);
        g.e_folding_orbits = Some(1.0 / rate);
        g.growth_fit_orbits = Some((t[a], t[b]));
    }
    g
}

/// Which longitude the precession rate was taken from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PrecessionSource {
    /// The m = 1 phase of the disk mass (+ 180°).
    M1Phase,
    /// The osculating eccentricity vector's longitude.
    Osculating,
}

impl PrecessionSource {
    /// Words for the printed summary and the picture.
    pub fn describe(self) -> &'static str {
        match self {
            PrecessionSource::M1Phase => "m = 1 phase",
            PrecessionSource::Osculating => "osculating periastron",
        }
    }
}

/// A row-to-row step of a longitude larger than this (degrees, inertial frame, after
/// unwrapping by the shortest way) is a jump: a periastron precessing at a few per cent of
/// Ω_orb moves by a degree or less between rows written every few hundredths of an orbit.
pub const JUMP_DEG: f64 = 45.0;

/// A longitude whose steps are jumps more often than this does not follow the periastron.
pub const MAX_JUMP_FRACTION: f64 = 0.01;

/// The m = 1 phase follows the periastron only while its longitude stays within this many
/// degrees of the osculating one's (the range of their difference): a slip of half a turn
/// or more is the m = 1 pattern turning with the binary for a while, in steps too small to
/// count as jumps (a tide-held pattern moves 7° per row at 50 rows per orbit). Eccentric
/// disks whose two longitudes agree wander 44–68° (3D and 2D runs of `superhump.toml`,
/// 1–5 turns); the supercycle run whose m = 1 phase slipped, 3 292°.
pub const MAX_SLIP_DEG: f64 = 180.0;

/// A straight line fitted to one unwrapped longitude track (degrees against time).
#[derive(Clone, Debug)]
struct Track {
    unwrapped: Vec<f64>,
    /// Slope in Ω_orb, and its error from four blocks.
    rate: f64,
    rate_err: f64,
    /// The share of row-to-row steps larger than [`JUMP_DEG`].
    jumps: f64,
}

impl Track {
    fn fit(t: &[f64], deg: &[f64]) -> Option<Track> {
        let unwrapped = unwrap_deg(deg);
        let rad: Vec<f64> = unwrapped.iter().map(|x| x.to_radians()).collect();
        let (_, rate) = line_fit(t, &rad)?;
        let blocks = 4;
        let len = t.len() / blocks;
        let slopes: Vec<f64> = (0..blocks)
            .filter_map(|k| {
                let r = k * len..(k + 1) * len;
                line_fit(&t[r.clone()], &rad[r]).map(|f| f.1)
            })
            .collect();
        let jumps = unwrapped
            .windows(2)
            .filter(|w| (w[1] - w[0]).abs() > JUMP_DEG)
            .count() as f64
            / (unwrapped.len() - 1) as f64;
        Some(Track {
            unwrapped,
            rate,
            rate_err: crate::analysis::standard_error(&slopes),
            jumps,
        })
    }

    fn follows_periastron(&self) -> bool {
        self.jumps <= MAX_JUMP_FRACTION && self.rate.is_finite() && self.rate_err.is_finite()
    }
}

/// The precession over the rows with `from` ≤ t ≤ `to` (orbits; module doc): from the m = 1
/// phase where it follows the periastron, else from the osculating eccentricity vector's
/// longitude; `None` where neither does (or fewer than 20 rows).
pub fn precession(rows: &[ModesRow], from: f64, to: f64) -> Option<Precession> {
    let used: Vec<&ModesRow> = rows
        .iter()
        .filter(|r| (from..=to).contains(&(r.t / TAU)) && r.m1_phase_deg.is_finite())
        .collect();
    if used.len() < 20 {
        return None;
    }
    let t: Vec<f64> = used.iter().map(|r| r.t).collect();
    let inertial = |turning: f64, t: f64| (turning + t.to_degrees()).rem_euclid(360.0);
    let m1: Vec<f64> = used
        .iter()
        .map(|r| inertial(r.m1_phase_deg + 180.0, r.t))
        .collect();
    let osc: Vec<f64> = used.iter().map(|r| r.periastron_inertial_deg).collect();
    let m1 = Track::fit(&t, &m1)?;
    let osc = Track::fit(&t, &osc).filter(|_| osc.iter().all(|x| x.is_finite()));
    // The m = 1 phase against the osculating periastron: their difference, from its 2% to
    // its 98% quantile (a few rows of noise aside), stays within degrees while both follow
    // the periastron, and grows by whole turns where the m = 1 pattern is held by the tide
    // in the turning frame and turns with it (module doc).
    let slip = osc.as_ref().filter(|o| o.follows_periastron()).map(|o| {
        let mut d: Vec<f64> = m1
            .unwrapped
            .iter()
            .zip(&o.unwrapped)
            .map(|(a, b)| a - b)
            .collect();
        d.sort_by(f64::total_cmp);
        let at = |f: f64| d[((d.len() - 1) as f64 * f).round() as usize];
        at(0.98) - at(0.02)
    });
    let m1_follows = m1.follows_periastron() && slip.is_none_or(|s| s <= MAX_SLIP_DEG);
    let (source, chosen) = if m1_follows {
        (PrecessionSource::M1Phase, &m1)
    } else {
        match &osc {
            Some(o) if o.follows_periastron() => (PrecessionSource::Osculating, o),
            _ => return None,
        }
    };
    let (rate, rate_err) = (chosen.rate, chosen.rate_err);
    let beat = 1.0 / (1.0 - rate);
    let peri = &chosen.unwrapped;
    Some(Precession {
        rate,
        rate_err,
        source,
        rate_m1_phase: m1.rate,
        rate_m1_phase_err: m1.rate_err,
        m1_phase_jumps: m1.jumps,
        m1_phase_slip_deg: slip.unwrap_or(f64::NAN),
        rate_osculating: osc.as_ref().map_or(f64::NAN, |o| o.rate),
        rate_osculating_err: osc.as_ref().map_or(f64::NAN, |o| o.rate_err),
        osculating_jumps: osc.as_ref().map_or(f64::NAN, |o| o.jumps),
        beat_period_orbits: beat,
        epsilon_beat: rate * beat,
        epsilon_beat_err: rate_err * beat * beat,
        turns: (peri[peri.len() - 1] - peri[0]) / 360.0,
        orbits: (t[0] / TAU, t[t.len() - 1] / TAU),
        points: t
            .iter()
            .map(|t| t / TAU)
            .zip(peri.iter().copied())
            .collect(),
    })
}

/// The whole analysis from the two series' rows and the run's q (module doc).
pub fn analyse(
    modes: &[ModesRow],
    light: &[lightcurve::Row],
    q: Option<f64>,
) -> Result<SuperhumpFigures> {
    let rows: Vec<&ModesRow> = modes.iter().filter(|r| r.m1.is_finite()).collect();
    if rows.len() < 20 {
        bail!(
            "modes.csv: {} rows with disk gas; need at least 20 (a run of a few orbits)",
            rows.len()
        );
    }
    let col = |f: fn(&ModesRow) -> f64| rows.iter().map(|r| f(r)).collect::<Vec<f64>>();
    let t: Vec<f64> = col(|r| r.t / TAU);
    let g = growth(
        &t,
        &col(|r| r.m1),
        &col(|r| r.e),
        &col(|r| r.m2),
        &col(|r| r.r_disk),
    );
    let mut notes = Vec::new();
    if !g.eccentric {
        notes.push(format!(
            "the disk did not turn eccentric: the m = 1 amplitude peaked at {:.4} (orbit {:.1}; floor {:.4}, {:.4} at the end); the light curve is analysed over the second half",
            g.e_peak, g.peak_orbit, g.e_floor, g.e_end
        ));
    }
    let (from, to) = g.active_orbits;
    let prec = if g.eccentric {
        precession(modes, from, to)
    } else {
        None
    };
    match &prec {
        None if g.eccentric => notes.push(format!(
            "no precession measured over orbits {from:.1}–{to:.1}: fewer than 20 rows, or neither the m = 1 phase nor the osculating periastron follows a periastron (more than {:.0}% of row-to-row steps jump by more than {JUMP_DEG}°)",
            100.0 * MAX_JUMP_FRACTION
        )),
        Some(p) if p.source == PrecessionSource::Osculating => notes.push(format!(
            "the m = 1 phase does not follow the periastron ({:.1}% of its row-to-row steps jump by more than {JUMP_DEG}°, its longitude wanders {:.0}° from the osculating one's; its slope would give ω_p = {:.4} Ω_orb): the precession is the osculating eccentricity vector's",
            100.0 * p.m1_phase_jumps,
            p.m1_phase_slip_deg,
            p.rate_m1_phase
        )),
        Some(p)
            if p.osculating_jumps <= MAX_JUMP_FRACTION
                && (p.rate_osculating - p.rate).abs()
                    > (3.0 * p.rate_err.hypot(p.rate_osculating_err)).max(0.1 * p.rate.abs()) =>
        {
            notes.push(format!(
                "the m = 1 phase's precession ({}) and the osculating periastron's ({}) disagree by more than 10% and three errors",
                lightcurve::plus_minus(p.rate, p.rate_err),
                lightcurve::plus_minus(p.rate_osculating, p.rate_osculating_err)
            ))
        }
        _ => {}
    }
    let light: Vec<lightcurve::Row> = light.iter().filter(|r| r.t / TAU <= to).copied().collect();
    let lc = match light.first() {
        Some(first) => {
            let skip = (from - first.t / TAU).max(0.0);
            match lightcurve::analyse_range(&light, skip, true, PERIOD_RANGE) {
                Ok(f) => Some(f),
                Err(e) => {
                    notes.push(format!("light curve: {e:#}"));
                    None
                }
            }
        }
        None => {
            notes.push("light curve: no rows".into());
            None
        }
    };
    if g.eccentric && g.faded {
        notes.push(format!(
            "the eccentricity peaked at {:.3} (orbit {:.1}) and faded to {:.3} by the end: precession and superhump are measured over orbits {from:.1}–{to:.1}",
            g.e_peak, g.peak_orbit, g.e_end
        ));
    }
    let predictions = q.map(|q| Predictions {
        q,
        r_31: roche::r_31(q),
        tidal_radius: roche::tidal_radius(q),
        epsilon_dynamical_r31: roche::epsilon_dynamical_r31(q),
        epsilon_dynamical_r_disk: g
            .r_disk_at_onset
            .map(|r| roche::epsilon_from_precession(roche::precession_rate(q, r))),
        epsilon_patterson2005: roche::epsilon_patterson2005(q),
        epsilon_kato2009: roche::epsilon_kato2009(q),
    });
    let beat_mismatch = match (&lc, &prec) {
        (Some(l), Some(p)) => Some((l.period_orbits - p.beat_period_orbits) / l.period_orbits),
        _ => None,
    };
    let hump = prec
        .as_ref()
        .and_then(|p| hump_phase(&p.points, p.rate, p.rate_err, &light, from, to));
    if let (Some(l), Some(p), Some(h)) = (&lc, &prec, &hump) {
        let apart = (l.period_excess - p.epsilon_beat).abs();
        if apart > 3.0 * l.period_excess_err.hypot(p.epsilon_beat_err) {
            notes.push(format!(
                "the light curve's ε ({}) and the beat's ({}) differ by {apart:.4}: the hump moves along the beat cycle by {}° per orbit, and the beat with that drift gives ε = {}",
                lightcurve::plus_minus(l.period_excess, l.period_excess_err),
                lightcurve::plus_minus(p.epsilon_beat, p.epsilon_beat_err),
                lightcurve::plus_minus(h.drift_deg_per_orbit, h.drift_err),
                lightcurve::plus_minus(h.epsilon_locked, h.epsilon_locked_err)
            ));
        }
    }
    if let Some(l) = &lc {
        notes.extend(l.notes.iter().map(|n| format!("light curve: {n}")));
    }
    Ok(SuperhumpFigures {
        orbits: (t[0], t[t.len() - 1]),
        superhump_period_orbits: lc.as_ref().map(|l| l.period_orbits),
        epsilon: lc.as_ref().map(|l| l.period_excess),
        epsilon_err: lc.as_ref().map(|l| l.period_excess_err),
        amplitude_rel: lc.as_ref().and_then(|l| l.amplitude_rel),
        amplitude_mag: lc.as_ref().and_then(|l| l.amplitude_mag),
        growth: g,
        precession: prec,
        lightcurve: lc,
        beat_mismatch,
        hump_phase: hump,
        predictions,
        notes,
    })
}

/// What `analyse superhump` found and wrote for one run.
pub struct SuperhumpReport {
    pub run: PathBuf,
    pub figures: SuperhumpFigures,
    pub files: Vec<PathBuf>,
}

/// Reads a run's `modes.csv`, `lightcurve.csv` and `run.toml`, analyses them, writes the
/// pictures and the JSON into the run folder and adds the figures to its `summary.json`.
pub fn analyse_superhump(run: &Path) -> Result<SuperhumpReport> {
    let path = run.join("modes.csv");
    let text = std::fs::read_to_string(&path).with_context(|| {
        format!(
            "{}: cannot read the disk's modes (written by cv runs)",
            path.display()
        )
    })?;
    let modes = parse_modes(&text).with_context(|| path.display().to_string())?;
    let lc_path = run.join("lightcurve.csv");
    let light = lightcurve::read_lightcurve(&lc_path)?;
    let (light, _) = lightcurve::supersede(&light);
    let lightcurve::RunBinary { q, note, .. } = lightcurve::binary_of(run);
    let mut f = analyse(&modes, &light, q).with_context(|| run.display().to_string())?;
    f.notes.extend(note);

    let mut files = Vec::new();
    let png = run.join("superhump_eccentricity.png");
    plot_panels(&png, (1400, 600), &[eccentricity_panel(&modes, &f)])?;
    files.push(png);
    if let Some(p) = &f.precession {
        let png = run.join("superhump_precession.png");
        plot_panels(&png, (1400, 600), &[precession_panel(p)])?;
        files.push(png);
    }
    if let Some(l) = &f.lightcurve {
        let png = run.join("superhump_lightcurve.png");
        plot_panels(&png, (1800, 600), &lightcurve::lightcurve_panels(&light, l))?;
        files.push(png);
        let png = run.join("superhump_periodogram.png");
        plot_panels(&png, (1100, 550), &[lightcurve::periodogram_panel(l)])?;
        files.push(png);
    }
    files.push(crate::io::summary::write_analysis(
        run,
        "superhump",
        "superhump",
        &f,
    )?);
    Ok(SuperhumpReport {
        run: run.to_path_buf(),
        figures: f,
        files,
    })
}

impl SuperhumpReport {
    /// A few lines for the terminal.
    pub fn summary(&self) -> String {
        let f = &self.figures;
        let g = &f.growth;
        let mut s = format!(
            "{}: orbits {:.1} to {:.1}\n",
            self.run.display(),
            f.orbits.0,
            f.orbits.1
        );
        let saturated = if g.eccentric {
            format!(
                ", saturated {:.4} (osculating {:.4}, m = 2 {:.4})",
                g.e_saturated, g.e_osculating_saturated, g.m2_saturated
            )
        } else {
            String::new()
        };
        s += &format!(
            "  eccentricity (m = 1): floor {:.4}, peak {:.4} at orbit {:.1}{saturated}, at the end {:.4}: {}\n",
            g.e_floor,
            g.e_peak,
            g.peak_orbit,
            g.e_end,
            if g.eccentric {
                "eccentric"
            } else {
                "not eccentric"
            }
        );
        if let Some(on) = g.onset_orbit {
            s += &format!(
                "  onset at orbit {on:.1} (R90 = {}), e-folding time {} orbits\n",
                g.r_disk_at_onset.map_or("?".into(), |r| format!("{r:.4}")),
                g.e_folding_orbits.map_or("?".into(), |x| format!("{x:.1}"))
            );
        }
        if let Some(p) = &f.precession {
            s += &format!(
                "  precession ω_p = {} Ω_orb from the {} (m = 1 phase {:.5}, osculating {:.5}), {:.2} turns; beat ε = {}\n",
                lightcurve::plus_minus(p.rate, p.rate_err),
                p.source.describe(),
                p.rate_m1_phase,
                p.rate_osculating,
                p.turns,
                lightcurve::plus_minus(p.epsilon_beat, p.epsilon_beat_err)
            );
        }
        if let (Some(e), Some(err), Some(ps)) =
            (f.epsilon, f.epsilon_err, f.superhump_period_orbits)
        {
            s += &format!(
                "  light curve: P_sh = {ps:.5} P_orb, ε = {}, amplitude {} mag\n",
                lightcurve::plus_minus(e, err),
                f.amplitude_mag.map_or("?".into(), |m| format!("{m:.4}"))
            );
        }
        if let Some(m) = f.beat_mismatch {
            s += &format!("  (P_sh − P_beat)/P_sh = {m:+.4}\n");
        }
        if let Some(h) = &f.hump_phase {
            s += &format!(
                "  hump against the apsidal line: drifts {}° per orbit ({} windows of {} orbits); beat with the drift: ε = {}\n",
                lightcurve::plus_minus(h.drift_deg_per_orbit, h.drift_err),
                h.phases.len(),
                h.window_orbits,
                lightcurve::plus_minus(h.epsilon_locked, h.epsilon_locked_err)
            );
        }
        if let Some(p) = &f.predictions {
            s += &format!(
                "  q = {}: ε dynamical at r_3:1 ({:.4}) {:.4}{}; observed Patterson 2005 {:.4}, Kato 2009 {:.4}\n",
                p.q,
                p.r_31,
                p.epsilon_dynamical_r31,
                p.epsilon_dynamical_r_disk
                    .map_or(String::new(), |e| format!(", at R90 {e:.4}")),
                p.epsilon_patterson2005,
                p.epsilon_kato2009
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

fn eccentricity_panel(modes: &[ModesRow], f: &SuperhumpFigures) -> Panel {
    let pts = |g: fn(&ModesRow) -> f64| -> Vec<(f64, f64)> {
        modes
            .iter()
            .filter(|r| g(r).is_finite())
            .map(|r| (r.t / TAU, g(r)))
            .collect()
    };
    let m1 = pts(|r| r.m1);
    let top = m1
        .iter()
        .chain(&pts(|r| r.e))
        .map(|p| p.1)
        .fold(0.0f64, f64::max)
        .max(0.01)
        * 1.1;
    let (a, b) = f.orbits;
    let g = &f.growth;
    let mut series = vec![
        Series {
            label: Some("m = 1 amplitude (e)".into()),
            points: m1,
            color: PALETTE[1],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("mean osculating e".into()),
            points: pts(|r| r.e),
            color: PALETTE[2],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("m = 2 amplitude".into()),
            points: pts(|r| r.m2),
            color: PALETTE[3],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("m = 1, one-orbit mean (analysed)".into()),
            points: {
                let rows: Vec<&ModesRow> = modes.iter().filter(|r| r.m1.is_finite()).collect();
                let t: Vec<f64> = rows.iter().map(|r| r.t / TAU).collect();
                let y: Vec<f64> = rows.iter().map(|r| r.m1).collect();
                t.iter()
                    .copied()
                    .zip(running_mean(&t, &y, 0.5 * SMOOTH_ORBITS))
                    .collect()
            },
            color: BLACK,
            style: SeriesStyle::Line,
        },
        Series {
            label: Some(format!("saturated e = {:.3}", g.e_saturated)),
            points: vec![(a, g.e_saturated), (b, g.e_saturated)],
            color: GREY,
            style: SeriesStyle::Dashed,
        },
    ];
    if let (Some(rate), Some((fa, fb)), Some(on)) =
        (g.growth_rate_per_orbit, g.growth_fit_orbits, g.onset_orbit)
    {
        let es = g.e_peak;
        series.push(Series {
            label: Some(format!(
                "logistic growth: e-folding {:.1} orbits",
                1.0 / rate
            )),
            points: (0..=50)
                .map(|k| {
                    let x = fa + (fb - fa) * k as f64 / 50.0;
                    (x, es / (1.0 + (-rate * (x - on)).exp()))
                })
                .collect(),
            color: RED,
            style: SeriesStyle::Dashed,
        });
    }
    Panel {
        title: "the disk's eccentricity (window 0.5–1.0 R90)".into(),
        x_label: "orbit (t / P_orb)".into(),
        y_label: "amplitude".into(),
        x_range: (a, b.max(a + 1e-9)),
        y_range: (0.0, top),
        series,
    }
}

fn precession_panel(p: &Precession) -> Panel {
    let points = p.points.clone();
    let (x0, y0) = points[0];
    let fit: Vec<(f64, f64)> = [p.orbits.0, p.orbits.1]
        .iter()
        .map(|&x| (x, y0 + p.rate * 360.0 * (x - x0)))
        .collect();
    let lo = points.iter().map(|q| q.1).fold(f64::INFINITY, f64::min);
    let hi = points.iter().map(|q| q.1).fold(f64::NEG_INFINITY, f64::max);
    let pad = 0.05 * (hi - lo).max(10.0);
    Panel {
        title: format!(
            "longitude of periastron (inertial): ω_p = {} Ω_orb",
            lightcurve::plus_minus(p.rate, p.rate_err)
        ),
        x_label: "orbit (t / P_orb)".into(),
        y_label: "ϖ (degrees, unwrapped)".into(),
        x_range: (p.orbits.0, p.orbits.1.max(p.orbits.0 + 1e-9)),
        y_range: (lo - pad, hi + pad),
        series: vec![
            Series {
                label: Some(format!("from the {}", p.source.describe())),
                points,
                color: PALETTE[1],
                style: SeriesStyle::Line,
            },
            Series {
                label: Some("linear fit".into()),
                points: fit,
                color: BLACK,
                style: SeriesStyle::Dashed,
            },
        ],
    }
}

/// The table of a q series (one row per run, sorted by q): CSV text.
pub fn scan_csv(reports: &[(f64, &SuperhumpFigures)]) -> String {
    let mut s = String::from(
        "q,eccentric,e_peak,peak_orbit,e_saturated,e_end,faded,onset_orbit,e_folding_orbits,r_disk_at_onset,epsilon,epsilon_err,epsilon_beat,epsilon_beat_err,hump_drift_deg_per_orbit,epsilon_locked,precession_source,amplitude_mag,epsilon_dynamical_r31,epsilon_dynamical_r_disk,epsilon_patterson2005,epsilon_kato2009\n",
    );
    let o = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6}"));
    for (q, f) in reports {
        let p = f.precession.as_ref();
        s.push_str(&format!(
            "{q},{},{:.6},{:.2},{},{:.6},{},{},{},{},{},{},{},{},{},{},{},{},{:.6},{},{:.6},{:.6}\n",
            f.growth.eccentric,
            f.growth.e_peak,
            f.growth.peak_orbit,
            o(f.growth.eccentric.then_some(f.growth.e_saturated)),
            f.growth.e_end,
            f.growth.faded,
            o(f.growth.onset_orbit),
            o(f.growth.e_folding_orbits),
            o(f.growth.r_disk_at_onset),
            // The light curve's period of a disk that did not turn eccentric is no superhump.
            o(f.epsilon.filter(|_| f.growth.eccentric)),
            o(f.epsilon_err.filter(|_| f.growth.eccentric)),
            o(p.map(|p| p.epsilon_beat)),
            o(p.map(|p| p.epsilon_beat_err)),
            o(f.hump_phase.as_ref().map(|h| h.drift_deg_per_orbit)),
            o(f.hump_phase.as_ref().map(|h| h.epsilon_locked)),
            p.map_or("", |p| match p.source {
                PrecessionSource::M1Phase => "m1_phase",
                PrecessionSource::Osculating => "osculating",
            }),
            o(f.amplitude_mag.filter(|_| f.growth.eccentric)),
            roche::epsilon_dynamical_r31(*q),
            o(f.growth
                .r_disk_at_onset
                .map(|r| roche::epsilon_from_precession(roche::precession_rate(*q, r)))),
            roche::epsilon_patterson2005(*q),
            roche::epsilon_kato2009(*q),
        ));
    }
    s
}

/// ε against q: the runs' light-curve ε (with ±1σ bars) and ε_beat, beside Patterson et al.
/// (2005), Kato et al. (2009) and the dynamical ε at r_3:1.
pub fn scan_panel(reports: &[(f64, &SuperhumpFigures)]) -> Panel {
    let curve = |f: fn(f64) -> f64| -> Vec<(f64, f64)> {
        (1..=80)
            .map(|k| (0.005 * k as f64, f(0.005 * k as f64)))
            .collect()
    };
    let mut runs = Vec::new();
    let mut bars = Vec::new();
    let mut beat = Vec::new();
    for (q, f) in reports {
        if let Some(e) = f.epsilon.filter(|_| f.growth.eccentric) {
            runs.push((*q, e));
            let err = f.epsilon_err.unwrap_or(0.0);
            bars.push(Series {
                label: None,
                points: vec![(*q, e - err), (*q, e + err)],
                color: BLACK,
                style: SeriesStyle::Line,
            });
        }
        if let Some(p) = &f.precession {
            beat.push((*q, p.epsilon_beat));
        }
    }
    let mut series = vec![
        Series {
            label: Some("Patterson et al. 2005".into()),
            points: curve(roche::epsilon_patterson2005),
            color: PALETTE[1],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("Kato et al. 2009".into()),
            points: curve(roche::epsilon_kato2009),
            color: PALETTE[2],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("dynamical precession at r_3:1".into()),
            points: curve(roche::epsilon_dynamical_r31),
            color: GREY,
            style: SeriesStyle::Dashed,
        },
        Series {
            label: Some("runs: light curve (±1σ)".into()),
            points: runs,
            color: BLACK,
            style: SeriesStyle::Markers,
        },
        Series {
            label: Some("runs: beat of the precession".into()),
            points: beat,
            color: RED,
            style: SeriesStyle::Markers,
        },
    ];
    series.extend(bars);
    Panel {
        title: "superhump period excess against q".into(),
        x_label: "q = M2/M1".into(),
        y_label: "ε = (P_sh − P_orb)/P_orb".into(),
        x_range: (0.0, 0.4),
        y_range: (0.0, 0.16),
        series,
    }
}

/// Writes the q series' table and plot into `out`; returns their paths.
pub fn write_scan(out: &Path, reports: &[(f64, &SuperhumpFigures)]) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut sorted = reports.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let csv = out.join("superhump_scan.csv");
    write_atomic(&csv, scan_csv(&sorted).as_bytes())?;
    let png = out.join("superhump_scan.png");
    plot_panels(&png, (1100, 700), &[scan_panel(&sorted)])?;
    Ok(vec![csv, png])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(t: f64, m1: f64, phase: f64) -> ModesRow {
        ModesRow {
            t,
            r_disk: 0.45,
            m1,
            m1_phase_deg: phase,
            m2: 0.01,
            e: m1,
            // No osculating longitude unless a test sets one.
            periastron_inertial_deg: f64::NAN,
        }
    }

    #[test]
    fn unwrap_follows_steps_across_the_cut() {
        let u = unwrap_deg(&[350.0, 5.0, 20.0, 340.0]);
        assert_eq!(u, vec![350.0, 365.0, 380.0, 340.0]);
    }

    #[test]
    fn growth_finds_the_rate_floor_and_saturation_of_a_logistic_mode() {
        // e(t) = e_s / (1 + (e_s/e_0 − 1) e^{−γ t}): exponential at γ while e ≪ e_s.
        let (e0, es, gamma) = (1e-3, 0.1, 0.2);
        let t: Vec<f64> = (0..4000).map(|k| k as f64 * 0.02).collect();
        let e: Vec<f64> = t
            .iter()
            .map(|t| es / (1.0 + (es / e0 - 1.0) * (-gamma * t).exp()))
            .collect();
        let g = growth(&t, &e, &e, &e, &vec![0.45; t.len()]);
        assert!(g.eccentric);
        assert!((g.e_peak / es - 1.0).abs() < 1e-3);
        assert!(!g.faded);
        // The median over the active stretch (from 0.8 e_s on) includes the last of the
        // rise: within 2% below e_s.
        assert!(g.e_saturated < es && g.e_saturated > 0.98 * es);
        // The linearised logistic is exact but for the one-orbit running mean, which
        // bends e by (γ²/24) e'' terms: 1% here.
        let rate = g.growth_rate_per_orbit.unwrap();
        assert!((rate / gamma - 1.0).abs() < 0.01, "rate {rate}");
        // Onset where e = e_s/2: t = ln(e_s/e_0 − 1)/γ.
        let on = (es / e0 - 1.0f64).ln() / gamma;
        assert!((g.onset_orbit.unwrap() - on).abs() < 0.6);
    }

    #[test]
    fn a_mode_that_grows_and_fades_is_measured_while_it_lasts() {
        // e rises as a logistic to 0.2, then decays on 15 orbits from orbit 50.
        let t: Vec<f64> = (0..5000).map(|k| k as f64 * 0.02).collect();
        let e: Vec<f64> = t
            .iter()
            .map(|&t| {
                let rise = 0.2 / (1.0 + 199.0 * (-0.3 * t).exp());
                if t < 50.0 {
                    rise
                } else {
                    rise * (-(t - 50.0) / 15.0).exp()
                }
            })
            .collect();
        let g = growth(&t, &e, &e, &e, &vec![0.45; t.len()]);
        assert!(g.eccentric && g.faded);
        assert!((g.peak_orbit - 50.0).abs() < 0.6, "{g:?}");
        // Half the peak again at 50 + 15 ln 2 = 60.4 orbits.
        assert!((g.active_orbits.1 - 60.4).abs() < 0.6, "{g:?}");
        assert!(
            (g.growth_rate_per_orbit.unwrap() / 0.3 - 1.0).abs() < 0.02,
            "{g:?}"
        );
        // The last quarter's median: 0.2 e^{−(87.5 − 50)/15} = 0.016.
        assert!((g.e_end - 0.0164).abs() < 0.001, "{g:?}");
    }

    #[test]
    fn a_set_up_transient_does_not_stand_for_the_floor() {
        // The disk starts lopsided and relaxes within an orbit (m = 1 from 0.055, as the
        // q = 0.15 disk of problems/superhump.toml at α = 0.2 starts at 0.025–0.05), sits at
        // 0.015 and then grows slowly (e-folding 12.5 orbits) to 0.075: five times its
        // floor, an eccentric disk. With the onset searched from the run's start the
        // transient was the onset and its 0.045 the floor, and the disk was called circular.
        let t: Vec<f64> = (0..6000).map(|k| k as f64 * 0.02).collect();
        let mode = |t: f64| 0.06 / (1.0 + 59.0 * (-0.08 * (t - 10.0)).exp());
        let e: Vec<f64> = t
            .iter()
            .map(|&t| 0.015 + 0.04 * (-t / 0.8).exp() + mode(t))
            .collect();
        let g = growth(&t, &e, &e, &e, &vec![0.45; t.len()]);
        assert!(g.eccentric, "{g:?}");
        assert!(g.e_floor < 0.017, "{g:?}");
        // Onset where e is half its peak: the logistic there is e_peak/2 − 0.015. The
        // one-orbit running mean moves it by far less than the orbit allowed.
        let e_peak = 0.015 + mode(t[t.len() - 1]);
        let half = e_peak / 2.0 - 0.015;
        let on = 10.0 + (59.0 / (0.06 / half - 1.0)).ln() / 0.08;
        assert!(
            (g.onset_orbit.unwrap() - on).abs() < 1.0,
            "{g:?} onset {on}"
        );
    }

    #[test]
    fn a_circular_disk_is_not_called_eccentric() {
        let t: Vec<f64> = (0..2000).map(|k| k as f64 * 0.02).collect();
        let e: Vec<f64> = t.iter().map(|t| 0.01 + 0.002 * (7.0 * t).sin()).collect();
        let g = growth(&t, &e, &e, &e, &vec![0.45; t.len()]);
        assert!(!g.eccentric);
        assert!(g.growth_rate_per_orbit.is_none());
    }

    #[test]
    fn precession_recovers_the_rate_of_a_turning_phase() {
        // An apoastron fixed in the inertial frame precessing at ω_p = 0.03 Ω_orb: in the
        // turning frame its azimuth moves at −(1 − ω_p) Ω.
        let w = 0.03;
        let rows: Vec<ModesRow> = (0..5000)
            .map(|k| {
                let t = k as f64 * TAU / 50.0;
                let phase = (40.0 + (w * t - t).to_degrees()).rem_euclid(360.0);
                row(t, 0.1, phase)
            })
            .collect();
        let p = precession(&rows, 0.0, f64::INFINITY).unwrap();
        assert!((p.rate - w).abs() < 1e-9, "rate {}", p.rate);
        assert!((p.epsilon_beat - w / (1.0 - w)).abs() < 1e-9);
        assert!(p.rate_err < 1e-9);
    }

    /// Rows of a strongly distorted disk, as the cooler q = 0.1 run (e ≈ 0.46, m = 2 ≈ 0.19)
    /// wrote them: the m = 1 phase no longer follows the periastron but is held by the
    /// binary, flipping between 30° and 210° in the turning frame every half orbit, while
    /// the osculating eccentricity vector's longitude precesses at `w` with a few degrees
    /// of noise (seeded).
    fn distorted_rows(w: f64) -> Vec<ModesRow> {
        let mut rng = crate::rng::Rng::new(12345);
        let mut noise = move || rng.uniform() - 0.5;
        (0..2000)
            .map(|k| {
                let t = k as f64 * TAU / 50.0;
                let flip = if (2.0 * t / TAU).floor() as i64 % 2 == 0 {
                    30.0
                } else {
                    210.0
                };
                let mut r = row(t, 0.4, (flip + 20.0 * noise()).rem_euclid(360.0));
                r.periastron_inertial_deg =
                    (300.0 + (w * t).to_degrees() + 6.0 * noise()).rem_euclid(360.0);
                r
            })
            .collect()
    }

    #[test]
    fn a_distorted_disks_precession_comes_from_its_osculating_periastron() {
        let w = 0.026;
        let p = precession(&distorted_rows(w), 0.0, f64::INFINITY).unwrap();
        // The osculating longitude's noise (±3°) over 40 orbits (2000 rows) moves the fitted
        // slope by ~1e-5 Ω_orb: 1e-3 is the bar; the m = 1 phase's fit is out by O(1).
        assert!(
            (p.rate - w).abs() < 1e-3,
            "rate {} ± {}",
            p.rate,
            p.rate_err
        );
        assert_eq!(p.source, PrecessionSource::Osculating);
        assert!(p.m1_phase_jumps > 0.01, "{}", p.m1_phase_jumps);
        assert!(p.osculating_jumps == 0.0);
        assert!((p.epsilon_beat - w / (1.0 - w)).abs() < 1.1e-3);
        // The error reflects the scatter of the osculating track, not the m = 1 phase's.
        assert!(p.rate_err < 1e-3, "{}", p.rate_err);
    }

    #[test]
    fn an_m1_phase_that_slips_turns_with_the_tide_does_not_give_the_precession() {
        // As the supercycle run's superoutburst wrote it: the m = 1 phase follows the
        // apoastron but for two orbits in which the distorted disk's m = 1 pattern is held
        // by the binary at a fixed turning-frame azimuth, turning with it 7.2° per row —
        // no step a jump (two steps of the 2000 are) — so its longitude slips two turns
        // against the osculating periastron's, and its slope over 40 orbits would read
        // ω_p = w + 0.05.
        let w = 0.025;
        let mut rows = distorted_rows(w);
        for r in rows.iter_mut() {
            let orbit = r.t / TAU;
            let turning_peri = r.periastron_inertial_deg - r.t.to_degrees();
            r.m1_phase_deg = if (10.0..12.0).contains(&orbit) {
                75.0
            } else {
                turning_peri + 180.0
            }
            .rem_euclid(360.0);
        }
        let p = precession(&rows, 0.0, f64::INFINITY).unwrap();
        assert!(
            p.m1_phase_jumps <= MAX_JUMP_FRACTION,
            "{}",
            p.m1_phase_jumps
        );
        assert!(p.m1_phase_slip_deg > 600.0, "{}", p.m1_phase_slip_deg);
        assert_eq!(p.source, PrecessionSource::Osculating);
        // The osculating track's noise: as in the distorted disk's test.
        assert!((p.rate - w).abs() < 1e-3, "{} ± {}", p.rate, p.rate_err);
        // Without the slip the same m = 1 phase is the source, and agrees.
        let mut clean = distorted_rows(w);
        for r in clean.iter_mut() {
            r.m1_phase_deg =
                (r.periastron_inertial_deg - r.t.to_degrees() + 180.0).rem_euclid(360.0);
        }
        let p = precession(&clean, 0.0, f64::INFINITY).unwrap();
        assert_eq!(p.source, PrecessionSource::M1Phase);
        assert!(p.m1_phase_slip_deg < 1.0, "{}", p.m1_phase_slip_deg);
        assert!((p.rate - w).abs() < 1e-3);
    }

    #[test]
    fn precession_is_refused_when_neither_longitude_follows_the_periastron() {
        let mut rows = distorted_rows(0.026);
        for (k, r) in rows.iter_mut().enumerate() {
            r.periastron_inertial_deg = if k % 2 == 0 { 10.0 } else { 190.0 };
        }
        assert!(precession(&rows, 0.0, f64::INFINITY).is_none());
    }

    #[test]
    fn the_parser_skips_an_unfinished_row_and_supersedes_resumed_ones() {
        let line = |t: f64| format!("{t},0,0.4,1,0.05,10,0.01,5,0.05,190,200\n");
        let mut text = format!("{HEADER}\n");
        for t in [0.0, 1.0, 2.0, 3.0, 1.5, 2.5] {
            text.push_str(&line(t));
        }
        text.push_str("3.5,0,0.4");
        let rows = parse_modes(&text).unwrap();
        let t: Vec<f64> = rows.iter().map(|r| r.t).collect();
        assert_eq!(t, vec![0.0, 1.0, 1.5, 2.5]);
        assert!(
            parse_modes("t,x\n")
                .unwrap_err()
                .to_string()
                .contains("header")
        );
        let bad = format!("{HEADER}\n1,2,3\n4,5,6\n");
        assert!(
            parse_modes(&bad)
                .unwrap_err()
                .to_string()
                .contains("line 2")
        );
    }
}
