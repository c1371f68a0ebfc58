//! Mass transfer through L1 (paper, Section 2.4: particles are inserted between steps):
//! the donor's gas leaves its Roche lobe through the nozzle around L1 and falls towards the
//! accretor as the stream that builds the disk.
//!
//! The nozzle (Lubow & Shu 1975; Meyer & Meyer-Hofmeister 1983): near L1 the Roche
//! potential is Φ ≈ Φ_L1 − ½ (2A+1) ξ² + ½ (A−1) η² + ½ A ζ² (Ω = 1, A from
//! `analysis::roche::l1_a`), so isothermal gas of sound speed c_s in hydrostatic balance
//! across the stream has a Gaussian cross-section with σ_y = c_s/√(A−1) in the orbital plane
//! and σ_z = c_s/√A out of it, and crosses L1 at about c_s. Each particle is placed at L1
//! plus a Gaussian offset across the stream, moving at c_s towards the accretor (corotating
//! frame), and released at its own time t_k = k / rate; a particle released within the
//! step just taken is moved on ballistically by the time since its release.
//!
//! Everything the injector carries between steps is in [`InjectorState`] (checkpointed):
//! a resumed run inserts the same particles with the same ids.

use serde::{Deserialize, Serialize};

use crate::analysis::roche;
use crate::limits::show;
use crate::particles::Particles;
use crate::rng::Rng;

/// `[stream]` of a problem file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamParams {
    /// Particles released per orbital period.
    pub particles_per_orbit: f64,
    /// Mass transferred per orbit, code units (or give `mdot_msun_per_year` with a
    /// physical binary). Only the density scale depends on it (no self-gravity).
    pub mass_per_orbit: Option<f64>,
    /// Transfer rate in solar masses per year (binaries given in physical values).
    pub mdot_msun_per_year: Option<f64>,
    /// Sound speed of the donor's gas at L1, code units (sets the nozzle and the launch
    /// speed); 0 gives a cold, infinitely thin stream. Default 0.
    #[serde(default)]
    pub cs: f64,
    /// The nozzle's width as a multiple of Lubow & Shu's (default 1); 0 launches every
    /// particle at L1 itself: one ballistic trajectory sampled in time (a test stream).
    #[serde(default = "one")]
    pub width: f64,
    /// Start inserting at this time (default 0).
    #[serde(default)]
    pub start: f64,
    /// Stop inserting at this time (default: never).
    pub stop: Option<f64>,
}

impl StreamParams {
    pub fn validate(&self, physical: bool) -> Result<(), String> {
        let n = self.particles_per_orbit;
        if !(n > 0.0 && n <= 1e7) {
            return Err(format!(
                "key `stream.particles_per_orbit`: must be > 0 and ≤ 1e7, got {}",
                show(n)
            ));
        }
        match (self.mass_per_orbit, self.mdot_msun_per_year) {
            (Some(m), None) => crate::limits::check_scale("stream.mass_per_orbit", m)?,
            (None, Some(m)) if !physical => {
                return Err(format!(
                    "key `stream.mdot_msun_per_year` ({m}) needs a binary in physical values \
                     (binary.m1_msun, m2_msun, period_days); in code units give stream.mass_per_orbit"
                ));
            }
            (None, Some(m)) if m > 0.0 && m < 1.0 => {}
            (None, Some(m)) => {
                return Err(format!(
                    "key `stream.mdot_msun_per_year`: must be > 0 and < 1, got {m}"
                ));
            }
            (Some(_), Some(_)) => {
                return Err(
                    "table `[stream]`: give mass_per_orbit or mdot_msun_per_year, not both".into(),
                );
            }
            (None, None) => {
                return Err(
                    "key `stream.mass_per_orbit`: missing (the transfer rate; or mdot_msun_per_year)"
                        .into(),
                );
            }
        }
        if !(self.cs >= 0.0 && self.cs < 1.0) {
            return Err(format!(
                "key `stream.cs`: must be ≥ 0 and < 1 (the orbital speed), got {}",
                self.cs
            ));
        }
        if !(self.width >= 0.0 && self.width <= 10.0) {
            return Err(format!(
                "key `stream.width`: must be between 0 and 10 (times Lubow & Shu's nozzle), got {}",
                self.width
            ));
        }
        if !(self.start >= 0.0 && self.start.is_finite()) {
            return Err(format!(
                "key `stream.start`: must be ≥ 0, got {}",
                self.start
            ));
        }
        if let Some(s) = self.stop
            && !(s > self.start && s.is_finite())
        {
            return Err(format!(
                "key `stream.stop`: must be later than stream.start, got {s}"
            ));
        }
        Ok(())
    }
}

fn one() -> f64 {
    1.0
}

/// What the injector carries between steps (checkpointed).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct InjectorState {
    /// Particles released so far.
    pub released: u64,
    /// The id of the next particle.
    pub next_id: u64,
    /// The random generator's state (positions across the nozzle).
    pub rng: u64,
}

/// The L1 nozzle of a binary with mass ratio `q`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct L1Stream {
    pub q: f64,
    /// Releases per unit code time.
    pub rate: f64,
    pub particle_mass: f64,
    pub cs: f64,
    pub start: f64,
    pub stop: f64,
    l1: [f64; 3],
    sigma_y: f64,
    sigma_z: f64,
}

