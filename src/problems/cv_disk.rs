//! A disk already in place around a CV's white dwarf (`[initial_disk]`), for runs that study
//! what a grown disk does (the 3:1 resonance and superhumps, paper Section 4) without first
//! spending the viscous time (~300 orbits at α = 0.1) letting the stream build it.
//!
//! The gas sits on concentric rings of radial spacing Δ between `r_in` and `r_out`,
//! azimuthal spacing about Δ (alternate rings staggered by half a step), every particle with
//! the stream's particle mass, so that the number density — and with a constant h the
//! density estimate — is uniform: Σ is constant in 2D. In 3D each ring point is a vertical
//! column of n_z = round(√(2π) H/Δ) particles at the quantiles of a Gaussian of scale height
//! H = c_s/Ω_K, so the midplane density is uniform and Σ ∝ H. Velocities are Kepler's about
//! the accretor (v_φ² = GM₁ R²/(R² + z²)^{3/2}), written in the turning frame (v − Ω × x);
//! the pressure gradient of a uniform disk vanishes inside, so only its edges adjust.
//! The ring lattice is symmetric: the m = 1 and m = 2 modes start at round-off and grow
//! from the stream's impact and the tides, as in a disk the stream built.

use serde::{Deserialize, Serialize};

use crate::analysis::roche;
use crate::particles::Particles;
use crate::physics::binary::Binary;

/// `[initial_disk]`: the disk a cv problem starts with, in units of a.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialDisk {
    /// Inner radius (at least the accretor's radius).
    pub r_in: f64,
    /// Outer radius (inside the accretor's Roche lobe: below L1).
    pub r_out: f64,
    /// Spacing of the particles; default h/1.2 (about 18 neighbours in 2D, 57 in 3D).
    pub spacing: Option<f64>,
}

/// The most particles an initial disk may hold (checked before anything is allocated).
pub const MAX_PARTICLES: f64 = 5e7;

impl InitialDisk {
    /// The particle spacing for smoothing length `h`.
    pub fn spacing(&self, h: f64) -> f64 {
        self.spacing.unwrap_or(h / 1.2)
    }

    /// Checks the radii against the binary and the particle count against
    /// [`MAX_PARTICLES`]; `cs_max` bounds the sound speed (3D column heights).
    pub fn validate(
        &self,
        q: f64,
        accretor_radius: f64,
        h: f64,
        dimension: usize,
        cs_max: f64,
    ) -> Result<(), String> {
        let l1 = roche::l1_distance(q);
        if !(self.r_in >= accretor_radius && self.r_in.is_finite()) {
            return Err(format!(
                "key `initial_disk.r_in`: must be at least the accretor's radius \
                 binary.accretor_radius = {accretor_radius}, got {}",
                self.r_in
            ));
        }
        if !(self.r_out > self.r_in && self.r_out < l1) {
            return Err(format!(
                "key `initial_disk.r_out`: must lie between initial_disk.r_in = {} and L1 at \
                 {l1:.4}, got {}",
                self.r_in, self.r_out
            ));
        }
        let dx = self.spacing(h);
        if !(dx >= 0.25 * h && dx <= self.r_out - self.r_in) {
            return Err(format!(
                "key `initial_disk.spacing`: must lie between h/4 = {} and r_out − r_in = {}, \
                 got {dx}",
                0.25 * h,
                self.r_out - self.r_in
            ));
        }
        let n = self.estimated_particles(dx, dimension, cs_max);
        if n > MAX_PARTICLES {
            return Err(format!(
                "key `initial_disk.spacing`: {dx} would place about {n:.2e} particles, more \
                 than {MAX_PARTICLES:e}"
            ));
        }
        Ok(())
    }

