//! Periods in unevenly sampled series: the generalised Lomb–Scargle periodogram
//! (Zechmeister & Kürster 2009, A&A 496, 577; "GLS"), which fits a sinusoid *plus a
//! floating mean* at every trial frequency, and the strongest period with its uncertainty
//! (Montgomery & O'Donoghue 1999, DSSN 13, 28).
//!
//! Conventions: frequencies are cycles per unit of `t` (not angular), periods are 1/f in
//! units of `t`. All points weigh the same (the light curves this serves carry no error
//! bars). The normalised power at f is p(f) = 1 − χ²(f)/χ²₀ ∈ [0, 1]: the fraction of the
//! variance about the mean that the best sinusoid of frequency f explains.
//!
//! **Floating trend.** The `*_trend` functions generalise the floating mean to a floating
//! polynomial of degree d ≤ [`MAX_TREND_DEGREE`] in time: at every trial frequency the
//! sinusoid and the polynomial are fitted *together* by least squares, and p(f) is the
//! fraction of the variance about the best polynomial alone that the sinusoid then
//! explains (d = 0 is the GLS above, to round-off). This removes a secular trend (a disk
//! that brightens as it builds up) without the bias of subtracting a fitted polynomial
//! first: a polynomial fitted alone absorbs part of any sinusoid (for a cubic over a span
//! of 4 cycles up to 11% of its amplitude, depending on phase; 18% at 3 cycles), a joint
//! fit does not. What the trend costs is information: only the part of the sinusoid not
//! shaped like a polynomial over the span measures it, so the uncertainties grow (the
//! Montgomery & O'Donoghue values are scaled by the Cramér–Rao ratio with and without the
//! trend: for a cubic at most 10% for the frequency and 6% for the amplitude at 4 cycles in
//! the span, 2% at 8, 0.4% at 20), and a period longer than about half the span cannot be
//! told from a trend: there a sinusoid plus a cubic is a smoother polynomial, and the power
//! measures how far the series departs from a cubic rather than a periodicity.
//!
//! A constant series (zero variance to round-off) has no period: [`lomb_scargle`] returns
//! zero power at every frequency for it (no NaN), and [`strongest_period`] / [`refine_peak`]
//! return an error that says so; with a trend, likewise a series that is a polynomial of
//! the trend's degree.
//!
//! The period uncertainty σ_f = √6 σ_resid / (π T A √N) (T the time span, A the fitted
//! semi-amplitude, N the number of points, σ_resid the rms of the residuals) is the
//! Cramér–Rao bound for a sinusoid in *white* noise. Correlated noise (flickering in a
//! light curve) makes the real scatter larger; read it as a lower bound there.

use std::f64::consts::{PI, TAU};

use anyhow::{Result, bail};
use rayon::prelude::*;

/// Oversampling of the frequency grid [`strongest_period`] scans: points per 1/T, the
/// width of a peak. At 10 the grid maximum lies within a tenth of a peak width of the true
/// one, close enough to bracket it for the refinement.
pub const OVERSAMPLE: f64 = 10.0;

/// Fewest points a sinusoid-plus-mean fit (three parameters) leaves residuals for.
pub const MIN_POINTS: usize = 4;

/// Highest degree of the floating polynomial trend the `*_trend` functions fit.
pub const MAX_TREND_DEGREE: usize = 3;

/// A uniform grid of trial frequencies `start + k·step`, k = 0..len.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrequencyGrid {
    pub start: f64,
    pub step: f64,
    pub len: usize,
}

impl FrequencyGrid {
    pub fn frequency(&self, k: usize) -> f64 {
        self.start + k as f64 * self.step
    }

    pub fn frequencies(&self) -> Vec<f64> {
        (0..self.len).map(|k| self.frequency(k)).collect()
    }

    /// The last frequency of the grid (≥ the `f_max` it was made for).
    pub fn end(&self) -> f64 {
        self.frequency(self.len.saturating_sub(1))
    }
}

/// Frequencies from `f_min` to (at least) `f_max` in steps of 1/(oversample·span), `span`
/// the time the series covers. Errors for a non-positive or non-finite range, span or
/// oversampling factor.
pub fn frequency_grid(span: f64, f_min: f64, f_max: f64, oversample: f64) -> Result<FrequencyGrid> {
    if !(span > 0.0 && span.is_finite()) {
        bail!("the series spans no time (T = {span})");
    }
    if !(f_min > 0.0 && f_max > f_min && f_max.is_finite()) {
        bail!("frequency range {f_min} .. {f_max}: need 0 < f_min < f_max");
    }
    if !(oversample >= 1.0 && oversample.is_finite()) {
        bail!("oversampling factor {oversample}: need ≥ 1");
    }
    let step = 1.0 / (oversample * span);
    let len = ((f_max - f_min) / step).ceil() as usize + 1;
    if len > 50_000_000 {
        bail!("frequency grid of {len} points: range too wide for the time span");
    }
    Ok(FrequencyGrid {
        start: f_min,
        step,
        len,
    })
}

/// A polynomial in time, mean + c₁x + c₂x² + c₃x³ with x = (t − t_mid)/t_half (x runs
/// over [−1, 1] across the fitted points): the floating trend of a fit.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PolynomialTrend {
    /// 0 for a floating mean.
    pub degree: usize,
    pub t_mid: f64,
    pub t_half: f64,
    /// Coefficients of x⁰..x³ (those above `degree` are zero).
    pub coefficients: [f64; MAX_TREND_DEGREE + 1],
}

impl PolynomialTrend {
    /// The trend's value at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        let x = (t - self.t_mid) / self.t_half;
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, &c| acc * x + c)
    }
}

/// The series made ready for the sums: times about their mid-point (small phases, less
/// round-off), values about their mean (and, with a trend, about their least-squares
/// polynomial), and the variance YY of Zechmeister & Kürster about that.
struct Centred {
    t: Vec<f64>,
    y: Vec<f64>,
    t_ref: f64,
    /// Half the time span: the trend's variable is x = (t − t_ref)/t_half.
    t_half: f64,
    mean: f64,
    /// Degree of the trend: the basis beyond the constant has this many functions.
    degree: usize,
    /// The trend's basis beyond the constant, point-major: `q[i·degree + k − 1]` is
    /// q_k(x_i), k = 1..=degree; orthogonal to 1 and to each other over the points, with
    /// Σ_i q_k(x_i)² = N (zero where the points do not resolve that degree).
    q: Vec<f64>,
    /// Monomial coefficients of q_k: q_k(x) = Σ_j `basis[k − 1][j]` xʲ.
    basis: Vec<[f64; MAX_TREND_DEGREE + 1]>,
    /// y's least-squares coefficients on q_k, taken out of `y`.
    beta: Vec<f64>,
    /// Σ_i y_i q_k(x_i) of the residual `y` (round-off), k = 1..=degree.
    yq: Vec<f64>,
    /// The points have fewer distinct times than a polynomial of `degree` needs.
    rank_deficient: bool,
    /// Σ y² / N of the residual; zero for a constant series (or one on its trend).
    yy: f64,
}

