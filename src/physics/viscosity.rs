//! Physical Navier–Stokes shear viscosity (paper, Section 1.3; Flebbe et al. 1994): the
//! kinematic viscosity ν of each particle (constant, or Shakura–Sunyaev ν = α c_s H), the
//! shear tensor of Eq. (9) from the velocity gradient of Eq. (10), and the viscous stress
//! that the force sum turns into Eq. (8).

use serde::{Deserialize, Serialize};

/// How ν is set. Absent both `nu` and `alpha`, physical viscosity is off.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscosityModel {
    /// Constant kinematic shear viscosity ν.
    pub nu: Option<f64>,
    /// Shakura–Sunyaev α: ν = α c_s H with H = c_s/Ω_K about the central mass.
    pub alpha: Option<f64>,
    /// Kinematic bulk viscosity, as a multiple of ν: adds ν_b (∇·v) δ_αβ to the stress.
    #[serde(default)]
    pub bulk: f64,
}

impl ViscosityModel {
    pub fn is_on(&self) -> bool {
        self.nu.is_some() || self.alpha.is_some()
    }

    pub fn validate(&self, has_central_mass: bool) -> Result<(), String> {
        if self.nu.is_some() && self.alpha.is_some() {
            return Err("viscosity: give either viscosity.nu or viscosity.alpha, not both".into());
        }
        if let Some(nu) = self.nu
            && !(nu >= 0.0 && nu.is_finite())
        {
            return Err(format!("key `viscosity.nu`: must be ≥ 0, got {nu}"));
        }
        if let Some(a) = self.alpha {
            if !(a >= 0.0 && a.is_finite()) {
                return Err(format!("key `viscosity.alpha`: must be ≥ 0, got {a}"));
            }
            if !has_central_mass {
                return Err(
                    "key `viscosity.alpha`: ν = α c_s H needs a central mass ([gravity] gm)".into(),
                );
            }
        }
        if !(self.bulk >= 0.0 && self.bulk.is_finite()) {
            return Err(format!(
                "key `viscosity.bulk`: must be ≥ 0, got {}",
                self.bulk
            ));
        }
        Ok(())
    }

    /// ν at a particle with sound speed `cs` at distance `r` from a central mass `gm`:
    /// constant, or α c_s H = α c_s² / Ω_K with Ω_K = √(GM / r³).
    #[inline]
    pub fn nu(&self, cs: f64, r: f64, gm: f64) -> f64 {
        match (self.nu, self.alpha) {
            (Some(nu), _) => nu,
            (None, Some(alpha)) => {
                let omega = (gm / (r * r * r).max(f64::MIN_POSITIVE)).sqrt();
                alpha * cs * cs / omega
            }
            _ => 0.0,
        }
    }

    /// The viscous stress S = ν σ + ν_b ν (∇·v) δ, with σ the traceless shear of Eq. (9),
    /// σ_αβ = V_αβ + V_βα − (2/D) δ_αβ V_γγ (the paper's 2/3 is 2/D for a tensor traceless
    /// in D dimensions).
    #[inline]
    pub fn stress<const D: usize>(&self, vgrad: &[[f64; D]; D], nu: f64) -> [[f64; D]; D] {
        let div: f64 = (0..D).map(|a| vgrad[a][a]).sum();
        let iso = -(2.0 / D as f64) * div + self.bulk * div;
        std::array::from_fn(|a| {
            std::array::from_fn(|b| {
                let mut s = vgrad[a][b] + vgrad[b][a];
                if a == b {
                    s += iso;
                }
                nu * s
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shear_is_traceless_and_symmetric() {
        let m = ViscosityModel {
            nu: Some(2.0),
            ..Default::default()
        };
        let v = [[1.0, 2.0, 0.5], [-1.0, 3.0, 0.0], [0.3, 0.2, -0.7]];
        let s = m.stress(&v, 2.0);
        let tr: f64 = (0..3).map(|a| s[a][a]).sum();
        assert!(tr.abs() < 1e-14);
        for a in 0..3 {
            for b in 0..3 {
                assert_eq!(s[a][b], s[b][a]);
            }
        }
        // Pure shear v_y = x: σ_xy = σ_yx = 1.
        let s2 = m.stress(&[[0.0, 0.0], [1.0, 0.0]], 1.0);
        assert_eq!(s2, [[0.0, 1.0], [1.0, 0.0]]);
    }

    #[test]
    fn alpha_viscosity_is_alpha_cs_h() {
        let m = ViscosityModel {
            alpha: Some(0.1),
            ..Default::default()
        };
        // Ω = 1 at r = 1 for GM = 1: ν = α c_s² / Ω.
        assert!((m.nu(0.05, 1.0, 1.0) - 0.1 * 0.0025).abs() < 1e-16);
        assert!(m.validate(false).is_err());
        assert!(m.validate(true).is_ok());
        let bad = ViscosityModel {
            nu: Some(-1.0),
            ..Default::default()
        };
        assert!(bad.validate(false).unwrap_err().contains("viscosity.nu"));
    }
}
