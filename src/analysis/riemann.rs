//! Exact Riemann solver for the 1D Euler equations of an ideal gas (E. F. Toro, *Riemann Solvers
//! and Numerical Methods for Fluid Dynamics*, 3rd ed. 2009, ch. 4):
//! star-region state by safeguarded Newton iteration on the pressure function, and
//! sampling of the self-similar solution (shocks, rarefaction fans, contact).

/// Primitive state of the 1D Euler equations: density, velocity, pressure.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimitiveState {
    /// Mass density ρ.
    pub rho: f64,
    /// Velocity v.
    pub v: f64,
    /// Pressure p.
    pub p: f64,
}

/// Wave speeds of the Riemann fan, in the self-similar coordinate ξ = (x − x0)/t.
///
/// For a shock the head and tail speeds are both equal to the shock speed.
#[derive(Clone, Copy, Debug)]
pub struct WaveSpeeds {
    /// Head of the left rarefaction (v_L − c_L), or the left shock speed.
    pub left_head: f64,
    /// Tail of the left rarefaction (v* − c*_L), or the left shock speed.
    pub left_tail: f64,
    /// Contact discontinuity speed v*.
    pub contact: f64,
    /// Tail of the right rarefaction (v* + c*_R), or the right shock speed.
    pub right_tail: f64,
    /// Head of the right rarefaction (v_R + c_R), or the right shock speed.
    pub right_head: f64,
}

/// Exact solution of a Riemann problem for an ideal gas with adiabatic index γ.
///
/// Built by [`RiemannSolution::solve`]; the solution is self-similar and is sampled
/// with [`RiemannSolution::sample`] at ξ = (x − x0)/t.
#[derive(Clone, Copy, Debug)]
pub struct RiemannSolution {
    left: PrimitiveState,
    right: PrimitiveState,
    gamma: f64,
    c_left: f64,
    c_right: f64,
    p_star: f64,
    v_star: f64,
    rho_star_left: f64,
    rho_star_right: f64,
}

/// Relative change of p* between Newton iterates at which the iteration stops.
const PRESSURE_TOLERANCE: f64 = 1.0e-14;
/// Maximum number of (safeguarded) Newton iterations.
const MAX_ITERATIONS: usize = 200;

/// Sound speed c = sqrt(γ p / ρ).
fn sound_speed(state: &PrimitiveState, gamma: f64) -> f64 {
    (gamma * state.p / state.rho).sqrt()
}

/// Toro's pressure function f_K(p) and its derivative for one side K (Toro §4.2–4.3).
///
/// Shock branch (p > p_K): f_K = (p − p_K) sqrt(A_K/(p + B_K)), A_K = 2/((γ+1)ρ_K),
/// B_K = (γ−1)/(γ+1) p_K.
/// Rarefaction branch (p ≤ p_K): f_K = 2c_K/(γ−1) [(p/p_K)^((γ−1)/(2γ)) − 1], evaluated with
/// `exp_m1` so that it stays accurate for γ → 1.
fn pressure_function(p: f64, state: &PrimitiveState, c: f64, gamma: f64) -> (f64, f64) {
    if p > state.p {
        let a = 2.0 / ((gamma + 1.0) * state.rho);
        let b = (gamma - 1.0) / (gamma + 1.0) * state.p;
        let q = (a / (p + b)).sqrt();
        let f = (p - state.p) * q;
        let df = q * (1.0 - 0.5 * (p - state.p) / (b + p));
        (f, df)
    } else {
        let ratio = p / state.p;
        // (p/p_K)^z - 1 via exp_m1 to avoid cancellation when gamma -> 1.
        let f = 2.0 * c / (gamma - 1.0) * ((gamma - 1.0) / (2.0 * gamma) * ratio.ln()).exp_m1();
        let df = ratio.powf(-(gamma + 1.0) / (2.0 * gamma)) / (state.rho * c);
        (f, df)
    }
}

