//! Exact solutions the validations compare against, and the measurements taken from particles
//! (error norms, binned profiles, front positions).

pub mod advection;
pub mod observer;
pub mod periodogram;
pub mod riemann;
pub mod ring;
pub mod roche;
pub mod sedov;
pub mod viscous_disk;

use crate::particles::Particles;

/// The standard error of the mean of `values`: their sample standard deviation (n − 1)
/// over √n; NaN for fewer than two values.
pub fn standard_error(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    var.sqrt() / n.sqrt()
}

/// The `fraction` quantile of values weighted by masses, (value, mass) pairs: the value at
/// which the mass sorted by value reaches `fraction` of the total; None without mass.
pub fn weighted_quantile(mut vm: Vec<(f64, f64)>, fraction: f64) -> Option<f64> {
    vm.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = vm.iter().map(|x| x.1).sum();
    if !(total > 0.0) {
        return None;
    }
    let mut acc = 0.0;
    for &(v, m) in &vm {
        acc += m;
        if acc >= fraction * total {
            return Some(v);
        }
    }
    vm.last().map(|x| x.0)
}

/// A point of a Kepler ellipse in the plane about a mass `gm` at the origin: semi-major axis
/// `a`, eccentricity `e` < 1, periastron at azimuth `varpi` (radians), mean anomaly `mean`.
/// Returns the position and the inertial velocity.
pub fn kepler_point(gm: f64, a: f64, e: f64, varpi: f64, mean: f64) -> ([f64; 2], [f64; 2]) {
    // Kepler's equation E − e sin E = M by Newton's method.
    let mut ecc = mean;
    for _ in 0..50 {
        ecc -= (ecc - e * ecc.sin() - mean) / (1.0 - e * ecc.cos());
    }
    let f =
        2.0 * ((1.0 + e).sqrt() * (0.5 * ecc).sin()).atan2((1.0 - e).sqrt() * (0.5 * ecc).cos());
    let semi_latus = a * (1.0 - e * e);
    let r = semi_latus / (1.0 + e * f.cos());
    let (s, c) = (f + varpi).sin_cos();
    // Radial and tangential speeds of a Kepler orbit.
    let vk = (gm / semi_latus).sqrt();
    let (vr, vt) = (vk * e * f.sin(), vk * (1.0 + e * f.cos()));
    ([r * c, r * s], [vr * c - vt * s, vr * s + vt * c])
}

/// Volume-weighted L1 norm ∫|e| dV / ∫dV with particle volumes m/ρ.
pub fn l1_norm<const D: usize>(p: &Particles<D>, err: impl Fn(usize) -> f64) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..p.len() {
        let v = p.mass[i] / p.rho[i];
        num += v * err(i).abs();
        den += v;
    }
    num / den
}

/// Mean density in bins of width `bin` along x, as (bin centre, mean ρ), empty bins skipped.
pub fn x_profile<const D: usize>(p: &Particles<D>, bin: f64) -> Vec<(f64, f64)> {
    binned(p.len(), |i| p.pos[0][i], |i| p.rho[i], bin)
}

