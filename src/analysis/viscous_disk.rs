//! The reference a viscous disk is measured against when ν is not constant: the
//! axisymmetric thin-disk diffusion equation for a disk whose specific angular momentum
//! ℓ(R) = R² Ω(R) does not change in time (Lynden-Bell & Pringle 1974; Pringle 1981, Section 2):
//!
//! ∂Σ/∂t = −(1/R) ∂/∂R [ (1/ℓ′) ∂/∂R (ν Σ R³ Ω′) ],   R³ Ω′ = R ℓ′ − 2ℓ,
//!
//! which for Keplerian rotation, ℓ = √(GM R), is the familiar
//! ∂Σ/∂t = (3/R) ∂/∂R [ R^(1/2) ∂/∂R (ν Σ R^(1/2)) ]. It is integrated numerically from a
//! given Σ(R, 0) on a fine uniform grid (explicit, conservative fluxes between cells). With
//! constant ν and Keplerian rotation it reproduces the ring's exact solution
//! (`analysis::ring`), which the unit test checks. A pressure-supported disk turns slower
//! than Keplerian where Σ falls outwards and faster where it rises (its edges), which changes
//! both the shear that ν acts on and how far a torque moves the gas: [`Rotation::from_fn`]
//! takes that rotation curve.

/// The disk's rotation on the grid: ℓ′ = dℓ/dR on the cell faces, and the shear factor
/// R³ Ω′ = R ℓ′ − 2ℓ at the cell centres (the viscous torque is 2π ν Σ R³ Ω′).
#[derive(Clone, Debug)]
pub struct Rotation {
    shear: Vec<f64>,
    dl_face: Vec<f64>,
}

impl Rotation {
    /// Keplerian rotation about a mass with G M = `gm` > 0: ℓ = √(GM R).
    pub fn keplerian(r: &[f64], gm: f64) -> Self {
        Self::from_fn(r, |x| (gm * x).sqrt()).expect("Keplerian ℓ rises outwards")
    }

    /// The rotation curve ℓ(R), sampled on the grid `r` with centred differences of a
    /// quarter cell. It must rise outwards (a Rayleigh-stable disk): otherwise the error
    /// names the first radius where it does not.
    pub fn from_fn(r: &[f64], ell: impl Fn(f64) -> f64) -> Result<Self, String> {
        let dr = r[1] - r[0];
        let eps = 0.25 * dr;
        let slope = |x: f64| (ell(x + eps) - ell(x - eps)) / (2.0 * eps);
        let shear = r.iter().map(|&x| x * slope(x) - 2.0 * ell(x)).collect();
        let dl_face: Vec<f64> = r
            .windows(2)
            .map(|w| (ell(w[1]) - ell(w[0])) / (w[1] - w[0]))
            .collect();
        if let Some(k) = dl_face.iter().position(|&d| !(d > 0.0)) {
            return Err(format!(
                "the specific angular momentum R²Ω does not rise outwards at R = {:.4} \
                 (Rayleigh-unstable rotation)",
                0.5 * (r[k] + r[k + 1])
            ));
        }
        Ok(Self { shear, dl_face })
    }
}

/// Σ(R) on a uniform grid of cell centres `r` (spacing `r[1] − r[0]`), evolved for a time
/// `t` with viscosity `nu(R)` in a disk turning as `rotation`. No mass crosses the grid's
/// ends; with `sink = Some(r_s)` the cells inside r_s are emptied after every step (an
/// accretion radius), and the removed mass is returned beside Σ.
pub fn evolve(
    r: &[f64],
    sigma0: &[f64],
    nu: impl Fn(f64) -> f64,
    rotation: &Rotation,
    t: f64,
    sink: Option<f64>,
) -> (Vec<f64>, f64) {
    let n = r.len();
    assert!(n >= 3 && sigma0.len() == n, "grid and Σ must match");
    assert!(
        rotation.shear.len() == n,
        "the rotation must be sampled on this grid"
    );
    let dr = r[1] - r[0];
    let nu_c: Vec<f64> = r.iter().map(|&x| nu(x)).collect();
    let face: Vec<f64> = (0..n - 1).map(|k| 0.5 * (r[k] + r[k + 1])).collect();
    // Explicit stability: Σ diffuses with the coefficient ν |R³ Ω′| / (R ℓ′) (3ν when
    // Keplerian); a quarter of the limit.
    let diffusivity = (0..n - 1)
        .map(|k| {
            let nu_f = nu_c[k].max(nu_c[k + 1]);
            let shear = rotation.shear[k].abs().max(rotation.shear[k + 1].abs());
            nu_f * shear / (face[k] * rotation.dl_face[k])
        })
        .fold(0.0, f64::max);
    let steps = ((t * 4.0 * diffusivity / (dr * dr)).ceil() as usize).max(1);
    let dt = t / steps as f64;
    let mut s = sigma0.to_vec();
    let mut g = vec![0.0; n];
    let mut flux = vec![0.0; n - 1];
    let mut accreted = 0.0;
    let cell_mass = |s: &[f64], k: usize| std::f64::consts::TAU * r[k] * dr * s[k];
    for _ in 0..steps {
        // The torque 2π ν Σ R³ Ω′ at the cell centres.
        for k in 0..n {
            g[k] = std::f64::consts::TAU * nu_c[k] * s[k] * rotation.shear[k];
        }
        // Mass flux inwards through each face: −2π R Σ v_R = −(∂G/∂R) / ℓ′.
        for k in 0..n - 1 {
            flux[k] = -(g[k + 1] - g[k]) / dr / rotation.dl_face[k];
        }
        for k in 0..n {
            let inflow =
                if k + 1 < n { flux[k] } else { 0.0 } - if k > 0 { flux[k - 1] } else { 0.0 };
            s[k] += dt * inflow / (std::f64::consts::TAU * r[k] * dr);
        }
        if let Some(rs) = sink {
            for k in 0..n {
                if r[k] < rs && s[k] != 0.0 {
                    accreted += cell_mass(&s, k);
                    s[k] = 0.0;
                }
            }
        }
    }
    (s, accreted)
}

