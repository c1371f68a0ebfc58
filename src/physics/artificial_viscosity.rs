//! Artificial viscosity for shocks: Monaghan's (1997) signal-velocity form, with an optional
//! Balsara (1995) switch. Off (α = β = 0) by default; shock problems turn it on.

use serde::{Deserialize, Serialize};

/// Π_ij = −α v_sig w_ij / (ρ_i + ρ_j) for approaching pairs (w_ij = v_ij·r̂_ij < 0), with
/// v_sig = c_i + c_j − β w_ij; zero for receding pairs. (This is Monaghan's −(α/2) v_sig w / ρ̄.)
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArtificialViscosity {
    pub alpha: f64,
    pub beta: f64,
    /// Multiply Π_ij by the mean Balsara factor |∇·v| / (|∇·v| + |∇×v| + 10⁻⁴ c/h).
    pub balsara: bool,
}

impl Default for ArtificialViscosity {
    fn default() -> Self {
        Self {
            alpha: 0.0,
            beta: 0.0,
            balsara: false,
        }
    }
}

impl ArtificialViscosity {
    /// The usual setting for shocks: α = 1, β = 2, no switch.
    pub fn for_shocks() -> Self {
        Self {
            alpha: 1.0,
            beta: 2.0,
            balsara: false,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(self.alpha >= 0.0 && self.alpha.is_finite()) {
            return Err(format!(
                "artificial_viscosity.alpha must be ≥ 0, got {}",
                self.alpha
            ));
        }
        if !(self.beta >= 0.0 && self.beta.is_finite()) {
            return Err(format!(
                "artificial_viscosity.beta must be ≥ 0, got {}",
                self.beta
            ));
        }
        Ok(())
    }

    /// (Π_ij, v_sig,ij) for a pair with v_ij·r_ij = `vdotr` at separation `r`.
    /// `balsara` is the pair's mean switch factor (1 without the switch).
    #[inline]
    pub fn pi(
        &self,
        vdotr: f64,
        r: f64,
        (ci, cj): (f64, f64),
        (rhoi, rhoj): (f64, f64),
        balsara: f64,
    ) -> (f64, f64) {
        let w = if r > 0.0 { vdotr / r } else { 0.0 };
        let approach = w.min(0.0);
        let vsig = ci + cj - self.beta.max(1.0) * approach;
        if approach < 0.0 && self.alpha > 0.0 {
            let vsig_av = ci + cj - self.beta * approach;
            (
                -self.alpha * vsig_av * approach / (rhoi + rhoj) * balsara,
                vsig,
            )
        } else {
            (0.0, vsig)
        }
    }
}

/// Balsara's switch from the velocity gradient V_αβ (Eq. 10): near 1 in compression, near 0
/// in pure shear.
pub fn balsara_factor<const D: usize>(vgrad: &[[f64; D]; D], cs: f64, h: f64) -> f64 {
    let div: f64 = (0..D).map(|a| vgrad[a][a]).sum();
    let curl2: f64 = match D {
        2 => (vgrad[1][0] - vgrad[0][1]).powi(2),
        3 => {
            (vgrad[2][1] - vgrad[1][2]).powi(2)
                + (vgrad[0][2] - vgrad[2][0]).powi(2)
                + (vgrad[1][0] - vgrad[0][1]).powi(2)
        }
        _ => 0.0,
    };
    let d = div.abs();
    d / (d + curl2.sqrt() + 1e-4 * cs / h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_approaching_pairs_are_damped() {
        let av = ArtificialViscosity::for_shocks();
        let (pi, vsig) = av.pi(-0.5, 1.0, (1.0, 1.0), (1.0, 1.0), 1.0);
        // w = −0.5, v_sig = 2 + 1 = 3, Π = 3 × 0.5 / 2.
        assert!((pi - 0.75).abs() < 1e-15);
        assert!((vsig - 3.0).abs() < 1e-15);
        let (pi, vsig) = av.pi(0.5, 1.0, (1.0, 1.0), (1.0, 1.0), 1.0);
        assert_eq!((pi, vsig), (0.0, 2.0));
    }

    #[test]
    fn balsara_is_one_in_compression_zero_in_shear() {
        let compress = [[-1.0, 0.0], [0.0, -1.0]];
        let shear = [[0.0, 1.0], [0.0, 0.0]];
        assert!(balsara_factor(&compress, 1.0, 1.0) > 0.999);
        assert!(balsara_factor(&shear, 1.0, 1.0) < 1e-3);
    }
}