impl L1Stream {
    /// `mass_per_orbit` in code units (converted from M☉/yr by the caller where physical).
    pub fn new(q: f64, params: &StreamParams, mass_per_orbit: f64) -> Self {
        let a = roche::l1_a(q);
        let rate = params.particles_per_orbit / std::f64::consts::TAU;
        Self {
            q,
            rate,
            particle_mass: mass_per_orbit / params.particles_per_orbit,
            cs: params.cs,
            start: params.start,
            stop: params.stop.unwrap_or(f64::INFINITY),
            l1: roche::l1_point(q),
            sigma_y: params.width * params.cs / (a - 1.0).sqrt(),
            sigma_z: params.width * params.cs / a.sqrt(),
        }
    }

    /// Width of the nozzle (σ in the orbital plane, σ out of it).
    pub fn nozzle(&self) -> (f64, f64) {
        (self.sigma_y, self.sigma_z)
    }

    /// Release time of particle k.
    fn release_time(&self, k: u64) -> f64 {
        self.start + k as f64 / self.rate
    }

    /// Releases due strictly before time `t`.
    pub fn due_before(&self, t: f64) -> u64 {
        let mut n = self.due(t);
        while n > 0 && self.release_time(n - 1) >= t {
            n -= 1;
        }
        n
    }

    /// Releases due by time `t` (particles k with t_k ≤ t and t_k < stop).
    fn due(&self, t: f64) -> u64 {
        let until = t.min(self.stop);
        if until < self.start {
            return 0;
        }
        let k = ((until - self.start) * self.rate).floor();
        // t_k < stop: a release exactly at `stop` is not made.
        let mut n = k as u64 + 1;
        while n > 0 && self.release_time(n - 1) >= self.stop {
            n -= 1;
        }
        n
    }

    /// Inserts every particle due by time `t` into `p` (with `u` its internal energy),
    /// each moved on from L1 by the time since its release, and returns how many.
    pub fn inject<const D: usize>(
        &self,
        st: &mut InjectorState,
        p: &mut Particles<D>,
        t: f64,
        u: f64,
    ) -> usize {
        let due = self.due(t);
        let mut rng = Rng::new(st.rng);
        let mut n = 0;
        while st.released < due {
            let lag = (t - self.release_time(st.released)).max(0.0);
            let dy = self.sigma_y * rng.normal();
            let dz = self.sigma_z * rng.normal();
            let mut x = [0.0; D];
            let mut v = [0.0; D];
            x[0] = self.l1[0] + self.cs * lag;
            v[0] = self.cs;
            x[1] = dy;
            if D == 3 {
                x[2] = dz;
            }
            p.push(st.next_id, x, v, self.particle_mass, u);
            st.next_id += 1;
            st.released += 1;
            n += 1;
        }
        st.rng = rng.state();
        n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stream(cs: f64) -> L1Stream {
        L1Stream::new(
            0.1,
            &StreamParams {
                particles_per_orbit: 100.0,
                mass_per_orbit: Some(1.0),
                mdot_msun_per_year: None,
                cs,
                width: 1.0,
                start: 0.0,
                stop: Some(2.0 * std::f64::consts::TAU),
            },
            1.0,
        )
    }

    #[test]
    fn releases_at_the_set_rate_with_unique_ids_and_stops() {
        let s = stream(0.05);
        let mut st = InjectorState {
            next_id: 1000,
            ..InjectorState::default()
        };
        let mut p = Particles::<2>::new();
        // One at t = 0, then one every 2π/100.
        assert_eq!(s.inject(&mut st, &mut p, 0.0, 0.0), 1);
        let mut t = 0.0;
        while t < 3.0 * std::f64::consts::TAU {
            t += 0.013;
            s.inject(&mut st, &mut p, t, 0.0);
        }
        assert_eq!(p.len(), 200, "two orbits at 100 per orbit, then none");
        let mut ids = p.id.clone();
        ids.dedup();
        assert_eq!(ids.len(), 200);
        assert_eq!(ids[0], 1000);
        assert!((p.mass.iter().sum::<f64>() - 2.0).abs() < 1e-12);
        // None is left after the stop, however long the run goes on.
        assert_eq!(s.inject(&mut st, &mut p, 1e6, 0.0), 0);
    }

    #[test]
    fn nozzle_width_follows_the_l1_curvature() {
        let mut s = stream(0.05);
        s.stop = f64::INFINITY;
        let mut st = InjectorState::default();
        let mut p = Particles::<3>::new();
        s.inject(&mut st, &mut p, 4000.0 * std::f64::consts::TAU / 100.0, 0.0);
        let n = p.len() as f64;
        let var = |d: usize| p.pos[d].iter().map(|y| y * y).sum::<f64>() / n;
        let (sy, sz) = s.nozzle();
        // 4001 samples: the sample variance is within 3·√(2/n) ≈ 7% of the true one.
        assert!((var(1) / (sy * sy) - 1.0).abs() < 0.07);
        assert!((var(2) / (sz * sz) - 1.0).abs() < 0.07);
        let a = roche::l1_a(0.1);
        assert!((sy - 0.05 / (a - 1.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_resumed_injector_repeats_itself() {
        let s = stream(0.05);
        let (mut a, mut pa) = (InjectorState::default(), Particles::<2>::new());
        s.inject(&mut a, &mut pa, 1.0, 0.0);
        let copy = a.clone();
        s.inject(&mut a, &mut pa, 2.0, 0.0);
        let (mut b, mut pb) = (copy, Particles::<2>::new());
        s.inject(&mut b, &mut pb, 2.0, 0.0);
        let k = pa.len() - pb.len();
        assert_eq!(&pa.pos[1][k..], &pb.pos[1][..]);
        assert_eq!(&pa.id[k..], &pb.id[..]);
    }
}
