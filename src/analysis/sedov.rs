//! Sedov–Taylor point-blast self-similar solution for a uniform, cold ambient medium: the
//! constant ξ0(γ, d) of the shock radius R(t) = ξ0 (E t²/ρ0)^(1/(d+2)) and the post-shock profiles.
//!
//! # Formulation
//!
//! With ξ = r/R, shock speed U = dR/dt = δ R/t, δ = 2/(d+2), the similarity ansatz
//! v = U ξ F(ξ), ρ = ρ0 g(ξ), p = ρ0 U² h(ξ) turns the Euler equations into ODEs in
//! s = ln ξ. The energy integral (Sedov 1959, ch. IV §11; Landau & Lifshitz, *Fluid Mechanics*
//! §106), (g ξ²F²/2 + h/(γ−1)) (1 − F) = h F, eliminates h:
//!
//! h = g ξ² (γ−1) F² (1−F) / (2(γF − 1)),
//!
//! leaving the autonomous equation dF/ds = Φ(F) and the quadrature dln g/ds = (Φ + dF)/(1 − F)
//! (Sedov's V = F, Z = γh/(gξ²)), integrated inward from the strong-shock Rankine–Hugoniot state
//! F = 2/(γ+1), g = (γ+1)/(γ−1), h = 2/(γ+1) at ξ = 1 with an adaptive Dormand–Prince 5(4)
//! scheme. The total energy is
//!
//! E = ρ0 δ² A_d J R^(d+2)/t², J = ∫₀¹ (g ξ² F²/2 + h/(γ−1)) ξ^(d−1) dξ,
//!
//! with A_1 = 2 (slab blast running both ways, E per unit area), A_2 = 2π (E per unit length),
//! A_3 = 4π; hence α = δ² A_d J and ξ0 = α^(−1/(d+2)).
//!
//! For d = 3 and γ > 7 the solution has an evacuated core (Sedov 1959; Kamm & Timmes 2007,
//! LA-UR-07-2849, the "vacuum" case ω > ω2 = (7 − γ)/(γ + 1) at ω = 0): F reaches 1 at a finite
//! radius ξ_v > 0 inside which ρ = p = 0. This case is handled too.

use std::f64::consts::PI;

/// Relative and absolute tolerance of the adaptive integrator.
const ODE_TOLERANCE: f64 = 1.0e-12;
/// Maximum number of integrator steps before giving up.
const MAX_STEPS: usize = 2_000_000;
/// Length of the integration in ln-variables: the neglected tail is ∝ exp(−DEPTH) before the
/// analytic tail correction.
const DEPTH: f64 = 40.0;

/// Post-shock state of the Sedov–Taylor blast at one radius (physical units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SedovState {
    /// Density ρ.
    pub rho: f64,
    /// Radial velocity v.
    pub v: f64,
    /// Pressure p.
    pub p: f64,
}

/// Returns the Sedov–Taylor constant ξ0(γ, d): R(t) = ξ0 (E t²/ρ0)^(1/(d+2)).
///
/// E is the total blast energy (d = 3), the energy per unit length (d = 2), or the energy per
/// unit area of a slab blast expanding to both sides (d = 1). Accurate to about 1e-11 relative.
/// Examples: ξ0(1.4, 3) = 1.03278, ξ0(5/3, 3) = 1.15167, ξ0(1.4, 2) = 1.00402,
/// ξ0(5/3, 2) = 1.15379.
///
/// # Errors
/// Returns a message for `gamma <= 1` (or non-finite) or `dimension` not in 1..=3.
pub fn sedov_xi0(gamma: f64, dimension: usize) -> Result<f64, String> {
    let sim = Similarity::new(gamma, dimension)?;
    let alpha = sim.energy_constant()?;
    Ok(alpha.powf(-1.0 / (sim.d + 2.0)))
}

/// Shock radius R(t) = ξ0 (E t²/ρ0)^(1/(d+2)), see [`sedov_xi0`] for the meaning of E.
///
/// # Errors
/// Returns a message for `gamma <= 1`, `dimension` not in 1..=3, non-positive `energy` or
/// `rho0`, or negative (or non-finite) `t`.
pub fn sedov_shock_radius(
    energy: f64,
    rho0: f64,
    t: f64,
    gamma: f64,
    dimension: usize,
) -> Result<f64, String> {
    validate_blast(energy, rho0, t)?;
    let xi0 = sedov_xi0(gamma, dimension)?;
    let d = dimension_f64(dimension)?;
    Ok(xi0 * (energy * t * t / rho0).powf(1.0 / (d + 2.0)))
}

