//! The smoothing kernels, normalised in 1, 2 and 3 dimensions: Monaghan's (1992) cubic
//! spline (the paper's, the default), the quintic spline (Morris 1996) and Wendland's C2, C4
//! and C6 functions (Wendland 1995; normalisations of Dehnen & Aly 2012, Table 1).
//!
//! **Convention (the only place it is stated):** `q = r / h`; the cubic spline and the
//! Wendland kernels vanish for `r ≥ 2h`, the quintic spline for `r ≥ 3h`
//! ([`KernelKind::support_factor`]). The smoothing length `h` is constant in space and time
//! (paper, Section 2.1); every module takes the support radius from [`Kernel::support`].

use std::f64::consts::PI;

use crate::lanes::{F64x2, Real};

use serde::{Deserialize, Serialize};

/// Support radius of the cubic spline (the default kernel) in units of h.
pub const KERNEL_SUPPORT: f64 = 2.0;

/// Which kernel a run uses: `[particles] kernel`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KernelKind {
    /// M4 cubic spline, support 2h (the paper's).
    #[default]
    Cubic,
    /// M6 quintic spline, support 3h.
    Quintic,
    /// Wendland C2, support 2h.
    WendlandC2,
    /// Wendland C4, support 2h.
    WendlandC4,
    /// Wendland C6, support 2h.
    WendlandC6,
}

impl KernelKind {
    /// Every kernel, in the order of the documentation.
    pub const ALL: [KernelKind; 5] = [
        KernelKind::Cubic,
        KernelKind::Quintic,
        KernelKind::WendlandC2,
        KernelKind::WendlandC4,
        KernelKind::WendlandC6,
    ];

    /// Support radius in units of h.
    pub const fn support_factor(self) -> f64 {
        match self {
            KernelKind::Quintic => 3.0,
            _ => KERNEL_SUPPORT,
        }
    }

    /// The name a problem file uses.
    pub const fn key(self) -> &'static str {
        match self {
            KernelKind::Cubic => "cubic",
            KernelKind::Quintic => "quintic",
            KernelKind::WendlandC2 => "wendland_c2",
            KernelKind::WendlandC4 => "wendland_c4",
            KernelKind::WendlandC6 => "wendland_c6",
        }
    }

    /// The kernel a problem file names `key`.
    pub fn from_key(key: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.key() == key)
    }

    /// Human-readable name, written into outputs.
    pub const fn description(self) -> &'static str {
        match self {
            KernelKind::Cubic => "cubic spline (Monaghan 1992), support 2h",
            KernelKind::Quintic => "quintic spline (Morris 1996), support 3h",
            KernelKind::WendlandC2 => "Wendland C2 (Dehnen & Aly 2012), support 2h",
            KernelKind::WendlandC4 => "Wendland C4 (Dehnen & Aly 2012), support 2h",
            KernelKind::WendlandC6 => "Wendland C6 (Dehnen & Aly 2012), support 2h",
        }
    }

    /// Length unit of the shape's argument in units of h: h for the splines, the support
    /// 2h for the Wendland functions (whose argument runs over [0, 1]).
    const fn unit(self) -> f64 {
        match self {
            KernelKind::Cubic | KernelKind::Quintic => 1.0,
            _ => 2.0,
        }
    }

    /// Normalisation σ in `dimension` dimensions: W = σ / unit^D · shape(r / unit).
    pub const fn sigma(self, dimension: usize) -> f64 {
        assert!(
            matches!(dimension, 1..=3),
            "the kernels are defined for 1, 2 or 3 dimensions"
        );
        let d = dimension - 1;
        match self {
            KernelKind::Cubic => [2.0 / 3.0, 10.0 / (7.0 * PI), 1.0 / PI][d],
            KernelKind::Quintic => [1.0 / 120.0, 7.0 / (478.0 * PI), 1.0 / (120.0 * PI)][d],
            KernelKind::WendlandC2 => [5.0 / 4.0, 7.0 / PI, 21.0 / (2.0 * PI)][d],
            KernelKind::WendlandC4 => [3.0 / 2.0, 9.0 / PI, 495.0 / (32.0 * PI)][d],
            KernelKind::WendlandC6 => [55.0 / 32.0, 78.0 / (7.0 * PI), 1365.0 / (64.0 * PI)][d],
        }
    }
}