impl Centred {
    fn new(t: &[f64], y: &[f64], degree: usize) -> Self {
        assert_eq!(t.len(), y.len(), "periodogram: t and y differ in length");
        assert!(
            degree <= MAX_TREND_DEGREE,
            "periodogram: trend degree {degree} above {MAX_TREND_DEGREE}"
        );
        let n = y.len().max(1) as f64;
        let (lo, hi) = t
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        let t_ref = if t.is_empty() { 0.0 } else { 0.5 * (lo + hi) };
        let t_half = if hi > lo { 0.5 * (hi - lo) } else { 1.0 };
        let constant = y.iter().all(|&v| v == y[0]);
        // Two passes: the second corrects the first mean's round-off (≲ N ε |y|) to ≲ ε |y|.
        let mean = if constant {
            y.first().copied().unwrap_or(0.0)
        } else {
            let m = y.iter().sum::<f64>() / n;
            m + y.iter().map(|v| v - m).sum::<f64>() / n
        };
        let mut yc: Vec<f64> = y.iter().map(|v| v - mean).collect();
        let tc: Vec<f64> = t.iter().map(|x| x - t_ref).collect();

        let mut cols: Vec<Vec<f64>> = Vec::with_capacity(degree);
        let mut basis = Vec::with_capacity(degree);
        let mut rank_deficient = false;
        let mut beta = vec![0.0; degree];
        let mut yq = vec![0.0; degree];
        if degree > 0 && !t.is_empty() {
            let x: Vec<f64> = tc.iter().map(|v| v / t_half).collect();
            for k in 1..=degree {
                let mut v: Vec<f64> = x.iter().map(|x| x.powi(k as i32)).collect();
                let mut coef = [0.0; MAX_TREND_DEGREE + 1];
                coef[k] = 1.0;
                let norm0 = v.iter().map(|a| a * a).sum::<f64>() / n;
                // Gram–Schmidt against 1 and the earlier columns, twice (the second pass
                // takes out what the first left to round-off).
                for _ in 0..2 {
                    let d0 = v.iter().sum::<f64>() / n;
                    v.iter_mut().for_each(|a| *a -= d0);
                    coef[0] -= d0;
                    for (q, b) in cols.iter().zip(&basis) {
                        let d = dot(&v, q) / n;
                        v.iter_mut().zip(q).for_each(|(a, q)| *a -= d * q);
                        coef.iter_mut().zip(b).for_each(|(c, b)| *c -= d * b);
                    }
                }
                let norm = v.iter().map(|a| a * a).sum::<f64>() / n;
                if norm > 1e-20 * norm0 && norm.is_finite() {
                    let s = 1.0 / norm.sqrt();
                    v.iter_mut().for_each(|a| *a *= s);
                    coef.iter_mut().for_each(|c| *c *= s);
                } else {
                    rank_deficient = true;
                    v.iter_mut().for_each(|a| *a = 0.0);
                    coef = [0.0; MAX_TREND_DEGREE + 1];
                }
                cols.push(v);
                basis.push(coef);
            }
            // The trend taken out, again in two passes.
            for _ in 0..2 {
                for (k, q) in cols.iter().enumerate() {
                    let d = dot(&yc, q) / n;
                    beta[k] += d;
                    yc.iter_mut().zip(q).for_each(|(a, q)| *a -= d * q);
                }
            }
            for (k, q) in cols.iter().enumerate() {
                yq[k] = dot(&yc, q);
            }
        }
        let mut yy = yc.iter().map(|v| v * v).sum::<f64>() / n;
        // Variations within a few ulps of the values are round-off, not signal: call a
        // series whose rms about the mean (or trend) is below 16 ε max|y| constant.
        let ymax = y.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if constant || yy.sqrt() <= 16.0 * f64::EPSILON * ymax || !(yy > 0.0) {
            yy = 0.0;
        }
        let q = (0..tc.len())
            .flat_map(|i| cols.iter().map(move |c| c[i]))
            .collect();
        Self {
            t: tc,
            y: yc,
            t_ref,
            t_half,
            mean,
            degree,
            q,
            basis,
            beta,
            yq,
            rank_deficient,
            yy,
        }
    }

    fn is_constant(&self) -> bool {
        self.yy == 0.0
    }

    /// The trend basis at point `i`.
    #[inline]
    fn q_row<const D: usize>(&self, i: usize) -> [f64; D] {
        std::array::from_fn(|k| self.q[i * D + k])
    }

    fn yq<const D: usize>(&self) -> [f64; D] {
        std::array::from_fn(|k| self.yq[k])
    }

