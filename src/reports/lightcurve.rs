//! `sphdisk analyse lightcurve <run>`: the strongest period in a run's light curve
//! (`lightcurve.csv`, written during binary runs) — for a cataclysmic variable, e.g. a
//! superhump and its period excess over the orbit.
//!
//! Code units of the binary: a = 1, G(M1 + M2) = 1, so Ω_orb = 1 and P_orb = 2π always; the
//! orbit column of the file is not trusted, orbits are t/2π. The first `skip_orbits`
//! orbits *of the light curve* (from its first row, which for a run started with `--from`
//! is not t = 0) are left out as the transient. The generalised Lomb–Scargle periodogram
//! ([`crate::analysis::periodogram`]) of l_total is scanned between 0.2 and 5 P_orb; its
//! highest peak, refined, gives the period, its uncertainty (Montgomery & O'Donoghue: a
//! white-noise bound, optimistic when the light curve flickers) and the semi-amplitude of
//! the fitted sinusoid.
//!
//! **Detrending.** A disk still building up brightens through the run; that secular rise
//! is the strongest "signal" a plain periodogram sees, and it puts the peak at the longest
//! period searched, not at the orbit or a superhump. So by default a cubic polynomial in
//! time (the trend, [`TREND_DEGREE`]) is fitted *together with* the sinusoid at every trial
//! period (the periodogram's floating trend), and the modulation is measured against it:
//! the amplitude relative to the trend is A over the trend's mean over the rows used.
//! Why a global cubic rather than a running mean: a running mean over P_orb nulls a signal
//! at exactly P_orb and passes one at 1.05 P_orb only in part; one over 3–5 P_orb loses half
//! a window at each end — most of a 4-orbit light curve — and still leaks the trend's
//! curvature. A cubic over the whole span uses every row and follows a rise that
//! accelerates, slows and levels off. Fitted *alone* first it would absorb part of any
//! signal (up to 11% of the amplitude at P_orb over a 4-orbit span, 7% over 5, 0.5% over
//! 20, depending on phase); fitted jointly it takes none: signals at or near P_orb keep
//! their amplitude and period, and only their uncertainties grow, by the Cramér–Rao ratio
//! with and without the trend (at most 10% for the period and 6% for the amplitude with 4
//! cycles in the span, 0.4% with 20). What the cubic cannot do is tell a period longer than
//! about half the span from a trend: there the power measures how far the trend departs
//! from a cubic, not a periodicity, and a note says so when the peak lies there.
//! `--no-detrend` ([`analyse`] with `detrend = false`) fits a floating mean only, as before.
//!
//! Rows whose time does not increase are taken for a run resumed from a checkpoint, which
//! writes again from an earlier time: the later rows replace the earlier ones from that
//! time on. A last line without its newline that does not parse is a row the running
//! simulation is still writing and is ignored.
//!
//! Writes into the run folder: `lightcurve.png` (luminosities against orbit with the trend;
//! l_total less the trend, relative to the trend's mean, folded on the period with the
//! fit), `periodogram.png` (power against period in P_orb, peak marked), `orbital.png`
//! (what the observer at `binary.inclination` sees, `l_observed` over its trend folded on
//! the orbit: the orbital hump and the eclipse; [`orbital`]), `lightcurve.json`
//! ([`LightcurveFigures`]). `run.toml` is optional: with
//! `binary.period_days` the period is also given in days, with `binary.q` (or the masses)
//! the period excess Patterson et al. (2005) predict for superhumps, ε = 0.18 q + 0.29 q².

use std::f64::consts::TAU;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use plotters::style::RGBColor;
use serde::Serialize;

use crate::analysis::periodogram::{
    OVERSAMPLE, PeriodEstimate, frequency_grid, lomb_scargle_grid_trend, refine_peak_trend,
};
use crate::io::atomic::write_atomic;
use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle, plot_panels};

/// The header line `lightcurve.csv` must start with: the one the run writes.
pub const HEADER: &str = crate::io::timeseries::LIGHTCURVE_HEADER;

/// Fewest rows (after the transient) the analysis accepts: with fewer the sinusoid's
/// three parameters leave almost nothing to judge a period by.
pub const MIN_ROWS: usize = 8;

/// The search range, in orbital periods.
pub const PERIOD_MIN_ORBITS: f64 = 0.2;
pub const PERIOD_MAX_ORBITS: f64 = 5.0;

/// Degree of the polynomial trend in time fitted with the sinusoid unless `--no-detrend`
/// (see the module's documentation).
pub const TREND_DEGREE: usize = 3;

/// One line of `lightcurve.csv`: code time, orbits, Σ m ε̇ in each region, and what the
/// binary's observer sees (`analysis::observer`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    pub t: f64,
    pub orbit: f64,
    pub l_total: f64,
    pub l_disk: f64,
    pub l_stream: f64,
    pub l_spot: f64,
    pub l_observed: f64,
}

/// Which column of the light curve is analysed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    /// l_total: the luminosity, the same in every direction.
    Total,
    /// l_observed: what the observer at `binary.inclination` sees.
    Observed,
}

impl Signal {
    fn of(self, r: &Row) -> f64 {
        match self {
            Signal::Total => r.l_total,
            Signal::Observed => r.l_observed,
        }
    }
}

/// Number of orbital-phase bins of the observed light curve's folded profile: 50 per
/// orbit, the run's default row interval, so that every bin holds one row per orbit.
pub const PHASE_BINS: usize = 50;