fn validate_state(state: &PrimitiveState, side: &str) -> Result<(), String> {
    if !(state.rho.is_finite() && state.rho > 0.0) {
        return Err(format!(
            "riemann: {side} density must be positive and finite, got {}",
            state.rho
        ));
    }
    if !(state.p.is_finite() && state.p > 0.0) {
        return Err(format!(
            "riemann: {side} pressure must be positive and finite, got {}",
            state.p
        ));
    }
    if !state.v.is_finite() {
        return Err(format!(
            "riemann: {side} velocity must be finite, got {}",
            state.v
        ));
    }
    Ok(())
}

impl RiemannSolution {
    /// Solves the Riemann problem with states `left` (x < x0) and `right` (x > x0) at t = 0.
    ///
    /// p* is the root of f(p) = f_L(p) + f_R(p) + (v_R − v_L) (Toro §4.2), found by Newton
    /// iteration (Toro §4.3) from Toro's adaptive initial guess, safeguarded by
    /// bisection inside a bracket [p_lo, p_hi] with f(p_lo) < 0 < f(p_hi), and stopped when the
    /// relative change of p is below 1e-14. Then v* = (v_L + v_R)/2 + (f_R(p*) − f_L(p*))/2
    /// (Toro §4.2), and the star densities follow from the shock or isentropic relations
    /// (Toro §4.4).
    ///
    /// # Errors
    /// Returns a message naming the cause for non-positive or non-finite densities or
    /// pressures, non-finite velocities, `gamma <= 1` (or non-finite), vacuum generation
    /// (v_R − v_L ≥ 2(c_L + c_R)/(γ − 1), Toro §4.3, §4.6), a star pressure so close to vacuum
    /// that it underflows f64 (p* < ~1e-308 max(p_L, p_R, 1); only for γ very close to 1 near
    /// the vacuum limit), or failure of the iteration. All error messages contain "vacuum"
    /// for the two vacuum cases.
    pub fn solve(left: PrimitiveState, right: PrimitiveState, gamma: f64) -> Result<Self, String> {
        if !(gamma.is_finite() && gamma > 1.0) {
            return Err(format!(
                "riemann: adiabatic index gamma must be > 1, got {gamma}"
            ));
        }
        validate_state(&left, "left")?;
        validate_state(&right, "right")?;

        let c_left = sound_speed(&left, gamma);
        let c_right = sound_speed(&right, gamma);
        let dv = right.v - left.v;
        let dv_crit = 2.0 * (c_left + c_right) / (gamma - 1.0);
        if dv >= dv_crit {
            return Err(format!(
                "riemann: vacuum generation (v_R - v_L = {dv} >= 2(c_L + c_R)/(gamma - 1) = {dv_crit})"
            ));
        }

        let f = |p: f64| {
            let (fl, dfl) = pressure_function(p, &left, c_left, gamma);
            let (fr, dfr) = pressure_function(p, &right, c_right, gamma);
            (fl + fr + dv, dfl + dfr)
        };

        // Below p_floor, p/p_K may underflow and f can no longer be evaluated reliably.
        let p_floor = f64::MIN_POSITIVE * left.p.max(right.p).max(1.0);
        let mut p = initial_guess(&left, &right, c_left, c_right, gamma);
        if p < p_floor {
            p = 0.5 * (left.p + right.p);
        }

        // Bracket 0 < p_lo < p_hi with f(p_lo) < 0 <= f(p_hi): f increases monotonically in p,
        // f(0+) = dv - dv_crit < 0 and f -> +inf as p -> inf.
        let (mut p_lo, mut p_hi) = if f(p).0 < 0.0 {
            let mut hi = p;
            while f(hi).0 < 0.0 {
                hi *= 4.0;
                if !hi.is_finite() {
                    return Err("riemann: could not bracket the star pressure".to_string());
                }
            }
            (0.25 * hi, hi)
        } else {
            let mut lo = p;
            while f(lo).0 >= 0.0 {
                lo *= 0.25;
                if lo < p_floor {
                    return Err(format!(
                        "riemann: near-vacuum, star pressure underflows f64 (v_R - v_L = {dv}, \
                         2(c_L + c_R)/(gamma - 1) = {dv_crit})"
                    ));
                }
            }
            (lo, 4.0 * lo)
        };
        p = p.clamp(p_lo, p_hi);

        // Newton iteration (Toro §4.3), falling back to geometric bisection whenever a Newton
        // step leaves the bracket.
        let mut converged = false;
        for _ in 0..MAX_ITERATIONS {
            let (fp, dfp) = f(p);
            if fp == 0.0 {
                converged = true;
                break;
            }
            if fp < 0.0 {
                p_lo = p_lo.max(p);
            } else {
                p_hi = p_hi.min(p);
            }
            let newton = p - fp / dfp;
            let p_new = if newton.is_finite() && newton > p_lo && newton < p_hi {
                newton
            } else {
                p_lo.sqrt() * p_hi.sqrt()
            };
            let change = 2.0 * (p_new - p).abs() / (p_new + p);
            p = p_new;
            if change < PRESSURE_TOLERANCE || p_hi - p_lo <= PRESSURE_TOLERANCE * p_hi {
                converged = true;
                break;
            }
        }
        if !(converged && p.is_finite() && p > 0.0) {
            return Err(format!(
                "riemann: Newton iteration for p* did not converge (last p = {p})"
            ));
        }

        let (fl, _) = pressure_function(p, &left, c_left, gamma);
        let (fr, _) = pressure_function(p, &right, c_right, gamma);
        let v_star = 0.5 * (left.v + right.v) + 0.5 * (fr - fl);
        let rho_star_left = star_density(p, &left, gamma);
        let rho_star_right = star_density(p, &right, gamma);

        Ok(Self {
            left,
            right,
            gamma,
            c_left,
            c_right,
            p_star: p,
            v_star,
            rho_star_left,
            rho_star_right,
        })
    }