    /// The trend mean + Σ_k (β_k + dβ_k) q_k as a polynomial in x.
    fn trend(&self, mean: f64, d_beta: &[f64]) -> PolynomialTrend {
        let mut coefficients = [0.0; MAX_TREND_DEGREE + 1];
        coefficients[0] = mean;
        for (k, b) in self.basis.iter().enumerate() {
            let beta = self.beta[k] + d_beta.get(k).copied().unwrap_or(0.0);
            coefficients
                .iter_mut()
                .zip(b)
                .for_each(|(c, b)| *c += beta * b);
        }
        PolynomialTrend {
            degree: self.degree,
            t_mid: self.t_ref,
            t_half: self.t_half,
            coefficients,
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// The weighted sums of one trial frequency (weights 1/N), Zechmeister & Kürster eqs. 10–15
/// before the mean products are subtracted, and the sums Σ q_k cos, Σ q_k sin of the `D`
/// trend functions beyond the constant.
#[derive(Clone, Copy)]
struct Sums<const D: usize> {
    y: f64,
    c: f64,
    s: f64,
    yc: f64,
    ys: f64,
    cc: f64,
    cs: f64,
    qc: [f64; D],
    qs: [f64; D],
}

impl<const D: usize> Default for Sums<D> {
    fn default() -> Self {
        Self {
            y: 0.0,
            c: 0.0,
            s: 0.0,
            yc: 0.0,
            ys: 0.0,
            cc: 0.0,
            cs: 0.0,
            qc: [0.0; D],
            qs: [0.0; D],
        }
    }
}

impl<const D: usize> Sums<D> {
    #[inline]
    fn add(&mut self, y: f64, c: f64, s: f64, q: &[f64; D]) {
        self.y += y;
        self.c += c;
        self.s += s;
        self.yc += y * c;
        self.ys += y * s;
        self.cc += c * c;
        self.cs += c * s;
        for k in 0..D {
            self.qc[k] += q[k] * c;
            self.qs[k] += q[k] * s;
        }
    }

    #[inline]
    fn merge(&mut self, o: &Self) {
        self.y += o.y;
        self.c += o.c;
        self.s += o.s;
        self.yc += o.yc;
        self.ys += o.ys;
        self.cc += o.cc;
        self.cs += o.cs;
        for k in 0..D {
            self.qc[k] += o.qc[k];
            self.qs[k] += o.qs[k];
        }
    }

    /// The products with the mean and trend projected out (YC, YS, CC, SS, CS, D) and the
    /// plain means (Y, C, S, and those of q_k·cos, q_k·sin, q_k·y).
    fn products(&self, n: f64, yq: &[f64; D]) -> Products<D> {
        let (y, c, s) = (self.y / n, self.c / n, self.s / n);
        let qc: [f64; D] = std::array::from_fn(|k| self.qc[k] / n);
        let qs: [f64; D] = std::array::from_fn(|k| self.qs[k] / n);
        let yq: [f64; D] = std::array::from_fn(|k| yq[k] / n);
        let (mut tcc, mut tss, mut tcs, mut tyc, mut tys) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for k in 0..D {
            tcc += qc[k] * qc[k];
            tss += qs[k] * qs[k];
            tcs += qc[k] * qs[k];
            tyc += yq[k] * qc[k];
            tys += yq[k] * qs[k];
        }
        let cc_hat = self.cc / n;
        let cc = cc_hat - c * c - tcc;
        let ss = (1.0 - cc_hat) - s * s - tss;
        let cs = self.cs / n - c * s - tcs;
        Products {
            y,
            c,
            s,
            yc: self.yc / n - y * c - tyc,
            ys: self.ys / n - y * s - tys,
            cc,
            ss,
            cs,
            d: cc * ss - cs * cs,
            qc,
            qs,
            yq,
        }
    }
}

struct Products<const D: usize> {
    y: f64,
    c: f64,
    s: f64,
    yc: f64,
    ys: f64,
    cc: f64,
    ss: f64,
    cs: f64,
    d: f64,
    qc: [f64; D],
    qs: [f64; D],
    yq: [f64; D],
}

impl<const D: usize> Products<D> {
    /// Below this D (at most 1/4, for well-spread phases) the cosine and sine columns are
    /// degenerate (f·T ≪ 1, or every point at the same phase): no sinusoid can be fitted.
    const D_MIN: f64 = 1e-14;

    /// Normalised power, ZK09 eq. 4 with eq. 5's coefficients: (SS·YC² + CC·YS² −
    /// 2 CS·YC·YS) / (YY·D), clamped to [0, 1] against round-off.
    fn power(&self, yy: f64) -> f64 {
        if yy == 0.0 || !(self.d > Self::D_MIN) {
            return 0.0;
        }
        let p = (self.ss * self.yc * self.yc + self.cc * self.ys * self.ys
            - 2.0 * self.cs * self.yc * self.ys)
            / (yy * self.d);
        if p.is_finite() {
            p.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Least-squares coefficients a, b of a·cos + b·sin, the offset and the changes of the
    /// trend coefficients (in centred units).
    fn coefficients(&self) -> Option<(f64, f64, f64, [f64; D])> {
        if !(self.d > Self::D_MIN) {
            return None;
        }
        let a = (self.yc * self.ss - self.ys * self.cs) / self.d;
        let b = (self.ys * self.cc - self.yc * self.cs) / self.d;
        let d_beta = std::array::from_fn(|k| self.yq[k] - a * self.qc[k] - b * self.qs[k]);
        Some((a, b, self.y - a * self.c - b * self.s, d_beta))
    }
}

fn sums_at<const D: usize>(c: &Centred, f: f64) -> Sums<D> {
    let w = TAU * f;
    let mut s = Sums::<D>::default();
    for (i, (&t, &y)) in c.t.iter().zip(&c.y).enumerate() {
        let (sn, cs) = (w * t).sin_cos();
        s.add(y, cs, sn, &c.q_row::<D>(i));
    }
    s
}

/// Calls `$f::<D>($args)` with the const `D` equal to the runtime degree `$deg` (which
/// must be at most [`MAX_TREND_DEGREE`]).
macro_rules! with_degree {
    ($deg:expr, $f:ident($($arg:expr),*)) => {
        match $deg {
            0 => $f::<0>($($arg),*),
            1 => $f::<1>($($arg),*),
            2 => $f::<2>($($arg),*),
            3 => $f::<3>($($arg),*),
            d => panic!("periodogram: trend degree {d} above {MAX_TREND_DEGREE}"),
        }
    };
}

/// Normalised GLS power (0..1) of the series (t, y) at each of `freqs` (cycles per unit
/// of t). Zero power for a constant series, an empty one, and at frequencies where no
/// sinusoid can be fitted. Panics if `t` and `y` differ in length.
pub fn lomb_scargle(t: &[f64], y: &[f64], freqs: &[f64]) -> Vec<f64> {
    lomb_scargle_trend(t, y, freqs, 0)
}

/// [`lomb_scargle`] with a floating polynomial trend of `degree` (0: the floating mean)
/// fitted together with the sinusoid at each frequency. Panics also for a degree above
/// [`MAX_TREND_DEGREE`].
pub fn lomb_scargle_trend(t: &[f64], y: &[f64], freqs: &[f64], degree: usize) -> Vec<f64> {
    let c = Centred::new(t, y, degree);
    if c.is_constant() || c.t.is_empty() {
        return vec![0.0; freqs.len()];
    }
    with_degree!(degree, lomb_scargle_d(&c, freqs))
}

fn lomb_scargle_d<const D: usize>(c: &Centred, freqs: &[f64]) -> Vec<f64> {
    let n = c.t.len() as f64;
    let yq = c.yq::<D>();
    freqs
        .par_iter()
        .map(|&f| sums_at::<D>(c, f).products(n, &yq).power(c.yy))
        .collect()
}

/// [`lomb_scargle`] on a uniform grid, faster: per point and block of frequencies, two
/// `sin_cos` calls and a rotation recurrence for the rest of the block (the round-off of
/// 128 rotations, ~1e-14, is far below anything the power resolves).
pub fn lomb_scargle_grid(t: &[f64], y: &[f64], grid: &FrequencyGrid) -> Vec<f64> {
    lomb_scargle_grid_trend(t, y, grid, 0)
}

/// [`lomb_scargle_grid`] with a floating polynomial trend of `degree`
/// ([`lomb_scargle_trend`]).
pub fn lomb_scargle_grid_trend(
    t: &[f64],
    y: &[f64],
    grid: &FrequencyGrid,
    degree: usize,
) -> Vec<f64> {
    let c = Centred::new(t, y, degree);
    if c.is_constant() || c.t.is_empty() {
        return vec![0.0; grid.len];
    }
    with_degree!(degree, lomb_scargle_grid_d(&c, grid))
}

fn lomb_scargle_grid_d<const D: usize>(c: &Centred, grid: &FrequencyGrid) -> Vec<f64> {
    const BLOCK: usize = 128;
    // LANES points at a time: their recurrences are independent, so the rotations run
    // side by side instead of waiting on one another's latency.
    const LANES: usize = 4;
    let n = c.t.len() as f64;
    let yq = c.yq::<D>();
    let blocks = grid.len.div_ceil(BLOCK);
    let full = c.t.len() / LANES * LANES;
    let per_block: Vec<Vec<f64>> = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let k0 = b * BLOCK;
            let len = BLOCK.min(grid.len - k0);
            let w0 = TAU * grid.frequency(k0);
            let dw = TAU * grid.step;
            let mut sums = vec![Sums::<D>::default(); len];
            for i0 in (0..full).step_by(LANES) {
                let (mut cs, mut sn, mut dc, mut ds) =
                    ([0.0; LANES], [0.0; LANES], [0.0; LANES], [0.0; LANES]);
                let y: [f64; LANES] = std::array::from_fn(|j| c.y[i0 + j]);
                let q: [[f64; D]; LANES] = std::array::from_fn(|j| c.q_row::<D>(i0 + j));
                for j in 0..LANES {
                    let t = c.t[i0 + j];
                    (sn[j], cs[j]) = (w0 * t).sin_cos();
                    (ds[j], dc[j]) = (dw * t).sin_cos();
                }
                for s in sums.iter_mut() {
                    let mut add = Sums::<D>::default();
                    for j in 0..LANES {
                        add.add(y[j], cs[j], sn[j], &q[j]);
                        (cs[j], sn[j]) =
                            (cs[j] * dc[j] - sn[j] * ds[j], sn[j] * dc[j] + cs[j] * ds[j]);
                    }
                    s.merge(&add);
                }
            }
            for i in full..c.t.len() {
                let (t, y, q) = (c.t[i], c.y[i], c.q_row::<D>(i));
                let (mut sn, mut cs) = (w0 * t).sin_cos();
                let (ds, dc) = (dw * t).sin_cos();
                for s in sums.iter_mut() {
                    s.add(y, cs, sn, &q);
                    (cs, sn) = (cs * dc - sn * ds, sn * dc + cs * ds);
                }
            }
            sums.iter()
                .map(|s| s.products(n, &yq).power(c.yy))
                .collect::<Vec<f64>>()
        })
        .collect();
    per_block.concat()
}

/// The least-squares sinusoid of a given frequency:
/// y ≈ mean + amplitude · cos(2π f t − phase).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SinusoidFit {
    pub frequency: f64,
    /// The fitted offset (the floating mean; for uneven sampling not the plain average).
    /// With a trend: the trend's mean over the points.
    pub mean: f64,
    /// Semi-amplitude A ≥ 0.
    pub amplitude: f64,
    /// φ in [0, 2π): maxima at t = (φ/2π + k)/f.
    pub phase: f64,
    /// √(Σ r²/(N − 3 − d)) of the residuals r: the noise estimate with the fitted
    /// parameters' degrees of freedom taken off (d the trend's degree; if N is not larger
    /// than the parameters, over N).
    pub residual_rms: f64,
    /// Normalised GLS power at this frequency.
    pub power: f64,
    /// The floating trend fitted with the sinusoid (degree 0: the constant `mean`).
    pub trend: PolynomialTrend,
}

impl SinusoidFit {
    /// The fitted trend plus the sinusoid at time `t`.
    pub fn model(&self, t: f64) -> f64 {
        self.trend.at(t) + self.amplitude * (TAU * self.frequency * t - self.phase).cos()
    }
}

/// Fits mean + A cos(2π f t − φ) by least squares. Errors for a length mismatch, an empty
/// series or a frequency at which cosine and sine cannot be told apart; a constant series
/// fits with zero amplitude.
pub fn fit_sinusoid(t: &[f64], y: &[f64], f: f64) -> Result<SinusoidFit> {
    fit_sinusoid_trend(t, y, f, 0)
}

/// [`fit_sinusoid`] with a polynomial trend of `degree` fitted together with the sinusoid:
/// trend(t) + A cos(2π f t − φ). Errors also for a degree above [`MAX_TREND_DEGREE`] and
/// for points that do not resolve a polynomial of that degree.
pub fn fit_sinusoid_trend(t: &[f64], y: &[f64], f: f64, degree: usize) -> Result<SinusoidFit> {
    if t.len() != y.len() {
        bail!("{} times but {} values", t.len(), y.len());
    }
    if t.is_empty() {
        bail!("no points to fit");
    }
    if degree > MAX_TREND_DEGREE {
        bail!("trend degree {degree}: at most {MAX_TREND_DEGREE}");
    }
    let c = Centred::new(t, y, degree);
    if c.rank_deficient {
        bail!("the points do not resolve a trend of degree {degree} (too few distinct times)");
    }
    with_degree!(degree, fit_d(&c, f))
}

fn fit_d<const D: usize>(c: &Centred, f: f64) -> Result<SinusoidFit> {
    let n = c.t.len() as f64;
    let p = sums_at::<D>(c, f).products(n, &c.yq::<D>());
    let (a, b, offset, d_beta) = if c.is_constant() {
        (0.0, 0.0, 0.0, [0.0; D])
    } else {
        p.coefficients().ok_or_else(|| {
            anyhow::anyhow!("frequency {f}: the points do not resolve a sinusoid (f·T too small)")
        })?
    };
    let w = TAU * f;
    let chi2: f64 =
        c.t.iter()
            .zip(&c.y)
            .enumerate()
            .map(|(i, (&t, &y))| {
                let (sn, cs) = (w * t).sin_cos();
                let q = c.q_row::<D>(i);
                let trend: f64 = (0..D).map(|k| d_beta[k] * q[k]).sum();
                (y - offset - trend - a * cs - b * sn).powi(2)
            })
            .sum();
    let params = 3 + D;
    let dof = if c.t.len() > params {
        n - params as f64
    } else {
        n
    };
    let mean = c.mean + offset;
    Ok(SinusoidFit {
        frequency: f,
        mean,
        amplitude: a.hypot(b),
        phase: (b.atan2(a) + w * c.t_ref).rem_euclid(TAU),
        residual_rms: (chi2 / dof).sqrt(),
        power: p.power(c.yy),
        trend: c.trend(mean, &d_beta),
    })
}

/// The strongest periodic signal in a frequency range, with Montgomery & O'Donoghue
/// uncertainties.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PeriodEstimate {
    /// 1/frequency, in units of t.
    pub period: f64,
    /// σ_f / f².
    pub period_err: f64,
    pub frequency: f64,
    /// √6 σ_resid / (π T A √N) (with a trend, times the Cramér–Rao ratio with and
    /// without it).
    pub frequency_err: f64,
    /// Normalised GLS power at the peak (0..1).
    pub power: f64,
    /// Semi-amplitude of the best-fit sinusoid.
    pub amplitude: f64,
    /// √(2/N) σ_resid (Montgomery & O'Donoghue; with a trend, times the amplitude's
    /// Cramér–Rao ratio).
    pub amplitude_err: f64,
    /// The fitted floating mean (with a trend: the trend's mean over the points).
    pub mean: f64,
    /// Phase φ of mean + A cos(2π f t − φ).
    pub phase: f64,
    pub residual_rms: f64,
    /// Points used.
    pub n: usize,
    /// Time span T of the points.
    pub span: f64,
    /// Probability that white noise alone gives a peak this high somewhere in the range
    /// (ZK09 eq. 24: 1 − [1 − (1 − p)^((N−3−d)/2)]^M with M = (f_max − f_min)·T
    /// independent frequencies, d the trend's degree; an estimate, not exact for uneven
    /// sampling).
    pub false_alarm: f64,
    /// The floating trend fitted with the sinusoid at the peak.
    pub trend: PolynomialTrend,
}

/// Scans `f_min..f_max` on a grid oversampled [`OVERSAMPLE`] times and refines the highest
/// peak ([`refine_peak`]). Errors (with a one-line reason) for mismatched lengths, fewer
/// than [`MIN_POINTS`] points, non-finite values, a bad range, or a constant series.
pub fn strongest_period(t: &[f64], y: &[f64], f_min: f64, f_max: f64) -> Result<PeriodEstimate> {
    strongest_period_trend(t, y, f_min, f_max, 0)
}

/// [`strongest_period`] with a floating polynomial trend of `degree`.
pub fn strongest_period_trend(
    t: &[f64],
    y: &[f64],
    f_min: f64,
    f_max: f64,
    degree: usize,
) -> Result<PeriodEstimate> {
    let span = check_series(t, y, degree)?;
    let grid = frequency_grid(span, f_min, f_max, OVERSAMPLE)?;
    let power = lomb_scargle_grid_trend(t, y, &grid, degree);
    refine_peak_trend(t, y, &grid, &power, degree)
}

/// Validates a series for a trend of `degree`; returns its time span.
fn check_series(t: &[f64], y: &[f64], degree: usize) -> Result<f64> {
    if t.len() != y.len() {
        bail!("{} times but {} values", t.len(), y.len());
    }
    if degree > MAX_TREND_DEGREE {
        bail!("trend degree {degree}: at most {MAX_TREND_DEGREE}");
    }
    if t.len() < MIN_POINTS + degree {
        if degree == 0 {
            bail!("{} points: a period needs at least {MIN_POINTS}", t.len());
        }
        bail!(
            "{} points: a period with a trend of degree {degree} needs at least {}",
            t.len(),
            MIN_POINTS + degree
        );
    }
    if let Some(i) = (0..t.len()).find(|&i| !(t[i].is_finite() && y[i].is_finite())) {
        bail!("point {i} is not finite (t = {}, y = {})", t[i], y[i]);
    }
    let (lo, hi) = t
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    if !(hi > lo) {
        bail!("all points at the same time t = {lo}");
    }
    Ok(hi - lo)
}

/// The highest point of `power` (computed on `grid`) refined by a golden-section search
/// between its grid neighbours, then the sinusoid fitted there and the uncertainties.
pub fn refine_peak(
    t: &[f64],
    y: &[f64],
    grid: &FrequencyGrid,
    power: &[f64],
) -> Result<PeriodEstimate> {
    refine_peak_trend(t, y, grid, power, 0)
}

/// [`refine_peak`] for a power computed with a floating trend of `degree`
/// ([`lomb_scargle_grid_trend`]).
pub fn refine_peak_trend(
    t: &[f64],
    y: &[f64],
    grid: &FrequencyGrid,
    power: &[f64],
    degree: usize,
) -> Result<PeriodEstimate> {
    let span = check_series(t, y, degree)?;
    if power.len() != grid.len || grid.len == 0 {
        bail!("{} power values for a grid of {}", power.len(), grid.len);
    }
    let c = Centred::new(t, y, degree);
    if c.rank_deficient {
        bail!("the points do not resolve a trend of degree {degree} (too few distinct times)");
    }
    if c.is_constant() {
        if degree == 0 {
            bail!("the series is constant: it has no period");
        }
        bail!(
            "the series is constant about a polynomial trend of degree {degree}: it has no period"
        );
    }
    with_degree!(degree, refine_d(&c, span, grid, power))
}

fn refine_d<const D: usize>(
    c: &Centred,
    span: f64,
    grid: &FrequencyGrid,
    power: &[f64],
) -> Result<PeriodEstimate> {
    let n = c.t.len() as f64;
    let yq = c.yq::<D>();
    let k = (0..power.len())
        .max_by(|&a, &b| power[a].total_cmp(&power[b]))
        .unwrap_or(0);
    let lo = grid.frequency(k.saturating_sub(1)).max(grid.start);
    let hi = grid.frequency((k + 1).min(grid.len - 1));
    let pw = |f: f64| sums_at::<D>(c, f).products(n, &yq).power(c.yy);
    // Golden-section search for the maximum in [lo, hi]: with the grid oversampled, the
    // peak is the only maximum there. 80 steps shrink the bracket by 0.618⁸⁰ ~ 1e-17.
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (lo, hi);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut p1, mut p2) = (pw(x1), pw(x2));
    for _ in 0..80 {
        if b - a <= 1e-13 * b {
            break;
        }
        if p1 >= p2 {
            (b, x2, p2) = (x2, x1, p1);
            x1 = b - g * (b - a);
            p1 = pw(x1);
        } else {
            (a, x1, p1) = (x1, x2, p2);
            x2 = a + g * (b - a);
            p2 = pw(x2);
        }
    }
    // The refined maximum, unless the grid point itself is higher (a peak at the range's
    // edge, or a flat top).
    let (f_best, _) = [(x1, p1), (x2, p2), (grid.frequency(k), power[k])]
        .into_iter()
        .fold((f64::NAN, f64::NEG_INFINITY), |best, (f, p)| {
            if p > best.1 { (f, p) } else { best }
        });
    let fit = fit_d::<D>(c, f_best)?;
    // How much the trend's freedom widens the Cramér–Rao bounds (1 without a trend).
    let (widen_f, widen_a) = if D == 0 {
        (1.0, 1.0)
    } else {
        trend_widening::<D>(c, f_best, fit.phase - TAU * f_best * c.t_ref)
    };
    let sigma_f = if fit.amplitude > 0.0 {
        widen_f * 6f64.sqrt() * fit.residual_rms / (PI * span * fit.amplitude * n.sqrt())
    } else {
        f64::INFINITY
    };
    let m = ((grid.end() - grid.start) * span).max(1.0);
    let single = ((n - 3.0 - D as f64).max(0.0) / 2.0 * (-fit.power).ln_1p()).exp();
    let false_alarm = (-(m * (-single).ln_1p()).exp_m1()).clamp(0.0, 1.0);
    Ok(PeriodEstimate {
        period: 1.0 / f_best,
        period_err: sigma_f / (f_best * f_best),
        frequency: f_best,
        frequency_err: sigma_f,
        power: fit.power,
        amplitude: fit.amplitude,
        amplitude_err: widen_a * (2.0 / n).sqrt() * fit.residual_rms,
        mean: fit.mean,
        phase: fit.phase,
        residual_rms: fit.residual_rms,
        n: c.t.len(),
        span,
        false_alarm,
        trend: fit.trend,
    })
}

