//! β cooling (`physics::cooling`): gas at rest at several radii about a central mass relaxes
//! towards the target profile exactly as du/dt = −(u − u₀) Ω/β prescribes, through the same
//! kick–drift–kick integrator the runs use.

use sphdisk::boundary::{BoundaryKind, SimBox};
use sphdisk::integrate::kdk_step_with;
use sphdisk::kernel::Kernel;
use sphdisk::particles::Particles;
use sphdisk::physics::artificial_viscosity::ArtificialViscosity;
use sphdisk::physics::cooling::Cooling;
use sphdisk::physics::eos::Eos;
use sphdisk::physics::gravity::PointMass;
use sphdisk::sweep::{Physics, SweepStats};

/// u(t) = u₀ + (u(0) − u₀) e^(−Ω t/β) at R = 0.3, 0.6, 1.0 over three cooling times of the
/// innermost, at Δt = 1/200 of its cooling time: the leapfrog's trapezoidal update of a linear
/// equation is second order, with a relative error ~ (Ω Δt/β)²/12 per cooling time
/// (~2e-6); 1e-4 of u(0) − u₀ bounds it with room.
#[test]
fn internal_energy_relaxes_exponentially_to_the_target() {
    let gamma = 5.0 / 3.0;
    let cooling = Cooling {
        beta: 2.0,
        cs0: 0.05,
        r0: 1.0,
        q: 0.5,
        heats: true,
    };
    let g = PointMass {
        gm: 1.0,
        softening: 0.0,
        accretion_radius: None,
    };
    let mut phys = Physics::<2>::hydro(
        Kernel::new(0.01),
        Eos::Ideal { gamma },
        ArtificialViscosity::default(),
    );
    phys.gravity = Some(g);
    phys.cooling = Some(cooling);
    let bx = SimBox {
        min: [-2.0; 2],
        max: [2.0; 2],
        kinds: [BoundaryKind::Open; 2],
    };
    let radii = [0.3, 0.6, 1.0];
    let mut p = Particles::<2>::new();
    for (k, &r) in radii.iter().enumerate() {
        // Ten times hotter than the target: the bright spot's gas after its shock.
        p.push(
            k as u64,
            [r, 0.0],
            [0.0, 0.0],
            1.0,
            10.0 * cooling.target_u(gamma, r),
        );
    }
    // Only the cooling acts (the particles stay where they are).
    let forces = |p: &mut Particles<2>| {
        for i in 0..p.len() {
            p.acc[0][i] = 0.0;
            p.acc[1][i] = 0.0;
            p.du[i] = 0.0;
        }
        cooling.add_to(p, &phys.eos, &g);
        SweepStats::default()
    };
    forces(&mut p);
    let t_cool = cooling.beta / (g.gm / 0.3_f64.powi(3)).sqrt();
    let dt = t_cool / 200.0;
    let u_start = p.u.clone();
    for _ in 0..600 {
        kdk_step_with(&mut p, &bx, &phys, dt, forces);
    }
    let t = 600.0 * dt;
    for (i, &r) in radii.iter().enumerate() {
        let u0 = cooling.target_u(gamma, r);
        let omega = (g.gm / (r * r * r)).sqrt();
        let exact = u0 + (u_start[i] - u0) * (-omega * t / cooling.beta).exp();
        let err = (p.u[i] - exact).abs() / (u_start[i] - u0);
        assert!(
            err < 1e-4,
            "R = {r}: u {} against {exact} ({err:e})",
            p.u[i]
        );
    }
    // The innermost has cooled by e^−3, the outermost far less.
    assert!(p.u[0] < 0.2 * u_start[0]);
    assert!(p.u[2] > 0.5 * u_start[2]);
}

/// `problems/overflow3d_cool.toml` measures a stream cooler than its disk: its header's
/// figures (stream/H 0.75, 6.8% passing the rim) are those of a stream leaving L1 at
/// T_stream/T_disk = (stream.cs / cooling.cs0)² = (0.06 / 0.2324)² = 0.067. The file must
/// run that stream (it once held stream.cs = 0.1273, T ratio 0.3, whose 58% passes); 10% on
/// the ratio separates the header's 0.067 from every other stream the header lists (0.02,
/// 0.09, 0.12, …).
#[test]
fn the_cool_overflow_file_runs_the_stream_its_header_measures() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/overflow3d_cool.toml");
    let cfg = sphdisk::config::Config::load(&path, &[]).unwrap();
    let stream = cfg.stream.expect("a stream");
    let cooling = cfg.cooling.expect("cooling");
    assert!(!cooling.heats, "the cooling only cools");
    let ratio = (stream.cs / cooling.cs0).powi(2);
    assert!(
        (ratio / 0.067 - 1.0).abs() < 0.1,
        "T_stream/T_disk = {ratio}"
    );
    let header = std::fs::read_to_string(&path).unwrap();
    assert!(
        header.contains("stream.cs = 0.06: T_stream/T_disk"),
        "the header names it"
    );
}