/// The orbital modulation an observer sees (`l_observed`): its periodogram between
/// [`ORBITAL_RANGE`] P_orb, and the mean profile folded on the orbit.
#[derive(Clone, Debug, Serialize)]
pub struct OrbitalFigures {
    /// `binary.inclination` of `run.toml` (degrees), if given there.
    pub inclination_deg: Option<f64>,
    /// The strongest period of l_observed in [`ORBITAL_RANGE`], in P_orb, its error, and
    /// (P − P_orb)/P_orb.
    pub period_orbits: f64,
    pub period_orbits_err: f64,
    pub period_offset: f64,
    pub power: f64,
    pub false_alarm: f64,
    /// Semi-amplitude of the fitted sinusoid over the trend's mean.
    pub amplitude_rel: Option<f64>,
    /// The folded profile: l_observed over its trend, averaged in [`PHASE_BINS`] bins of
    /// orbital phase (0 = the donor in front), as (bin centre, mean); empty bins left out.
    pub profile: Vec<(f64, f64)>,
    /// Phase of the profile's brightest bin (the orbital hump) and its height over the
    /// profile's median in magnitudes.
    pub hump_phase: f64,
    pub hump_mag: f64,
    /// Phase of the faintest bin and its depth under the median in magnitudes (the
    /// eclipse, where the inclination gives one).
    pub minimum_phase: f64,
    /// `None` where the faintest bin holds no light at all.
    pub minimum_depth_mag: Option<f64>,
}

/// The periods searched for the orbital modulation, in P_orb.
pub const ORBITAL_RANGE: (f64, f64) = (0.5, 2.0);

/// The binary's physical values, where `run.toml` gives them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BinaryFigures {
    /// q = M2/M1 (`binary.q`, or `binary.m2_msun / binary.m1_msun`).
    pub q: Option<f64>,
    /// `binary.period_days`.
    pub orbital_period_days: Option<f64>,
    /// The period found, in days (with `orbital_period_days`).
    pub period_days: Option<f64>,
    pub period_days_err: Option<f64>,
    /// Patterson et al. (2005) superhump excess for this q: 0.18 q + 0.29 q².
    pub excess_patterson2005: Option<f64>,
}

/// What the analysis measured (`lightcurve.json`).
#[derive(Clone, Debug, Serialize)]
pub struct LightcurveFigures {
    /// Rows given, rows dropped as replaced by a resumed run, rows analysed.
    pub rows_read: usize,
    pub rows_superseded: usize,
    pub rows_used: usize,
    pub skip_orbits: f64,
    /// The analysed stretch, in orbits (t/2π), and its length in periods found.
    pub orbit_start: f64,
    pub orbit_end: f64,
    pub cycles: f64,
    /// The period in code units (P_orb = 2π) and its 1σ error.
    pub period: f64,
    pub period_err: f64,
    /// The period in orbital periods.
    pub period_orbits: f64,
    pub period_orbits_err: f64,
    /// (P − P_orb)/P_orb.
    pub period_excess: f64,
    pub period_excess_err: f64,
    /// Normalised periodogram power at the peak (0..1) and the white-noise false-alarm
    /// probability of a peak that high in the range.
    pub power: f64,
    pub false_alarm: f64,
    /// Fitted mean of l_total (detrended: the trend's mean over the rows used) and
    /// semi-amplitude of the sinusoid (luminosity units).
    pub mean: f64,
    pub amplitude: f64,
    pub amplitude_err: f64,
    /// Semi-amplitude over the mean — detrended, the amplitude relative to the trend (null
    /// if the mean is not positive) — and its error.
    pub amplitude_rel: Option<f64>,
    pub amplitude_rel_err: Option<f64>,
    /// Peak-to-peak modulation in magnitudes, 2.5 log10((mean + A)/(mean − A)) (null if
    /// mean ≤ A).
    pub amplitude_mag: Option<f64>,
    /// The peak lies at the end of the search range: the period may lie beyond it.
    pub at_range_edge: bool,
    /// The periods searched, in P_orb.
    pub period_range_orbits: (f64, f64),
    /// Whether a polynomial trend was fitted with the sinusoid (not `--no-detrend`), its
    /// degree (0: a floating mean only), and its values at the first and last rows used
    /// (luminosity units; the whole polynomial is `fit.trend`).
    pub detrended: bool,
    pub trend_degree: usize,
    pub trend_start: f64,
    pub trend_end: f64,
    /// `run.toml`'s binary, if any (set by [`analyse_lightcurve`], not by [`analyse`]).
    pub binary: Option<BinaryFigures>,
    /// The orbital hump and eclipse in what the observer sees (set by
    /// [`analyse_lightcurve`] through [`orbital`] where l_observed is not all 0).
    pub orbital: Option<OrbitalFigures>,
    /// Caveats, one line each.
    pub notes: Vec<String>,
    /// The full estimate in code units.
    pub fit: PeriodEstimate,
    /// (period / P_orb, power) of the scanned grid, for the plot.
    #[serde(skip)]
    pub periodogram: Vec<(f64, f64)>,
    /// Index of the first row analysed in the rows after superseding ([`supersede`]).
    #[serde(skip)]
    pub first_used: usize,
}

/// What `analyse lightcurve` found and wrote.
pub struct LightcurveReport {
    pub csv: PathBuf,
    pub figures: LightcurveFigures,
    pub files: Vec<PathBuf>,
}

/// Reads `lightcurve.csv`. Errors, one line each naming the file: missing or unreadable,
/// empty, a header other than [`HEADER`], a row with the wrong number of cells, a cell
/// that is not a finite number (with its line number).
pub fn read_lightcurve(path: &Path) -> Result<Vec<Row>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the light curve", path.display()))?;
    parse_lightcurve(&text).with_context(|| path.display().to_string())
}

/// [`read_lightcurve`] on the file's text; errors do not name the file.
pub fn parse_lightcurve(text: &str) -> Result<Vec<Row>> {
    Ok(crate::io::timeseries::parse_series(text, HEADER, false)?
        .into_iter()
        .map(|v| Row {
            t: v[0],
            orbit: v[1],
            l_total: v[2],
            l_disk: v[3],
            l_stream: v[4],
            l_spot: v[5],
            l_observed: v[6],
        })
        .collect())
}

