//! The smoothing kernel: Monaghan's (1992) cubic spline, normalised in 1, 2 and 3 dimensions.
//!
//! **Convention (the only place it is stated):** the kernel has compact support of radius
//! `KERNEL_SUPPORT * h = 2h`, with `q = r / h`. The smoothing length `h` is constant in space
//! and time (paper, Section 2.1); every module takes the support radius from [`Kernel::support`].

use std::f64::consts::PI;

/// Support radius in units of the smoothing length: `W(r, h) = 0` for `r >= 2h`.
pub const KERNEL_SUPPORT: f64 = 2.0;

/// Human-readable name of the kernel, written into outputs.
pub const KERNEL_NAME: &str = "cubic spline (Monaghan 1992), support 2h";

/// The cubic-spline kernel for a fixed smoothing length `h` in `D` dimensions,
/// with the normalisation constants precomputed.
#[derive(Clone, Copy, Debug)]
pub struct Kernel<const D: usize> {
    h: f64,
    /// σ_D / h^D.
    norm: f64,
    /// σ_D / h^(D+2), the prefactor of `(1/r) dW/dr`.
    grad_norm: f64,
}

/// Normalisation σ_D of the cubic spline: 2/3, 10/(7π), 1/π.
pub const fn sigma(dimension: usize) -> f64 {
    match dimension {
        1 => 2.0 / 3.0,
        2 => 10.0 / (7.0 * PI),
        3 => 1.0 / PI,
        _ => panic!("the kernel is defined for 1, 2 or 3 dimensions"),
    }
}

impl<const D: usize> Kernel<D> {
    pub fn new(h: f64) -> Self {
        let s = sigma(D);
        let hd = h.powi(D as i32);
        Self {
            h,
            norm: s / hd,
            grad_norm: s / (hd * h * h),
        }
    }

    pub fn h(&self) -> f64 {
        self.h
    }

    /// Radius beyond which the kernel vanishes (2h).
    pub fn support(&self) -> f64 {
        KERNEL_SUPPORT * self.h
    }

    /// W(r, h), the kernel of Eq. (1), normalised to unity.
    #[inline]
    pub fn w(&self, r: f64) -> f64 {
        let q = r / self.h;
        self.norm * shape(q)
    }

    /// W(0, h): a particle's contribution to its own density in Eq. (5).
    #[inline]
    pub fn w0(&self) -> f64 {
        self.norm
    }

    /// F(r) = (1/r) dW/dr, so that ∇_i W_ij = F(r_ij) (r_i − r_j). Finite at r = 0.
    #[inline]
    pub fn f(&self, r: f64) -> f64 {
        let q = r / self.h;
        self.grad_norm * grad_shape_over_q(q)
    }

    /// Both W and F at once, as the sweep stores them with each pair.
    #[inline]
    pub fn w_and_f(&self, r: f64) -> (f64, f64) {
        let q = r / self.h;
        (self.norm * shape(q), self.grad_norm * grad_shape_over_q(q))
    }
}

/// Dimensionless shape: 1 − 3/2 q² + 3/4 q³ (q < 1), 1/4 (2 − q)³ (q < 2), 0 beyond.
#[inline]
fn shape(q: f64) -> f64 {
    if q < 1.0 {
        1.0 - 1.5 * q * q + 0.75 * q * q * q
    } else if q < 2.0 {
        let t = 2.0 - q;
        0.25 * t * t * t
    } else {
        0.0
    }
}

/// (1/q) d(shape)/dq: −3 + 9/4 q (q < 1), −3/4 (2 − q)²/q (q < 2), 0 beyond.
#[inline]
fn grad_shape_over_q(q: f64) -> f64 {
    if q < 1.0 {
        -3.0 + 2.25 * q
    } else if q < 2.0 {
        let t = 2.0 - q;
        -0.75 * t * t / q
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫ W dV over the support by the midpoint rule in radius, using the D-sphere surface.
    fn radial_integral<const D: usize>(h: f64) -> f64 {
        let k = Kernel::<D>::new(h);
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
    fn kernel_is_normalised_in_1d_2d_3d() {
        for h in [0.1, 1.0, 3.7] {
            assert!((radial_integral::<1>(h) - 1.0).abs() < 1e-6);
            assert!((radial_integral::<2>(h) - 1.0).abs() < 1e-6);
            assert!((radial_integral::<3>(h) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn kernel_normalised_on_a_cartesian_grid_in_2d() {
        // Independent of the radial formula: sum W over a fine 2D grid.
        let k = Kernel::<2>::new(1.0);
        let n = 1000;
        let d = 2.0 * k.support() / n as f64;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = -k.support() + (i as f64 + 0.5) * d;
                let y = -k.support() + (j as f64 + 0.5) * d;
                sum += k.w((x * x + y * y).sqrt()) * d * d;
            }
        }
        assert!((sum - 1.0).abs() < 1e-5, "{sum}");
    }

    #[test]
    fn gradient_matches_finite_difference_and_is_continuous() {
        let k = Kernel::<3>::new(0.7);
        for i in 1..280 {
            let r = i as f64 * 0.005;
            let eps = 1e-6;
            let fd = (k.w(r + eps) - k.w(r - eps)) / (2.0 * eps);
            assert!((k.f(r) * r - fd).abs() < 1e-6, "r = {r}");
        }
        assert_eq!(k.w(k.support()), 0.0);
        assert_eq!(k.f(k.support() * 1.01), 0.0);
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
