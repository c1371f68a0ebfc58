//! The superhump's phase against the disk's apsidal line (part of `analyse superhump`): why
//! the light curve's period can differ from the beat of the measured precession.
//!
//! The superhump is the tidal dissipation peaking once per beat of the precessing eccentric
//! disk with the orbit, so the light curve follows the longitude of periastron in the frame
//! turning with the binary, ψ(t) = ϖ(t) − Ω t: L(t) ≈ L̄(t) + A cos(ψ(t) − φ), with φ the
//! angle between the secondary and the apsidal line at which the disk shines most. If φ is
//! fixed, P_sh is exactly the beat P_orb/(1 − ω_p). If the hump moves along the beat cycle
//! as the disk's shape changes (its eccentricity growing, its rim shrinking — the period
//! changes of observed superhumps' stages A–C, Kato et al. 2009), φ drifts and the light
//! curve's frequency in cycles per orbit is
//!
//!   f_sh = (1 − ω_p) + φ̇ / 360°   (φ̇ in degrees per orbit),
//!
//! so ε = 1/f_sh − 1 differs from ε_beat by about φ̇/360° — a drift of −1° per orbit adds
//! 0.0028 to ε. This module measures φ in consecutive windows of [`WINDOW_ORBITS`]: in each,
//! the light curve less a straight line is fitted by least squares with cos ψ and sin ψ
//! (ψ interpolated from the precession's longitude track), φ = atan2 of the two
//! coefficients; a line through the unwrapped φ against time gives φ̇ and its error (the
//! windows do not overlap, so their phases are independent to the extent the noise is), and
//! `epsilon_locked` is the ε that the beat and the drift together predict — what the
//! periodogram should find if the light curve is the dissipation of the measured disk.

use std::f64::consts::TAU;

use serde::Serialize;

use crate::reports::lightcurve::Row;
use crate::reports::superhump::{line_fit, unwrap_deg};

/// Length of the windows in which the hump's phase is fitted, in orbits: a few beat cycles,
/// long against the 1/f_sh − 1/f_beat mismatch that a window of one cycle could not tell
/// from noise, short against the stretch (tens of orbits) over which the drift is fitted.
pub const WINDOW_ORBITS: f64 = 4.0;

/// Fewest windows for a drift and its error: four leave the line's error two degrees of
/// freedom.
pub const MIN_WINDOWS: usize = 4;

/// The hump's phase against the apsidal line and its drift.
#[derive(Clone, Debug, Serialize)]
pub struct HumpPhase {
    pub window_orbits: f64,
    /// (window centre in orbits, φ in degrees unwrapped, relative semi-amplitude A/L̄).
    pub phases: Vec<(f64, f64, f64)>,
    /// φ̇ in degrees per orbit and its least-squares error.
    pub drift_deg_per_orbit: f64,
    pub drift_err: f64,
    /// ε = 1/((1 − ω_p) + φ̇/360°) − 1 and its error (from ω_p's and φ̇'s, combined).
    pub epsilon_locked: f64,
    pub epsilon_locked_err: f64,
}

/// The turning-frame longitude of periastron (degrees, unwrapped) at `orbit`, linear
/// between the points of the precession's track ((orbit, unwrapped inertial longitude));
/// None outside it.
fn turning_longitude(track: &[(f64, f64)], orbit: f64) -> Option<f64> {
    let k = track.partition_point(|p| p.0 < orbit);
    if k == 0 || k == track.len() {
        return (track.first()?.0 == orbit).then(|| track[0].1 - 360.0 * orbit);
    }
    let (a, b) = (track[k - 1], track[k]);
    let s = (orbit - a.0) / (b.0 - a.0);
    Some(a.1 + s * (b.1 - a.1) - 360.0 * orbit)
}