/// The radii enclosing the fractions `q` of the mass of Σ on the grid `r` (linear within a
/// cell).
pub fn mass_quantiles(r: &[f64], sigma: &[f64], q: &[f64]) -> Vec<f64> {
    let dr = r[1] - r[0];
    let masses: Vec<f64> = r
        .iter()
        .zip(sigma)
        .map(|(&x, &s)| std::f64::consts::TAU * x * dr * s)
        .collect();
    let total: f64 = masses.iter().sum();
    q.iter()
        .map(|&f| {
            let mut acc = 0.0;
            for (k, &m) in masses.iter().enumerate() {
                if acc + m >= f * total && m > 0.0 {
                    return r[k] - 0.5 * dr + dr * (f * total - acc) / m;
                }
                acc += m;
            }
            r[r.len() - 1]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::ring::SpreadingRing;

    #[test]
    fn constant_viscosity_reproduces_the_exact_ring() {
        // The ring of problems/ring.toml: R0 = 1, ν = 1e-3, from τ = 0.016 to 0.064
        // (τ = 12 ν t / R0²). 2000 cells of 1.25e-3 (the ring's width at τ0 is ≈ 0.13):
        // second-order fluxes, so the L1 difference is ≪ 1%; measured 2e-4.
        let nu = 1e-3;
        let ring = SpreadingRing {
            mass: 1.0,
            r0: 1.0,
            nu,
        };
        let (tau0, tau1) = (0.016, 0.064);
        let t = |tau: f64| ring.time(tau);
        let r: Vec<f64> = (0..2000).map(|k| (k as f64 + 0.5) * 1.25e-3).collect();
        let s0: Vec<f64> = r.iter().map(|&x| ring.sigma(x, tau0)).collect();
        let kepler = Rotation::keplerian(&r, 1.0);
        let (s1, accreted) = evolve(&r, &s0, |_| nu, &kepler, t(tau1) - t(tau0), None);
        assert_eq!(accreted, 0.0);
        let (mut num, mut den) = (0.0, 0.0);
        for (k, &x) in r.iter().enumerate() {
            let exact = ring.sigma(x, tau1);
            num += x * (s1[k] - exact).abs();
            den += x * exact;
        }
        let l1 = num / den;
        assert!(l1 < 5e-3, "L1 {l1}");
        // Mass is conserved by the flux form to round-off.
        let mass = |s: &[f64]| r.iter().zip(s).map(|(x, s)| x * s).sum::<f64>();
        assert!((mass(&s1) / mass(&s0) - 1.0).abs() < 1e-12);
    }

    /// A narrow Gaussian ring at R = 1 on 800 cells from R = 0.2 to 2.2: (grid, Σ).
    fn narrow_ring() -> (Vec<f64>, Vec<f64>) {
        let r: Vec<f64> = (0..800).map(|k| 0.2 + (k as f64 + 0.5) * 2.5e-3).collect();
        let s = r
            .iter()
            .map(|&x| (-(x - 1.0f64).powi(2) / 0.005).exp())
            .collect();
        (r, s)
    }

    /// ℓ(R) of a ring turning faster than Keplerian inside R = 1 and slower outside, by up
    /// to 2% (ℓ′ > 0 still), as a pressure maximum does.
    fn pressure_supported_ell(x: f64) -> f64 {
        x.sqrt() * (1.0 - 0.02 * ((x - 1.0) / 0.1).tanh())
    }

    /// ∫ Σ f(R) R dR on the grid (up to the factor 2π dR).
    fn moment(r: &[f64], s: &[f64], f: impl Fn(f64) -> f64) -> f64 {
        r.iter().zip(s).map(|(&x, s)| x * s * f(x)).sum()
    }

    fn rms_width(r: &[f64], s: &[f64]) -> f64 {
        (moment(r, s, |x| (x - 1.0).powi(2)) / moment(r, s, |_| 1.0)).sqrt()
    }

    /// Guards the non-Keplerian form: the torque flux and the mass flux are built from the
    /// same ℓ′, so the disk's angular momentum Σ m ℓ changes only by the torque at the
    /// grid's ends (zero where Σ is), to round-off, whatever the rotation curve.
    #[test]
    fn a_pressure_supported_ring_conserves_mass_and_angular_momentum() {
        let (r, s0) = narrow_ring();
        let rot = Rotation::from_fn(&r, pressure_supported_ell).unwrap();
        let (s1, _) = evolve(&r, &s0, |_| 1e-3, &rot, 1.0, None);
        let (m0, m1) = (moment(&r, &s0, |_| 1.0), moment(&r, &s1, |_| 1.0));
        let (j0, j1) = (
            moment(&r, &s0, pressure_supported_ell),
            moment(&r, &s1, pressure_supported_ell),
        );
        assert!((m1 / m0 - 1.0).abs() < 1e-12, "mass {m0} → {m1}");
        assert!(
            (j1 / j0 - 1.0).abs() < 1e-12,
            "angular momentum {j0} → {j1}"
        );
        // It spread: the rms width grew by more than 10%.
        let (w0, w1) = (rms_width(&r, &s0), rms_width(&r, &s1));
        assert!(w1 > 1.1 * w0, "{w0} → {w1}");
    }

    /// Guards the pressure-supported reference of `problems/disk3d.toml`: a steeper fall of
    /// Ω (a ring's outer side turning slower than Keplerian) shears more, so the same ν
    /// spreads the ring further than with Keplerian rotation.
    #[test]
    fn sub_keplerian_outer_side_spreads_a_ring_faster() {
        let (r, s0) = narrow_ring();
        let kepler = Rotation::keplerian(&r, 1.0);
        let steeper = Rotation::from_fn(&r, pressure_supported_ell).unwrap();
        let (a, _) = evolve(&r, &s0, |_| 1e-3, &kepler, 5.0, None);
        let (b, _) = evolve(&r, &s0, |_| 1e-3, &steeper, 5.0, None);
        let (wa, wb) = (rms_width(&r, &a), rms_width(&r, &b));
        assert!(wb > wa, "{wb} vs {wa}");
    }

    #[test]
    fn a_rotation_curve_falling_outwards_is_an_error() {
        let (r, _) = narrow_ring();
        let err = Rotation::from_fn(&r, |x| x.sqrt() * (1.0 - 0.2 * ((x - 1.0) / 0.1).tanh()))
            .unwrap_err();
        // ℓ′ = ℓ/2R − 2√R sech²((R − 1)/0.1) first turns negative at R ≈ 0.885.
        assert!(err.contains("R = 0.88"), "{err}");
    }

    #[test]
    fn sink_takes_the_mass_that_reaches_it() {
        let r: Vec<f64> = (0..400).map(|k| (k as f64 + 0.5) * 5e-3).collect();
        let s0: Vec<f64> = r
            .iter()
            .map(|&x| (-(x - 0.6f64).powi(2) / 0.01).exp())
            .collect();
        let (s1, accreted) = evolve(
            &r,
            &s0,
            |_| 1e-3,
            &Rotation::keplerian(&r, 1.0),
            20.0,
            Some(0.3),
        );
        let mass = |s: &[f64]| {
            r.iter()
                .zip(s)
                .map(|(x, s)| std::f64::consts::TAU * x * 5e-3 * s)
                .sum::<f64>()
        };
        assert!(accreted > 0.01 * mass(&s0));
        assert!((mass(&s1) + accreted - mass(&s0)).abs() < 1e-12 * mass(&s0));
    }

    #[test]
    fn quantiles_of_a_uniform_annulus() {
        // Σ = 1 on 1 < R < 2: the mass inside R is ∝ R² − 1, so the median is √2.5.
        let r: Vec<f64> = (0..3000).map(|k| (k as f64 + 0.5) * 1e-3).collect();
        let s: Vec<f64> = r
            .iter()
            .map(|&x| if (1.0..2.0).contains(&x) { 1.0 } else { 0.0 })
            .collect();
        let q = mass_quantiles(&r, &s, &[0.5]);
        assert!((q[0] - 2.5f64.sqrt()).abs() < 1e-3, "{q:?}");
    }
}