/// The rows as the run finally had them: wherever the time does not increase (a resumed
/// run writing again from its checkpoint), the earlier rows from that time on are dropped.
/// Returns the rows and how many were dropped.
pub fn supersede(rows: &[Row]) -> (Vec<Row>, usize) {
    let kept = crate::io::timeseries::supersede(rows.iter().copied(), |r| r.t);
    let dropped = rows.len() - kept.len();
    (kept, dropped)
}

/// The analysis without files: supersedes resumed stretches, skips the first
/// `skip_orbits` orbits after the first row, finds the strongest period of l_total between
/// [`PERIOD_MIN_ORBITS`] and [`PERIOD_MAX_ORBITS`] orbital periods — with `detrend`, against
/// a cubic trend in time fitted with it (see the module's documentation), else against a
/// floating mean.
pub fn analyse(rows: &[Row], skip_orbits: f64, detrend: bool) -> Result<LightcurveFigures> {
    analyse_range(
        rows,
        skip_orbits,
        detrend,
        (PERIOD_MIN_ORBITS, PERIOD_MAX_ORBITS),
    )
}

/// [`analyse`] with the periods searched limited to `range` (in P_orb; within 0.05–50).
pub fn analyse_range(
    rows: &[Row],
    skip_orbits: f64,
    detrend: bool,
    range: (f64, f64),
) -> Result<LightcurveFigures> {
    analyse_signal(rows, skip_orbits, detrend, range, Signal::Total)
}

/// [`analyse_range`] of the column `signal`.
pub fn analyse_signal(
    rows: &[Row],
    skip_orbits: f64,
    detrend: bool,
    range: (f64, f64),
    signal: Signal,
) -> Result<LightcurveFigures> {
    if !(range.0 >= 0.05 && range.1 > range.0 && range.1 <= 50.0) {
        bail!(
            "period range {}..{} P_orb: must lie within 0.05..50 and be increasing",
            range.0,
            range.1
        );
    }
    if !(skip_orbits >= 0.0 && skip_orbits.is_finite()) {
        bail!("--skip-orbits {skip_orbits}: must be a number ≥ 0");
    }
    let (rows_all, superseded) = supersede(rows);
    let Some(first) = rows_all.first() else {
        bail!("no rows; need at least {MIN_ROWS}");
    };
    let t_cut = first.t + skip_orbits * TAU;
    let first_used = rows_all.partition_point(|r| r.t < t_cut);
    let used = &rows_all[first_used..];
    if used.len() < MIN_ROWS && first_used == 0 {
        bail!("only {} rows; need at least {MIN_ROWS}", used.len());
    }
    if used.len() < MIN_ROWS {
        bail!(
            "only {} rows after skipping the first {} orbits (of {} rows over {:.3} orbits); need at least {MIN_ROWS}",
            used.len(),
            crate::limits::show(skip_orbits),
            rows_all.len(),
            (rows_all[rows_all.len() - 1].t - first.t) / TAU
        );
    }
    let t: Vec<f64> = used.iter().map(|r| r.t).collect();
    let y: Vec<f64> = used.iter().map(|r| signal.of(r)).collect();
    let span = t[t.len() - 1] - t[0];
    if !(span > 0.0) {
        bail!("the rows used cover no time");
    }
    let (f_min, f_max) = (1.0 / (range.1 * TAU), 1.0 / (range.0 * TAU));
    let degree = if detrend { TREND_DEGREE } else { 0 };
    let grid = frequency_grid(span, f_min, f_max, OVERSAMPLE)?;
    let power = lomb_scargle_grid_trend(&t, &y, &grid, degree);
    let name = match signal {
        Signal::Total => "l_total",
        Signal::Observed => "l_observed",
    };
    let est = refine_peak_trend(&t, &y, &grid, &power, degree).context(name)?;
    let periodogram: Vec<(f64, f64)> = (0..grid.len)
        .map(|k| (1.0 / (grid.frequency(k) * TAU), power[k]))
        .collect();

    let period_orbits = est.period / TAU;
    let period_orbits_err = est.period_err / TAU;
    let cycles = span / est.period;
    // Within one grid step of either end: the maximum may lie outside the range.
    let at_range_edge = est.frequency - f_min < grid.step || f_max - est.frequency < grid.step;
    let (amplitude_rel, amplitude_rel_err, amplitude_mag) = if est.mean > 0.0 {
        let rel = est.amplitude / est.mean;
        let mag = (rel < 1.0).then(|| 2.5 * ((1.0 + rel) / (1.0 - rel)).log10());
        (Some(rel), Some(est.amplitude_err / est.mean), mag)
    } else {
        (None, None, None)
    };
    let (trend_start, trend_end) = (est.trend.at(t[0]), est.trend.at(t[t.len() - 1]));
    let mut notes = Vec::new();
    if superseded > 0 {
        notes.push(format!(
            "{superseded} rows replaced by a resumed run's (time went back)"
        ));
    }
    if at_range_edge {
        notes.push(format!(
            "the peak lies at the end of the search range ({}..{} P_orb): the true period may lie outside it",
            range.0,
            range.1
        ));
    }
    if cycles < 3.0 {
        notes.push(format!(
            "the light curve covers only {cycles:.1} cycles of the period: the figures are rough"
        ));
    }
    if detrend && 2.0 * est.period > span {
        notes.push(format!(
            "the period is longer than half the span analysed ({:.2} orbits): it cannot be told from the departure of the trend from a cubic",
            span / TAU
        ));
    }
    if est.false_alarm > 0.01 {
        notes.push(format!(
            "false-alarm probability {:.2}: the peak may be noise",
            est.false_alarm
        ));
    }
    Ok(LightcurveFigures {
        rows_read: rows.len(),
        rows_superseded: superseded,
        rows_used: used.len(),
        skip_orbits,
        orbit_start: t[0] / TAU,
        orbit_end: t[t.len() - 1] / TAU,
        cycles,
        period: est.period,
        period_err: est.period_err,
        period_orbits,
        period_orbits_err,
        period_excess: period_orbits - 1.0,
        period_excess_err: period_orbits_err,
        power: est.power,
        false_alarm: est.false_alarm,
        mean: est.mean,
        amplitude: est.amplitude,
        amplitude_err: est.amplitude_err,
        amplitude_rel,
        amplitude_rel_err,
        amplitude_mag,
        at_range_edge,
        period_range_orbits: range,
        detrended: detrend,
        trend_degree: degree,
        trend_start,
        trend_end,
        binary: None,
        orbital: None,
        notes,
        fit: est,
        periodogram,
        first_used,
    })
}