    /// An upper bound on the particle count (3D columns as tall as at r_out with `cs_max`).
    fn estimated_particles(&self, dx: f64, dimension: usize, cs_max: f64) -> f64 {
        let rings = (self.r_out * self.r_out - self.r_in * self.r_in) * std::f64::consts::PI
            / (dx * dx)
            + 2.0 * std::f64::consts::PI * self.r_out / dx;
        match dimension {
            3 => {
                let h = cs_max / (1.0 / self.r_out.powi(3)).sqrt();
                rings * (1.0 + (2.0 * std::f64::consts::PI).sqrt() * h / dx)
            }
            _ => rings,
        }
    }

    /// Appends the disk to `p`: ids from `first_id`, each particle of mass `mass`;
    /// `thermo(R)` gives the internal energy u at R and the isothermal sound speed √(P/ρ)
    /// that sets the 3D scale height H = √(P/ρ)/Ω_K. Returns the number placed.
    pub fn place<const D: usize>(
        &self,
        b: &Binary,
        h: f64,
        mass: f64,
        thermo: impl Fn(f64) -> (f64, f64),
        first_id: u64,
        p: &mut Particles<D>,
    ) -> usize {
        let dx = self.spacing(h);
        let gm = b.accretor().gm;
        let rings = ((self.r_out - self.r_in) / dx).floor().max(1.0) as usize;
        let mut id = first_id;
        for k in 0..rings {
            let r = self.r_in + (k as f64 + 0.5) * dx;
            let n_phi = ((std::f64::consts::TAU * r / dx).round() as usize).max(1);
            let omega_k = (gm / (r * r * r)).sqrt();
            let (u, cs) = thermo(r);
            let hz = cs / omega_k;
            let column = if D == 3 {
                ((2.0 * std::f64::consts::PI).sqrt() * hz / dx)
                    .round()
                    .max(1.0) as usize
            } else {
                1
            };
            for j in 0..n_phi {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5 * (k % 2) as f64) / n_phi as f64;
                let (s, c) = phi.sin_cos();
                for l in 0..column {
                    let z = if column > 1 {
                        hz * normal_quantile((l as f64 + 0.5) / column as f64)
                    } else {
                        0.0
                    };
                    let v_phi = (gm * r * r / (r * r + z * z).powf(1.5)).sqrt();
                    let mut x = [0.0; D];
                    let mut v = [0.0; D];
                    x[0] = r * c;
                    x[1] = r * s;
                    // Turning frame: subtract Ω × x (Ω along z).
                    v[0] = -v_phi * s + b.omega * x[1];
                    v[1] = v_phi * c - b.omega * x[0];
                    if D == 3 {
                        x[2] = z;
                    }
                    p.push(id, x, v, mass, u);
                    id += 1;
                }
            }
        }
        (id - first_id) as usize
    }
}