/// √ of the ratio of the Cramér–Rao variances of the frequency and of the amplitude of
/// A cos(2π f t − φ) (`phase` = φ in centred time) fitted with the trend to those fitted
/// with a floating mean only, for these sampling times: (frequency, amplitude) factors ≥ 1.
/// Infinite where the fit is degenerate.
fn trend_widening<const D: usize>(c: &Centred, f: f64, phase: f64) -> (f64, f64) {
    let w = TAU * f;
    let (ca, sa) = (phase.cos(), phase.sin());
    // Regressors: 1, q_1..q_D, cos, sin, and ∂/∂ω of ca·cos + sa·sin (unit amplitude).
    let m = D + 4;
    let mut g = vec![vec![0.0; m]; m];
    let mut row = vec![0.0; m];
    for (i, &t) in c.t.iter().enumerate() {
        let (sn, cs) = (w * t).sin_cos();
        row[0] = 1.0;
        row[1..=D].copy_from_slice(&c.q_row::<D>(i));
        row[D + 1] = cs;
        row[D + 2] = sn;
        row[D + 3] = t * (sa * cs - ca * sn);
        for a in 0..m {
            for b in 0..=a {
                g[a][b] += row[a] * row[b];
            }
        }
    }
    let mut amp = vec![0.0; m];
    amp[D + 1] = ca;
    amp[D + 2] = sa;
    let mut freq = vec![0.0; m];
    freq[D + 3] = 1.0;
    let keep_mean_only: Vec<usize> = [0, D + 1, D + 2, D + 3].to_vec();
    let sub = |v: &[f64]| -> Vec<f64> { keep_mean_only.iter().map(|&i| v[i]).collect() };
    let g_sub: Vec<Vec<f64>> = keep_mean_only
        .iter()
        .map(|&a| {
            keep_mean_only
                .iter()
                .map(|&b| g[a.max(b)][a.min(b)])
                .collect()
        })
        .collect();
    let ratio = |v: &[f64]| {
        let full = inverse_form(&g, v);
        let mean_only = inverse_form(&g_sub, &sub(v));
        match (full, mean_only) {
            (Some(a), Some(b)) if b > 0.0 => (a / b).sqrt().max(1.0),
            _ => f64::INFINITY,
        }
    };
    (ratio(&freq), ratio(&amp))
}

