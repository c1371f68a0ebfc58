//! What an observer of a cataclysmic variable sees of the dissipated energy: the orbital
//! hump and the eclipse (paper, Section 4; exact-solutions.md 4b for the Roche geometry).
//! The light curve the run writes is the luminosity L = Σ mᵢ ε̇ᵢ, the same from every
//! direction; a real binary at inclination i shows the bright spot on the rim only while
//! the spot faces us — once per orbit, the orbital hump — and, at high i, the donor
//! passing in front of the disk. Pure geometry of the Roche binary; nothing here depends on
//! the solver.
//!
//! **The emission model.** Each particle's luminosity leaves through one of three surfaces,
//! each a Lambert (cosine-law) radiator normalised so that its flux averaged over all
//! directions is its luminosity (the "isotropic-equivalent" luminosity 4π d² F an observer
//! infers):
//! - disk gas (near-circular orbits) from the two faces of a flat disk: factor 2 |cos i|;
//! - bright-spot gas (the stream striking the disk) from the disk's rim, a surface whose
//!   outward normal is the cylindrical radius R̂ from the white dwarf: factor
//!   4 max(0, R̂ · ô), ô the unit vector towards the observer;
//! - free stream gas, isotropically: factor 1.
//!
//! With linear limb darkening (coefficient u: intensity ∝ 1 − u (1 − μ), μ the cosine
//! between the line of sight and the surface's normal) the faces' and the rim's factors
//! become μ (1 − u + u μ) times 6/(3 − u) and 12/(3 − u) — the same mean over all
//! directions, less light at grazing angles and more face-on; u = 0 (the default) is the
//! Lambert radiator above.
//!
//! A particle is eclipsed when the ray from it towards the observer passes through the
//! donor's Roche lobe (Φ < Φ_L1 on the donor's side of L1).
//!
//! **The rim's shadow.** A disk seen nearly edge-on hides part of its own face behind its
//! rim: the disk is vertically isothermal, so it flares, H(R) = c_s/Ω_K(R) ∝ R^{3/2}, and
//! its photosphere lies [`PHOTOSPHERE_SCALE_HEIGHTS`] scale heights above the midplane.
//! Face light from radius R leaves the photosphere at z = k H(R) (k that number) and is
//! hidden when its ray towards the observer is still below the photosphere where it crosses
//! the disk's edge R_rim: k H(R) + s* |cos i| < k H(R_rim), s* the ray's length to the edge.
//! Checking the edge alone is exact for this surface: along the ray the height of the
//! surface beneath it, H(R(s)), is convex in s (H convex and increasing in R, R(s) convex),
//! so its difference from the ray's straight rise is largest at one end — the start, where
//! it is 0, or the edge. Each particle's own sound speed sets the H of both ends.
//!
//! **Phase.** The simulation frame turns with the binary (accretor at the origin, donor at
//! (−1, 0, 0)); an observer fixed in space turns the other way in it. Orbital phase 0 is
//! the conjunction with the donor in front (the white dwarf's mid-eclipse), taken at t = 0:
//! at phase φ the observer lies at azimuth π − 2πφ, so a spot at azimuth ψ faces the
//! observer at phase φ = (π − ψ)/2π mod 1.

use std::f64::consts::{PI, TAU};

use crate::analysis::roche;

/// Height of the disk's photosphere in scale heights H = c_s/Ω_K: an optically thick
/// disk's surface lies a few H above its midplane (2–3 H for dwarf-nova disks in outburst,
/// e.g. Smak 1992); 2 here.
pub const PHOTOSPHERE_SCALE_HEIGHTS: f64 = 2.0;

/// Inclination assumed where a binary gives none: the median of randomly oriented orbits
/// (cos i uniform on [0, 1] puts half of them above i = 60°).
pub const DEFAULT_INCLINATION_DEG: f64 = 60.0;

/// Through which surface a particle's light leaves (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    /// The two faces of the disk.
    Face,
    /// The disk's rim, facing out from the white dwarf.
    Rim,
    /// No surface: the same in every direction.
    Isotropic,
}

/// An observer of the binary of mass ratio `q` at inclination `inclination` (radians; 0 is
/// pole-on, π/2 in the orbital plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer {
    sin_i: f64,
    cos_i: f64,
    /// The donor's lobe, and its farthest point from the donor (1 − d_L1).
    lobe: roche::DonorLobe,
    lobe_reach: f64,
    /// Linear limb-darkening coefficient u of the faces and the rim (0: Lambert).
    limb_darkening: f64,
    /// G M1 in code units (1/(1 + q)), for the disk's scale height.
    gm_accretor: f64,
}

