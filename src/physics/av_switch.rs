//! Artificial-viscosity switches: each particle's own α. Two are offered.
//!
//! **Morris & Monaghan (1997, J. Comput. Phys. 136, 41)**,
//! with the source term of Rosswog et al. (2000, A&A 360, 171): each particle carries its
//! own coefficient α_i, which compression raises towards α_max and which otherwise decays to
//! α_min on a few sound-crossing times of the kernel,
//!
//! dα_i/dt = −(α_i − α_min)/τ_i + max(−∇·v_i, 0) (α_max − α_i),  τ_i = h / (ℓ c_s,i),
//!
//! with ∇·v_i the trace of the velocity gradient of Eq. (10) and ℓ = `switch_decay` (0.1,
//! as Phantom's `avdecayconst`). The pair term of the viscosity then uses
//! α_ij = ½ (α_i + α_j) in place of the constant α (`[artificial_viscosity] alpha` is α_max).
//! A shock keeps α near α_max; smooth flow — sound waves of small amplitude, rarefactions,
//! the gas far from a blast, a disk's orbits — runs at α_min, where a constant α would
//! damp it.
//!
//! For frozen ∇·v and c_s over a step the equation is linear in α, so [`AvSwitch::advance`]
//! integrates it exactly: α relaxes exponentially to α_eq = (α_min/τ + S α_max)/(1/τ + S)
//! at the rate 1/τ + S (S = max(−∇·v, 0)), which keeps α within [α_min, α_max] for any Δt.
//! The integrator calls it once per step after the evaluation, with that evaluation's ∇·v.
//!
//! **Cullen & Dehnen (2010, MNRAS 408, 669)**, as Phantom runs it (without their limiter
//! for shear; `balsara` can be combined): the trigger is compression *growing*,
//! A = max(−d(∇·v)/dt, 0), measured from ∇·v of consecutive evaluations, which sees a shock
//! before it arrives and not the steady convergence of a smooth flow; α_loc =
//! α_max h² A / (h² A + c_s²) is taken at once where it exceeds α, else α decays towards it
//! on τ as above ([`AvSwitch::advance_cd`]).
//!
//! α_i is part of the particle state (`Particles::alpha`): checkpoints, migration and
//! resumes carry it. Particles start at α_max (the first steps' discontinuities need it);
//! particles added during a run (an L1 stream) start at 0 and are raised to α_min by their
//! first step.

use serde::{Deserialize, Serialize};

use crate::particles::Particles;

/// `[artificial_viscosity] switch`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SwitchKind {
    /// A constant α for every particle (the default).
    #[default]
    None,
    /// Morris & Monaghan (1997) with the Rosswog et al. (2000) source.
    MorrisMonaghan,
    /// Cullen & Dehnen (2010): α set by the rate at which compression grows.
    CullenDehnen,
}

/// The switch's constants: α_max, α_min and ℓ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AvSwitch {
    pub kind: SwitchKind,
    pub alpha_max: f64,
    pub alpha_min: f64,
    /// ℓ in the decay time τ = h / (ℓ c_s).
    pub decay: f64,
}

impl AvSwitch {
    /// The exact solution of the module's equation over `dt` for frozen ∇·v = `div_v`,
    /// sound speed `cs` and smoothing length `h`, from `alpha`; the result is clamped to
    /// [α_min, α_max] (a particle added at α = 0 starts from α_min).
    #[inline]
    pub fn advance(&self, alpha: f64, div_v: f64, cs: f64, h: f64, dt: f64) -> f64 {
        let alpha = alpha.clamp(self.alpha_min, self.alpha_max);
        let inv_tau = self.decay * cs / h;
        let source = (-div_v).max(0.0);
        let rate = inv_tau + source;
        if !(rate > 0.0) {
            return alpha;
        }
        let eq = (self.alpha_min * inv_tau + source * self.alpha_max) / rate;
        let next = eq + (alpha - eq) * (-rate * dt).exp();
        next.clamp(self.alpha_min, self.alpha_max)
    }

    /// Cullen & Dehnen's (2010) update over `dt` from `alpha`, with ∇·v = `div_old` at the
    /// step's start and `div_new` at its end: the local value
    /// α_loc = α_max h² A / (h² A + c_s²), A = max(−d(∇·v)/dt, 0), taken at once where it
    /// exceeds α (compression building up: a shock arriving), else α decays towards it as
    /// in Morris & Monaghan, exp(−dt/τ), τ = h/(ℓ c_s); clamped to [α_min, α_max].
    #[inline]
    pub fn advance_cd(
        &self,
        alpha: f64,
        (div_old, div_new): (f64, f64),
        cs: f64,
        h: f64,
        dt: f64,
    ) -> f64 {
        let alpha = alpha.clamp(self.alpha_min, self.alpha_max);
        if !(dt > 0.0) {
            return alpha;
        }
        let a = (-(div_new - div_old) / dt).max(0.0);
        let ha = h * h * a;
        let local = if ha > 0.0 {
            self.alpha_max * ha / (ha + cs * cs)
        } else {
            0.0
        };
        let next = if local >= alpha {
            local
        } else {
            local + (alpha - local) * (-self.decay * cs / h * dt).exp()
        };
        next.clamp(self.alpha_min, self.alpha_max)
    }