    /// Left initial state.
    pub fn left(&self) -> PrimitiveState {
        self.left
    }

    /// Right initial state.
    pub fn right(&self) -> PrimitiveState {
        self.right
    }

    /// Adiabatic index γ.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Pressure p* in the star region (between the two nonlinear waves).
    pub fn p_star(&self) -> f64 {
        self.p_star
    }

    /// Velocity v* in the star region (speed of the contact discontinuity).
    pub fn v_star(&self) -> f64 {
        self.v_star
    }

    /// Density in the star region left of the contact.
    pub fn rho_star_left(&self) -> f64 {
        self.rho_star_left
    }

    /// Density in the star region right of the contact.
    pub fn rho_star_right(&self) -> f64 {
        self.rho_star_right
    }

    /// Wave speeds: left wave (head, tail), contact, right wave (tail, head).
    ///
    /// Shock speeds S_L = v_L − c_L Q_L, S_R = v_R + c_R Q_R with
    /// Q_K = sqrt((γ+1)/(2γ) p*/p_K + (γ−1)/(2γ)); rarefaction heads v_L − c_L, v_R + c_R and tails
    /// v* − c*_L, v* + c*_R with c*_K = c_K (p*/p_K)^((γ−1)/(2γ)) (Toro §4.4).
    pub fn wave_speeds(&self) -> WaveSpeeds {
        let g = self.gamma;
        let (left_head, left_tail) = if self.p_star > self.left.p {
            let s = self.left.v
                - self.c_left
                    * ((g + 1.0) / (2.0 * g) * self.p_star / self.left.p + (g - 1.0) / (2.0 * g))
                        .sqrt();
            (s, s)
        } else {
            let c_star = self.c_left * (self.p_star / self.left.p).powf((g - 1.0) / (2.0 * g));
            (self.left.v - self.c_left, self.v_star - c_star)
        };
        let (right_tail, right_head) = if self.p_star > self.right.p {
            let s = self.right.v
                + self.c_right
                    * ((g + 1.0) / (2.0 * g) * self.p_star / self.right.p + (g - 1.0) / (2.0 * g))
                        .sqrt();
            (s, s)
        } else {
            let c_star = self.c_right * (self.p_star / self.right.p).powf((g - 1.0) / (2.0 * g));
            (self.v_star + c_star, self.right.v + self.c_right)
        };
        WaveSpeeds {
            left_head,
            left_tail,
            contact: self.v_star,
            right_tail,
            right_head,
        }
    }