/// The orbital modulation of l_observed over the same rows as `analyse` would use: its
/// strongest period in [`ORBITAL_RANGE`] against a cubic trend, and the profile folded on
/// P_orb relative to that trend. `None` where l_observed is 0 throughout (a light curve
/// without dissipation).
pub fn orbital(
    rows: &[Row],
    skip_orbits: f64,
    inclination_deg: Option<f64>,
) -> Result<Option<OrbitalFigures>> {
    if rows.iter().all(|r| r.l_observed == 0.0) {
        return Ok(None);
    }
    let f = analyse_signal(rows, skip_orbits, true, ORBITAL_RANGE, Signal::Observed)?;
    let (kept, _) = supersede(rows);
    let used = &kept[f.first_used..];
    let mean = f.fit.mean;
    let mut sums = [(0.0, 0usize); PHASE_BINS];
    for r in used {
        let trend = f.fit.trend.at(r.t);
        if !(trend > 0.0) {
            continue;
        }
        let phase = (r.t / TAU).rem_euclid(1.0);
        let k = ((phase * PHASE_BINS as f64) as usize).min(PHASE_BINS - 1);
        sums[k].0 += r.l_observed / trend;
        sums[k].1 += 1;
    }
    let profile: Vec<(f64, f64)> = sums
        .iter()
        .enumerate()
        .filter(|(_, s)| s.1 > 0)
        .map(|(k, s)| ((k as f64 + 0.5) / PHASE_BINS as f64, s.0 / s.1 as f64))
        .collect();
    if profile.is_empty() {
        bail!("l_observed: its trend is not positive anywhere; no profile");
    }
    let mut values: Vec<f64> = profile.iter().map(|p| p.1).collect();
    values.sort_by(f64::total_cmp);
    let median = values[values.len() / 2];
    let max = profile.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1));
    let min = profile.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1));
    let (Some(max), Some(min)) = (max, min) else {
        bail!("l_observed: no profile");
    };
    let mag = |a: f64, b: f64| 2.5 * (a / b).log10();
    Ok(Some(OrbitalFigures {
        inclination_deg,
        period_orbits: f.period_orbits,
        period_orbits_err: f.period_orbits_err,
        period_offset: f.period_orbits - 1.0,
        power: f.power,
        false_alarm: f.false_alarm,
        amplitude_rel: (mean > 0.0).then(|| f.amplitude / mean),
        profile,
        hump_phase: max.0,
        hump_mag: mag(max.1, median),
        minimum_phase: min.0,
        minimum_depth_mag: (min.1 > 0.0).then(|| mag(median, min.1)),
    }))
}

impl LightcurveFigures {
    /// Adds the physical values of `run.toml`'s `[binary]`.
    pub fn with_binary(mut self, q: Option<f64>, orbital_period_days: Option<f64>) -> Self {
        if q.is_none() && orbital_period_days.is_none() {
            return self;
        }
        self.binary = Some(BinaryFigures {
            q,
            orbital_period_days,
            period_days: orbital_period_days.map(|p| p * self.period_orbits),
            period_days_err: orbital_period_days.map(|p| p * self.period_orbits_err),
            excess_patterson2005: q.map(|q| 0.18 * q + 0.29 * q * q),
        });
        self
    }
}

/// What `run.toml`'s `[binary]` says, read leniently: no file, no table or no keys give
/// `None`s; a file that does not parse gives a note instead.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct RunBinary {
    /// q = M2/M1 (`binary.q`, or `binary.m2_msun / binary.m1_msun`).
    pub q: Option<f64>,
    /// `binary.period_days`.
    pub period_days: Option<f64>,
    /// `binary.inclination`, its default where the table has a binary without the key.
    pub inclination_deg: Option<f64>,
    pub note: Option<String>,
}

/// [`RunBinary`] of the run in `run`.
pub(crate) fn binary_of(run: &Path) -> RunBinary {
    let path = run.join("run.toml");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return RunBinary::default();
    };
    let value: toml::Value = match text.parse() {
        Ok(v) => v,
        Err(e) => {
            let first = e.to_string();
            let first = first.lines().next().unwrap_or("").trim().to_string();
            return RunBinary {
                note: Some(format!(
                    "{}: not read ({first}); no physical values",
                    path.display()
                )),
                ..RunBinary::default()
            };
        }
    };
    let Some(b) = value.get("binary") else {
        return RunBinary::default();
    };
    let number = |k: &str| {
        b.get(k)
            .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
    };
    let num = |k: &str| number(k).filter(|v| v.is_finite() && *v > 0.0);
    RunBinary {
        q: num("q").or_else(|| Some(num("m2_msun")? / num("m1_msun")?)),
        period_days: num("period_days"),
        inclination_deg: Some(
            number("inclination").unwrap_or(crate::analysis::observer::DEFAULT_INCLINATION_DEG),
        ),
        note: None,
    }
}

