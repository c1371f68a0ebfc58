//! The approach to a steady disk in a cataclysmic-variable run (paper, Section 4): where the
//! gas the L1 stream brings goes, over time. From `monitor.csv` (cumulative masses injected,
//! accreted by the white dwarf, returned to the donor, escaped; the disk's mass and its
//! radius R90), over consecutive windows of [`WINDOW_ORBITS`] (fewer where the run is short,
//! so that it holds at least [`MIN_WINDOWS`]):
//!
//! - the rates of accretion, return and escape, and the growth of the mass still in
//!   particles (of which the disk's), each as a share of the mass injected in the same
//!   window — accreted + returned + escaped + kept = 1 where the ledger closes, as it does to
//!   round-off;
//! - the first orbit (a window's end) at which the accretion rate reaches half and 90% of
//!   the transfer rate — a disk is steady when the white dwarf takes what the donor gives;
//! - the disk's radius over the last window (median R90) against the tidal truncation radius
//!   0.60 a/(1+q) and 0.9 of the accretor's Roche-lobe radius (Eggleton 1983), the range in
//!   which a steady disk's edge is expected (exact-solutions.md 4), and against r_3:1, past
//!   which the disk turns eccentric where q ≲ 0.25.
//!
//! - the disk's viscosity from its steady state ([`steady_viscosity`]): inside the radius
//!   where the stream's gas joins the disk, a steady disk carries the accretion rate Ṁ
//!   inwards, and with no torque at its inner edge R_in its surface density is
//!   Σ = Ṁ (1 − √(R_in/R)) / (3π ν) (Pringle 1981, Eq. 3.8 integrated; Frank, King & Raine
//!   §5.3) — so ν(R) = Ṁ (1 − √(R_in/R)) / (3π Σ(R)), with Σ averaged over the snapshots of
//!   the last quarter of the run and Ṁ the white dwarf's accretion rate over the same
//!   stretch; for isothermal gas also α_eff = ν Ω_K / c_s², the α of a ν = α c_s H disk.
//!   It measures all the viscosity the disk feels — the physical one of Eqs. (8)–(10) and
//!   the shear viscosity of the artificial viscosity, α_AV c_s h / 8 in 2D (Murray 1996),
//!   unless `artificial_viscosity.orbital` removes the Keplerian shear from it.
//!
//! Pure arithmetic on the rows; `reports::cv` reads the file and writes the figures into
//! `cv.json` (key `accretion`), `cv_accretion.csv` and `cv_accretion.png`.

use std::f64::consts::TAU;

use serde::Serialize;

use crate::analysis::roche;
use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle};

/// Width of the windows over which the rates are taken (orbits).
pub const WINDOW_ORBITS: f64 = 10.0;

/// A run shorter than this many windows of [`WINDOW_ORBITS`] gets narrower windows.
pub const MIN_WINDOWS: usize = 4;

/// The monitor's columns the measurement reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LedgerRow {
    pub t: f64,
    pub mass: f64,
    pub disk_mass: f64,
    pub r_disk: f64,
    pub injected: f64,
    pub accreted: f64,
    pub returned: f64,
    pub escaped: f64,
    /// The mass on the hot branch of `[outbursts]` (0 without it).
    pub hot_mass: f64,
}

/// Parses `monitor.csv` (header `io::timeseries::MONITOR_HEADER`), keeping the rows of the
/// latest pass through each time (a resumed run).
pub fn parse_ledger(text: &str) -> anyhow::Result<Vec<LedgerRow>> {
    let rows =
        crate::io::timeseries::parse_series(text, crate::io::timeseries::MONITOR_HEADER, false)?
            .into_iter()
            .map(|v| LedgerRow {
                t: v[0],
                mass: v[3],
                disk_mass: v[4],
                r_disk: v[5],
                injected: v[6],
                accreted: v[7],
                returned: v[8],
                escaped: v[9],
                hot_mass: v[10],
            });
    Ok(crate::io::timeseries::supersede(rows, |r| r.t))
}

/// One window: its end (orbits), the mass injected per orbit, and where it went, each as a
/// share of what was injected in the window.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RateWindow {
    pub orbit_start: f64,
    pub orbit_end: f64,
    pub injected_per_orbit: f64,
    pub accreted: f64,
    pub returned: f64,
    pub escaped: f64,
    /// The growth of the mass in particles, and of the disk's part of it.
    pub kept: f64,
    pub disk_growth: f64,
    /// The median R90 over the window's rows.
    pub r_disk_90: f64,
}

