//! External gravity of a central point mass at the origin, with optional Plummer softening
//! and an accretion radius inside which particles are removed between steps.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMass {
    /// G M of the central object.
    pub gm: f64,
    /// Plummer softening length ε: Φ = −GM / √(r² + ε²).
    #[serde(default)]
    pub softening: f64,
    /// Particles closer than this to the centre are accreted (removed) between steps.
    pub accretion_radius: Option<f64>,
}

impl PointMass {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.gm > 0.0 && self.gm.is_finite()) {
            return Err(format!("key `gravity.gm`: must be > 0, got {}", self.gm));
        }
        if !(self.softening >= 0.0 && self.softening.is_finite()) {
            return Err(format!(
                "key `gravity.softening`: must be ≥ 0, got {}",
                self.softening
            ));
        }
        if let Some(r) = self.accretion_radius
            && !(r > 0.0 && r.is_finite())
        {
            return Err(format!(
                "key `gravity.accretion_radius`: must be > 0, got {r}"
            ));
        }
        Ok(())
    }

    /// Acceleration −GM x / (r² + ε²)^(3/2).
    #[inline]
    pub fn acceleration<const D: usize>(&self, x: &[f64; D]) -> [f64; D] {
        let r2: f64 = x.iter().map(|c| c * c).sum::<f64>() + self.softening * self.softening;
        let k = -self.gm / (r2 * r2.sqrt());
        std::array::from_fn(|d| k * x[d])
    }

    /// Potential Φ = −GM / √(r² + ε²).
    #[inline]
    pub fn potential<const D: usize>(&self, x: &[f64; D]) -> f64 {
        let r2: f64 = x.iter().map(|c| c * c).sum::<f64>() + self.softening * self.softening;
        -self.gm / r2.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acceleration_is_minus_gradient_of_potential() {
        let g = PointMass {
            gm: 2.0,
            softening: 0.1,
            accretion_radius: None,
        };
        let x = [0.3, -0.4, 0.2];
        let a = g.acceleration(&x);
        for d in 0..3 {
            let mut xp = x;
            let mut xm = x;
            xp[d] += 1e-6;
            xm[d] -= 1e-6;
            let grad = (g.potential(&xp) - g.potential(&xm)) / 2e-6;
            assert!((a[d] + grad).abs() < 1e-6);
        }
    }
}