/// Reads `run/lightcurve.csv` (and `run/run.toml` if there), analyses it ([`analyse`]),
/// writes the two pictures and the JSON into `run`.
pub fn analyse_lightcurve(run: &Path, skip_orbits: f64, detrend: bool) -> Result<LightcurveReport> {
    let csv = run.join("lightcurve.csv");
    let rows = read_lightcurve(&csv)?;
    let figures =
        analyse(&rows, skip_orbits, detrend).with_context(|| csv.display().to_string())?;
    let binary = binary_of(run);
    let mut figures = figures.with_binary(binary.q, binary.period_days);
    figures.notes.extend(binary.note);
    figures.orbital = orbital(&rows, skip_orbits, binary.inclination_deg)
        .with_context(|| format!("{}: the observed light curve", csv.display()))?;
    let (rows, _) = supersede(&rows);

    let lc_png = run.join("lightcurve.png");
    plot_panels(&lc_png, (1800, 600), &lightcurve_panels(&rows, &figures))?;
    let pg_png = run.join("periodogram.png");
    plot_panels(&pg_png, (1100, 550), &[periodogram_panel(&figures)])?;
    let mut files = vec![lc_png, pg_png];
    if let Some(o) = &figures.orbital {
        let png = run.join("orbital.png");
        plot_panels(&png, (1100, 550), &[orbital_panel(o)])?;
        files.push(png);
    }
    let json = run.join("lightcurve.json");
    let mut text = serde_json::to_string_pretty(&figures)?;
    text.push('\n');
    write_atomic(&json, text.as_bytes())?;
    files.push(json);
    Ok(LightcurveReport {
        csv,
        figures,
        files,
    })
}

const BLACK: RGBColor = RGBColor(0, 0, 0);
const GREY: RGBColor = RGBColor(140, 140, 140);
const ORANGE: RGBColor = RGBColor(230, 120, 20);
const RED: RGBColor = RGBColor(200, 30, 30);

/// (lo, hi) of the values, padded by 6% (a flat series by ±1 or ±10% of its value).
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.06 * (hi - lo)
    } else {
        (0.1 * lo.abs()).max(1.0)
    };
    (lo - pad, hi + pad)
}

pub(crate) fn lightcurve_panels(rows: &[Row], f: &LightcurveFigures) -> Vec<Panel> {
    let orbit = |r: &Row| r.t / TAU;
    let curve = |g: &dyn Fn(&Row) -> f64| rows.iter().map(|r| (orbit(r), g(r))).collect();
    let x_range = {
        let (a, b) = (orbit(&rows[0]), orbit(&rows[rows.len() - 1]));
        if b > a { (a, b) } else { (a - 0.5, a + 0.5) }
    };
    let y_range = padded_range(
        rows.iter()
            .flat_map(|r| [r.l_total, r.l_disk, r.l_stream, r.l_spot]),
    );
    let mut series = vec![
        Series {
            label: Some("total".into()),
            points: curve(&|r| r.l_total),
            color: BLACK,
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("disk".into()),
            points: curve(&|r| r.l_disk),
            color: PALETTE[1],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("stream".into()),
            points: curve(&|r| r.l_stream),
            color: PALETTE[2],
            style: SeriesStyle::Line,
        },
        Series {
            label: Some("hot spot".into()),
            points: curve(&|r| r.l_spot),
            color: ORANGE,
            style: SeriesStyle::Line,
        },
    ];
    let used = &rows[f.first_used..];
    let fit = &f.fit;
    if f.detrended {
        series.push(Series {
            label: Some(format!("trend (degree {})", f.trend_degree)),
            points: used.iter().map(|r| (orbit(r), fit.trend.at(r.t))).collect(),
            color: RED,
            style: SeriesStyle::Dashed,
        });
    }
    if f.first_used > 0 {
        series.push(Series {
            label: Some("end of transient".into()),
            points: vec![(f.orbit_start, y_range.0), (f.orbit_start, y_range.1)],
            color: GREY,
            style: SeriesStyle::Dashed,
        });
    }
    // Detrended: l_total less the trend, over the trend's mean where that is positive (the
    // fitted sinusoid then has the relative amplitude); raw: l_total.
    let scale = if f.detrended && fit.mean > 0.0 {
        1.0 / fit.mean
    } else {
        1.0
    };
    let value = |r: &Row| {
        if f.detrended {
            (r.l_total - fit.trend.at(r.t)) * scale
        } else {
            r.l_total
        }
    };
    let centre = if f.detrended { 0.0 } else { fit.mean };
    // Phase 0 at the fitted maximum; two cycles shown.
    let phase = |t: f64| (t * fit.frequency - fit.phase / TAU).rem_euclid(1.0);
    let mut folded: Vec<(f64, f64)> = used.iter().map(|r| (phase(r.t), value(r))).collect();
    folded.extend(used.iter().map(|r| (phase(r.t) + 1.0, value(r))));
    let model: Vec<(f64, f64)> = (0..=400)
        .map(|k| {
            let x = 2.0 * k as f64 / 400.0;
            (x, centre + scale * fit.amplitude * (TAU * x).cos())
        })
        .collect();
    let fold_range = padded_range(folded.iter().chain(&model).map(|p| p.1));
    let (fold_title, fold_y) = match (f.detrended, scale != 1.0) {
        (true, true) => ("l_total − trend", "(l_total − trend) / mean of the trend"),
        (true, false) => ("l_total − trend", "l_total − trend"),
        _ => ("l_total", "l_total"),
    };
    vec![
        Panel {
            title: "light curve".into(),
            x_label: "orbit (t / P_orb)".into(),
            y_label: "luminosity Σ m dε/dt".into(),
            x_range,
            y_range,
            series,
        },
        Panel {
            title: format!(
                "{fold_title} folded on P = {} P_orb",
                plus_minus(f.period_orbits, f.period_orbits_err)
            ),
            x_label: "phase (cycles, 0 at the fitted maximum)".into(),
            y_label: fold_y.into(),
            x_range: (0.0, 2.0),
            y_range: fold_range,
            series: vec![
                Series {
                    label: Some(format!("orbits {:.1} to {:.1}", f.orbit_start, f.orbit_end)),
                    points: folded,
                    color: PALETTE[1],
                    style: SeriesStyle::Dots,
                },
                Series {
                    label: Some("fitted sinusoid".into()),
                    points: model,
                    color: BLACK,
                    style: SeriesStyle::Dashed,
                },
            ],
        },
    ]
}