    /// Advances every particle's α over the step `dt` with the velocity gradients and sound
    /// speeds of the evaluation just done (and, for Cullen & Dehnen, ∇·v at the step's
    /// start, `div_old`).
    pub fn advance_all<const D: usize>(
        &self,
        p: &mut Particles<D>,
        div_old: &[f64],
        h: f64,
        dt: f64,
    ) {
        for i in 0..p.len() {
            let div = divergence_at(p, i);
            p.alpha[i] = match self.kind {
                SwitchKind::CullenDehnen => {
                    self.advance_cd(p.alpha[i], (div_old[i], div), p.cs[i], h, dt)
                }
                _ => self.advance(p.alpha[i], div, p.cs[i], h, dt),
            };
        }
    }

    /// ∇·v of every particle from its stored velocity gradient (the last evaluation's).
    pub fn divergence<const D: usize>(p: &Particles<D>) -> Vec<f64> {
        (0..p.len()).map(|i| divergence_at(p, i)).collect()
    }

    /// α_max for every particle: the state a run starts from.
    pub fn initialise<const D: usize>(&self, p: &mut Particles<D>) {
        p.alpha.iter_mut().for_each(|a| *a = self.alpha_max);
    }
}

/// ∇·v of particle `i`: the trace of its stored velocity gradient (Eq. 10).
#[inline]
fn divergence_at<const D: usize>(p: &Particles<D>, i: usize) -> f64 {
    (0..D).map(|a| p.vgrad[a][a][i]).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    const SW: AvSwitch = AvSwitch {
        kind: SwitchKind::MorrisMonaghan,
        alpha_max: 1.0,
        alpha_min: 0.1,
        decay: 0.1,
    };

    #[test]
    fn without_compression_alpha_decays_to_alpha_min_on_tau() {
        // τ = h/(ℓ c) = 0.5/(0.1 × 2) = 2.5: after one τ, α − α_min falls by e.
        let (cs, h) = (2.0, 0.5);
        let a = SW.advance(1.0, 0.0, cs, h, 2.5);
        assert!((a - (0.1 + 0.9 / std::f64::consts::E)).abs() < 1e-14, "{a}");
        // Expansion is no source either.
        assert_eq!(SW.advance(1.0, 5.0, cs, h, 2.5), a);
        // In many small steps the same as one long one (the update is exact).
        let mut b = 1.0;
        for _ in 0..1000 {
            b = SW.advance(b, 0.0, cs, h, 2.5e-3);
        }
        assert!((a - b).abs() < 1e-12, "{a} {b}");
        // Long after: α_min, never below.
        let late = SW.advance(1.0, 0.0, cs, h, 1e6);
        assert!((0.1..0.1 + 1e-15).contains(&late), "{late}");
    }

    #[test]
    fn compression_drives_alpha_to_its_equilibrium_below_alpha_max() {
        let (cs, h) = (1.0, 0.1);
        // 1/τ = 1; S = 9: α_eq = (0.1 + 9)/10 = 0.91, reached from α_min at the rate 10.
        let a = SW.advance(0.1, -9.0, cs, h, 0.1);
        let expect = 0.91 + (0.1 - 0.91) * (-1.0f64).exp();
        assert!((a - expect).abs() < 1e-14, "{a} {expect}");
        let late = SW.advance(0.1, -9.0, cs, h, 100.0);
        assert!((late - 0.91).abs() < 1e-14);
        // A strong shock (S ≫ 1/τ) takes α to α_max, not past it.
        assert!(SW.advance(0.1, -1e9, cs, h, 1.0) <= 1.0);
        assert!(SW.advance(0.1, -1e9, cs, h, 1.0) > 0.999_999);
    }

    #[test]
    fn cullen_dehnen_rises_at_once_with_growing_compression_and_decays_otherwise() {
        let cd = AvSwitch {
            kind: SwitchKind::CullenDehnen,
            alpha_min: 0.0,
            ..SW
        };
        let (cs, h, dt) = (1.0, 0.1, 0.01);
        // d(∇·v)/dt = −(−3 − 0)/0.01 → A = 300, h²A = 3: α_loc = 3/4 of α_max, at once.
        let a = cd.advance_cd(0.0, (0.0, -3.0), cs, h, dt);
        assert!((a - 0.75).abs() < 1e-14, "{a}");
        // Steady compression (∇·v constant) is no trigger: α decays on τ = h/(ℓ c) = 1.
        let b = cd.advance_cd(0.75, (-3.0, -3.0), cs, h, 1.0);
        assert!((b - 0.75 / std::f64::consts::E).abs() < 1e-14, "{b}");
        // Nor is compression easing off.
        assert_eq!(
            cd.advance_cd(0.5, (-3.0, -1.0), cs, h, 1.0),
            0.5 / std::f64::consts::E
        );
        // A local value below the current α does not pull it down faster than the decay.
        let c = cd.advance_cd(1.0, (0.0, -0.3), cs, h, 0.1);
        assert!(c < 1.0 && c > 0.9, "{c}");
        // α_max caps it, α_min floors it.
        assert!(cd.advance_cd(0.0, (0.0, -1e12), cs, h, dt) <= 1.0);
        let floored = AvSwitch {
            alpha_min: 0.1,
            ..cd
        };
        assert_eq!(floored.advance_cd(0.1, (0.0, 0.0), cs, h, 100.0), 0.1);
    }

    #[test]
    fn a_particle_added_at_zero_starts_from_alpha_min() {
        assert_eq!(SW.advance(0.0, 0.0, 1.0, 1.0, 0.0), 0.1);
        // Cold gas at rest (c_s = 0, no compression) keeps its α.
        assert_eq!(SW.advance(0.7, 0.0, 0.0, 1.0, 1.0), 0.7);
    }
}