/// Samples along the part of a line of sight that crosses the sphere bounding the donor's
/// lobe: steps of 2 (1 − d_L1)/128 ≈ 0.004 a at q = 0.1, below the smoothing length of any
/// run, so an eclipse contact is placed to within a fraction of a particle.
const RAY_SAMPLES: usize = 128;

impl Observer {
    pub fn new(q: f64, inclination: f64) -> Self {
        let lobe = roche::DonorLobe::new(q);
        Self {
            sin_i: inclination.sin(),
            cos_i: inclination.cos(),
            lobe,
            lobe_reach: 1.0 - lobe.d_l1,
            limb_darkening: 0.0,
            gm_accretor: 1.0 / (1.0 + q),
        }
    }

    /// The same observer seeing limb-darkened surfaces (coefficient `u` in [0, 1]).
    pub fn with_limb_darkening(self, u: f64) -> Self {
        Self {
            limb_darkening: u,
            ..self
        }
    }

    /// Lambert's factor `lambert` μ of a surface seen at cosine μ from its normal, limb
    /// darkened: `lambert` · 3/(3 − u) · μ (1 − u + u μ), which keeps the mean over the sky
    /// (∫₀¹ μ (1 − u + u μ) dμ = (3 − u)/6 against Lambert's 1/2).
    fn darkened(&self, mu: f64, lambert: f64) -> f64 {
        let u = self.limb_darkening;
        lambert * 3.0 / (3.0 - u) * mu * (1.0 - u + u * mu)
    }

    /// Unit vector towards the observer at orbital phase `phase`, in the simulation frame.
    pub fn direction(&self, phase: f64) -> [f64; 3] {
        let az = PI - TAU * phase;
        [self.sin_i * az.cos(), self.sin_i * az.sin(), self.cos_i]
    }

    /// Whether the donor's Roche lobe hides `x` from an observer in direction `o`.
    pub fn eclipsed(&self, x: [f64; 3], o: [f64; 3]) -> bool {
        // The lobe lies within `lobe_reach` of the donor (L1 is its farthest point): only a
        // ray passing that close, ahead of x, can cross it.
        let rel = [x[0] - roche::DONOR[0], x[1], x[2]];
        let along = -(rel[0] * o[0] + rel[1] * o[1] + rel[2] * o[2]);
        let miss2 = rel.iter().map(|c| c * c).sum::<f64>() - along * along;
        let reach2 = self.lobe_reach * self.lobe_reach;
        if miss2 >= reach2 {
            return false;
        }
        let half = (reach2 - miss2).sqrt();
        let (s0, s1) = ((along - half).max(0.0), along + half);
        if s1 <= 0.0 {
            return false;
        }
        (0..=RAY_SAMPLES).any(|k| {
            let s = s0 + (s1 - s0) * k as f64 / RAY_SAMPLES as f64;
            let p = [x[0] + s * o[0], x[1] + s * o[1], x[2] + s * o[2]];
            self.lobe.contains(p)
        })
    }

    /// The factor by which a particle at `x` emitting through `surface` appears brighter
    /// (> 1) or fainter than its luminosity to an observer in direction `o`; 0 when
    /// eclipsed.
    pub fn visibility(&self, x: [f64; 3], surface: Surface, o: [f64; 3]) -> f64 {
        let f = match surface {
            Surface::Face => self.darkened(self.cos_i.abs(), 2.0),
            Surface::Isotropic => 1.0,
            Surface::Rim => {
                let r = x[0].hypot(x[1]);
                if r == 0.0 {
                    0.0
                } else {
                    self.darkened(((x[0] * o[0] + x[1] * o[1]) / r).max(0.0), 4.0)
                }
            }
        };
        if f > 0.0 && self.eclipsed(x, o) {
            0.0
        } else {
            f
        }
    }

    /// Height of the photosphere above the midplane at cylindrical radius `r` of a disk with
    /// sound speed `cs`: k c_s/Ω_K(r) (k = [`PHOTOSPHERE_SCALE_HEIGHTS`]).
    pub fn photosphere(&self, cs: f64, r: f64) -> f64 {
        PHOTOSPHERE_SCALE_HEIGHTS * cs * (r * r * r / self.gm_accretor).sqrt()
    }