    /// Samples the self-similar solution at ξ = (x − x0)/t (Toro §4.5).
    ///
    /// Inside a left fan: v = 2/(γ+1) [c_L + (γ−1)/2 v_L + ξ],
    /// ρ = ρ_L [2/(γ+1) + (γ−1)/((γ+1)c_L) (v_L − ξ)]^(2/(γ−1)), p = p_L (ρ/ρ_L)^γ
    /// (Toro §4.5); the right fan is the mirror image. Exactly on a
    /// discontinuity the state on its left is returned.
    pub fn sample(&self, xi: f64) -> PrimitiveState {
        let g = self.gamma;
        let w = self.wave_speeds();
        if xi <= self.v_star {
            let star = PrimitiveState {
                rho: self.rho_star_left,
                v: self.v_star,
                p: self.p_star,
            };
            if xi <= w.left_head {
                self.left
            } else if xi >= w.left_tail {
                star
            } else {
                let base =
                    2.0 / (g + 1.0) + (g - 1.0) / ((g + 1.0) * self.c_left) * (self.left.v - xi);
                let rho = self.left.rho * base.powf(2.0 / (g - 1.0));
                PrimitiveState {
                    rho,
                    v: 2.0 / (g + 1.0) * (self.c_left + 0.5 * (g - 1.0) * self.left.v + xi),
                    p: self.left.p * base.powf(2.0 * g / (g - 1.0)),
                }
            }
        } else {
            let star = PrimitiveState {
                rho: self.rho_star_right,
                v: self.v_star,
                p: self.p_star,
            };
            if xi > w.right_head {
                self.right
            } else if xi <= w.right_tail {
                star
            } else {
                let base =
                    2.0 / (g + 1.0) - (g - 1.0) / ((g + 1.0) * self.c_right) * (self.right.v - xi);
                let rho = self.right.rho * base.powf(2.0 / (g - 1.0));
                PrimitiveState {
                    rho,
                    v: 2.0 / (g + 1.0) * (-self.c_right + 0.5 * (g - 1.0) * self.right.v + xi),
                    p: self.right.p * base.powf(2.0 * g / (g - 1.0)),
                }
            }
        }
    }
}

/// Toro's adaptive initial guess for p* (Toro §4.3 and §9.5): the primitive-variable estimate
/// p_PV = (p_L + p_R)/2 − (v_R − v_L)(ρ_L + ρ_R)(c_L + c_R)/8 for weak waves, the
/// two-rarefaction estimate when p_PV is below both pressures, and the two-shock estimate
/// otherwise.
fn initial_guess(
    left: &PrimitiveState,
    right: &PrimitiveState,
    c_left: f64,
    c_right: f64,
    gamma: f64,
) -> f64 {
    let dv = right.v - left.v;
    let p_min = left.p.min(right.p);
    let p_max = left.p.max(right.p);
    let p_pv = (0.5 * (left.p + right.p)
        - 0.125 * dv * (left.rho + right.rho) * (c_left + c_right))
        .max(0.0);
    let guess = if p_max / p_min < 2.0 && p_min <= p_pv && p_pv <= p_max {
        p_pv
    } else if p_pv < p_min {
        let z = (gamma - 1.0) / (2.0 * gamma);
        ((c_left + c_right - 0.5 * (gamma - 1.0) * dv)
            / (c_left / left.p.powf(z) + c_right / right.p.powf(z)))
        .powf(1.0 / z)
    } else {
        let g_k = |state: &PrimitiveState| {
            let a = 2.0 / ((gamma + 1.0) * state.rho);
            let b = (gamma - 1.0) / (gamma + 1.0) * state.p;
            (a / (p_pv + b)).sqrt()
        };
        let (g_l, g_r) = (g_k(left), g_k(right));
        (g_l * left.p + g_r * right.p - dv) / (g_l + g_r)
    };
    if guess.is_finite() && guess > 0.0 {
        guess
    } else {
        0.5 * (left.p + right.p)
    }
}

