//! The Roche binary (paper, Section 4; exact-solutions.md 4b): a test particle keeps its
//! Jacobi constant in the turning frame, the ballistic L1 stream against Lubow & Shu and
//! the circularisation-radius fits, the mass budget of a stream run, and a resumed run with
//! injections.

mod common;

use common::{error, run_problem};
use sphdisk::analysis::roche;
use sphdisk::boundary::{BoundaryKind, SimBox};
use sphdisk::integrate::{add_gravity, kdk_step_with};
use sphdisk::kernel::Kernel;
use sphdisk::particles::Particles;
use sphdisk::physics::artificial_viscosity::ArtificialViscosity;
use sphdisk::physics::binary::{Binary, BinaryParams};
use sphdisk::physics::eos::Eos;
use sphdisk::sweep::{Physics, SweepStats};

fn binary(q: f64) -> Binary {
    Binary::new(&BinaryParams::with_q(q))
}

/// A test particle on an orbit about the accretor, perturbed by the donor, for 100 orbits
/// of the binary at Δt = P_orb/8000 (1/820 of the particle's own orbit): its Jacobi
/// constant stays within 1e-6 (relative) — the leapfrog in the turning frame has a bounded
/// O(Δt²) error (3.8e-6 at P_orb/4000, a quarter of it at half the step) and no drift: the
/// largest error of the last 10 orbits is no larger than that of the first 10.
#[test]
fn test_particle_keeps_its_jacobi_constant_for_100_orbits() {
    let b = binary(0.1);
    let mut phys = Physics::<2>::hydro(
        Kernel::new(0.01),
        Eos::Cold {},
        ArtificialViscosity::default(),
    );
    phys.gravity = Some(b.accretor());
    phys.binary = Some(b);
    let bx = SimBox {
        min: [-2.0; 2],
        max: [2.0; 2],
        kinds: [BoundaryKind::Open; 2],
    };
    let mut p = Particles::<2>::new();
    // Inertial speed of a circular orbit at R = 0.25, minus the frame's: corotating.
    let x = [0.0, 0.25];
    let vk = ((1.0 - b.mu) / 0.25_f64).sqrt();
    let f = b.frame_velocity(&x);
    p.push(0, x, [-vk - f[0], -f[1]], 1.0, 0.0);
    let forces = |p: &mut Particles<2>| {
        for d in 0..2 {
            p.acc[d][0] = 0.0;
        }
        add_gravity(p, &phys);
        SweepStats::default()
    };
    let mut q = p.clone();
    forces(&mut q);
    let c0 = b.jacobi(&q.position(0), &q.velocity(0));
    let steps_per_orbit = 8000;
    let dt = std::f64::consts::TAU / steps_per_orbit as f64;
    let (mut worst, mut first, mut last): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 0..100 * steps_per_orbit {
        kdk_step_with(&mut q, &bx, &phys, dt, forces);
        let c = b.jacobi(&q.position(0), &q.velocity(0));
        let e = ((c - c0) / c0).abs();
        worst = worst.max(e);
        if k < 10 * steps_per_orbit {
            first = first.max(e);
        } else if k >= 90 * steps_per_orbit {
            last = last.max(e);
        }
    }
    assert!(worst < 1e-6, "Jacobi constant drifted by {worst:e}");
    assert!(
        last <= 1.1 * first,
        "secular drift: {first:e} then {last:e}"
    );
    // The orbit stayed bound to the accretor (the donor's perturbation is small at 0.25 a).
    let r = q.pos[0][0].hypot(q.pos[1][0]);
    assert!((0.2..0.3).contains(&r), "r = {r}");
}

/// The cold stream from L1 at q = 0.05, 0.1, 0.2: launch angle within 1° of Lubow & Shu's,
/// closest approach and circularisation radius within 2% of the fits in
/// exact-solutions.md 4b (fits to Lubow & Shu's tables; the launch speed 1e-4 shifts the
/// trajectory by far less). At q = 0.05, the end of the fits' range, the r_circ fit itself
/// lies 2.6% above the ballistic value (an independent RK4 integration from L1 along the
/// saddle's unstable direction at Δt = 1e-5 gives 0.29990, this run 0.29991): 3% there.
#[test]
fn ballistic_stream_matches_lubow_and_shu() {
    for q in [0.05, 0.1, 0.2] {
        let run = run_problem::<2>("roche_stream.toml", &[&format!("binary.q={q}")]);
        let s = &run.summary;
        let angle = error(s, "stream_launch_angle_deg");
        let angle_ls = roche::stream_angle(q).to_degrees();
        assert!(
            (angle - angle_ls).abs() < 1.0,
            "q = {q}: launch angle {angle:.2}° against {angle_ls:.2}°"
        );
        let r_min = error(s, "stream_r_min");
        let r_min_fit = roche::r_min_fit(q);
        assert!(
            (r_min / r_min_fit - 1.0).abs() < 0.02,
            "q = {q}: r_min {r_min:.4} against {r_min_fit:.4}"
        );
        let r_circ = error(s, "stream_r_circ");
        let r_circ_fit = roche::r_circ_fit(q);
        let tol = if q < 0.07 { 0.03 } else { 0.02 };
        assert!(
            (r_circ / r_circ_fit - 1.0).abs() < tol,
            "q = {q}: r_circ {r_circ:.4} against {r_circ_fit:.4}"
        );
        // The budget closes: injected = present + accreted + returned + escaped.
        let b = s
            .mass_budget
            .as_ref()
            .expect("a binary run has a mass budget");
        assert!(b.residual.abs() < 1e-12, "budget residual {}", b.residual);
        assert!(b.flows.injected.particles > 1900);
    }
}
