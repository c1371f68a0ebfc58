//! Artificial viscosity for shocks: Monaghan's (1997) signal-velocity form, with an optional
//! Balsara (1995) switch, and optionally acting on the velocity relative to circular orbits
//! about the central mass (for disks). Off (α = β = 0) by default; shock problems turn it on.
//! Also the artificial conductivity of the energy equation (Price 2008), off by default, and
//! the choice of a per-particle α (the Morris & Monaghan switch, `physics::av_switch`).

use serde::{Deserialize, Serialize};

use crate::lanes::Real;
use crate::physics::av_switch::{AvSwitch, SwitchKind};

/// Π_ij = −α v_sig w_ij / (ρ_i + ρ_j) for approaching pairs (w_ij = v_ij·r̂_ij < 0), with
/// v_sig = c_i + c_j − β w_ij; zero for receding pairs. (This is Monaghan's −(α/2) v_sig w / ρ̄.)
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ArtificialViscosity {
    pub alpha: f64,
    pub beta: f64,
    /// Multiply Π_ij by the mean Balsara factor |∇·v| / (|∇·v| + |∇×v| + 10⁻⁴ c/h).
    pub balsara: bool,
    /// Measure the approach w_ij with the velocities relative to the circular orbit about the
    /// central mass at each particle's position, v − v_c(x) (needs `[gravity]`).
    ///
    /// A Keplerian disk shears: half its neighbour pairs approach, and the usual Π_ij turns
    /// that shear into an effective viscosity α_SS ≈ 0.06 α h/H that spreads the disk
    /// (Meru & Bate 2012), while with α = 0 the particle noise that shear creates is never
    /// damped and grows from the disk's edges (the SPH pressure force's zeroth-order error
    /// feeds it; Raskin & Owen 2016 find the same). Measured in the frame of the orbits, the
    /// shear of a circular flow is no approach at all: Π_ij acts only on departures from
    /// circular orbits (epicycles, noise, shocks), in the spirit of Cartwright & Stamatellos
    /// (2010, A&A 516, A99), who switch AV on only where neighbours are not on Keplerian
    /// orbits about the same point. Π_ij stays symmetric in i, j and along r_ij, so linear
    /// and angular momentum are conserved as before; the pair's heating ½ Π_ij v_ij·∇_i W_ij
    /// uses the true velocities, so total energy is conserved exactly too.
    pub orbital: bool,
    /// Artificial conductivity α_u (Price 2008): du_i/dt += Σ_j m_j α_u v_sig,u (u_i − u_j)
    /// r̂_ij·∇_i W_ij / ρ̄_ij with v_sig,u = √(|p_i − p_j| / ρ̄_ij), which smooths u where the
    /// pressure jumps (shocks) but not across a contact in pressure balance, where it
    /// removes the pressure blip. 0 (off) by default; ignored for gas without an energy
    /// equation.
    pub conductivity: f64,
    /// The conductivity's signal speed: "pressure" (default, v_sig,u = √(|p_i − p_j| / ρ̄_ij),
    /// Price 2008) or "velocity" (v_sig,u = |v_ij·r̂_ij|, Wadsley et al. 2008; Price et al.
    /// 2018): the latter conducts only where the gas moves relative to itself, so it leaves
    /// a contact at rest alone — the choice for the pressure–energy formulation
    /// (`[hydro] scheme`), whose smooth p̄ needs no conduction there, while the residual
    /// noise in p̄ would drive the pressure signal across the contact's jump in u.
    pub conductivity_signal: ConductivitySignal,
    /// "none" (a constant α, the default), "morris_monaghan" or "cullen_dehnen": each
    /// particle's own α_i, raised by compression (Morris & Monaghan) or by compression
    /// setting in (Cullen & Dehnen) towards `alpha` (then α_max), and decaying to
    /// `alpha_min` elsewhere (`physics::av_switch`).
    pub switch: SwitchKind,
    /// The switch's floor α_min (default 0.1, Morris & Monaghan's value; only with a
    /// switch).
    pub alpha_min: Option<f64>,
    /// The switch's decay constant ℓ: α_i − α_min decays on τ = h / (ℓ c_s) (default 0.1;
    /// only with a switch).
    pub switch_decay: Option<f64>,
}

/// The artificial conductivity's signal speed (`artificial_viscosity.conductivity_signal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConductivitySignal {
    /// √(|p_i − p_j| / ρ̄_ij) (Price 2008).
    #[default]
    Pressure,
    /// |v_ij · r̂_ij|.
    Velocity,
}

impl ConductivitySignal {
    /// v_sig,u of a pair with pressures `p_i`, `p_j`, mean density `rho_mean`, and
    /// v_ij·r_ij = `vdotr` at separation `r`.
    #[inline]
    pub fn speed(self, p_i: f64, p_j: f64, rho_mean: f64, vdotr: f64, r: f64) -> f64 {
        match self {
            ConductivitySignal::Pressure => ((p_i - p_j).abs() / rho_mean).sqrt(),
            ConductivitySignal::Velocity => vdotr.abs() / r,
        }
    }
}