/// φ (degrees) and A/L̄ of one window's rows: the residual of L about its straight line,
/// fitted as c cos ψ + s sin ψ. None for fewer than 8 rows or a singular fit.
fn window_phase(orbit: &[f64], l: &[f64], psi_deg: &[f64]) -> Option<(f64, f64)> {
    let n = orbit.len();
    if n < 8 {
        return None;
    }
    let ml = l.iter().sum::<f64>() / n as f64;
    let (a0, slope) = line_fit(orbit, l)?;
    if ml == 0.0 {
        return None;
    }
    let (mut cc, mut ss, mut cs, mut cy, mut sy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..n {
        let y = l[k] - a0 - slope * orbit[k];
        let (s, c) = psi_deg[k].to_radians().sin_cos();
        cc += c * c;
        ss += s * s;
        cs += c * s;
        cy += c * y;
        sy += s * y;
    }
    let det = cc * ss - cs * cs;
    if !(det > 1e-9 * cc * ss) {
        return None;
    }
    let a = (cy * ss - sy * cs) / det;
    let b = (sy * cc - cy * cs) / det;
    Some((b.atan2(a).to_degrees(), a.hypot(b) / ml.abs()))
}

/// The hump's phase and drift over `from`..`to` orbits (module doc): `track` is the
/// precession's (orbit, unwrapped inertial longitude of periastron) and `rate`, `rate_err`
/// its ω_p in Ω_orb; `light` the light curve (l_total). None with fewer than
/// [`MIN_WINDOWS`] windows that fit.
pub fn hump_phase(
    track: &[(f64, f64)],
    rate: f64,
    rate_err: f64,
    light: &[Row],
    from: f64,
    to: f64,
) -> Option<HumpPhase> {
    let windows = ((to - from) / WINDOW_ORBITS).floor();
    if !(windows >= MIN_WINDOWS as f64) {
        return None;
    }
    let mut phases = Vec::new();
    for w in 0..windows as usize {
        let (lo, hi) = (
            from + w as f64 * WINDOW_ORBITS,
            from + (w + 1) as f64 * WINDOW_ORBITS,
        );
        let (mut t, mut l, mut psi) = (Vec::new(), Vec::new(), Vec::new());
        for r in light {
            let orbit = r.t / TAU;
            if (lo..hi).contains(&orbit)
                && r.l_total.is_finite()
                && let Some(p) = turning_longitude(track, orbit)
            {
                t.push(orbit);
                l.push(r.l_total);
                psi.push(p);
            }
        }
        if let Some((phi, amp)) = window_phase(&t, &l, &psi) {
            phases.push((0.5 * (lo + hi), phi, amp));
        }
    }
    if phases.len() < MIN_WINDOWS {
        return None;
    }
    let t: Vec<f64> = phases.iter().map(|p| p.0).collect();
    let phi = unwrap_deg(&phases.iter().map(|p| p.1).collect::<Vec<f64>>());
    for (p, u) in phases.iter_mut().zip(&phi) {
        p.1 = *u;
    }
    let (a, drift) = line_fit(&t, &phi)?;
    let n = t.len() as f64;
    let mt = t.iter().sum::<f64>() / n;
    let stt: f64 = t.iter().map(|x| (x - mt).powi(2)).sum();
    let rss: f64 = t
        .iter()
        .zip(&phi)
        .map(|(x, y)| (y - a - drift * x).powi(2))
        .sum();
    let drift_err = (rss / (n - 2.0) / stt).sqrt();
    let f = (1.0 - rate) + drift / 360.0;
    // dε/dω_p = 1/f², dε/dφ̇ = −1/(360 f²).
    let epsilon_locked_err = (rate_err.hypot(drift_err / 360.0)) / (f * f);
    Some(HumpPhase {
        window_orbits: WINDOW_ORBITS,
        phases,
        drift_deg_per_orbit: drift,
        drift_err,
        epsilon_locked: 1.0 / f - 1.0,
        epsilon_locked_err,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A disk precessing at `w` Ω_orb (its periastron's inertial longitude 30° + w Ω t) and a
    /// light curve L = 1 + 0.2 cos(ψ − φ(t)), φ(t) = 40° + `drift` · orbit, with seeded uniform
    /// noise of ±0.05: rows every 0.02 orbit over 60 orbits.
    fn disk(w: f64, drift: f64) -> (Vec<(f64, f64)>, Vec<Row>) {
        let mut rng = crate::rng::Rng::new(99);
        let mut noise = move || rng.uniform() - 0.5;
        let track: Vec<(f64, f64)> = (0..=600)
            .map(|k| {
                let orbit = k as f64 * 0.1;
                (orbit, 30.0 + 360.0 * w * orbit)
            })
            .collect();
        let light = (0..3000)
            .map(|k| {
                let orbit = k as f64 * 0.02;
                let psi = (30.0 + 360.0 * (w - 1.0) * orbit).to_radians();
                let phi = (40.0 + drift * orbit).to_radians();
                let l = 1.0 + 0.2 * (psi - phi).cos() + 0.1 * noise();
                Row {
                    t: orbit * TAU,
                    orbit,
                    l_total: l,
                    l_disk: l,
                    l_stream: 0.0,
                    l_spot: 0.0,
                    l_observed: l,
                }
            })
            .collect();
        (track, light)
    }

    #[test]
    fn a_hump_locked_to_the_apsides_has_the_beat_period() {
        let w = 0.026;
        let (track, light) = disk(w, 0.0);
        let h = hump_phase(&track, w, 0.0, &light, 0.0, 60.0).unwrap();
        assert_eq!(h.phases.len(), 15);
        // Noise ±0.05 over ~200 rows per window against an amplitude 0.2 puts each φ within
        // about a degree: 0.1°/orbit bounds the drift, 3° each phase.
        assert!(
            h.drift_deg_per_orbit.abs() < 0.1,
            "{}",
            h.drift_deg_per_orbit
        );
        for p in &h.phases {
            assert!((p.1 - 40.0).abs() < 3.0, "{p:?}");
            assert!((p.2 - 0.2).abs() < 0.02, "{p:?}");
        }
        assert!((h.epsilon_locked - w / (1.0 - w)).abs() < 3e-4);
    }

    #[test]
    fn a_drifting_hump_gives_the_light_curves_period_not_the_beats() {
        // φ drifts by −1° per orbit: the light curve's frequency is (1 − w) − 1/360 cycles
        // per orbit, ε = 0.0295 against the beat's 0.0267 — the size of the mismatch found
        // in the cooler disks.
        let (w, drift) = (0.026, -1.0);
        let (track, light) = disk(w, drift);
        let h = hump_phase(&track, w, 0.0, &light, 0.0, 60.0).unwrap();
        assert!(
            (h.drift_deg_per_orbit - drift).abs() < 0.1,
            "{} ± {}",
            h.drift_deg_per_orbit,
            h.drift_err
        );
        assert!(h.drift_err < 0.1);
        let expected = 1.0 / (1.0 - w + drift / 360.0) - 1.0;
        // 0.1°/orbit in the drift is 2.9e-4 in ε.
        assert!(
            (h.epsilon_locked - expected).abs() < 3e-4,
            "{}",
            h.epsilon_locked
        );
        // The periodogram of the same light curve finds the same period.
        let f = crate::reports::lightcurve::analyse_range(&light, 0.0, true, (0.8, 1.5)).unwrap();
        assert!(
            (f.period_excess - h.epsilon_locked).abs() < 5e-4,
            "periodogram ε {} against locked {}",
            f.period_excess,
            h.epsilon_locked
        );
        assert!((f.period_excess - w / (1.0 - w)).abs() > 2e-3);
    }

    #[test]
    fn too_short_a_stretch_gives_no_drift() {
        let (track, light) = disk(0.026, 0.0);
        assert!(hump_phase(&track, 0.026, 0.0, &light, 0.0, 15.0).is_none());
        assert!(hump_phase(&track, 0.026, 0.0, &light, 0.0, f64::NAN).is_none());
    }
}