/// Human-readable name of the default kernel.
pub const KERNEL_NAME: &str = KernelKind::Cubic.description();

/// A kernel for a fixed smoothing length `h` in `D` dimensions, with the normalisation
/// constants precomputed.
#[derive(Clone, Copy, Debug)]
pub struct Kernel<const D: usize> {
    kind: KernelKind,
    h: f64,
    /// Length unit of the shape's argument (h, or 2h for the Wendland functions).
    unit: f64,
    /// σ_D / unit^D.
    norm: f64,
    /// σ_D / unit^(D+2), the prefactor of `(1/r) dW/dr`.
    grad_norm: f64,
}

/// Normalisation σ_D of the cubic spline: 2/3, 10/(7π), 1/π.
pub const fn sigma(dimension: usize) -> f64 {
    KernelKind::Cubic.sigma(dimension)
}

impl<const D: usize> Kernel<D> {
    /// The cubic spline (the paper's kernel).
    pub fn new(h: f64) -> Self {
        Self::of_kind(KernelKind::Cubic, h)
    }

    pub fn of_kind(kind: KernelKind, h: f64) -> Self {
        let s = kind.sigma(D);
        let unit = kind.unit() * h;
        let ud = unit.powi(D as i32);
        Self {
            kind,
            h,
            unit,
            norm: s / ud,
            grad_norm: s / (ud * unit * unit),
        }
    }

    pub fn kind(&self) -> KernelKind {
        self.kind
    }

    pub fn h(&self) -> f64 {
        self.h
    }

    /// Radius beyond which the kernel vanishes (2h, or 3h for the quintic spline).
    pub fn support(&self) -> f64 {
        self.kind.support_factor() * self.h
    }

    /// W(r, h), the kernel of Eq. (1), normalised to unity.
    #[inline]
    pub fn w(&self, r: f64) -> f64 {
        let q = r / self.unit;
        self.norm * shape::<D>(self.kind, q)
    }

    /// W(0, h): a particle's contribution to its own density in Eq. (5).
    #[inline]
    pub fn w0(&self) -> f64 {
        self.norm * shape::<D>(self.kind, 0.0)
    }

    /// F(r) = (1/r) dW/dr, so that ∇_i W_ij = F(r_ij) (r_i − r_j). Finite at r = 0.
    #[inline]
    pub fn f(&self, r: f64) -> f64 {
        let q = r / self.unit;
        self.grad_norm * grad_shape_over_q::<D>(self.kind, q)
    }

    /// W and F of two pairs at once: for the cubic spline in the two lanes of `F64x2`
    /// (both pieces computed and one selected per lane, so no branch; the same bits as
    /// [`Self::w_and_f`] on each), for the other kernels one after the other.
    #[inline]
    pub fn w_and_f_two(&self, r: [f64; 2]) -> [(f64, f64); 2] {
        match self.kind {
            KernelKind::Cubic => {
                let q = F64x2::new(r[0], r[1]) / F64x2::splat(self.unit);
                let w = F64x2::splat(self.norm) * cubic(q);
                let f = F64x2::splat(self.grad_norm) * cubic_grad(q);
                [(w.lane(0), f.lane(0)), (w.lane(1), f.lane(1))]
            }
            _ => r.map(|r| self.w_and_f(r)),
        }
    }

    /// Both W and F at once, as the sweep stores them with each pair.
    #[inline]
    pub fn w_and_f(&self, r: f64) -> (f64, f64) {
        let q = r / self.unit;
        match self.kind {
            KernelKind::Cubic => (self.norm * cubic(q), self.grad_norm * cubic_grad(q)),
            k => (
                self.norm * shape::<D>(k, q),
                self.grad_norm * grad_shape_over_q::<D>(k, q),
            ),
        }
    }
}