/// The standard normal quantile Φ⁻¹(p) for p in (0, 1) (Acklam's rational approximation,
/// relative error below 1.2e-9: far below a particle spacing).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const E: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((E[0] * q + E[1]) * q + E[2]) * q + E[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::binary::BinaryParams;

    fn disk() -> InitialDisk {
        InitialDisk {
            r_in: 0.1,
            r_out: 0.45,
            spacing: None,
        }
    }

    #[test]
    fn normal_quantile_inverts_the_known_points() {
        assert!(normal_quantile(0.5).abs() < 1e-12);
        // Φ(1) = 0.841344746068543, Φ(−2.5) = 0.00620966532577613 (tables).
        assert!((normal_quantile(0.841_344_746_068_543) - 1.0).abs() < 1e-8);
        assert!((normal_quantile(0.006_209_665_325_776_13) + 2.5).abs() < 1e-8);
        assert!((normal_quantile(0.3) + normal_quantile(0.7)).abs() < 1e-12);
    }

    #[test]
    fn the_disk_is_uniform_circular_and_keplerian() {
        let b = Binary::new(&BinaryParams::with_q(0.1));
        let mut p = Particles::<2>::new();
        let h = 0.01;
        let n = disk().place(&b, h, 1e-6, |_| (0.0, 0.05), 7, &mut p);
        assert_eq!(n, p.len());
        assert_eq!(p.id[0], 7);
        // Uniform number density: the count over the annulus's area per Δ² is within one
        // ring's worth (2π r_out/Δ) of the area, since the rings are round()ed.
        let dx = h / 1.2;
        let area = std::f64::consts::PI * (0.45f64.powi(2) - 0.1f64.powi(2));
        assert!((n as f64 - area / (dx * dx)).abs() < 0.45 * std::f64::consts::TAU / dx);
        for i in 0..n {
            let x = p.position(i);
            let e = b.eccentricity(&x, &p.velocity(i));
            // Circular Kepler orbits about the accretor: e = 0 to round-off.
            assert!(e < 1e-12, "particle {i}: e = {e}");
            let r = x[0].hypot(x[1]);
            assert!((0.1..=0.45).contains(&r));
        }
        // Symmetric: the m = 1 sum vanishes to round-off.
        let (c, s): (f64, f64) = (0..n).fold((0.0, 0.0), |(c, s), i| {
            let phi = p.pos[1][i].atan2(p.pos[0][i]);
            (c + phi.cos(), s + phi.sin())
        });
        assert!(c.hypot(s) / (n as f64) < 1e-12);
    }

    #[test]
    fn the_3d_columns_follow_the_scale_height() {
        let b = Binary::new(&BinaryParams::with_q(0.1));
        let mut p = Particles::<3>::new();
        let d = InitialDisk {
            r_in: 0.3,
            r_out: 0.32,
            spacing: Some(0.002),
        };
        d.place(&b, 0.0024, 1.0, |_| (0.0, 0.05), 0, &mut p);
        let n = p.len() as f64;
        let rms = (p.pos[2].iter().map(|z| z * z).sum::<f64>() / n).sqrt();
        // H = c_s/Ω_K at r ≈ 0.31 with GM₁ = 1/1.1 is 0.00905: columns of 11. The rms of
        // the 11 Gaussian quantiles (j + ½)/11 is 0.948 H (the tails beyond the end
        // quantiles are missing), so the rms lies within 7% below H.
        let r: f64 = 0.31;
        let hz = 0.05 / (1.0 / 1.1 / r.powi(3)).sqrt();
        assert!(rms < hz && rms > 0.93 * hz, "rms {rms}, H {hz}");
        // v_φ² = GM R²/(R² + z²)^{3/2} is the midplane's pull, not the circular speed at
        // the distance √(R² + z²): the orbit through (R, 0, z) moving along y is at its
        // apoastron with e = z²/(R² + z²) exactly.
        for i in 0..p.len() {
            let x = p.position(i);
            let expect = x[2] * x[2] / (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            let e = b.eccentricity(&x, &p.velocity(i));
            assert!((e - expect).abs() < 1e-9, "e {e}, expected {expect}");
        }
    }

    #[test]
    fn bad_radii_and_counts_name_the_key() {
        let q = 0.1;
        let bad = |d: InitialDisk| d.validate(q, 0.05, 0.01, 2, 0.05).unwrap_err();
        assert!(
            bad(InitialDisk {
                r_in: 0.01,
                ..disk()
            })
            .contains("initial_disk.r_in")
        );
        assert!(
            bad(InitialDisk {
                r_out: 0.9,
                ..disk()
            })
            .contains("initial_disk.r_out")
        );
        assert!(
            bad(InitialDisk {
                r_out: f64::NAN,
                ..disk()
            })
            .contains("initial_disk.r_out")
        );
        let tiny = InitialDisk {
            spacing: Some(1e-9),
            ..disk()
        };
        assert!(bad(tiny).contains("initial_disk.spacing"));
        assert!(
            disk()
                .validate(q, 1e-3, 1e-5, 3, 0.05)
                .unwrap_err()
                .contains("particles")
        );
        assert!(disk().validate(q, 0.05, 0.01, 2, 0.05).is_ok());
    }
}