/// Exact state (ρ, v, p) of the Sedov–Taylor blast at radius `r` and time `t > 0`.
///
/// Outside the shock the cold ambient state (ρ0, 0, 0) is returned; exactly at r = R the
/// post-shock state. At the centre (r = 0) ρ = v = 0 and p is the finite central pressure.
/// Inside the vacuum core (d = 3, γ > 7) ρ = v = p = 0. Accuracy is about 1e-10 relative, lower
/// very close to a vacuum boundary where ρ → 0.
///
/// # Errors
/// As [`sedov_shock_radius`], plus `t <= 0` and negative or non-finite `r`.
pub fn sedov_state(
    energy: f64,
    rho0: f64,
    t: f64,
    r: f64,
    gamma: f64,
    dimension: usize,
) -> Result<SedovState, String> {
    validate_blast(energy, rho0, t)?;
    if t <= 0.0 {
        return Err(format!("sedov: time must be positive, got {t}"));
    }
    if !(r.is_finite() && r >= 0.0) {
        return Err(format!(
            "sedov: radius must be non-negative and finite, got {r}"
        ));
    }
    let sim = Similarity::new(gamma, dimension)?;
    let alpha = sim.energy_constant()?;
    let radius = (energy * t * t / (alpha * rho0)).powf(1.0 / (sim.d + 2.0));
    let shock_speed = 2.0 / (sim.d + 2.0) * radius / t;
    if r > radius {
        return Ok(SedovState {
            rho: rho0,
            v: 0.0,
            p: 0.0,
        });
    }
    let (g, f, h) = sim.profile(r / radius)?;
    Ok(SedovState {
        rho: rho0 * g,
        v: shock_speed * f,
        p: rho0 * shock_speed * shock_speed * h,
    })
}

fn validate_blast(energy: f64, rho0: f64, t: f64) -> Result<(), String> {
    if !(energy.is_finite() && energy > 0.0) {
        return Err(format!(
            "sedov: energy must be positive and finite, got {energy}"
        ));
    }
    if !(rho0.is_finite() && rho0 > 0.0) {
        return Err(format!(
            "sedov: ambient density must be positive and finite, got {rho0}"
        ));
    }
    if !(t.is_finite() && t >= 0.0) {
        return Err(format!(
            "sedov: time must be non-negative and finite, got {t}"
        ));
    }
    Ok(())
}

fn dimension_f64(dimension: usize) -> Result<f64, String> {
    match dimension {
        1 => Ok(1.0),
        2 => Ok(2.0),
        3 => Ok(3.0),
        _ => Err(format!(
            "sedov: dimension must be 1, 2 or 3, got {dimension}"
        )),
    }
}

/// The reduced similarity equations for given γ and d.
struct Similarity {
    gamma: f64,
    d: f64,
    /// Geometric factor A_d of the energy integral.
    area: f64,
}

impl Similarity {
    fn new(gamma: f64, dimension: usize) -> Result<Self, String> {
        if !(gamma.is_finite() && gamma > 1.0) {
            return Err(format!(
                "sedov: adiabatic index gamma must be > 1, got {gamma}"
            ));
        }
        let d = dimension_f64(dimension)?;
        let area = match dimension {
            1 => 2.0,
            2 => 2.0 * PI,
            _ => 4.0 * PI,
        };
        Ok(Self { gamma, d, area })
    }

    /// F at the shock.
    fn f_shock(&self) -> f64 {
        2.0 / (self.gamma + 1.0)
    }

    /// Φ(F)/(γF − 1) where dF/ds = Φ(F); `one_minus_f` = 1 − F is passed separately to keep
    /// precision as F → 1. Derived from the continuity, momentum and entropy equations with
    /// the energy integral substituted:
    /// Φ/(γF−1) = [d − (d + 2(1−F))/((γ−1)F)] / (γ Dn), Dn = 2(γF−1)(1−F)/(γ(γ−1)F²) − 1,
    /// where Dn = (w² − c²)/c² < 0 expresses that the flow is subsonic relative to ξ = const.
    fn phi_over_e(&self, f: f64, one_minus_f: f64) -> Result<f64, String> {
        let g = self.gamma;
        let e = g * f - 1.0;
        let denom = 2.0 * e * one_minus_f / (g * (g - 1.0) * f * f) - 1.0;
        if denom >= 0.0 || !denom.is_finite() {
            return Err(format!(
                "sedov: similarity equations hit a sonic point (F = {f}, gamma = {g})"
            ));
        }
        let bracket = self.d - (self.d + 2.0 * one_minus_f) / ((g - 1.0) * f);
        Ok(bracket / (g * denom))
    }

    /// Energy integrand (g ξ²F²/2 + h/(γ−1)) ξ^d = g ξ^(d+2) F³ (γ−1)/(2(γF−1)), written with
    /// ln g, s = ln ξ and ln(γF − 1).
    fn energy_density(&self, ln_g: f64, s: f64, ln_e: f64, f: f64) -> f64 {
        (ln_g + (self.d + 2.0) * s - ln_e).exp() * f * f * f * (self.gamma - 1.0) / 2.0
    }