/// Dimensionless shape of `kind` at q = r / unit.
#[inline]
fn shape<const D: usize>(kind: KernelKind, q: f64) -> f64 {
    match kind {
        KernelKind::Cubic => cubic(q),
        KernelKind::Quintic => quintic(q),
        _ if q >= 1.0 => 0.0,
        // Wendland functions ψ(x) on [0, 1): in 1D those of one dimension, in 2D and 3D
        // those of three (Dehnen & Aly 2012, Table 1).
        KernelKind::WendlandC2 => {
            let t = 1.0 - q;
            if D == 1 {
                t * t * t * (1.0 + 3.0 * q)
            } else {
                t * t * t * t * (1.0 + 4.0 * q)
            }
        }
        KernelKind::WendlandC4 => {
            let t = 1.0 - q;
            let t2 = t * t;
            if D == 1 {
                t2 * t2 * t * (1.0 + q * (5.0 + 8.0 * q))
            } else {
                t2 * t2 * t2 * (1.0 + q * (6.0 + 35.0 / 3.0 * q))
            }
        }
        KernelKind::WendlandC6 => {
            let t = 1.0 - q;
            let t2 = t * t;
            let t4 = t2 * t2;
            if D == 1 {
                t4 * t2 * t * (1.0 + q * (7.0 + q * (19.0 + 21.0 * q)))
            } else {
                t4 * t4 * (1.0 + q * (8.0 + q * (25.0 + 32.0 * q)))
            }
        }
    }
}

/// (1/q) d(shape)/dq of `kind`, finite at q = 0.
#[inline]
fn grad_shape_over_q<const D: usize>(kind: KernelKind, q: f64) -> f64 {
    match kind {
        KernelKind::Cubic => cubic_grad(q),
        KernelKind::Quintic => quintic_grad(q),
        _ if q >= 1.0 => 0.0,
        KernelKind::WendlandC2 => {
            let t = 1.0 - q;
            if D == 1 {
                -12.0 * t * t
            } else {
                -20.0 * t * t * t
            }
        }
        KernelKind::WendlandC4 => {
            let t = 1.0 - q;
            let t2 = t * t;
            if D == 1 {
                -14.0 * t2 * t2 * (1.0 + 4.0 * q)
            } else {
                -56.0 / 3.0 * t2 * t2 * t * (1.0 + 5.0 * q)
            }
        }
        KernelKind::WendlandC6 => {
            let t = 1.0 - q;
            let t2 = t * t;
            let t4 = t2 * t2;
            if D == 1 {
                -6.0 * t4 * t2 * (3.0 + q * (18.0 + 35.0 * q))
            } else {
                -22.0 * t4 * t2 * t * (1.0 + q * (7.0 + 16.0 * q))
            }
        }
    }
}

/// Cubic spline: 1 − 3/2 q² + 3/4 q³ (q < 1), 1/4 (2 − q)³ (q < 2), 0 beyond.
#[inline]
fn cubic<T: Real>(q: T) -> T {
    let c = T::splat;
    q.if_less(
        1.0,
        || c(1.0) - c(1.5) * q * q + c(0.75) * q * q * q,
        || {
            q.if_less(
                2.0,
                || {
                    let t = c(2.0) - q;
                    c(0.25) * t * t * t
                },
                || c(0.0),
            )
        },
    )
}

/// (1/q) d(cubic)/dq: −3 + 9/4 q (q < 1), −3/4 (2 − q)²/q (q < 2), 0 beyond.
#[inline]
fn cubic_grad<T: Real>(q: T) -> T {
    let c = T::splat;
    q.if_less(
        1.0,
        || c(-3.0) + c(2.25) * q,
        || {
            q.if_less(
                2.0,
                || {
                    let t = c(2.0) - q;
                    c(-0.75) * t * t / q
                },
                || c(0.0),
            )
        },
    )
}

/// Quintic spline: (3 − q)⁵ − 6 (2 − q)⁵ + 15 (1 − q)⁵, each term where its base is
/// positive; below q = 1 as the polynomial 66 − 60 q² + 30 q⁴ − 10 q⁵.
#[inline]
fn quintic(q: f64) -> f64 {
    if q < 1.0 {
        let q2 = q * q;
        66.0 - 60.0 * q2 + q2 * q2 * (30.0 - 10.0 * q)
    } else if q < 2.0 {
        let (a, b) = (3.0 - q, 2.0 - q);
        let (a2, b2) = (a * a, b * b);
        a2 * a2 * a - 6.0 * b2 * b2 * b
    } else if q < 3.0 {
        let a = 3.0 - q;
        let a2 = a * a;
        a2 * a2 * a
    } else {
        0.0
    }
}