/// The largest α, β or α_u accepted. Shock problems use α ≈ 1, β ≈ 2 (switches go up to
/// α ≈ 2–3); a hundred times that leaves only time steps too short to run (and at ~10¹⁸ the
/// forces overflow to infinity).
pub const MAX_COEFFICIENT: f64 = 100.0;

/// α_min of a switch unless set (Morris & Monaghan 1997).
pub const DEFAULT_ALPHA_MIN: f64 = 0.1;
/// ℓ of a switch's decay time h/(ℓ c_s) unless set (Phantom's `avdecayconst`).
pub const DEFAULT_SWITCH_DECAY: f64 = 0.1;

impl Default for ArtificialViscosity {
    fn default() -> Self {
        Self {
            alpha: 0.0,
            beta: 0.0,
            balsara: false,
            orbital: false,
            conductivity: 0.0,
            conductivity_signal: ConductivitySignal::Pressure,
            switch: SwitchKind::None,
            alpha_min: None,
            switch_decay: None,
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
            orbital: false,
            conductivity: 0.0,
            conductivity_signal: ConductivitySignal::Pressure,
            switch: SwitchKind::None,
            alpha_min: None,
            switch_decay: None,
        }
    }

    /// Each coefficient must lie in [0, [`MAX_COEFFICIENT`]].
    pub fn validate(&self) -> Result<(), String> {
        for (key, v) in [
            ("alpha", self.alpha),
            ("beta", self.beta),
            ("conductivity", self.conductivity),
        ] {
            if !((0.0..=MAX_COEFFICIENT).contains(&v)) {
                return Err(format!(
                    "artificial_viscosity.{key} must lie between 0 and {MAX_COEFFICIENT}, got {v:?}"
                ));
            }
        }
        if self.switch == SwitchKind::None {
            for (key, v) in [
                ("alpha_min", self.alpha_min),
                ("switch_decay", self.switch_decay),
            ] {
                if v.is_some() {
                    return Err(format!(
                        "artificial_viscosity.{key} must go with a switch: set artificial_viscosity.switch (morris_monaghan or cullen_dehnen) or remove it"
                    ));
                }
            }
        } else {
            if !(self.alpha > 0.0) {
                return Err(format!(
                    "artificial_viscosity.alpha must be > 0 with a switch (it is α_max), got {:?}",
                    self.alpha
                ));
            }
            let alpha_min = self.alpha_min.unwrap_or(DEFAULT_ALPHA_MIN);
            if !((0.0..=self.alpha).contains(&alpha_min)) {
                return Err(format!(
                    "artificial_viscosity.alpha_min must lie between 0 and alpha = {}, got {alpha_min:?}",
                    self.alpha
                ));
            }
            // ℓ sets τ = h/(ℓ c_s): ℓ ≳ 10 would follow the gas faster than a time step
            // resolves; ℓ = 0 would never decay.
            let decay = self.switch_decay.unwrap_or(DEFAULT_SWITCH_DECAY);
            if !(decay > 0.0 && decay <= 10.0) {
                return Err(format!(
                    "artificial_viscosity.switch_decay must lie in (0, 10], got {decay:?}"
                ));
            }
        }
        Ok(())
    }

    /// The per-particle switch, when one is chosen.
    pub fn switch(&self) -> Option<AvSwitch> {
        match self.switch {
            SwitchKind::None => None,
            kind => Some(AvSwitch {
                kind,
                alpha_max: self.alpha,
                alpha_min: self.alpha_min.unwrap_or(DEFAULT_ALPHA_MIN),
                decay: self.switch_decay.unwrap_or(DEFAULT_SWITCH_DECAY),
            }),
        }
    }

    /// A particle's factor on the pair's α from its own α_i: α_i/α_max with the switch (so
    /// that α_max × the pair's mean factor is ½ (α_i + α_j)), 1 with a constant α.
    #[inline]
    pub fn alpha_factor(&self, alpha_i: f64) -> f64 {
        if self.switch == SwitchKind::None || !(self.alpha > 0.0) {
            1.0
        } else {
            alpha_i / self.alpha
        }
    }

    /// (Π_ij, v_sig,ij) for a pair with v_ij·r_ij = `vdotr` at separation `r`.
    /// `scale` is the pair's mean of the particles' factors on α: Balsara's factor times
    /// α_i/α_max with the switch (1 with neither), so that α_ij = ½ (α_i + α_j).
    /// Over [`Real`]: one pair (`f64`) or several in lanes, the same to the bit.
    #[inline(always)]
    pub fn pi<T: Real>(
        &self,
        vdotr: T,
        r: T,
        (ci, cj): (T, T),
        (rhoi, rhoj): (T, T),
        scale: T,
    ) -> (T, T) {
        let w = r.where_positive(vdotr / r);
        // A selection rather than `f64::min` (the same for every w, NaN included: both
        // give 0) and Π computed for every pair, then selected: pairs approach at random,
        // and a branch on it is mispredicted about every other pair.
        let approach = w.where_negative(w);
        let vsig = ci + cj - T::splat(self.beta.max(1.0)) * approach;
        let vsig_av = ci + cj - T::splat(self.beta) * approach;
        let pi = T::splat(-self.alpha) * vsig_av * approach / (rhoi + rhoj) * scale;
        (
            if self.alpha > 0.0 {
                approach.where_negative(pi)
            } else {
                T::splat(0.0)
            },
            vsig,
        )
    }
}