/// What the run's ledger says about its approach to a steady disk (module doc).
#[derive(Clone, Debug, Serialize)]
pub struct AccretionFigures {
    pub window_orbits: f64,
    /// Every window, first to last (in `cv_accretion.csv`, not in the JSON).
    #[serde(skip)]
    pub windows: Vec<RateWindow>,
    /// The last window.
    pub last: RateWindow,
    /// The first window end at which the accretion rate reached half and 90% of the
    /// transfer rate (`None`: not in this run).
    pub accretion_half_orbit: Option<f64>,
    pub accretion_ninety_orbit: Option<f64>,
    /// The disk's radius over the last window against the tidal radius, 0.9 of the
    /// accretor's Roche-lobe radius and r_3:1.
    pub tidal_radius: f64,
    pub roche_lobe_09: f64,
    pub r_31: f64,
    pub r_disk_over_tidal: f64,
    /// The viscosity the steady disk shows (`None` where the run is not long enough, or
    /// the white dwarf accretes less than half the transfer rate over its last quarter).
    pub viscosity: Option<SteadyViscosity>,
}

/// The fewest radial bins with gas for [`steady_viscosity`].
pub const MIN_VISCOSITY_BINS: usize = 3;

/// ν from the steady disk's Σ(R) and Ṁ (module doc).
#[derive(Clone, Debug, Serialize)]
pub struct SteadyViscosity {
    /// The stretch (orbits) over which Σ and Ṁ were averaged, and the snapshots in it.
    pub orbits: (f64, f64),
    pub snapshots: usize,
    /// Ṁ onto the white dwarf (mass per unit code time), and its ratio to the transfer
    /// rate over the same stretch.
    pub accretion_rate: f64,
    pub accretion_share: f64,
    /// (R, Σ, ν, α_eff) per radial bin from 1.5 R_in to the stream's circularisation
    /// radius r_circ; α_eff is NaN (null) unless the gas is isothermal.
    pub bins: Vec<(f64, f64, f64, f64)>,
    /// The mass-weighted mean ν and α_eff over those bins.
    pub nu: f64,
    pub alpha_eff: f64,
}

impl SteadyViscosity {
    /// The line `analyse cv` prints; α_eff only where the gas is isothermal (else it
    /// would read "NaN").
    pub fn summary_line(&self) -> String {
        let iso = self.alpha_eff.is_finite();
        let bins = self
            .bins
            .iter()
            .map(|(r, _, nu, al)| match iso {
                true => format!("{r:.3} {nu:.2e} {al:.2}"),
                false => format!("{r:.3} {nu:.2e}"),
            })
            .collect::<Vec<_>>()
            .join("; ");
        let (alpha, columns) = match iso {
            true => (format!(", α_eff = {:.3}", self.alpha_eff), "R, ν, α_eff"),
            false => (
                " (α_eff needs an isothermal sound speed; the gas is not isothermal)".into(),
                "R, ν",
            ),
        };
        format!(
            "the steady disk's viscosity (orbits {:.1}–{:.1}, {} snapshots, Ṁ = {:.3} of the \
             transfer rate): ν = {:.3e} a² Ω_orb{alpha} ({columns}: {bins})",
            self.orbits.0, self.orbits.1, self.snapshots, self.accretion_share, self.nu,
        )
    }
}

/// The disk particles' cylindrical radii and masses of the snapshots averaged over.
pub struct DiskSample {
    pub orbit: f64,
    pub radius_mass: Vec<(f64, f64)>,
}