    /// Right-hand side in τ = −ln ξ for y = [ln(γF − 1), ln g, J].
    fn rhs_tau(&self, tau: f64, y: &[f64; 3]) -> Result<[f64; 3], String> {
        let g = self.gamma;
        let e = y[0].exp();
        let f = (1.0 + e) / g;
        let one_minus_f = (g - 1.0 - e) / g;
        let phi_e = self.phi_over_e(f, one_minus_f)?;
        let phi = e * phi_e;
        Ok([
            -g * phi_e,
            -(phi + self.d * f) / one_minus_f,
            self.energy_density(y[1], -tau, y[0], f),
        ])
    }

    /// Dimensionless energy α = δ² A_d J with E = α ρ0 R^(d+2)/t².
    fn energy_constant(&self) -> Result<f64, String> {
        let g = self.gamma;
        let f_s = self.f_shock();
        let ln_g_s = ((g + 1.0) / (g - 1.0)).ln();
        let ln_e_s = ((g - 1.0) / (g + 1.0)).ln();
        let bracket_s = self.d - (self.d + 2.0 * (1.0 - f_s)) / ((g - 1.0) * f_s);
        let j = if bracket_s <= 1.0e-12 {
            // Standard case: F → 1/γ as ξ → 0 with γF − 1 ∝ ξ^(2 + d/(γ−1)); the energy
            // integrand decays as ξ^d = exp(−d τ), integrated to τ = DEPTH/d, and the remaining
            // tail ∫ C exp(−d τ) dτ is added analytically.
            let tau_end = DEPTH / self.d;
            let y = integrate(
                |tau, y| self.rhs_tau(tau, y),
                0.0,
                [ln_e_s, ln_g_s, 0.0],
                tau_end,
            )?;
            let f_end = (1.0 + y[0].exp()) / g;
            y[2] + self.energy_density(y[1], -tau_end, y[0], f_end) / self.d
        } else {
            let (j, _) = self.vacuum_core(ln_g_s)?;
            j
        };
        let delta = 2.0 / (self.d + 2.0);
        Ok(delta * delta * self.area * j)
    }

    /// Vacuum case (d = 3, γ > 7): integrates in χ = −ln((1 − F)/(1 − F_s)) for y = [s, ln g, J]
    /// up to F = 1, where g ∝ (1 − F)^(2/(γ−2)). Returns (J, s_v = ln ξ_v).
    fn vacuum_core(&self, ln_g_s: f64) -> Result<(f64, f64), String> {
        let g = self.gamma;
        let one_minus_f_s = 1.0 - self.f_shock();
        let state = |chi: f64| {
            let one_minus_f = one_minus_f_s * (-chi).exp();
            (1.0 - one_minus_f, one_minus_f)
        };
        let rhs = |chi: f64, y: &[f64; 3]| -> Result<[f64; 3], String> {
            let (f, one_minus_f) = state(chi);
            let e = g * f - 1.0;
            let phi = e * self.phi_over_e(f, one_minus_f)?;
            let ds = one_minus_f / phi;
            Ok([
                ds,
                1.0 + self.d * f / phi,
                -self.energy_density(y[1], y[0], e.ln(), f) * ds,
            ])
        };
        let y = integrate(rhs, 0.0, [0.0, ln_g_s, 0.0], DEPTH)?;
        // Tail: dJ/dχ ∝ (1 − F)^(1 + 2/(γ−2)) = exp(−(1 + 2/(γ−2)) χ).
        let tail = rhs(DEPTH, &y)?[2] / (1.0 + 2.0 / (g - 2.0));
        let (f_end, one_minus_f_end) = state(DEPTH);
        let phi_end = (g * f_end - 1.0) * self.phi_over_e(f_end, one_minus_f_end)?;
        Ok((y[2] + tail, y[0] + one_minus_f_end / phi_end))
    }