/// The velocity the artificial viscosity measures at position `x` with velocity `v`: `v`
/// itself, or (with `orbital` and a central mass) v − v_c, with v_c the circular velocity
/// √(R g_R) in the azimuthal direction about the z axis (2D: the plane's normal).
#[inline]
pub fn av_velocity<const D: usize>(
    av: &ArtificialViscosity,
    gravity: Option<&crate::physics::gravity::PointMass>,
    x: &[f64; D],
    v: [f64; D],
) -> [f64; D] {
    match gravity {
        Some(g) if av.orbital && D >= 2 => {
            let a = g.acceleration(x);
            let r = x[0].hypot(x[1]);
            if r == 0.0 {
                return v;
            }
            // g_R = −(x a_x + y a_y)/R; v_c = √(R g_R) φ̂, φ̂ = (−y, x)/R.
            let g_r = -(x[0] * a[0] + x[1] * a[1]) / r;
            let vc = (r * g_r).max(0.0).sqrt() / r;
            let mut out = v;
            out[0] += vc * x[1];
            out[1] -= vc * x[0];
            out
        }
        _ => v,
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
    fn orbital_frame_sees_no_approach_in_keplerian_shear() {
        // Two particles on circular Keplerian orbits (GM = 1) at R = 1 and 1.05, the inner one
        // 0.04 behind in azimuth: it catches up, so the shear makes them approach in the inertial frame (Π > 0), but relative
        // to their circular orbits both are at rest (Π = 0). An epicyclic radial kick is
        // still seen in full.
        let g = crate::physics::gravity::PointMass {
            gm: 1.0,
            softening: 0.0,
            accretion_radius: None,
        };
        let at = |r: f64, phi: f64, kick: f64| -> ([f64; 2], [f64; 2]) {
            let (s, c) = phi.sin_cos();
            let v = r.powf(-0.5);
            ([r * c, r * s], [-v * s + kick * c, v * c + kick * s])
        };
        let (xi, vi) = at(1.0, 0.0, 0.0);
        let (xj, vj) = at(1.05, 0.04, 0.0);
        let dx = [xi[0] - xj[0], xi[1] - xj[1]];
        let r = dx[0].hypot(dx[1]);
        let approach = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]) * dx[0] + (a[1] - b[1]) * dx[1];
        let mut av = ArtificialViscosity::for_shocks();
        assert!(
            approach(vi, vj) < 0.0,
            "the shear closes the pair in the inertial frame"
        );
        assert!(av.pi(approach(vi, vj), r, (0.1, 0.1), (1.0, 1.0), 1.0).0 > 0.0);
        av.orbital = true;
        let (wi, wj) = (
            av_velocity(&av, Some(&g), &xi, vi),
            av_velocity(&av, Some(&g), &xj, vj),
        );
        assert!(
            wi.iter().chain(&wj).all(|c| c.abs() < 1e-15),
            "{wi:?} {wj:?}"
        );
        // Round-off only: the inertial frame's Π is ~10⁻³.
        let inertial = av.pi(approach(vi, vj), r, (0.1, 0.1), (1.0, 1.0), 1.0).0;
        let orbital = av.pi(approach(wi, wj), r, (0.1, 0.1), (1.0, 1.0), 1.0).0;
        assert!(orbital < 1e-12 * inertial, "{orbital} against {inertial}");
        // A radial kick of j (an epicycle) is what the orbital frame sees, in full.
        let (_, vk) = at(1.05, 0.04, -0.05);
        let wk = av_velocity(&av, Some(&g), &xj, vk);
        let (s, c) = 0.04f64.sin_cos();
        assert!((wk[0] + 0.05 * c).abs() < 1e-15 && (wk[1] + 0.05 * s).abs() < 1e-15);
        assert!(av.pi(approach(wi, wk), r, (0.1, 0.1), (1.0, 1.0), 1.0).0 > 0.0);
        // Without a central mass the option changes nothing.
        assert_eq!(av_velocity(&av, None, &xi, vi), vi);
    }

    #[test]
    fn balsara_is_one_in_compression_zero_in_shear() {
        let compress = [[-1.0, 0.0], [0.0, -1.0]];
        let shear = [[0.0, 1.0], [0.0, 0.0]];
        assert!(balsara_factor(&compress, 1.0, 1.0) > 0.999);
        assert!(balsara_factor(&shear, 1.0, 1.0) < 1e-3);
    }
}
