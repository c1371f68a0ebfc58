//! The choice of SPH formulation for gas with an energy equation: the paper's density–energy
//! form (Eqs. 5 and 7: p_i = (γ − 1) ρ_i u_i from the density sum), or the pressure–energy
//! form of Saitoh & Makino (2013) and Hopkins (2013), in which the pressure itself is the
//! smoothed quantity:
//!
//!   p̄_i = (γ − 1) Σ_j m_j u_j W_ij   (self term included),
//!
//! with, for a constant h (the paper's choice, so no grad-h terms),
//!
//!   dv_i/dt = −Σ_j (γ − 1)² m_j u_i u_j (1/p̄_i + 1/p̄_j) ∇_i W_ij,
//!   du_i/dt =  Σ_j (γ − 1)² m_j u_i u_j / p̄_i  v_ij · ∇_i W_ij,
//!
//! which conserve momentum and total energy pairwise like Eq. (7), reduce to it where ρ and u
//! are uniform, and give the first law du_i/dt = −(p̄_i/ρ*_i) ∇·v with ρ*_i = p̄_i/((γ − 1) u_i).
//! At a contact discontinuity in pressure balance p̄ is smooth whatever u and ρ do, so the
//! spurious pressure blip of the density–energy form (and the force that moves the contact)
//! does not arise, without conducting heat across it. The pair terms are in
//! [`crate::physics::hydro::force_pair`]; the sweep adds Σ m_j u_j W_ij to its density sum.
//! Only for an ideal gas (the isothermal kinds have no u to smooth).

use serde::{Deserialize, Serialize};

/// The SPH formulation (`[hydro] scheme`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scheme {
    /// p = (γ − 1) ρ u from the density sum (the paper's Eq. 7; the default).
    #[default]
    DensityEnergy,
    /// p̄ = (γ − 1) Σ m u W (Saitoh & Makino 2013; Hopkins 2013).
    PressureEnergy,
}

impl Scheme {
    pub fn name(self) -> &'static str {
        match self {
            Scheme::DensityEnergy => "density_energy",
            Scheme::PressureEnergy => "pressure_energy",
        }
    }
}

/// The `[hydro]` table of a problem file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HydroSection {
    /// "density_energy" (default) or "pressure_energy".
    #[serde(default)]
    pub scheme: Scheme,
}

/// p̄ and the sound speed √(γ p̄/ρ) of a particle of mass `m`, energy `u` and density `rho`,
/// from its neighbours' Σ m_j u_j W_ij (`sum_mu_w`, without the self term) and W(0).
#[inline]
pub fn smoothed_pressure(
    gamma: f64,
    sum_mu_w: f64,
    m: f64,
    u: f64,
    w0: f64,
    rho: f64,
) -> (f64, f64) {
    let p = ((gamma - 1.0) * (sum_mu_w + m * u * w0)).max(0.0);
    (p, sound_speed(gamma, p, rho))
}

/// √(γ p̄/ρ) (zero without density).
#[inline]
pub fn sound_speed(gamma: f64, p: f64, rho: f64) -> f64 {
    if rho > 0.0 {
        (gamma * p / rho).sqrt()
    } else {
        0.0
    }
}

/// p̄ after u changed from `u_eval` (the value the evaluation smoothed) to `u_new` at fixed
/// positions, to first order: ρ*_i = p̄_i/((γ − 1) u_i) held (p̄ is next recomputed by the
/// following evaluation; this keeps the pressure written between evaluations consistent
/// with the corrected energy).
#[inline]
pub fn rescaled_pressure(p: f64, u_eval: f64, u_new: f64) -> f64 {
    if u_eval > 0.0 {
        p * (u_new.max(0.0) / u_eval)
    } else {
        p
    }
}

/// The pressure–energy pair weights: (γ − 1)² u_i u_j/p̄_i and (γ − 1)² u_i u_j/p̄_j, from
/// y = (γ − 1) u and p̄ of each side (zero where a side has no pressure, which only happens
/// where its y, hence the product, is zero).
#[inline]
pub fn pair_weights(y_i: f64, p_i: f64, y_j: f64, p_j: f64) -> (f64, f64) {
    let yy = y_i * y_j;
    let a_i = if p_i > 0.0 { yy / p_i } else { 0.0 };
    let a_j = if p_j > 0.0 { yy / p_j } else { 0.0 };
    (a_i, a_j)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_gas_gives_the_density_energy_pressure_and_pair_terms() {
        // N equal particles of mass m and energy u, all at W: Σ m u W = N m u W and
        // ρ = N m W, so p̄ = (γ − 1) ρ u, and (γ − 1)² u² (2/p̄) = 2 p/ρ², Eq. (7)'s term.
        let (gamma, m, u, w, w0, n) = (1.4, 0.3, 2.5, 0.7, 1.1, 6.0);
        let rho = n * m * w + m * w0;
        let (p, cs) = smoothed_pressure(gamma, n * m * u * w, m, u, w0, rho);
        let p_de = (gamma - 1.0) * rho * u;
        assert!((p - p_de).abs() < 1e-14 * p_de);
        assert!((cs - (gamma * (gamma - 1.0) * u).sqrt()).abs() < 1e-14);
        let y = (gamma - 1.0) * u;
        let (a_i, a_j) = pair_weights(y, p, y, p);
        let de = 2.0 * p_de / (rho * rho);
        assert!((a_i + a_j - de).abs() < 1e-14 * de);
    }

    #[test]
    fn a_contact_in_pressure_balance_has_a_smooth_pressure() {
        // Two sides of a contact at one pressure: (ρ, u) = (1, 2.5) and (0.125, 20). Any
        // mix of their particles' Σ m u W gives the same p̄ per unit kernel volume, since
        // m u is the same per unit volume on both sides (ρ u = p/(γ − 1)).
        let gamma = 1.4;
        let (dense_mu, sparse_mu) = (1.0 * 2.5, 0.125 * 20.0);
        assert_eq!(dense_mu, sparse_mu);
        let (p, _) = smoothed_pressure(gamma, 0.5 * dense_mu + 0.5 * sparse_mu, 0.0, 0.0, 0.0, 1.0);
        assert!((p - 0.4 * 2.5).abs() < 1e-15);
    }

    #[test]
    fn rescaling_follows_the_energy_and_cold_gas_has_no_weight() {
        assert_eq!(rescaled_pressure(2.0, 1.0, 1.5), 3.0);
        assert_eq!(rescaled_pressure(2.0, 0.0, 1.5), 2.0);
        assert_eq!(pair_weights(0.0, 0.0, 1.0, 1.0), (0.0, 0.0));
    }

    #[test]
    fn scheme_names_parse() {
        let s: HydroSection = toml::from_str("scheme = \"pressure_energy\"").unwrap();
        assert_eq!(s.scheme, Scheme::PressureEnergy);
        assert_eq!(s.scheme.name(), "pressure_energy");
        assert!(toml::from_str::<HydroSection>("scheme = \"pe\"").is_err());
        assert_eq!(HydroSection::default().scheme, Scheme::DensityEnergy);
    }
}