/// ν(R) of a steady disk (module doc) between `r_lo` and `r_hi` in `bins` annuli, from the
/// samples' mean Σ and the accretion rate `mdot` (mass per unit time); `gm` = G M1 and
/// `cs` the isothermal sound speed (`None`: no α_eff). `None` with fewer than
/// [`MIN_VISCOSITY_BINS`] annuli holding gas.
#[allow(clippy::too_many_arguments)]
pub fn steady_viscosity(
    samples: &[DiskSample],
    mdot: f64,
    accretion_share: f64,
    r_in: f64,
    (r_lo, r_hi): (f64, f64),
    bins: usize,
    gm: f64,
    cs: Option<f64>,
) -> Option<SteadyViscosity> {
    if samples.is_empty() || !(mdot > 0.0) || !(r_hi > r_lo) || bins == 0 {
        return None;
    }
    let width = (r_hi - r_lo) / bins as f64;
    let mut mass = vec![0.0; bins];
    for s in samples {
        for &(r, m) in &s.radius_mass {
            let k = ((r - r_lo) / width).floor();
            if k >= 0.0 && (k as usize) < bins {
                mass[k as usize] += m;
            }
        }
    }
    let n = samples.len() as f64;
    let mut out = Vec::new();
    let (mut w, mut nu_sum, mut alpha_sum) = (0.0, 0.0, 0.0);
    for (k, &m) in mass.iter().enumerate() {
        if m <= 0.0 {
            continue;
        }
        let (a, b) = (r_lo + k as f64 * width, r_lo + (k + 1) as f64 * width);
        let r = 0.5 * (a + b);
        let sigma = m / n / (std::f64::consts::PI * (b * b - a * a));
        let nu = mdot * (1.0 - (r_in / r).sqrt()) / (3.0 * std::f64::consts::PI * sigma);
        let omega = (gm / r.powi(3)).sqrt();
        let alpha = cs.map_or(f64::NAN, |c| nu * omega / (c * c));
        out.push((r, sigma, nu, alpha));
        w += m;
        nu_sum += m * nu;
        alpha_sum += m * alpha;
    }
    if out.len() < MIN_VISCOSITY_BINS {
        return None;
    }
    Some(SteadyViscosity {
        orbits: (samples[0].orbit, samples[samples.len() - 1].orbit),
        snapshots: samples.len(),
        accretion_rate: mdot,
        accretion_share,
        bins: out,
        nu: nu_sum / w,
        alpha_eff: alpha_sum / w,
    })
}

/// The white dwarf's accretion rate (mass per unit time) and its share of the transfer
/// rate between orbits `from` and `to` (the rows nearest them).
pub fn accretion_rate(rows: &[LedgerRow], from: f64, to: f64) -> Option<(f64, f64)> {
    if rows.is_empty() {
        return None;
    }
    let (a, b) = (&rows[row_at(rows, from)], &rows[row_at(rows, to)]);
    let (dt, inj) = (b.t - a.t, b.injected - a.injected);
    (dt > 0.0 && inj > 0.0).then(|| {
        let acc = b.accreted - a.accreted;
        (acc / dt, acc / inj)
    })
}

/// The windows and figures of the rows (module doc); `None` with fewer than two windows'
/// worth of rows or where no mass was injected.
pub fn accretion_figures(rows: &[LedgerRow], q: f64) -> Option<AccretionFigures> {
    let (first, last) = (rows.first()?, rows.last()?);
    let span = (last.t - first.t) / TAU;
    if rows.len() < 2 * MIN_WINDOWS || !(span > 0.0) || !(last.injected > first.injected) {
        return None;
    }
    let width = WINDOW_ORBITS.min(span / MIN_WINDOWS as f64);
    let count = (span / width).floor() as usize;
    // Windows end at the last row and are laid back from it, so the last is always full.
    let t_end = last.t / TAU;
    let at = |orbit: f64| row_at(rows, orbit);
    let mut windows = Vec::with_capacity(count);
    for k in (0..count).rev() {
        let (o0, o1) = (t_end - (k + 1) as f64 * width, t_end - k as f64 * width);
        let (a, b) = (&rows[at(o0)], &rows[at(o1)]);
        let dt_orbits = (b.t - a.t) / TAU;
        let injected = b.injected - a.injected;
        if !(dt_orbits > 0.0) || !(injected > 0.0) {
            continue;
        }
        let share = |x0: f64, x1: f64| (x1 - x0) / injected;
        let mut radii: Vec<f64> = rows[at(o0)..=at(o1)]
            .iter()
            .map(|r| r.r_disk)
            .filter(|r| r.is_finite() && *r > 0.0)
            .collect();
        radii.sort_by(f64::total_cmp);
        windows.push(RateWindow {
            orbit_start: a.t / TAU,
            orbit_end: b.t / TAU,
            injected_per_orbit: injected / dt_orbits,
            accreted: share(a.accreted, b.accreted),
            returned: share(a.returned, b.returned),
            escaped: share(a.escaped, b.escaped),
            kept: share(a.mass, b.mass),
            disk_growth: share(a.disk_mass, b.disk_mass),
            r_disk_90: radii.get(radii.len() / 2).copied().unwrap_or(f64::NAN),
        });
    }
    let last_window = *windows.last()?;
    let reaches = |x: f64| {
        windows
            .iter()
            .find(|w| w.accreted >= x)
            .map(|w| w.orbit_end)
    };
    let tidal_radius = roche::tidal_radius(q);
    Some(AccretionFigures {
        window_orbits: width,
        accretion_half_orbit: reaches(0.5),
        accretion_ninety_orbit: reaches(0.9),
        tidal_radius,
        roche_lobe_09: 0.9 * roche::eggleton_radius(1.0 / q),
        r_31: roche::r_31(q),
        r_disk_over_tidal: last_window.r_disk_90 / tidal_radius,
        viscosity: None,
        last: last_window,
        windows,
    })
}

