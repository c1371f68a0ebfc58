//! Equations of state: pressure and sound speed from density, specific internal energy and
//! (for the locally isothermal disk EOS) the cylindrical distance from the central mass.
//! In 2D the density is the surface density Σ and the pressure the vertically integrated P.

use serde::{Deserialize, Serialize};

/// An equation of state. Only `Ideal` evolves the internal energy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Eos {
    /// p = (γ − 1) ρ u, c = √(γ p / ρ).
    Ideal { gamma: f64 },
    /// p = c_s² ρ, c = c_s.
    Isothermal { cs: f64 },
    /// The standard disk EOS: c_s(R) = cs0 (R / r0)^(−q), p = c_s(R)² ρ, R the cylindrical
    /// distance from the origin (where the central mass sits).
    LocallyIsothermal { cs0: f64, r0: f64, q: f64 },
    /// Pressure-less gas: p = 0, c = 0.
    Cold {},
}

impl Eos {
    /// (pressure, sound speed) at density `rho`, specific internal energy `u` and cylindrical
    /// radius `radius`.
    #[inline]
    pub fn pressure_sound_speed(&self, rho: f64, u: f64, radius: f64) -> (f64, f64) {
        match *self {
            Eos::Ideal { gamma } => {
                let p = (gamma - 1.0) * rho * u;
                (p, (gamma * (gamma - 1.0) * u.max(0.0)).sqrt())
            }
            Eos::Isothermal { cs } => (cs * cs * rho, cs),
            Eos::LocallyIsothermal { cs0, r0, q } => {
                let cs = cs0 * (radius.max(1e-12 * r0) / r0).powf(-q);
                (cs * cs * rho, cs)
            }
            Eos::Cold {} => (0.0, 0.0),
        }
    }

    /// Specific internal energy that gives pressure `p` at density `rho` (ideal gas); for the
    /// isothermal kinds the energy is not used and c_s² is returned.
    pub fn internal_energy(&self, rho: f64, p: f64) -> f64 {
        match *self {
            Eos::Ideal { gamma } => p / ((gamma - 1.0) * rho),
            Eos::Isothermal { cs } => cs * cs,
            Eos::LocallyIsothermal { cs0, .. } => cs0 * cs0,
            Eos::Cold {} => 0.0,
        }
    }

    /// Whether the pressure depends on the cylindrical radius (so that it need be computed).
    #[inline]
    pub fn needs_radius(&self) -> bool {
        matches!(self, Eos::LocallyIsothermal { .. })
    }

    /// Whether the energy equation is integrated (and total energy is a conserved figure).
    pub fn evolves_energy(&self) -> bool {
        matches!(self, Eos::Ideal { .. })
    }

    pub fn validate(&self) -> Result<(), String> {
        match *self {
            Eos::Ideal { gamma } if !(gamma > 1.0 && gamma.is_finite()) => {
                Err(format!("eos.gamma must be > 1, got {gamma:?}"))
            }
            Eos::Isothermal { cs } if !(cs > 0.0 && cs.is_finite()) => {
                Err(format!("eos.cs must be > 0, got {cs:?}"))
            }
            Eos::LocallyIsothermal { cs0, .. } if !(cs0 > 0.0 && cs0.is_finite()) => {
                Err(format!("eos.cs0 must be > 0, got {cs0:?}"))
            }
            Eos::LocallyIsothermal { r0, .. } if !(r0 > 0.0 && r0.is_finite()) => {
                Err(format!("eos.r0 must be > 0, got {r0:?}"))
            }
            Eos::LocallyIsothermal { q, .. } if !q.is_finite() => {
                Err(format!("eos.q must be finite, got {q:?}"))
            }
            _ => Ok(()),
        }
    }
}

/// Cylindrical distance from the origin: |x| in 1D, √(x² + y²) in 2D and 3D.
#[inline]
pub fn cylindrical_radius<const D: usize>(x: &[f64; D]) -> f64 {
    if D == 1 { x[0].abs() } else { x[0].hypot(x[1]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ideal_gas_round_trips_pressure() {
        let eos = Eos::Ideal { gamma: 1.4 };
        let u = eos.internal_energy(0.125, 0.1);
        let (p, c) = eos.pressure_sound_speed(0.125, u, 0.0);
        assert!((p - 0.1).abs() < 1e-15);
        assert!((c - (1.4f64 * 0.1 / 0.125).sqrt()).abs() < 1e-14);
    }

    #[test]
    fn isothermal_ignores_internal_energy() {
        let eos = Eos::Isothermal { cs: 0.5 };
        assert_eq!(eos.pressure_sound_speed(2.0, 123.0, 7.0), (0.5, 0.5));
        assert!(!eos.evolves_energy());
        assert!(Eos::Isothermal { cs: -1.0 }.validate().is_err());
        assert!(Eos::Ideal { gamma: 1.0 }.validate().is_err());
    }

    #[test]
    fn locally_isothermal_sound_speed_falls_with_radius() {
        let eos = Eos::LocallyIsothermal {
            cs0: 0.05,
            r0: 1.0,
            q: 0.5,
        };
        let (p, c) = eos.pressure_sound_speed(2.0, 0.0, 4.0);
        assert!((c - 0.025).abs() < 1e-15);
        assert!((p - 2.0 * 0.025 * 0.025).abs() < 1e-15);
        assert_eq!(Eos::Cold {}.pressure_sound_speed(1.0, 1.0, 1.0), (0.0, 0.0));
        assert_eq!(cylindrical_radius(&[3.0, 4.0, 12.0]), 5.0);
    }

    #[test]
    fn a_key_of_another_kind_is_refused() {
        let t: toml::Table = "kind = \"cold\"\ncs = 0.05".parse().unwrap();
        assert!(toml::Value::Table(t).try_into::<Eos>().is_err());
        let t: toml::Table = "kind = \"cold\"".parse().unwrap();
        assert_eq!(
            toml::Value::Table(t).try_into::<Eos>().unwrap(),
            Eos::Cold {}
        );
    }
}