    /// Scaled profile (g, v/U, p/(ρ0 U²)) at λ = r/R ∈ [0, 1].
    fn profile(&self, lambda: f64) -> Result<(f64, f64, f64), String> {
        let g = self.gamma;
        let f_s = self.f_shock();
        let ln_g_s = ((g + 1.0) / (g - 1.0)).ln();
        let ln_e_s = ((g - 1.0) / (g + 1.0)).ln();
        let bracket_s = self.d - (self.d + 2.0 * (1.0 - f_s)) / ((g - 1.0) * f_s);
        let vacuum = bracket_s > 1.0e-12;
        if vacuum {
            let (_, s_v) = self.vacuum_core(ln_g_s)?;
            if lambda <= s_v.exp() {
                return Ok((0.0, 0.0, 0.0));
            }
        }
        let at_centre = lambda <= 0.0;
        let tau_end = if at_centre { DEPTH } else { -lambda.ln() };
        let y = integrate(
            |tau, y| self.rhs_tau(tau, y),
            0.0,
            [ln_e_s, ln_g_s, 0.0],
            tau_end,
        )?;
        let e = y[0].exp();
        let f = (1.0 + e) / g;
        let one_minus_f = (g - 1.0 - e) / g;
        // h = g ξ² (γ−1) F² (1−F) / (2(γF − 1)), finite at the centre.
        let h = (y[1] - 2.0 * tau_end - y[0]).exp() * (g - 1.0) * f * f * one_minus_f / 2.0;
        if at_centre {
            Ok((0.0, 0.0, h))
        } else {
            Ok((y[1].exp(), lambda * f, h))
        }
    }
}

/// Adaptive Dormand–Prince 5(4) integration of y' = rhs(x, y) from x0 to x_end > x0 with mixed
/// absolute/relative tolerance [`ODE_TOLERANCE`] (Hairer, Nørsett & Wanner, *Solving ODEs I*,
/// §II.4–5).
fn integrate<R>(rhs: R, x0: f64, y0: [f64; 3], x_end: f64) -> Result<[f64; 3], String>
where
    R: Fn(f64, &[f64; 3]) -> Result<[f64; 3], String>,
{
    const C: [f64; 6] = [1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
    const A: [[f64; 6]; 6] = [
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
        [
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
            0.0,
            0.0,
        ],
        [
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
            0.0,
        ],
        [
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ];
    // Difference between the 5th- and 4th-order weights (the 7th stage is FSAL).
    const E: [f64; 7] = [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ];

    let step = |x: f64, y: &[f64; 3], k0: &[f64; 3], h: f64| -> Result<_, String> {
        let mut k = [[0.0; 3]; 7];
        k[0] = *k0;
        let mut ys = *y;
        for stage in 0..6 {
            ys = *y;
            for (i, yi) in ys.iter_mut().enumerate() {
                *yi += h * (0..=stage).map(|j| A[stage][j] * k[j][i]).sum::<f64>();
            }
            k[stage + 1] = rhs(x + C[stage] * h, &ys)?;
        }
        // The last stage is evaluated at the 5th-order solution (FSAL).
        let mut err = 0.0_f64;
        for i in 0..3 {
            let est = h * (0..7).map(|j| E[j] * k[j][i]).sum::<f64>();
            let scale = ODE_TOLERANCE * (1.0 + y[i].abs().max(ys[i].abs()));
            err = err.max((est / scale).abs());
        }
        Ok((ys, k[6], err))
    };

    let mut x = x0;
    let mut y = y0;
    let mut k0 = rhs(x, &y)?;
    let mut h = 1.0e-3 * (x_end - x0);
    for _ in 0..MAX_STEPS {
        if x >= x_end {
            return Ok(y);
        }
        let last = x + h >= x_end;
        if last {
            h = x_end - x;
        }
        match step(x, &y, &k0, h) {
            Ok((ys, k6, err)) if err.is_finite() => {
                if err <= 1.0 {
                    x = if last { x_end } else { x + h };
                    y = ys;
                    k0 = k6;
                }
                h *= (0.9 * err.powf(-0.2)).clamp(0.2, 5.0);
            }
            // A trial step that leaves the domain of the equations is rejected like one with a
            // large error estimate.
            outcome => {
                h *= 0.1;
                if h <= 1.0e-14 * (x_end - x0) {
                    return Err(match outcome {
                        Err(message) => message,
                        Ok(_) => "sedov: non-finite error estimate in the similarity integration"
                            .to_string(),
                    });
                }
            }
        }
    }
    Err("sedov: too many steps in the similarity integration".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_rel(actual: f64, expected: f64, tol: f64, what: &str) {
        let err = (actual - expected).abs() / expected.abs();
        assert!(
            err <= tol,
            "{what}: got {actual}, expected {expected} (relative error {err:e} > {tol:e})"
        );
    }

    #[test]
    fn reference_values_3d_and_2d() {
        assert_rel(sedov_xi0(5.0 / 3.0, 3).unwrap(), 1.15167, 1e-5, "3D 5/3");
        assert_rel(sedov_xi0(1.4, 3).unwrap(), 1.03278, 1e-5, "3D 1.4");
        assert_rel(sedov_xi0(5.0 / 3.0, 2).unwrap(), 1.15379, 1e-5, "2D 5/3");
        assert_rel(sedov_xi0(1.4, 2).unwrap(), 1.00402, 1e-5, "2D 1.4");
    }
}