/// Density behind a shock, ρ_K [(p*/p_K + G)/(G p*/p_K + 1)] with G = (γ−1)/(γ+1), or a
/// rarefaction, ρ_K (p*/p_K)^(1/γ) (Toro §4.4).
fn star_density(p_star: f64, state: &PrimitiveState, gamma: f64) -> f64 {
    let ratio = p_star / state.p;
    if p_star > state.p {
        let g6 = (gamma - 1.0) / (gamma + 1.0);
        state.rho * (ratio + g6) / (g6 * ratio + 1.0)
    } else {
        state.rho * ratio.powf(1.0 / gamma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(rho: f64, v: f64, p: f64) -> PrimitiveState {
        PrimitiveState { rho, v, p }
    }

    fn assert_rel(actual: f64, expected: f64, tol: f64, what: &str) {
        let err = (actual - expected).abs() / expected.abs().max(f64::MIN_POSITIVE);
        assert!(
            err <= tol,
            "{what}: got {actual}, expected {expected} (relative error {err:e} > {tol:e})"
        );
    }

    fn assert_abs(actual: f64, expected: f64, tol: f64, what: &str) {
        assert!(
            (actual - expected).abs() <= tol,
            "{what}: got {actual}, expected {expected} (tolerance {tol:e})"
        );
    }

    fn sod() -> RiemannSolution {
        RiemannSolution::solve(state(1.0, 0.0, 1.0), state(0.125, 0.0, 0.1), 1.4).unwrap()
    }

    /// Checks the Rankine–Hugoniot mass, momentum and energy jump conditions across a shock
    /// moving at speed `s` between states `a` and `b`.
    fn assert_rankine_hugoniot(a: PrimitiveState, b: PrimitiveState, s: f64, gamma: f64) {
        let mass = |q: PrimitiveState| q.rho * (q.v - s);
        let momentum = |q: PrimitiveState| q.rho * (q.v - s) * (q.v - s) + q.p;
        let energy = |q: PrimitiveState| {
            let h = gamma / (gamma - 1.0) * q.p / q.rho;
            q.rho * (q.v - s) * (h + 0.5 * (q.v - s) * (q.v - s))
        };
        let scale = momentum(a).abs().max(momentum(b).abs());
        assert_abs(mass(a), mass(b), 1e-12 * scale.max(1.0), "RH mass flux");
        assert_abs(momentum(a), momentum(b), 1e-12 * scale, "RH momentum flux");
        let escale = energy(a).abs().max(energy(b).abs()).max(1.0);
        assert_abs(energy(a), energy(b), 1e-12 * escale, "RH energy flux");
    }

    #[test]
    fn sod_star_state_and_wave_speeds() {
        let sol = sod();
        assert_rel(sol.p_star(), 0.303130, 1e-5, "p*");
        assert_rel(sol.v_star(), 0.927453, 1e-5, "v*");
        assert_rel(sol.rho_star_left(), 0.426319, 1e-5, "rho*_L");
        assert_rel(sol.rho_star_right(), 0.265574, 1e-5, "rho*_R");
        let w = sol.wave_speeds();
        assert_rel(w.left_head, -1.183216, 1e-5, "rarefaction head");
        assert_rel(w.left_tail, -0.070273, 1e-5, "rarefaction tail");
        assert_rel(w.contact, 0.927453, 1e-5, "contact");
        assert_rel(w.right_tail, 1.752156, 1e-5, "shock speed (tail)");
        assert_rel(w.right_head, 1.752156, 1e-5, "shock speed (head)");
    }

    #[test]
    fn sod_positions_at_t_0_2() {
        // Reference positions are quoted to 5 decimals, so compare to half a unit in the last place.
        let w = sod().wave_speeds();
        let (t, x0) = (0.2, 0.5);
        assert_abs(x0 + w.left_head * t, 0.26336, 5e-6, "head position");
        assert_abs(x0 + w.left_tail * t, 0.48595, 5e-6, "tail position");
        assert_abs(x0 + w.contact * t, 0.68549, 5e-6, "contact position");
        assert_abs(x0 + w.right_head * t, 0.85043, 5e-6, "shock position");
    }

    #[test]
    fn sod_sampled_regions() {
        let sol = sod();
        let w = sol.wave_speeds();
        assert_eq!(sol.sample(-2.0), state(1.0, 0.0, 1.0));
        assert_eq!(sol.sample(2.0), state(0.125, 0.0, 0.1));
        let star_l = sol.sample(0.5 * (w.left_tail + w.contact));
        assert_rel(star_l.rho, 0.426319, 1e-5, "sampled rho*_L");
        assert_rel(star_l.p, 0.303130, 1e-5, "sampled p*_L");
        let star_r = sol.sample(0.5 * (w.contact + w.right_tail));
        assert_rel(star_r.rho, 0.265574, 1e-5, "sampled rho*_R");
        assert_rel(star_r.v, 0.927453, 1e-5, "sampled v*_R");
        // Rankine–Hugoniot across the right shock.
        assert_rankine_hugoniot(star_r, sol.right(), w.right_head, 1.4);
    }

    #[test]
    fn sod_rarefaction_fan() {
        let sol = sod();
        let gamma = 1.4_f64;
        let c_l = gamma.sqrt();
        let xi = -0.5;
        let s = sol.sample(xi);
        let v = 2.0 / (gamma + 1.0) * (c_l + xi);
        let c = v - xi; // the C- characteristic through the point has speed v - c = ξ
        let rho = (c / c_l).powf(2.0 / (gamma - 1.0));
        assert_rel(s.v, v, 1e-12, "fan velocity");
        assert_rel(s.rho, rho, 1e-12, "fan density");
        assert_rel(s.p, rho.powf(gamma), 1e-12, "fan pressure (isentropic)");
        assert_rel((gamma * s.p / s.rho).sqrt(), c, 1e-12, "fan sound speed");
        // Continuity of the fan at its head and tail.
        let w = sol.wave_speeds();
        let eps = 1e-9;
        let head = sol.sample(w.left_head + eps);
        assert_abs(head.rho, 1.0, 1e-8, "fan head density");
        assert_abs(head.v, 0.0, 1e-8, "fan head velocity");
        let tail = sol.sample(w.left_tail - eps);
        assert_abs(tail.rho, sol.rho_star_left(), 1e-8, "fan tail density");
        assert_abs(tail.v, sol.v_star(), 1e-8, "fan tail velocity");
        assert_abs(tail.p, sol.p_star(), 1e-8, "fan tail pressure");
    }

    #[test]
    fn mirror_states_give_mirrored_solution() {
        let gamma = 1.4;
        let (l, r) = (state(1.0, 0.3, 1.0), state(0.125, -0.2, 0.1));
        let mirror = |q: PrimitiveState| state(q.rho, -q.v, q.p);
        let sol = RiemannSolution::solve(l, r, gamma).unwrap();
        let mir = RiemannSolution::solve(mirror(r), mirror(l), gamma).unwrap();
        assert_rel(mir.p_star(), sol.p_star(), 1e-13, "mirrored p*");
        assert_abs(mir.v_star(), -sol.v_star(), 1e-13, "mirrored v*");
        assert_rel(
            mir.rho_star_left(),
            sol.rho_star_right(),
            1e-13,
            "mirrored rho*_L",
        );
        assert_rel(
            mir.rho_star_right(),
            sol.rho_star_left(),
            1e-13,
            "mirrored rho*_R",
        );
        let (w, wm) = (sol.wave_speeds(), mir.wave_speeds());
        assert_abs(wm.left_head, -w.right_head, 1e-13, "mirrored left head");
        assert_abs(wm.left_tail, -w.right_tail, 1e-13, "mirrored left tail");
        assert_abs(wm.right_tail, -w.left_tail, 1e-13, "mirrored right tail");
        assert_abs(wm.right_head, -w.left_head, 1e-13, "mirrored right head");
        for i in 0..=60 {
            let xi = -3.0 + 0.1 * f64::from(i) + 0.0123;
            let a = sol.sample(xi);
            let b = mirror(mir.sample(-xi));
            assert_rel(b.rho, a.rho, 1e-12, "mirrored sampled rho");
            assert_abs(b.v, a.v, 1e-12, "mirrored sampled v");
            assert_rel(b.p, a.p, 1e-12, "mirrored sampled p");
        }
    }

    #[test]
    fn colliding_streams_two_shocks() {
        let gamma = 1.4;
        let sol =
            RiemannSolution::solve(state(1.0, 1.0, 1.0), state(1.0, -1.0, 1.0), gamma).unwrap();
        assert_abs(sol.v_star(), 0.0, 1e-14, "v*");
        assert!(sol.p_star() > 1.0, "p* = {} must exceed 1", sol.p_star());
        assert_rel(
            sol.rho_star_left(),
            sol.rho_star_right(),
            1e-14,
            "rho* symmetric",
        );
        // Each shock decelerates the stream by 1: (p* − 1) sqrt(A/(p* + B)) = 1.
        let (a, b) = (2.0 / (gamma + 1.0), (gamma - 1.0) / (gamma + 1.0));
        let p = sol.p_star();
        assert_rel(
            (p - 1.0) * (a / (p + b)).sqrt(),
            1.0,
            1e-13,
            "shock jump in v",
        );
        let w = sol.wave_speeds();
        assert_eq!(w.left_head, w.left_tail);
        assert_eq!(w.right_head, w.right_tail);
        assert_abs(w.left_head, -w.right_head, 1e-14, "symmetric shock speeds");
        let star = sol.sample(0.0);
        assert_rankine_hugoniot(sol.left(), star, w.left_head, gamma);
        assert_rankine_hugoniot(star, sol.right(), w.right_head, gamma);
    }

    #[test]
    fn toro_test_5_two_shocks() {
        // Toro (2009) table 4.1 test 5 / table 4.3.
        let sol = RiemannSolution::solve(
            state(5.99924, 19.5975, 460.894),
            state(5.99242, -6.19633, 46.0950),
            1.4,
        )
        .unwrap();
        assert_rel(sol.p_star(), 1691.64, 1e-5, "p*");
        assert_rel(sol.v_star(), 8.68975, 1e-5, "v*");
        assert_rel(sol.rho_star_left(), 14.2823, 1e-5, "rho*_L");
        assert_rel(sol.rho_star_right(), 31.0426, 1e-5, "rho*_R");
        let w = sol.wave_speeds();
        assert!(sol.p_star() > sol.left().p && sol.p_star() > sol.right().p);
        let star_l = sol.sample(0.5 * (w.left_head + w.contact));
        let star_r = sol.sample(0.5 * (w.contact + w.right_head));
        assert_rankine_hugoniot(sol.left(), star_l, w.left_head, 1.4);
        assert_rankine_hugoniot(star_r, sol.right(), w.right_head, 1.4);
    }

    #[test]
    fn toro_tests_3_and_4_strong_waves() {
        // Toro (2009) table 4.3.
        let t3 =
            RiemannSolution::solve(state(1.0, 0.0, 1000.0), state(1.0, 0.0, 0.01), 1.4).unwrap();
        assert_rel(t3.p_star(), 460.894, 1e-5, "test 3 p*");
        assert_rel(t3.v_star(), 19.5975, 1e-5, "test 3 v*");
        assert_rel(t3.rho_star_left(), 0.57506, 1e-4, "test 3 rho*_L");
        assert_rel(t3.rho_star_right(), 5.99924, 1e-5, "test 3 rho*_R");
        let t4 =
            RiemannSolution::solve(state(1.0, 0.0, 0.01), state(1.0, 0.0, 100.0), 1.4).unwrap();
        assert_rel(t4.p_star(), 46.0950, 1e-5, "test 4 p*");
        assert_rel(t4.v_star(), -6.19633, 1e-5, "test 4 v*");
        assert_rel(t4.rho_star_left(), 5.99242, 1e-5, "test 4 rho*_L");
        assert_rel(t4.rho_star_right(), 0.57511, 1e-4, "test 4 rho*_R");
    }

    #[test]
    fn toro_test_2_two_rarefactions() {
        // Toro (2009) table 4.3: p* = 0.00189, u* = 0, rho*_L = rho*_R = 0.02185.
        let gamma = 1.4;
        let sol =
            RiemannSolution::solve(state(1.0, -2.0, 0.4), state(1.0, 2.0, 0.4), gamma).unwrap();
        assert_rel(sol.p_star(), 0.00189, 3e-3, "p*");
        assert_abs(sol.v_star(), 0.0, 1e-14, "v*");
        assert_rel(sol.rho_star_left(), 0.02185, 3e-4, "rho*_L");
        assert_rel(sol.rho_star_right(), 0.02185, 3e-4, "rho*_R");
        // The two-rarefaction relation is exact here: each fan brings its stream to rest.
        let c = (gamma * 0.4_f64).sqrt();
        let z = (gamma - 1.0) / (2.0 * gamma);
        let f = 2.0 * c / (gamma - 1.0) * ((sol.p_star() / 0.4).powf(z) - 1.0);
        assert_rel(f, -2.0, 1e-13, "rarefaction velocity jump");
        let w = sol.wave_speeds();
        assert!(w.left_head < w.left_tail && w.left_tail < w.contact);
        assert!(w.contact < w.right_tail && w.right_tail < w.right_head);
        // Isentropic fans: p/rho^gamma equals its initial value everywhere.
        for xi in [-2.5, -1.0, -0.1, 0.0, 0.1, 1.0, 2.5] {
            let s = sol.sample(xi);
            assert_rel(s.p / s.rho.powf(gamma), 0.4, 1e-12, "entropy");
        }
    }

    #[test]
    fn bad_input_is_rejected() {
        let good = state(1.0, 0.0, 1.0);
        let neg_rho = RiemannSolution::solve(state(-1.0, 0.0, 1.0), good, 1.4).unwrap_err();
        assert!(neg_rho.contains("density"), "{neg_rho}");
        let zero_p = RiemannSolution::solve(good, state(1.0, 0.0, 0.0), 1.4).unwrap_err();
        assert!(zero_p.contains("pressure"), "{zero_p}");
        let nan_v = RiemannSolution::solve(good, state(1.0, f64::NAN, 1.0), 1.4).unwrap_err();
        assert!(nan_v.contains("velocity"), "{nan_v}");
        let gamma_one = RiemannSolution::solve(good, good, 1.0).unwrap_err();
        assert!(gamma_one.contains("gamma"), "{gamma_one}");
        let vacuum =
            RiemannSolution::solve(state(1.0, -10.0, 1.0), state(1.0, 10.0, 1.0), 1.4).unwrap_err();
        assert!(vacuum.contains("vacuum"), "{vacuum}");
    }

    #[test]
    fn trivial_problem_is_uniform() {
        let s = state(2.0, 0.7, 3.0);
        let sol = RiemannSolution::solve(s, s, 5.0 / 3.0).unwrap();
        assert_rel(sol.p_star(), 3.0, 1e-13, "p*");
        assert_rel(sol.v_star(), 0.7, 1e-13, "v*");
        for xi in [-5.0, -1.0, 0.0, 0.7, 1.0, 5.0] {
            let q = sol.sample(xi);
            assert_rel(q.rho, 2.0, 1e-12, "rho");
            assert_rel(q.v, 0.7, 1e-12, "v");
            assert_rel(q.p, 3.0, 1e-12, "p");
        }
    }
}