/// (1/q) d(quintic)/dq: −120 + 120 q² − 50 q³ below q = 1, then
/// [−5 (3 − q)⁴ + 30 (2 − q)⁴] / q and −5 (3 − q)⁴ / q.
#[inline]
fn quintic_grad(q: f64) -> f64 {
    if q < 1.0 {
        q * q * (120.0 - 50.0 * q) - 120.0
    } else if q < 2.0 {
        let (a, b) = (3.0 - q, 2.0 - q);
        let (a2, b2) = (a * a, b * b);
        (-5.0 * a2 * a2 + 30.0 * b2 * b2) / q
    } else if q < 3.0 {
        let a = 3.0 - q;
        let a2 = a * a;
        -5.0 * a2 * a2 / q
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ W dV over the support by the midpoint rule in radius, using the D-sphere surface.
    fn radial_integral<const D: usize>(kind: KernelKind, h: f64) -> f64 {
        let k = Kernel::<D>::of_kind(kind, h);
        let n = 200_000;
        let dr = k.support() / n as f64;
        let surface = |r: f64| match D {
            1 => 2.0,
            2 => 2.0 * PI * r,
            _ => 4.0 * PI * r * r,
        };
        (0..n)
            .map(|i| {
                let r = (i as f64 + 0.5) * dr;
                k.w(r) * surface(r) * dr
            })
            .sum()
    }

    #[test]
    fn every_kernel_is_normalised_in_1d_2d_3d() {
        // The midpoint rule with 2·10⁵ intervals integrates these piecewise polynomials to
        // ~1e-10; 1e-6 leaves room and still catches any wrong constant (candidate
        // normalisations differ by percents).
        for kind in KernelKind::ALL {
            for h in [0.1, 1.0, 3.7] {
                let i = [
                    radial_integral::<1>(kind, h),
                    radial_integral::<2>(kind, h),
                    radial_integral::<3>(kind, h),
                ];
                for (d, v) in i.iter().enumerate() {
                    assert!((v - 1.0).abs() < 1e-6, "{kind:?} in {}D: ∫W = {v}", d + 1);
                }
            }
        }
    }

    #[test]
    fn kernels_are_normalised_on_a_cartesian_grid_in_2d_and_3d() {
        // Independent of the radial formula: sum W over a fine grid. The midpoint sum of a
        // smooth kernel converges as (cell/h)²: well below 1e-4 at 300 cells per axis in
        // 2D and 1e-3 at 80 in 3D.
        for kind in KernelKind::ALL {
            let k = Kernel::<2>::of_kind(kind, 1.0);
            let n = 300;
            let d = 2.0 * k.support() / n as f64;
            let c = |i: usize| -k.support() + (i as f64 + 0.5) * d;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    sum += k.w((c(i) * c(i) + c(j) * c(j)).sqrt()) * d * d;
                }
            }
            assert!((sum - 1.0).abs() < 1e-4, "{kind:?} 2D: {sum}");
            let k = Kernel::<3>::of_kind(kind, 1.0);
            let n = 80;
            let d = 2.0 * k.support() / n as f64;
            let c = |i: usize| -k.support() + (i as f64 + 0.5) * d;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    for l in 0..n {
                        let r = (c(i) * c(i) + c(j) * c(j) + c(l) * c(l)).sqrt();
                        sum += k.w(r) * d * d * d;
                    }
                }
            }
            assert!((sum - 1.0).abs() < 1e-3, "{kind:?} 3D: {sum}");
        }
    }

    fn check_gradient<const D: usize>(kind: KernelKind) {
        let k = Kernel::<D>::of_kind(kind, 0.7);
        let n = 400;
        let scale = k.w0() / k.h();
        for i in 1..n {
            let r = k.support() * i as f64 / n as f64;
            // Central differences: truncation ~ eps² W''' (1e-12 of W(0)/h) plus round-off
            // ~ 1e-16 W / eps (1e-10); 1e-7 of W(0)/h bounds both and catches any wrong
            // term of the derivative (errors of order W(0)/h).
            let eps = 1e-6;
            let fd = (k.w(r + eps) - k.w(r - eps)) / (2.0 * eps);
            assert!(
                (k.f(r) * r - fd).abs() < 1e-7 * scale,
                "{kind:?} {D}D r = {r}: {} vs {fd}",
                k.f(r) * r
            );
            let (w, f) = k.w_and_f(r);
            assert_eq!((w, f), (k.w(r), k.f(r)));
        }
        // At the edge (support · h / h may round just below the edge: then a fifth power of
        // ~1e-16) and beyond it.
        assert!(k.w(k.support()) < 1e-60 * k.w0());
        assert_eq!(k.f(k.support() * 1.01), 0.0);
        assert!(k.f(0.0).is_finite() && k.f(0.0) < 0.0);
        assert!(k.w(0.0) > k.w(0.1 * k.support()));
    }

    /// Pair finding takes the kernel two pairs at a time (`w_and_f_two`, the cubic spline
    /// in SIMD lanes): each must be `w_and_f` of its distance to the bit, across both
    /// pieces, at their joins q = 1 and q = 2 exactly, beyond the support and at r = 0.
    fn check_two_at_once<const D: usize>(kind: KernelKind) {
        let k = Kernel::<D>::of_kind(kind, 0.7);
        let unit = k.support() / kind.support_factor();
        let mut rs: Vec<f64> = (0..=500)
            .map(|i| 1.1 * k.support() * i as f64 / 500.0)
            .collect();
        rs.extend([unit, 2.0 * unit, k.support(), f64::MIN_POSITIVE, 1e-300]);
        for (n, a) in rs.iter().enumerate() {
            let b = rs[(7 * n + 3) % rs.len()];
            let two = k.w_and_f_two([*a, b]);
            for (l, r) in [*a, b].into_iter().enumerate() {
                let (w, f) = k.w_and_f(r);
                assert_eq!(
                    (two[l].0.to_bits(), two[l].1.to_bits()),
                    (w.to_bits(), f.to_bits()),
                    "{kind:?} {D}D lane {l}, r = {r}"
                );
            }
        }
    }

    #[test]
    fn kernel_values_two_at_once_are_those_one_at_a_time_to_the_bit() {
        for kind in KernelKind::ALL {
            check_two_at_once::<1>(kind);
            check_two_at_once::<2>(kind);
            check_two_at_once::<3>(kind);
        }
    }

    #[test]
    fn gradient_matches_finite_differences_for_every_kernel() {
        for kind in KernelKind::ALL {
            check_gradient::<1>(kind);
            check_gradient::<2>(kind);
            check_gradient::<3>(kind);
        }
    }

    #[test]
    fn the_cubic_spline_keeps_its_values() {
        // σ/h^D (1 − 3/2 q² + 3/4 q³) at q = 0.5 and 1/4 (2 − q)³ at q = 1.5, h = 1, 3D.
        let k = Kernel::<3>::new(1.0);
        assert_eq!(k.kind(), KernelKind::Cubic);
        let w = |q: f64| (1.0 - 1.5 * q * q + 0.75 * q * q * q) / PI;
        assert!((k.w(0.5) - w(0.5)).abs() < 1e-15);
        assert!((k.w(1.5) - 0.25 * 0.125 / PI).abs() < 1e-15);
        assert_eq!(k.support(), 2.0);
        assert_eq!(
            Kernel::<3>::of_kind(KernelKind::Quintic, 1.0).support(),
            3.0
        );
    }

    #[test]
    fn gradient_is_antisymmetric() {
        // ∇_i W_ij = F (r_i − r_j) = −∇_j W_ji for any pair.
        let k = Kernel::<2>::new(0.3);
        let (a, b): ([f64; 2], [f64; 2]) = ([0.1, 0.2], [0.35, -0.05]);
        let r = ((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])).sqrt();
        for d in 0..2 {
            let gi = k.f(r) * (a[d] - b[d]);
            let gj = k.f(r) * (b[d] - a[d]);
            assert_eq!(gi, -gj);
            assert!(gi != 0.0);
        }
    }
}