    /// Whether the rim of a disk reaching to `rim` hides the face light of disk gas at `x`
    /// (its cylindrical radius counts; sound speed `cs`) from an observer in direction `o`
    /// (module doc: the rim's shadow). Gas at or beyond the rim, and any seen pole-on, is
    /// never hidden.
    pub fn rim_hides(&self, x: [f64; 3], cs: f64, rim: f64, o: [f64; 3]) -> bool {
        let r2 = x[0] * x[0] + x[1] * x[1];
        let d2 = o[0] * o[0] + o[1] * o[1];
        if r2 >= rim * rim || d2 < 1e-24 {
            return false;
        }
        // The ray's horizontal track x + s ô_xy reaches R = rim at s*.
        let b = x[0] * o[0] + x[1] * o[1];
        let s = (-b + (b * b + d2 * (rim * rim - r2)).sqrt()) / d2;
        self.photosphere(cs, r2.sqrt()) + s * o[2].abs() < self.photosphere(cs, rim)
    }

    /// The phase at which a rim point at azimuth `psi` (radians, about the white dwarf)
    /// faces the observer: (π − ψ)/2π mod 1.
    pub fn facing_phase(psi: f64) -> f64 {
        ((PI - psi) / TAU).rem_euclid(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The white dwarf's eclipse at i = 90°: it lasts while the line of sight in the orbital
    /// plane cuts the donor's lobe, i.e. for observer azimuths within the lobe's angular
    /// half-width seen from the accretor. That half-width, computed independently from the
    /// lobe's outline (bisected equipotential, `roche::lobe_outline`), must match the
    /// eclipse's half-width from the ray test to the phase step used (1e-4), plus the ray's
    /// sampling (a contact placed within 0.004 a at a distance of ~1 a: ≤ 0.004 rad =
    /// 6.4e-4 in phase).
    #[test]
    fn white_dwarf_eclipse_width_matches_the_lobe_outline_edge_on() {
        for q in [0.1, 0.25] {
            let outline = roche::lobe_outline(q, true, roche::Plane::Orbital, 4000);
            let half_angle = outline
                .iter()
                .map(|p| (p[1] / -p[0]).atan())
                .fold(0.0_f64, f64::max);
            let expected = half_angle / TAU;
            let obs = Observer::new(q, PI / 2.0);
            let wd = [1e-9, 0.0, 0.0];
            let mut phase = 0.0;
            while obs.eclipsed(wd, obs.direction(phase)) {
                phase += 1e-4;
            }
            assert!(
                (phase - expected).abs() < 1e-4 + 6.4e-4,
                "q = {q}: eclipse half-width {phase} vs outline {expected}"
            );
            // Symmetric, and nothing at quadrature or opposition.
            assert!(obs.eclipsed(wd, obs.direction(1.0 - 0.9 * expected)));
            assert!(!obs.eclipsed(wd, obs.direction(0.25)));
            assert!(!obs.eclipsed(wd, obs.direction(0.5)));
        }
    }

    /// Pole-on nothing is eclipsed; at OY Car's i = 83.3° (Wood et al. 1989) the white dwarf
    /// is, and a point at the disk's far side (x = +0.3 a, behind the white dwarf as seen at
    /// phase 0) too, while at i = 65° the line of sight passes 0.47 a above the donor, over
    /// its lobe (volume radius 0.21 a at q = 0.1).
    #[test]
    fn eclipses_depend_on_the_inclination() {
        let q = 0.1;
        let wd = [0.0, 0.0, 0.0];
        assert!(!Observer::new(q, 0.0).eclipsed(wd, Observer::new(q, 0.0).direction(0.0)));
        let oy = Observer::new(q, 83.3_f64.to_radians());
        assert!(oy.eclipsed(wd, oy.direction(0.0)));
        assert!(oy.eclipsed([0.3, 0.0, 0.0], oy.direction(0.0)));
        assert!(!oy.eclipsed(wd, oy.direction(0.5)));
        let low = Observer::new(q, 65f64.to_radians());
        assert!(!low.eclipsed(wd, low.direction(0.0)));
    }

    /// Each surface's factor averages to 1 over all directions (the luminosity is what the
    /// observers see on average): a quadrature over the sphere to 1e-3.
    #[test]
    fn visibility_averages_to_one_over_the_sky() {
        // The factors without the eclipse (which removes only the directions through the
        // lobe), on a midpoint grid uniform in cos i and azimuth; with and without limb
        // darkening.
        let x = [0.2, 0.1, 0.0];
        for (u, surface) in [0.0, 0.6, 1.0]
            .into_iter()
            .flat_map(|u| [Surface::Face, Surface::Rim, Surface::Isotropic].map(|s| (u, s)))
        {
            let (n_mu, n_az) = (200, 200);
            let mut sum = 0.0;
            for a in 0..n_mu {
                let mu = -1.0 + (a as f64 + 0.5) * 2.0 / n_mu as f64;
                let inc = mu.acos();
                let obs = Observer::new(0.1, inc).with_limb_darkening(u);
                // Limb darkening written out for this test: I(μ) ∝ 1 − u (1 − μ), normalised
                // by its flux integral 2π ∫ I μ dμ = π (1 − u/3).
                let ld = |m: f64| m * (1.0 - u * (1.0 - m)) / (1.0 - u / 3.0);
                for b in 0..n_az {
                    let o = obs.direction((b as f64 + 0.5) / n_az as f64);
                    // Without the eclipse: the factor alone.
                    let f = match surface {
                        Surface::Face => 2.0 * ld(mu.abs()),
                        Surface::Isotropic => 1.0,
                        Surface::Rim => {
                            4.0 * ld(((x[0] * o[0] + x[1] * o[1]) / x[0].hypot(x[1])).max(0.0))
                        }
                    };
                    let v = obs.visibility(x, surface, o);
                    assert!((v - f).abs() < 1e-12 || v == 0.0, "{v} vs {f}");
                    sum += f;
                }
            }
            let mean = sum / (n_mu * n_az) as f64;
            assert!((mean - 1.0).abs() < 1e-3, "{surface:?}, u = {u}: {mean}");
        }
    }

    /// Limb darkening moves a face's light from grazing to face-on views: with u = 0.6 the
    /// pole-on factor is 2 · 3/2.4 = 2.5 (Lambert: 2), and at OY Car's i = 83.3° (μ = 0.117)
    /// it is 2.5 · 0.117 · 0.47 ≈ 0.137 against Lambert's 0.233 — 1.7 times fainter.
    #[test]
    fn limb_darkening_dims_the_grazing_view() {
        let x = [0.3, 0.0, 0.0];
        let face = |i: f64, u: f64| {
            let obs = Observer::new(0.1, i.to_radians()).with_limb_darkening(u);
            obs.visibility(x, Surface::Face, obs.direction(0.5))
        };
        assert!((face(0.0, 0.6) - 2.5).abs() < 1e-12);
        assert!((face(0.0, 0.0) - 2.0).abs() < 1e-12);
        let mu = 83.3f64.to_radians().cos();
        assert!((face(83.3, 0.0) - 2.0 * mu).abs() < 1e-12);
        let dark = face(83.3, 0.6);
        assert!((dark - 2.5 * mu * (0.4 + 0.6 * mu)).abs() < 1e-12);
        assert!(face(83.3, 0.0) / dark > 1.6, "{dark}");
    }

    /// The rim's shadow against a brute-force march along the ray: face light is hidden
    /// exactly when some point of its ray, before it leaves the disk, lies below the flared
    /// photosphere k c_s/Ω_K(R) — which also checks that testing the edge alone suffices.
    /// 4000 rays from random points and directions (deterministic seed), steps of 1/20000 of
    /// the ray; rays passing the edge within 1e-9 a of the photosphere are left out (the
    /// march cannot place those).
    #[test]
    fn the_rim_hides_what_a_march_along_the_ray_finds_under_the_surface() {
        let mut state = 0x9e3779b97f4a7c15_u64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (rim, cs) = (0.35, 0.05);
        let (mut hidden, mut tested) = (0, 0);
        while tested < 4000 {
            let inc = (80.0 + 10.0 * uniform()).to_radians();
            let obs = Observer::new(0.1, inc);
            let o = obs.direction(uniform());
            let (r, phi) = (rim * uniform().sqrt(), TAU * uniform());
            let x = [r * phi.cos(), r * phi.sin(), 0.0];
            let z0 = obs.photosphere(cs, r);
            let d2 = o[0] * o[0] + o[1] * o[1];
            let b = x[0] * o[0] + x[1] * o[1];
            let s_edge = (-b + (b * b + d2 * (rim * rim - r * r)).sqrt()) / d2;
            if (z0 + s_edge * o[2] - obs.photosphere(cs, rim)).abs() < 1e-9 {
                continue;
            }
            let n = 20000;
            let under = (1..=n).any(|k| {
                let s = s_edge * k as f64 / n as f64;
                let rr = (x[0] + s * o[0]).hypot(x[1] + s * o[1]);
                z0 + s * o[2] < obs.photosphere(cs, rr) - 1e-12
            });
            let h = obs.rim_hides(x, cs, rim, o);
            assert_eq!(h, under, "x = {x:?}, i = {inc}, o = {o:?}");
            hidden += h as usize;
            tested += 1;
        }
        // Both outcomes occur (the test is not vacuous).
        assert!(hidden > 100 && hidden < 3900, "{hidden} of 4000 hidden");
        // Pole-on nothing is hidden; beyond the rim nothing; edge-on all of the face inside.
        let pole = Observer::new(0.1, 0.0);
        assert!(!pole.rim_hides([0.1, 0.0, 0.0], cs, rim, pole.direction(0.3)));
        let edge = Observer::new(0.1, PI / 2.0);
        assert!(!edge.rim_hides([0.36, 0.0, 0.0], cs, rim, edge.direction(0.5)));
        assert!(edge.rim_hides([-0.3, 0.0, 0.0], cs, rim, edge.direction(0.5)));
        assert!(edge.rim_hides([0.3, 0.0, 0.0], cs, rim, edge.direction(0.5)));
    }

    /// A point on the line of sight at distance d inside the rim is hidden while
    /// d cot i < k c_s (Ω_K(R_rim)⁻¹ − Ω_K(R_rim − d)⁻¹): at i = 86° (cot i = 0.0699),
    /// c_s = 0.05, R_rim = 0.35 a, q = 0.1 that bound is d = 0.2867 a (bisected here from the
    /// closed form, independently of `rim_hides`). Near the rim the photosphere rises at
    /// 1.5 k H/R = 0.093 (5.3°), so below i = 84.7° (cot i > 0.093) nothing is hidden.
    #[test]
    fn the_shadow_reaches_as_far_as_the_closed_form_says() {
        let (q, cs, rim) = (0.1, 0.05, 0.35);
        let inc = 86_f64.to_radians();
        let obs = Observer::new(q, inc);
        let h = |r: f64| 2.0 * cs * (r * r * r * (1.0 + q)).sqrt();
        let gap = |d: f64| d / inc.tan() - (h(rim) - h(rim - d));
        let (mut lo, mut hi) = (1e-6, rim);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if gap(mid) < 0.0 { lo = mid } else { hi = mid }
        }
        assert!((lo - 0.2867).abs() < 5e-4, "{lo}");
        // The observer at phase 0.5 looks along +x: the near rim is at x = +rim.
        let o = obs.direction(0.5);
        assert!((o[0] - inc.sin()).abs() < 1e-12);
        assert!(obs.rim_hides([rim - 0.99 * lo, 0.0, 0.0], cs, rim, o));
        assert!(!obs.rim_hides([rim - 1.01 * lo, 0.0, 0.0], cs, rim, o));
        let low = Observer::new(q, 84.5_f64.to_radians());
        let o = low.direction(0.5);
        assert!((1..100).all(|k| !low.rim_hides([rim * k as f64 / 100.0, 0.0, 0.0], cs, rim, o)));
    }

    #[test]
    fn a_rim_point_faces_the_observer_at_its_phase() {
        let obs = Observer::new(0.1, 80f64.to_radians());
        let psi = 225f64.to_radians();
        let phase = Observer::facing_phase(psi);
        assert!((phase - 0.875).abs() < 1e-12);
        let x = [0.3 * psi.cos(), 0.3 * psi.sin(), 0.0];
        let best = (0..1000)
            .map(|k| k as f64 / 1000.0)
            .max_by(|a, b| {
                let f = |p: f64| obs.visibility(x, Surface::Rim, obs.direction(p));
                f(*a).total_cmp(&f(*b))
            })
            .unwrap();
        assert!((best - phase).abs() < 1.5e-3, "{best} vs {phase}");
    }
}