/// The index of the first row at or after `orbit` (the last row if none is); `rows` is not
/// empty and sorted by time.
fn row_at(rows: &[LedgerRow], orbit: f64) -> usize {
    rows.partition_point(|r| r.t / TAU < orbit - 1e-9)
        .min(rows.len() - 1)
}

/// `cv_accretion.csv`: a header and a row per window.
pub fn windows_csv(windows: &[RateWindow]) -> String {
    let mut s = String::from(
        "orbit_start,orbit_end,injected_per_orbit,accreted,returned,escaped,kept,disk_growth,r_disk_90\n",
    );
    for w in windows {
        s.push_str(&format!(
            "{:.4},{:.4},{:.6e},{:.6},{:.6},{:.6},{:.6},{:.6},{:.5}\n",
            w.orbit_start,
            w.orbit_end,
            w.injected_per_orbit,
            w.accreted,
            w.returned,
            w.escaped,
            w.kept,
            w.disk_growth,
            w.r_disk_90
        ));
    }
    s
}

/// The two panels of `cv_accretion.png`: where the injected mass goes, window by window;
/// the disk's radius against the radii that bound it.
pub fn panels(f: &AccretionFigures) -> Vec<Panel> {
    let x_range = (
        f.windows.first().map_or(0.0, |w| w.orbit_start),
        f.windows.last().map_or(1.0, |w| w.orbit_end),
    );
    let pts = |g: fn(&RateWindow) -> f64| -> Vec<(f64, f64)> {
        f.windows
            .iter()
            .map(|w| (0.5 * (w.orbit_start + w.orbit_end), g(w)))
            .collect()
    };
    let line = |label: &str, points, color, style| Series {
        label: Some(label.into()),
        points,
        color,
        style,
    };
    let shares = [
        pts(|w| w.accreted),
        pts(|w| w.returned),
        pts(|w| w.escaped),
        pts(|w| w.kept),
        pts(|w| w.disk_growth),
    ];
    let (lo, hi) = shares
        .iter()
        .flatten()
        .fold((0.0f64, 1.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let [acc, ret, esc, kept, grow] = shares;
    let level = |y: f64| vec![(x_range.0, y), (x_range.1, y)];
    let radius = pts(|w| w.r_disk_90);
    let r_hi = radius
        .iter()
        .map(|p| p.1)
        .fold(f.tidal_radius.max(f.roche_lobe_09), f64::max);
    vec![
        Panel {
            title: format!(
                "where the stream's gas goes ({:.1}-orbit windows)",
                f.window_orbits
            ),
            x_label: "orbit (t / P_orb)".into(),
            y_label: "share of the mass injected".into(),
            x_range,
            y_range: (lo - 0.05, hi + 0.05),
            series: vec![
                line(
                    "accreted by the white dwarf",
                    acc,
                    PALETTE[0],
                    SeriesStyle::Line,
                ),
                line("returned to the donor", ret, PALETTE[1], SeriesStyle::Line),
                line("escaped", esc, PALETTE[2], SeriesStyle::Line),
                line("kept in particles", kept, PALETTE[3], SeriesStyle::Line),
                line(
                    "of which in the disk",
                    grow,
                    PALETTE[3],
                    SeriesStyle::Dashed,
                ),
            ],
        },
        Panel {
            title: "the disk's radius R90".into(),
            x_label: "orbit (t / P_orb)".into(),
            y_label: "R90 / a".into(),
            x_range,
            y_range: (0.0, 1.05 * r_hi),
            series: vec![
                line("R90", radius, PALETTE[0], SeriesStyle::Line),
                line(
                    "tidal radius 0.60 a/(1+q)",
                    level(f.tidal_radius),
                    PALETTE[1],
                    SeriesStyle::Dashed,
                ),
                line(
                    "0.9 R_L (Eggleton)",
                    level(f.roche_lobe_09),
                    PALETTE[2],
                    SeriesStyle::Dashed,
                ),
                line("r_3:1", level(f.r_31), PALETTE[4], SeriesStyle::Dashed),
            ],
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ledger whose white dwarf takes a share 0.95 (1 − e^{−t/τ}) of the transfer rate,
    /// the donor a fixed 5%, nothing escaping, the particles the rest, 98% of them in the
    /// disk; R90 growing to 0.46 a.
    fn ledger(orbits: f64, tau: f64) -> Vec<LedgerRow> {
        let rate = 1e-6; // per orbit
        (0..=(orbits * 50.0) as usize)
            .map(|k| {
                let o = k as f64 / 50.0;
                let injected = rate * o;
                // ∫ (1 − e^{−s/τ}) ds − 5%.
                let accreted = rate * (o - tau * (1.0 - (-o / tau).exp())) * 0.95;
                let returned = 0.05 * injected;
                LedgerRow {
                    t: o * TAU,
                    mass: injected - accreted - returned,
                    disk_mass: 0.98 * (injected - accreted - returned),
                    r_disk: 0.46 * (1.0 - (-o / 20.0).exp()),
                    injected,
                    accreted,
                    returned,
                    escaped: 0.0,
                    hot_mass: 0.0,
                }
            })
            .collect()
    }

    #[test]
    fn the_shares_of_a_known_ledger_add_up_and_the_accretion_reaches_the_transfer_rate() {
        let (orbits, tau) = (200.0, 30.0);
        let f = accretion_figures(&ledger(orbits, tau), 0.1).unwrap();
        assert_eq!(f.window_orbits, WINDOW_ORBITS);
        assert_eq!(f.windows.len(), 20);
        for w in &f.windows {
            let sum = w.accreted + w.returned + w.escaped + w.kept;
            assert!((sum - 1.0).abs() < 1e-9, "{w:?}");
            assert!((w.disk_growth - 0.98 * w.kept).abs() < 1e-12, "{w:?}");
            assert!((w.injected_per_orbit - 1e-6).abs() < 1e-15);
            assert!((w.returned - 0.05).abs() < 1e-9);
            // The window's mean of 0.95 (1 − e^{−s/τ}), exactly.
            let (a, b) = (w.orbit_start, w.orbit_end);
            let mean = 0.95 * (1.0 - tau * ((-a / tau).exp() - (-b / tau).exp()) / (b - a));
            assert!((w.accreted - mean).abs() < 1e-9, "{w:?} vs {mean}");
        }
        // 0.95 (1 − e^{−s/τ}) averaged over a 10-orbit window reaches 0.5 in the window
        // ending at orbit 30 (mean 0.535 over 20–30; 0.371 over 10–20) and 0.9 at orbit 100
        // (0.910 over 90–100; 0.894 over 80–90).
        let near = |x: Option<f64>, y: f64| x.is_some_and(|x| (x - y).abs() < 1e-9);
        assert!(near(f.accretion_half_orbit, 30.0), "{f:?}");
        assert!(near(f.accretion_ninety_orbit, 100.0), "{f:?}");
        assert!((f.last.r_disk_90 - 0.46).abs() < 1e-3);
        assert!((f.tidal_radius - 0.6 / 1.1).abs() < 1e-12);
        assert!((f.r_disk_over_tidal - 0.46 / (0.6 / 1.1)).abs() < 2e-3);
    }

    /// A steady disk with ν = 2.4e-4 (the shear viscosity measured in cv2d_steady with the
    /// artificial viscosity on shear) sampled by equal-mass particles placed at the radii
    /// where its cumulative mass reaches (k + ½)/N: ν comes back to within the binning
    /// (each of 10 annuli of 0.012 a holds ~100 particles of the 1000 in each of 4
    /// snapshots; the mid-point Σ of a smooth profile is right to (Δr/R)² ~ 1%).
    #[test]
    fn the_viscosity_of_a_steady_disk_comes_back_from_its_surface_density() {
        let (nu, mdot, r_in, gm, cs) = (2.4e-4, 1e-3 / TAU, 0.1, 1.0 / 1.1, 0.05);
        let sigma = |r: f64| mdot * (1.0 - (r_in / r).sqrt()) / (3.0 * std::f64::consts::PI * nu);
        // Cumulative mass on a fine grid from 0.1 to 0.3, then inverted.
        let grid: Vec<f64> = (0..=20_000)
            .map(|k| 0.1 + 0.2 * k as f64 / 20_000.0)
            .collect();
        let mut cum = vec![0.0];
        for w in grid.windows(2) {
            let r = 0.5 * (w[0] + w[1]);
            cum.push(cum.last().unwrap() + sigma(r) * TAU * r * (w[1] - w[0]));
        }
        let total = *cum.last().unwrap();
        let n = 1000;
        let m = total / n as f64;
        let radius_mass: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let target = (k as f64 + 0.5) * m;
                let j = cum.partition_point(|c| *c < target).min(grid.len() - 1);
                (grid[j], m)
            })
            .collect();
        let samples: Vec<DiskSample> = (0..4)
            .map(|k| DiskSample {
                orbit: 100.0 + k as f64,
                radius_mass: radius_mass.clone(),
            })
            .collect();
        let v =
            steady_viscosity(&samples, mdot, 0.9, r_in, (0.15, 0.27), 10, gm, Some(cs)).unwrap();
        assert_eq!(v.bins.len(), 10);
        for &(r, _, nu_r, alpha) in &v.bins {
            assert!((nu_r / nu - 1.0).abs() < 0.03, "R {r}: ν {nu_r}");
            let expected = nu * (gm / r.powi(3)).sqrt() / (cs * cs);
            assert!((alpha / expected - 1.0).abs() < 0.03, "R {r}: α {alpha}");
        }
        assert!((v.nu / nu - 1.0).abs() < 0.01, "{}", v.nu);
        assert_eq!(v.orbits, (100.0, 103.0));
        // Too few annuli with gas: no figure.
        assert!(steady_viscosity(&samples, mdot, 0.9, r_in, (0.29, 0.5), 10, gm, None).is_none());
        // Without an isothermal c_s the line gives ν alone, never "NaN".
        let v = steady_viscosity(&samples, mdot, 0.9, r_in, (0.15, 0.27), 10, gm, None).unwrap();
        let line = v.summary_line();
        assert!(
            !line.contains("NaN") && line.contains("isothermal"),
            "{line}"
        );
        let iso = steady_viscosity(&samples, mdot, 0.9, r_in, (0.15, 0.27), 10, gm, Some(cs));
        let line = iso.unwrap().summary_line();
        assert!(line.contains("α_eff = ") && !line.contains("NaN"), "{line}");
    }

    #[test]
    fn the_accretion_rate_between_two_orbits_is_read_off_the_ledger() {
        let rows = ledger(200.0, 30.0);
        let (mdot, share) = accretion_rate(&rows, 150.0, 200.0).unwrap();
        // 0.95 (1 − e^{−s/τ}) averaged over 150–200 orbits: 0.95 (1 − 30 (e^{−5} − e^{−20/3})/50).
        let expected = 0.95 * (1.0 - 30.0 * ((-5.0f64).exp() - (-20.0f64 / 3.0).exp()) / 50.0);
        assert!((share - expected).abs() < 1e-9, "{share} vs {expected}");
        assert!((mdot - expected * 1e-6 / TAU).abs() < 1e-15);
    }

    #[test]
    fn a_short_run_gets_narrower_windows_and_a_run_without_a_stream_none() {
        let f = accretion_figures(&ledger(20.0, 30.0), 0.1).unwrap();
        assert!((f.window_orbits - 5.0).abs() < 1e-12);
        assert_eq!(f.windows.len(), MIN_WINDOWS);
        assert_eq!(f.accretion_ninety_orbit, None);
        let mut dry = ledger(20.0, 30.0);
        for r in &mut dry {
            r.injected = 0.0;
        }
        assert!(accretion_figures(&dry, 0.1).is_none());
        assert!(accretion_figures(&ledger(20.0, 30.0)[..5], 0.1).is_none());
    }
}