/// The observed light curve's profile folded on the orbit, two cycles.
fn orbital_panel(o: &OrbitalFigures) -> Panel {
    let mut points: Vec<(f64, f64)> = o.profile.clone();
    points.extend(o.profile.iter().map(|p| (p.0 + 1.0, p.1)));
    let inclination = o
        .inclination_deg
        .map_or(String::new(), |i| format!(" at i = {i}°"));
    Panel {
        title: format!(
            "observed light{inclination} folded on P_orb (hump at phase {:.2}, {:.3} mag)",
            o.hump_phase, o.hump_mag
        ),
        x_label: "orbital phase (0: donor in front)".into(),
        y_label: "l_observed / trend".into(),
        x_range: (0.0, 2.0),
        y_range: padded_range(points.iter().map(|p| p.1)),
        series: vec![Series {
            label: Some(format!("{} phase bins", PHASE_BINS)),
            points,
            color: PALETTE[1],
            style: SeriesStyle::Line,
        }],
    }
}

pub(crate) fn periodogram_panel(f: &LightcurveFigures) -> Panel {
    let top = f
        .periodogram
        .iter()
        .map(|p| p.1)
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.15;
    Panel {
        title: if f.detrended {
            format!(
                "Lomb–Scargle periodogram of l_total, floating cubic trend ({} rows)",
                f.rows_used
            )
        } else {
            format!(
                "generalised Lomb–Scargle periodogram of l_total ({} rows)",
                f.rows_used
            )
        },
        x_label: "period / P_orb".into(),
        y_label: "normalised power".into(),
        x_range: f.period_range_orbits,
        y_range: (0.0, top),
        series: vec![
            Series {
                label: None,
                points: f.periodogram.clone(),
                color: PALETTE[1],
                style: SeriesStyle::Line,
            },
            Series {
                label: Some("P_orb".into()),
                points: vec![(1.0, 0.0), (1.0, top)],
                color: GREY,
                style: SeriesStyle::Dashed,
            },
            Series {
                label: Some(format!(
                    "peak: P = {} P_orb",
                    plus_minus(f.period_orbits, f.period_orbits_err)
                )),
                points: vec![(f.period_orbits, 0.0), (f.period_orbits, f.power)],
                color: RED,
                style: SeriesStyle::Dashed,
            },
        ],
    }
}

/// "v ± e" with two significant digits of the error (six decimals at most shown for v if
/// the error is not finite or zero).
pub fn plus_minus(v: f64, e: f64) -> String {
    if !(e.is_finite() && e > 0.0) {
        return format!("{v:.6} ± {e}");
    }
    let decimals = (1 - e.log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.decimals$} ± {e:.decimals$}")
}