/// Mean density in spherical (circular) shells of width `bin` about `centre`.
pub fn radial_profile<const D: usize>(
    p: &Particles<D>,
    centre: [f64; D],
    bin: f64,
) -> Vec<(f64, f64)> {
    let r = |i: usize| {
        (0..D)
            .map(|d| (p.pos[d][i] - centre[d]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    binned(p.len(), r, |i| p.rho[i], bin)
}

fn binned(
    n: usize,
    coord: impl Fn(usize) -> f64,
    value: impl Fn(usize) -> f64,
    bin: f64,
) -> Vec<(f64, f64)> {
    let (lo, hi) = (0..n)
        .map(&coord)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if n == 0 {
        return Vec::new();
    }
    let nb = ((hi - lo) / bin).floor() as usize + 1;
    let mut sum = vec![0.0; nb];
    let mut count = vec![0usize; nb];
    for i in 0..n {
        let b = (((coord(i) - lo) / bin).floor() as usize).min(nb - 1);
        sum[b] += value(i);
        count[b] += 1;
    }
    (0..nb)
        .filter(|&b| count[b] > 0)
        .map(|b| (lo + (b as f64 + 0.5) * bin, sum[b] / count[b] as f64))
        .collect()
}

/// Statistics of the particles' density in one annulus about the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Annulus {
    /// Mean radius of the particles in the annulus (the bin centre if it is empty).
    pub r: f64,
    pub count: usize,
    pub mean: f64,
    pub min: f64,
    pub max: f64,
    /// 10th and 90th percentiles.
    pub p10: f64,
    pub p90: f64,
}

/// Azimuthal averages: the particles' density (in 2D the surface density Σ) in annuli of
/// width `bin` from the origin out to the farthest particle. Empty annuli report zeros.
pub fn annulus_stats<const D: usize>(p: &Particles<D>, bin: f64) -> Vec<Annulus> {
    let radius = |i: usize| {
        (0..D.min(2))
            .map(|d| p.pos[d][i].powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let rmax = (0..p.len()).map(radius).fold(0.0, f64::max);
    let nb = (rmax / bin).floor() as usize + 1;
    let mut vals: Vec<Vec<f64>> = vec![Vec::new(); nb];
    let mut rsum = vec![0.0; nb];
    for i in 0..p.len() {
        let r = radius(i);
        let b = ((r / bin) as usize).min(nb - 1);
        vals[b].push(p.rho[i]);
        rsum[b] += r;
    }
    vals.into_iter()
        .enumerate()
        .map(|(b, mut v)| {
            if v.is_empty() {
                let r = (b as f64 + 0.5) * bin;
                return Annulus {
                    r,
                    count: 0,
                    mean: 0.0,
                    min: 0.0,
                    max: 0.0,
                    p10: 0.0,
                    p90: 0.0,
                };
            }
            v.sort_by(f64::total_cmp);
            let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
            Annulus {
                r: rsum[b] / v.len() as f64,
                count: v.len(),
                mean: v.iter().sum::<f64>() / v.len() as f64,
                min: v[0],
                max: v[v.len() - 1],
                p10: q(0.1),
                p90: q(0.9),
            }
        })
        .collect()
}

/// Scanning a profile from the right, starting below `x_max`, the first place where it rises
/// to `threshold`: linear interpolation between the bins on either side of the crossing.
pub fn crossing_from_right(profile: &[(f64, f64)], threshold: f64, x_max: f64) -> Option<f64> {
    let start = profile.iter().rposition(|&(x, _)| x < x_max)?;
    let k = profile[..=start]
        .iter()
        .rposition(|&(_, v)| v >= threshold)?;
    if k == start {
        return Some(profile[k].0);
    }
    let ((x0, v0), (x1, v1)) = (profile[k], profile[k + 1]);
    Some(x0 + (v0 - threshold) / (v0 - v1) * (x1 - x0))
}

/// Where a profile jumps from `left` (towards smaller x) to `right` (towards larger x),
/// searched only within `[lo, hi]`: the crossings of the mid-value (left + right)/2 that go
/// from left's side to right's side between neighbouring bins, linearly interpolated; of
/// several, the one nearest `near`. Works for either ordering of the two values, so that
/// a window holding just one discontinuity of the exact solution measures that one.
pub fn jump_position(
    profile: &[(f64, f64)],
    lo: f64,
    hi: f64,
    left: f64,
    right: f64,
    near: f64,
) -> Option<f64> {
    let mid = 0.5 * (left + right);
    let sign = if right > left { 1.0 } else { -1.0 };
    // Signed so that the left side is negative and the right side non-negative.
    let side = |v: f64| sign * (v - mid);
    let inside: Vec<(f64, f64)> = profile
        .iter()
        .copied()
        .filter(|&(x, _)| x >= lo && x <= hi)
        .collect();
    inside
        .windows(2)
        .filter(|w| side(w[0].1) < 0.0 && side(w[1].1) >= 0.0)
        .map(|w| {
            let ((x0, v0), (x1, v1)) = (w[0], w[1]);
            x0 + (mid - v0) / (v1 - v0) * (x1 - x0)
        })
        .min_by(|a, b| (a - near).abs().total_cmp(&(b - near).abs()))
}

/// Scanning from the left, the bin where the profile peaks (the first maximum), refined by
/// a parabola through it and its neighbours.
pub fn peak_position(profile: &[(f64, f64)]) -> Option<(f64, f64)> {
    let k = (0..profile.len()).max_by(|&a, &b| profile[a].1.total_cmp(&profile[b].1))?;
    if k == 0 || k + 1 == profile.len() {
        return Some(profile[k]);
    }
    let ((x0, y0), (x1, y1), (x2, y2)) = (profile[k - 1], profile[k], profile[k + 1]);
    let denom = (x0 - x1) * (x0 - x2) * (x1 - x2);
    let a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denom;
    let b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denom;
    if a >= 0.0 {
        return Some(profile[k]);
    }
    let xv = -b / (2.0 * a);
    Some((xv.clamp(x0, x2), y1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1, 2, 3, 4: sample variance 5/3, so the standard error is √(5/3)/2; one value has none.
    #[test]
    fn standard_error_of_four_values() {
        assert!(
            (standard_error(&[1.0, 2.0, 3.0, 4.0]) - (5.0f64 / 3.0).sqrt() / 2.0).abs() < 1e-15
        );
        assert!(standard_error(&[1.0]).is_nan());
    }

    #[test]
    fn crossing_interpolates_between_bins() {
        let prof = [(0.0, 1.0), (1.0, 1.0), (2.0, 0.2), (3.0, 0.2)];
        let x = crossing_from_right(&prof, 0.6, f64::INFINITY).unwrap();
        assert!((x - 1.5).abs() < 1e-12);
        assert_eq!(crossing_from_right(&prof, 5.0, f64::INFINITY), None);
    }

    #[test]
    fn jump_position_takes_the_crossing_in_the_window_in_either_direction() {
        // Rising then falling: 1 | 3 | 2 with jumps at 1.5 and 3.5.
        let prof: Vec<(f64, f64)> = (0..6)
            .map(|i| (i as f64, [1.0, 1.0, 3.0, 3.0, 2.0, 2.0][i]))
            .collect();
        let up = jump_position(&prof, 0.0, 2.5, 1.0, 3.0, 1.5).unwrap();
        assert!((up - 1.5).abs() < 1e-12, "{up}");
        let down = jump_position(&prof, 2.5, 5.0, 3.0, 2.0, 3.5).unwrap();
        assert!((down - 3.5).abs() < 1e-12, "{down}");
        // The falling jump is not found where the profile only rises.
        assert_eq!(jump_position(&prof, 0.0, 2.5, 3.0, 1.0, 1.5), None);
    }

    #[test]
    fn peak_of_a_parabola_is_found_between_bins() {
        let prof: Vec<(f64, f64)> = (0..10)
            .map(|i| (i as f64, -(i as f64 - 4.3).powi(2)))
            .collect();
        let (x, _) = peak_position(&prof).unwrap();
        assert!((x - 4.3).abs() < 1e-9, "{x}");
    }

    #[test]
    fn l1_norm_is_volume_weighted() {
        let mut p = Particles::<1>::new();
        p.push(0, [0.0], [0.0], 1.0, 1.0);
        p.push(1, [1.0], [0.0], 1.0, 1.0);
        p.rho = vec![1.0, 0.5];
        // Volumes 1 and 2: (1·1 + 2·4)/3 = 3.
        let e = l1_norm(&p, |i| [1.0, -4.0][i]);
        assert!((e - 3.0).abs() < 1e-15);
    }
}
