//! The advected pulse: a smooth, exactly periodic density bump in pressure equilibrium,
//! carried at constant velocity. Exact solution: the initial profile, shifted.
//!
//! ρ(x, t) = ρ0 [1 + A Π_d exp(κ (cos(2π (x_d − v t − L/2)/L) − 1))], κ = (L / (2π w))², so
//! that near its centre the bump is a Gaussian of standard deviation `w`.

use std::f64::consts::TAU;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pulse {
    pub rho0: f64,
    pub amplitude: f64,
    pub width: f64,
    pub velocity: f64,
    pub length: f64,
}

impl Pulse {
    /// Exact density at position `x` and time `t`.
    pub fn density<const D: usize>(&self, x: [f64; D], t: f64) -> f64 {
        let kappa = (self.length / (TAU * self.width)).powi(2);
        let mut f = 1.0;
        for xd in x {
            let phase = TAU * (xd - self.velocity * t - 0.5 * self.length) / self.length;
            f *= (kappa * (phase.cos() - 1.0)).exp();
        }
        self.rho0 * (1.0 + self.amplitude * f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pulse_is_periodic_and_peaks_in_the_centre() {
        let p = Pulse {
            rho0: 1.0,
            amplitude: 0.5,
            width: 0.1,
            velocity: 1.0,
            length: 1.0,
        };
        assert!((p.density([0.5, 0.5], 0.0) - 1.5).abs() < 1e-15);
        // One period later the profile is back (up to the phase's round-off).
        assert!((p.density([0.3, 0.7], 1.0) - p.density([0.3, 0.7], 0.0)).abs() < 1e-12);
        // Near the centre: Gaussian of width 0.1.
        let g = 1.0 + 0.5 * (-0.5f64 * (0.01f64 / 0.1).powi(2)).exp();
        assert!((p.density([0.51], 0.0) - g).abs() < 1e-4);
    }
}
