//! Where a binary's gas enters and leaves between steps (paper, Section 2.4: "the time to
//! remove or insert particles"): the L1 stream inserts particles, and particles leave by
//! accretion onto the white dwarf, by return into the donor's Roche lobe, or by escape.
//! Every crossing is booked in the [`MassBudget`], which closes to round-off.

use crate::config::Config;
use crate::io::summary::MassBudget;
use crate::particles::Particles;
use crate::physics::binary::{Binary, MSUN_G, Sink, YEAR_S};
use crate::physics::eos::Eos;
use crate::physics::l1_stream::{InjectorState, L1Stream};
use rayon::prelude::*;

/// A binary's sources and sinks.
#[derive(Clone, Copy, Debug)]
pub struct MassTransfer {
    pub binary: Binary,
    pub stream: Option<L1Stream>,
    /// Internal energy of inserted gas: that of the stream's sound speed.
    u_inject: f64,
}

impl MassTransfer {
    /// The binary and stream of a problem file (None without `[binary]`).
    pub fn from_config(cfg: &Config) -> Option<Self> {
        let bp = cfg.binary.as_ref()?;
        let binary = Binary::new(bp);
        let stream = cfg.stream.as_ref().map(|s| {
            let per_orbit = match (s.mass_per_orbit, s.mdot_msun_per_year) {
                (Some(m), _) => m,
                (None, Some(mdot)) => {
                    // M☉/yr → code mass per orbit: mass unit M1 + M2, P_orb = 2π time units.
                    let u = cfg.units();
                    let period_s = std::f64::consts::TAU * u.time_cgs;
                    mdot * MSUN_G / YEAR_S * period_s / u.mass_cgs
                }
                (None, None) => 0.0,
            };
            L1Stream::new(binary.q, s, per_orbit)
        });
        let cs = stream.map_or(0.0, |s| s.cs);
        let u_inject = match cfg.eos {
            Eos::Ideal { gamma } => cs * cs / (gamma * (gamma - 1.0)),
            _ => 0.0,
        };
        Some(Self {
            binary,
            stream,
            u_inject,
        })
    }

    /// Internal energy of inserted gas (0 unless the gas is ideal).
    pub fn u_inject(&self) -> f64 {
        self.u_inject
    }

    /// The injector's state at the start of a run whose particles' ids end below `next_id`.
    pub fn start_state(&self, seed: u64, next_id: u64) -> InjectorState {
        InjectorState {
            released: 0,
            next_id,
            rng: seed ^ 0x5EED_0F11_5712_EA11,
        }
    }

    /// The longest step that keeps releases one at a time: 1 / rate.
    pub fn max_step(&self) -> f64 {
        self.stream.map_or(f64::INFINITY, |s| 1.0 / s.rate)
    }

    /// Removes every particle that reached a sink and books it; returns how many went.
    pub fn remove<const D: usize>(&self, p: &mut Particles<D>, budget: &mut MassBudget) -> usize {
        let b = &self.binary;
        // The sinks' tests in parallel (the donor lobe's potential for every particle on the
        // donor's side); the booking in index order, so the sums are those of a serial scan.
        let sinks: Vec<Option<Sink>> = (0..p.len())
            .into_par_iter()
            .map(|i| b.sink(&p.position(i)))
            .collect();
        let mut keep = vec![true; p.len()];
        let mut gone = 0;
        for (i, sink) in sinks.into_iter().enumerate() {
            let Some(sink) = sink else { continue };
            let x = p.position(i);
            let l = p.mass[i] * b.angular_momentum_z(&x, &p.velocity(i));
            let flow = match sink {
                Sink::Accreted => &mut budget.accreted,
                Sink::Returned => &mut budget.returned,
                Sink::Escaped => &mut budget.escaped,
            };
            flow.add(p.mass[i], l);
            keep[i] = false;
            gone += 1;
        }
        if gone > 0 {
            p.retain(&keep);
        }
        gone
    }

    /// Counts the stream's releases due before time `t` as made (a run that starts at `t`).
    pub fn skip_releases_before(&self, st: &mut InjectorState, t: f64) {
        if let Some(s) = &self.stream {
            st.released = st.released.max(s.due_before(t));
        }
    }

    /// Inserts the stream's particles due by time `t`, books them, and gives them the
    /// binary's gravity as their acceleration (the SPH forces follow at the next step).
    /// Returns how many were inserted.
    pub fn inject<const D: usize>(
        &self,
        st: &mut InjectorState,
        p: &mut Particles<D>,
        t: f64,
        budget: &mut MassBudget,
        gravity: impl Fn(&[f64; D]) -> [f64; D],
    ) -> usize {
        let Some(s) = &self.stream else { return 0 };
        let first = p.len();
        let n = s.inject(st, p, t, self.u_inject);
        for i in first..p.len() {
            let x = p.position(i);
            let a = gravity(&x);
            for d in 0..D {
                p.acc[d][i] = a[d];
            }
            let l = p.mass[i] * self.binary.angular_momentum_z(&x, &p.velocity(i));
            budget.injected.add(p.mass[i], l);
        }
        n
    }
}