impl LightcurveReport {
    /// A short human summary, several lines, each ending in a newline.
    pub fn summary(&self) -> String {
        let f = &self.figures;
        let mut s = String::new();
        let _ = write!(
            s,
            "{}: {} rows, {} used (orbits {:.2} to {:.2}",
            self.csv.display(),
            f.rows_read,
            f.rows_used,
            f.orbit_start,
            f.orbit_end
        );
        if f.skip_orbits > 0.0 {
            let _ = write!(s, "; first {} orbits skipped", f.skip_orbits);
        }
        let _ = writeln!(s, ")");
        let _ = writeln!(
            s,
            "period {} P_orb ({} code units); (P − P_orb)/P_orb = {} %",
            plus_minus(f.period_orbits, f.period_orbits_err),
            plus_minus(f.period, f.period_err),
            plus_minus(100.0 * f.period_excess, 100.0 * f.period_excess_err)
        );
        if let Some(b) = &f.binary {
            if let (Some(p), Some(e), Some(po)) =
                (b.period_days, b.period_days_err, b.orbital_period_days)
            {
                let _ = writeln!(s, "        = {} d (P_orb = {po} d)", plus_minus(p, e));
            }
            if let (Some(q), Some(eps)) = (b.q, b.excess_patterson2005) {
                let _ = writeln!(
                    s,
                    "        superhump excess expected at q = {q}: {:.2} % (Patterson et al. 2005)",
                    100.0 * eps
                );
            }
        }
        if f.detrended {
            let _ = writeln!(
                s,
                "trend: polynomial of degree {} in time fitted with the sinusoid, {:.3e} at the first row used to {:.3e} at the last (--no-detrend: none)",
                f.trend_degree, f.trend_start, f.trend_end
            );
        } else {
            let _ = writeln!(
                s,
                "trend: none (--no-detrend): a secular rise or fall shows as a long period"
            );
        }
        let of = if f.detrended {
            "of the mean trend"
        } else {
            "of the mean"
        };
        let amp = match (f.amplitude_rel, f.amplitude_mag) {
            (Some(r), Some(m)) => format!(
                "semi-amplitude {} % {of} ({m:.4} mag peak to peak)",
                plus_minus(100.0 * r, 100.0 * f.amplitude_err / f.mean)
            ),
            (Some(r), None) => format!("semi-amplitude {:.2} % {of}", 100.0 * r),
            _ => format!(
                "semi-amplitude {} (the mean is not positive)",
                plus_minus(f.amplitude, f.amplitude_err)
            ),
        };
        let fap = if f.false_alarm > 1e-300 {
            format!("{:.1e}", f.false_alarm)
        } else {
            "< 1e-300".into()
        };
        let _ = writeln!(
            s,
            "modulation: {amp}; power {:.3}, false-alarm probability {fap}",
            f.power
        );
        if let Some(o) = &f.orbital {
            let incl = o
                .inclination_deg
                .map_or(String::new(), |i| format!(" (i = {i}°)"));
            let depth = o
                .minimum_depth_mag
                .map_or("all light hidden".to_string(), |d| format!("{d:.3} mag"));
            let _ = writeln!(
                s,
                "observed{incl}: period {} P_orb, orbital hump at phase {:.2} ({:.3} mag over the median), minimum at phase {:.2} ({depth} under it)",
                plus_minus(o.period_orbits, o.period_orbits_err),
                o.hump_phase,
                o.hump_mag,
                o.minimum_phase
            );
        }
        for n in &f.notes {
            let _ = writeln!(s, "note: {n}");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A light curve sampled every 0.01–0.05 code times (uneven, like "every few steps" of
    /// a varying time step) over `orbits` orbits: a disk modulated at `period_orbits` with
    /// relative semi-amplitude `rel`, a steady stream and spot, white noise.
    fn synthetic(seed: u64, orbits: f64, period_orbits: f64, rel: f64) -> Vec<Row> {
        let mut rng = Rng::new(seed);
        let mut rows = Vec::new();
        let mut t = 0.0;
        while t < orbits * TAU {
            let disk = 2.0 * (1.0 + rel * (t / period_orbits + 0.3).cos()) + 0.05 * rng.normal();
            let (stream, spot) = (0.2, 0.3 + 0.01 * rng.normal());
            rows.push(Row {
                t,
                orbit: t / TAU,
                l_total: disk + stream + spot,
                l_disk: disk,
                l_stream: stream,
                l_spot: spot,
                l_observed: 0.0,
            });
            t += 0.01 + 0.04 * rng.uniform();
        }
        rows
    }

    #[test]
    fn finds_a_superhump_period_and_its_amplitude() {
        let rows = synthetic(3, 30.0, 1.035, 0.05);
        let f = analyse(&rows, 5.0, true).unwrap();
        // 3σ of the stated (white-noise, here exact) uncertainty; seed fixed.
        assert!(
            (f.period_orbits - 1.035).abs() < 3.0 * f.period_orbits_err,
            "{f:?}"
        );
        // σ_f ≈ √6·0.051/(π·157·0.1·√5200) ≈ 3.5e-5, σ_P = σ_f P² ≈ 2.3e-4 P_orb: the test
        // is not vacuous.
        assert!(f.period_orbits_err < 1e-3, "{f:?}");
        assert!((f.period - 1.035 * TAU).abs() < 3.0 * f.period_err);
        assert!((f.period_excess - 0.035).abs() < 3.0 * f.period_excess_err);
        // Semi-amplitude 0.1 on a mean of 2.5: 4%. σ_A/A ≈ √(2/5200)·0.051/0.1 ≈ 1%: 5%.
        assert!(
            (f.amplitude_rel.unwrap() - 0.04).abs() < 0.05 * 0.04,
            "{f:?}"
        );
        let mag = 2.5 * (1.04f64 / 0.96).log10();
        assert!((f.amplitude_mag.unwrap() - mag).abs() < 0.05 * mag);
        assert!(
            f.power > 0.5 && f.false_alarm < 1e-6 && !f.at_range_edge,
            "{f:?}"
        );
        // Rows before orbit 5 were skipped.
        assert!((f.orbit_start - 5.0).abs() < 0.01 && f.rows_used < f.rows_read);
        assert_eq!(f.rows_used + f.first_used, rows.len());
        assert!(f.notes.is_empty(), "{:?}", f.notes);
        assert!(f.detrended && f.trend_degree == TREND_DEGREE);
        // On a steady disk the trend is flat and detrending changes next to nothing.
        assert!((f.trend_start / f.trend_end - 1.0).abs() < 0.01, "{f:?}");
        let raw = analyse(&rows, 5.0, false).unwrap();
        assert!(!raw.detrended && raw.trend_degree == 0 && raw.trend_start == raw.mean);
        assert!(
            (raw.period - f.period).abs() < 0.1 * f.period_err,
            "{raw:?}"
        );
        assert!((raw.amplitude - f.amplitude).abs() < 0.1 * f.amplitude_err);
        let f = f.with_binary(Some(0.1), Some(0.07));
        let b = f.binary.unwrap();
        assert!((b.period_days.unwrap() - 0.07 * f.period_orbits).abs() < 1e-12);
        assert!((b.excess_patterson2005.unwrap() - 0.0209).abs() < 1e-12);
    }

    /// 13 orbits of a disk that brightens as it builds up, `base(x)` at x = t/T ∈ [0, 1]
    /// (T the whole span), modulated at 1.05 P_orb: additively with semi-amplitude `amp`,
    /// or multiplicatively (`amp` relative to the base); white noise of 0.03; sampled
    /// unevenly every 0.01–0.05 code times (~2700 rows).
    fn growing(seed: u64, base: &dyn Fn(f64) -> f64, amp: f64, multiplicative: bool) -> Vec<Row> {
        let mut rng = Rng::new(seed);
        let span = 13.0 * TAU;
        let mut rows = Vec::new();
        let mut t = 0.0;
        while t < span {
            let b = base(t / span);
            let wave = (t / 1.05 + 1.3).cos();
            let disk = if multiplicative {
                b * (1.0 + amp * wave)
            } else {
                b + amp * wave
            } + 0.03 * rng.normal();
            rows.push(Row {
                t,
                orbit: t / TAU,
                l_total: disk,
                l_disk: disk,
                l_stream: 0.0,
                l_spot: 0.0,
                l_observed: 0.0,
            });
            t += 0.01 + 0.04 * rng.uniform();
        }
        rows
    }

    #[test]
    fn detrending_finds_a_superhump_on_a_growing_disk_that_the_raw_periodogram_misses() {
        // A disk that triples linearly under a constant 0.06 modulation (relative to the
        // trend's mean over orbits 1..13, 1 + 2·7/13 ≈ 2.08: 2.9%), and one that quadruples
        // quadratically under a 4% modulation proportional to its light.
        let linear = |x: f64| 1.0 + 2.0 * x;
        let quadratic = |x: f64| 1.0 + 3.0 * x * x;
        let mean_linear = 1.0 + 2.0 * 7.0 / 13.0;
        type Base<'a> = &'a dyn Fn(f64) -> f64;
        let cases: [(&str, Base, f64, bool, f64); 2] = [
            ("linear", &linear, 0.06, false, 0.06 / mean_linear),
            ("quadratic", &quadratic, 0.04, true, 0.04),
        ];
        for (name, base, amp, multiplicative, rel) in cases {
            let rows = growing(7, base, amp, multiplicative);
            let f = analyse(&rows, 1.0, true).unwrap();
            // Within 3 of the stated σ (seed fixed), and the σ small enough to mean
            // something: σ_f ≈ √6·0.03/(π·75·0.06·√2300) ≈ 1e-4, σ_P ≈ 6e-4 P_orb.
            assert!(
                (f.period_orbits - 1.05).abs() < 3.0 * f.period_orbits_err,
                "{name}: {}",
                plus_minus(f.period_orbits, f.period_orbits_err)
            );
            assert!(f.period_orbits_err < 3e-3, "{name}: {f:?}");
            // The amplitude relative to the trend, within 10% (σ_A/A ≈ 2-3%).
            let got = f.amplitude_rel.unwrap();
            assert!((got - rel).abs() < 0.1 * rel, "{name}: {got} vs {rel}");
            assert!((got - rel).abs() < 4.0 * f.amplitude_rel_err.unwrap());
            assert!(f.power > 0.3 && f.false_alarm < 1e-10, "{name}: {f:?}");
            // The trend follows the base.
            let t_end = rows[rows.len() - 1].t;
            assert!(
                (f.trend_end - base(t_end / (13.0 * TAU))).abs() < 0.03,
                "{name}: {f:?}"
            );
            // Without detrending the rise dominates: the peak goes to the long end of the
            // range (~4 P_orb, a third of the span), many of its own σ (and thousands of
            // the detrended one) from 1.05 P_orb.
            let raw = analyse(&rows, 1.0, false).unwrap();
            let miss = (raw.period_orbits - 1.05).abs();
            let brief = |g: &LightcurveFigures| {
                format!(
                    "P = {} P_orb, power {:.3}",
                    plus_minus(g.period_orbits, g.period_orbits_err),
                    g.power
                )
            };
            eprintln!("{name}: detrended {}; raw {}", brief(&f), brief(&raw));
            assert!(raw.period_orbits > 3.0, "{name}: raw {}", brief(&raw));
            assert!(
                miss > 20.0 * raw.period_orbits_err && miss > 1000.0 * f.period_orbits_err,
                "{name}: raw {}",
                brief(&raw)
            );
        }
    }

    #[test]
    fn resumed_rows_replace_the_earlier_ones() {
        let t = [0.0, 1.0, 2.0, 3.0, 1.5, 2.5, 3.5];
        let rows: Vec<Row> = t
            .iter()
            .map(|&t| Row {
                t,
                orbit: t / TAU,
                l_total: 1.0,
                l_disk: 1.0,
                l_stream: 0.0,
                l_spot: 0.0,
                l_observed: 0.0,
            })
            .collect();
        let (kept, dropped) = supersede(&rows);
        let kt: Vec<f64> = kept.iter().map(|r| r.t).collect();
        assert_eq!(kt, vec![0.0, 1.0, 1.5, 2.5, 3.5]);
        assert_eq!(dropped, 2);
    }

    #[test]
    fn parse_errors_name_the_line() {
        // The header of the brief, which the run writes (io::timeseries).
        assert_eq!(HEADER, "t,orbit,l_total,l_disk,l_stream,l_spot,l_observed");
        let ok = format!("{HEADER}\n0,0,1,1,0,0,0\n0.1,0.0159,1,1,0,0,0\n");
        assert_eq!(parse_lightcurve(&ok).unwrap().len(), 2);
        let e = parse_lightcurve("t,orbit,l_total\n0,0,1\n").unwrap_err();
        assert!(e.to_string().contains("header is `t,orbit,l_total`"), "{e}");
        let e = parse_lightcurve(&format!("{HEADER}\n0,0,1,1,0,0,0\n0.1,0,x1,1,0,0,0\n"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("line 3") && e.contains("l_total") && e.contains("x1"),
            "{e}"
        );
        let e = parse_lightcurve(&format!("{HEADER}\n0,0,1,1,0\n")).unwrap_err();
        assert!(e.to_string().contains("line 2: 5 cells"), "{e}");
        let e = parse_lightcurve(&format!("{HEADER}\n0,0,NaN,1,0,0,0\n")).unwrap_err();
        assert!(e.to_string().contains("not a finite number"), "{e}");
        assert!(parse_lightcurve("").is_err());
        // Half a last row (the run is writing it) is left out; a whole one is not.
        let partial = format!("{HEADER}\n0,0,1,1,0,0,0\n0.1,0.01");
        assert_eq!(parse_lightcurve(&partial).unwrap().len(), 1);
        let whole = format!("{HEADER}\r\n0,0,1,1,0,0,0\r\n0.1,0.01,1,1,0,0,0");
        assert_eq!(parse_lightcurve(&whole).unwrap().len(), 2);
    }

    #[test]
    fn too_few_rows_or_a_flat_curve_are_errors() {
        let rows = synthetic(4, 3.0, 1.0, 0.05);
        let e = analyse(&rows, 3.0, true).unwrap_err().to_string();
        assert!(
            e.contains("rows after skipping") && e.contains("at least 8"),
            "{e}"
        );
        assert!(analyse(&rows, -1.0, true).is_err());
        assert!(analyse(&[], 0.0, true).is_err());
        let flat: Vec<Row> = rows.iter().map(|r| Row { l_total: 1.0, ..*r }).collect();
        for detrend in [true, false] {
            let e = format!("{:#}", analyse(&flat, 0.0, detrend).unwrap_err());
            assert!(e.contains("constant"), "{e}");
        }
    }

    #[test]
    fn plus_minus_shows_two_digits_of_the_error() {
        assert_eq!(plus_minus(1.034_567, 0.002_34), "1.0346 ± 0.0023");
        assert_eq!(plus_minus(123.4, 12.0), "123 ± 12");
    }
}