/// vᵀ G⁻¹ v for a symmetric positive definite G given by its lower triangle (Cholesky,
/// after scaling to unit diagonal); `None` if G is not positive definite to round-off.
fn inverse_form(g: &[Vec<f64>], v: &[f64]) -> Option<f64> {
    let m = v.len();
    let scale: Vec<f64> = (0..m).map(|i| g[i][i].sqrt()).collect();
    if scale.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
        return None;
    }
    let mut l = vec![vec![0.0; m]; m];
    for i in 0..m {
        for j in 0..=i {
            let mut s = g[i][j] / (scale[i] * scale[j]);
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 1e-12) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // Solve L z = v (scaled): vᵀ G⁻¹ v = |z|².
    let mut z = vec![0.0; m];
    for i in 0..m {
        let s: f64 = v[i] / scale[i] - (0..i).map(|k| l[i][k] * z[k]).sum::<f64>();
        z[i] = s / l[i][i];
    }
    Some(z.iter().map(|z| z * z).sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// `n` times drawn uniformly over [t0, t0 + span], sorted: uneven sampling.
    fn uneven_times(rng: &mut Rng, n: usize, t0: f64, span: f64) -> Vec<f64> {
        let mut t: Vec<f64> = (0..n).map(|_| t0 + span * rng.uniform()).collect();
        t.sort_by(f64::total_cmp);
        t
    }

    #[test]
    fn noiseless_sinusoid_fits_exactly() {
        let mut rng = Rng::new(1);
        let t = uneven_times(&mut rng, 50, 100.0, 30.0);
        let (f, mean, amp, phase) = (0.37, 2.5, 0.8, 1.1);
        let y: Vec<f64> = t
            .iter()
            .map(|&t| mean + amp * (TAU * f * t - phase).cos())
            .collect();
        let fit = fit_sinusoid(&t, &y, f).unwrap();
        // Exact data: only round-off (phases up to ~300 rad lose ~1e-13) separates them.
        assert!((fit.mean - mean).abs() < 1e-10, "{fit:?}");
        assert!((fit.amplitude - amp).abs() < 1e-10, "{fit:?}");
        assert!((fit.phase - phase).abs() < 1e-10, "{fit:?}");
        assert!(fit.residual_rms < 1e-10 && (fit.power - 1.0).abs() < 1e-10);
        assert!((fit.model(t[7]) - y[7]).abs() < 1e-10);
    }

    #[test]
    fn grid_recurrence_matches_direct_sums() {
        let mut rng = Rng::new(2);
        // 303 points: 75 chunks of four lanes and a remainder of three.
        let t = uneven_times(&mut rng, 303, 0.0, 200.0);
        let y: Vec<f64> = t
            .iter()
            .map(|&t| (0.05 * TAU * t).sin() + 0.5 * rng.normal())
            .collect();
        let grid = frequency_grid(200.0, 0.01, 1.0, 10.0).unwrap();
        assert!(grid.end() >= 1.0 && grid.end() < 1.0 + grid.step);
        assert!((grid.step - 1.0 / 2000.0).abs() < 1e-18);
        let fast = lomb_scargle_grid(&t, &y, &grid);
        let direct = lomb_scargle(&t, &y, &grid.frequencies());
        // 128 rotations per block, each off by ~1 ulp: differences ~1e-14.
        let worst = fast
            .iter()
            .zip(&direct)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10, "{worst}");
    }

    /// One noisy, unevenly sampled sinusoid: N = 1000 points over 25 periods, A = 1,
    /// σ_noise = 0.3, so the signal-to-noise of the fit is high but the noise is visible.
    fn noisy_series(seed: u64, period: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = Rng::new(seed);
        let t = uneven_times(&mut rng, 1000, 3.0, 25.0 * period);
        let y: Vec<f64> = t
            .iter()
            .map(|&t| 4.0 + (TAU * t / period + 0.7).cos() + 0.3 * rng.normal())
            .collect();
        (t, y)
    }

    #[test]
    fn period_of_a_noisy_sinusoid_is_found_within_its_uncertainty() {
        let p_true = TAU * 1.03;
        let (t, y) = noisy_series(11, p_true);
        let est = strongest_period(&t, &y, 1.0 / (5.0 * TAU), 1.0 / (0.2 * TAU)).unwrap();
        // 3σ: a Gaussian error exceeds it with probability 0.27%; the seed is fixed, so the
        // test is deterministic, and the 20-seed test below checks σ itself.
        assert!(
            (est.period - p_true).abs() < 3.0 * est.period_err,
            "{est:?} vs {p_true}"
        );
        // The stated σ_A = √(2/N) σ = 0.013 (1.3%): 5% is ~4σ.
        assert!((est.amplitude - 1.0).abs() < 0.05, "{est:?}");
        assert!((est.mean - 4.0).abs() < 0.05, "{est:?}");
        // The residual rms estimates the noise: its own relative error is 1/√(2N) ≈ 2%.
        assert!((est.residual_rms - 0.3).abs() < 0.03, "{est:?}");
        // Power ≈ (A²/2)/(A²/2 + σ²) = 0.5/0.59 = 0.85.
        assert!((est.power - 0.85).abs() < 0.05, "{est:?}");
        assert!(est.false_alarm < 1e-100, "{est:?}");
    }

    #[test]
    fn stated_period_uncertainty_matches_the_scatter_over_seeds() {
        let p_true = 2.0;
        let mut errs = Vec::new();
        let mut sigmas = Vec::new();
        for seed in 100..120 {
            let (t, y) = noisy_series(seed, p_true);
            let est = strongest_period(&t, &y, 0.05, 2.0).unwrap();
            errs.push(est.period - p_true);
            sigmas.push(est.period_err);
        }
        let n = errs.len() as f64;
        let scatter = (errs.iter().map(|e| e * e).sum::<f64>() / n).sqrt();
        let sigma = sigmas.iter().sum::<f64>() / n;
        let ratio = scatter / sigma;
        eprintln!(
            "scatter of the periods {scatter:.3e}, mean stated σ {sigma:.3e}: ratio {ratio:.2}"
        );
        // The rms of 20 Gaussian draws scatters by 1/√(2·20) ≈ 16% about σ: a factor of 2
        // either way is > 4 of those deviations, so a σ that is wrong by 2 fails and a
        // right one passes for any seeds. (Uniform random times have the same variance of
        // t, T²/12, as the even sampling Montgomery & O'Donoghue assume.)
        assert!(
            (0.5..2.0).contains(&ratio),
            "scatter {scatter} vs σ {sigma}"
        );
        // The mean error is bias: it must be small against σ (20 draws: ±σ/√20 ≈ 0.22σ).
        let bias = errs.iter().sum::<f64>() / n;
        assert!(bias.abs() < 0.7 * sigma, "bias {bias} vs σ {sigma}");
    }

    #[test]
    fn the_stronger_of_two_sinusoids_wins() {
        let mut rng = Rng::new(5);
        let t = uneven_times(&mut rng, 800, 0.0, 60.0);
        // Periods 3.3 and 1.7, not harmonics of each other; amplitudes 1 and 0.6.
        let y: Vec<f64> = t
            .iter()
            .map(|&t| {
                (TAU * t / 3.3).cos() + 0.6 * (TAU * t / 1.7 + 2.0).sin() + 0.3 * rng.normal()
            })
            .collect();
        let est = strongest_period(&t, &y, 1.0 / 10.0, 1.0).unwrap();
        // The second sinusoid adds 0.6²/2 = 0.18 of variance to the residuals: σ_resid
        // ≈ 0.52, σ_P ≈ 3.3²·√6·0.52/(π·60·1·√800) ≈ 0.003; 5σ absorbs the leakage of the
        // other sinusoid into the peak's position.
        assert!((est.period - 3.3).abs() < 5.0 * est.period_err, "{est:?}");
        assert!((est.period - 3.3).abs() < 0.02, "{est:?}");
        // σ_A ≈ √(2/800)·0.52 = 0.026: 0.1 is ~4σ.
        assert!((est.amplitude - 1.0).abs() < 0.1, "{est:?}");
    }

    #[test]
    fn pure_noise_has_low_power() {
        let mut rng = Rng::new(9);
        let t = uneven_times(&mut rng, 500, 0.0, 100.0);
        let y: Vec<f64> = (0..500).map(|_| rng.normal()).collect();
        let est = strongest_period(&t, &y, 0.01, 1.0).unwrap();
        // ZK09 eq. 24 with N = 500, M = (1 − 0.01)·100 ≈ 100 independent frequencies: the
        // highest of them exceeds p = 0.1 with probability 100·0.9^248.5 ≈ 4e-10. A sinusoid
        // as strong as the noise would reach p ≈ 0.33.
        eprintln!(
            "noise: highest power {:.4}, false alarm {:.3}",
            est.power, est.false_alarm
        );
        assert!(est.power < 0.1, "{est:?}");
        assert!(est.false_alarm > 0.01, "{est:?}");
        let grid = frequency_grid(100.0, 0.01, 1.0, 10.0).unwrap();
        let p = lomb_scargle_grid(&t, &y, &grid);
        // The mean power of noise is ≈ 2/N = 0.004 at any one frequency.
        let mean = p.iter().sum::<f64>() / p.len() as f64;
        assert!(mean < 0.01, "{mean}");
    }

    #[test]
    fn a_constant_series_has_zero_power_and_no_period() {
        let t: Vec<f64> = (0..40).map(|k| 0.1 * (k * k) as f64).collect();
        for value in [0.0, 0.1, 3.0e7] {
            let y = vec![value; 40];
            let p = lomb_scargle(&t, &y, &[0.01, 0.1, 1.0]);
            assert_eq!(p, vec![0.0; 3]);
            let grid = frequency_grid(156.0, 0.01, 1.0, 10.0).unwrap();
            assert!(lomb_scargle_grid(&t, &y, &grid).iter().all(|&v| v == 0.0));
            let err = strongest_period(&t, &y, 0.01, 1.0).unwrap_err();
            assert!(err.to_string().contains("constant"), "{err}");
            let fit = fit_sinusoid(&t, &y, 0.1).unwrap();
            assert_eq!(fit.amplitude, 0.0);
            assert!(
                (fit.mean - value).abs() <= 1e-15 * value.abs() && fit.residual_rms.is_finite()
            );
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let t = [0.0, 1.0, 2.0];
        let y = [1.0, 2.0, 0.0];
        assert!(strongest_period(&t, &y, 0.1, 1.0).is_err());
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.0, 2.0, f64::NAN, 0.0, 1.0];
        assert!(strongest_period(&t, &y, 0.1, 1.0).is_err());
        let y = [1.0, 2.0, 3.0, 0.0, 1.0];
        assert!(strongest_period(&t, &y, 1.0, 0.1).is_err());
        assert!(strongest_period(&[1.0; 5], &y, 0.1, 1.0).is_err());
    }

    #[test]
    fn a_trend_of_degree_zero_is_the_floating_mean() {
        let (t, y) = noisy_series(21, 2.0);
        let grid = frequency_grid(50.0, 0.05, 2.0, 10.0).unwrap();
        let plain = lomb_scargle_grid(&t, &y, &grid);
        let zero = lomb_scargle_grid_trend(&t, &y, &grid, 0);
        assert_eq!(plain, zero);
        let direct = lomb_scargle_trend(&t, &y, &grid.frequencies()[..50], 3);
        let fast = lomb_scargle_grid_trend(&t, &y, &grid, 3);
        let worst = direct
            .iter()
            .zip(&fast)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10, "{worst}");
        let fit = fit_sinusoid(&t, &y, 0.5).unwrap();
        assert_eq!(fit.trend.degree, 0);
        assert_eq!(fit.trend.coefficients, [fit.mean, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn a_cubic_trend_and_a_sinusoid_are_fitted_together_exactly() {
        let mut rng = Rng::new(22);
        // 3.2 cycles over the span: a cubic fitted on its own would take ~15% of the
        // sinusoid's amplitude, the joint fit none.
        let t = uneven_times(&mut rng, 300, 40.0, 16.0);
        let cubic = |t: f64| {
            1e-13 * (2.0 + 0.3 * (t - 45.0) - 0.02 * (t - 45.0).powi(2) + 1e-3 * (t - 45.0).powi(3))
        };
        let (f, amp, phase) = (0.2, 1e-14, 2.0);
        let y: Vec<f64> = t
            .iter()
            .map(|&t| cubic(t) + amp * (TAU * f * t - phase).cos())
            .collect();
        let fit = fit_sinusoid_trend(&t, &y, f, 3).unwrap();
        assert!((fit.amplitude - amp).abs() < 1e-9 * amp, "{fit:?}");
        assert!((fit.phase - phase).abs() < 1e-9, "{fit:?}");
        assert!((fit.power - 1.0).abs() < 1e-9 && fit.residual_rms < 1e-9 * amp);
        for &s in &[40.0, 47.5, 56.0] {
            assert!((fit.trend.at(s) - cubic(s)).abs() < 1e-9 * 1e-13, "{fit:?}");
        }
        assert!((fit.model(t[9]) - y[9]).abs() < 1e-9 * y[9]);
        // The trend's mean over the points is the fit's mean.
        let trend_mean = t.iter().map(|&s| fit.trend.at(s)).sum::<f64>() / t.len() as f64;
        assert!((trend_mean - fit.mean).abs() < 1e-9 * fit.mean);
        // A pure cubic has no period with a cubic trend; degree 4 is refused.
        let only: Vec<f64> = t.iter().map(|&s| cubic(s)).collect();
        let e = strongest_period_trend(&t, &only, 0.05, 1.0, 3).unwrap_err();
        assert!(e.to_string().contains("constant about"), "{e}");
        assert!(strongest_period_trend(&t, &y, 0.05, 1.0, 4).is_err());
        assert!(
            fit_sinusoid_trend(
                &[1.0, 1.0, 2.0, 2.0, 1.0],
                &[1.0, 2.0, 3.0, 4.0, 5.0],
                0.3,
                3
            )
            .is_err()
        );
    }

    #[test]
    fn a_floating_trend_finds_a_sinusoid_on_a_rising_baseline() {
        let mut rng = Rng::new(23);
        let p_true = 1.05 * TAU;
        // 12 cycles, a baseline that triples (quadratically) under a 3% modulation.
        let t = uneven_times(&mut rng, 600, 10.0, 12.0 * p_true);
        let span = 12.0 * p_true;
        let base = |t: f64| 1.0 + 2.0 * ((t - 10.0) / span).powi(2) + 0.5 * (t - 10.0) / span;
        let y: Vec<f64> = t
            .iter()
            .map(|&t| base(t) + 0.05 * (TAU * t / p_true + 0.4).cos() + 0.02 * rng.normal())
            .collect();
        let (f_min, f_max) = (1.0 / (5.0 * TAU), 1.0 / (0.2 * TAU));
        let raw = strongest_period(&t, &y, f_min, f_max).unwrap();
        assert!((raw.period - p_true).abs() > 0.5 * TAU, "{raw:?}");
        for degree in [2, 3] {
            let est = strongest_period_trend(&t, &y, f_min, f_max, degree).unwrap();
            assert!(
                (est.period - p_true).abs() < 3.0 * est.period_err,
                "degree {degree}: {est:?} vs {p_true}"
            );
            // σ_A = √(2/600)·0.02 ≈ 0.0012: 0.005 is ~4σ.
            assert!((est.amplitude - 0.05).abs() < 0.005, "{est:?}");
            assert!((est.residual_rms - 0.02).abs() < 0.003, "{est:?}");
            // 12 cycles in the span: the trend widens the bounds by a percent or so.
            let plain = est.residual_rms * (2.0 / 600f64).sqrt();
            assert!(
                est.amplitude_err >= plain && est.amplitude_err < 1.1 * plain,
                "{est:?}"
            );
            for s in [t[0], t[300], t[599]] {
                assert!((est.trend.at(s) - base(s)).abs() < 0.01, "{est:?} at {s}");
            }
        }
    }

    #[test]
    fn stated_uncertainties_with_a_trend_match_the_scatter_over_seeds() {
        // Few cycles in the span, where a cubic trend takes most information: at 3 cycles
        // the plain Montgomery & O'Donoghue σ_f is ~15% below the scatter, the widened one
        // is not. 300 draws: the rms scatters by 1/√600 ≈ 4%, so 0.8..1.25 is ~5σ.
        for cycles in [3.0, 8.0] {
            let (mut ef, mut ea, mut sf, mut sa) = (0.0, 0.0, 0.0, 0.0);
            let draws = 300;
            for seed in 0..draws {
                let mut rng = Rng::new(1000 + seed);
                let t = uneven_times(&mut rng, 200, 0.0, cycles);
                let y: Vec<f64> = t
                    .iter()
                    .map(|&t| {
                        3.0 + 0.5 * t + (TAU * t + 0.3 * seed as f64).cos() + 0.5 * rng.normal()
                    })
                    .collect();
                let est = strongest_period_trend(&t, &y, 0.5, 1.6, 3).unwrap();
                ef += (est.frequency - 1.0).powi(2);
                ea += (est.amplitude - 1.0).powi(2);
                sf += est.frequency_err;
                sa += est.amplitude_err;
            }
            let n = draws as f64;
            let (rf, ra) = ((ef / n).sqrt() / (sf / n), (ea / n).sqrt() / (sa / n));
            eprintln!("{cycles} cycles: scatter/σ {rf:.2} (frequency), {ra:.2} (amplitude)");
            assert!(
                (0.8..1.25).contains(&rf) && (0.8..1.25).contains(&ra),
                "{rf} {ra}"
            );
        }
    }
}
