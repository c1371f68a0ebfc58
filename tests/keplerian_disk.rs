//! Guards the disk machinery (point-mass gravity, locally isothermal EOS, α viscosity, the
//! equilibrium set-up balanced against the SPH forces, artificial viscosity measured
//! relative to circular orbits): a 3D Keplerian disk keeps its shape, its noise stays small,
//! and it moves towards what the thin-disk diffusion equation with its own ν(R) predicts.
//!
//! Known and open (issue 3): over 10 orbits the edges spread about 1.5× faster than ν
//! predicts (BENCHMARKS.md); the radii bars below are loose enough for that.

mod common;
use common::{error, run_problem};

#[test]
fn thin_disk_keeps_its_shape_and_follows_its_viscosity_for_four_orbits() {
    // Coarse (11k particles, h = 0.12 against H = 0.1 at R = 1) and 4 orbits at the inner
    // edge, to stay fast. Measured: rms radial velocity 0.09 c_s (before the orbital-frame
    // artificial viscosity and the balanced start it was 0.2 c_s after 2 orbits and 1 c_s
    // after 5, growing from the inner edge); thickness +4.4%; the radii enclosing 10, 50,
    // 90% of the mass move by −1.8%, −1.7%, +4.3% where the diffusion equation predicts
    // −3.4%, +0.6%, +1.8%. At this resolution the rings' discreteness (one ring per
    // 0.1 = H) makes a few per cent of scatter; the bars allow it and fail for the old
    // growth, a missing pressure or viscous term, or a wrong vertical gravity (each moves
    // these by tens of per cent). The finer runs are in BENCHMARKS.md.
    let r = run_problem::<3>("disk3d.toml", &["particles.n=6", "disk.orbits=4"]);
    let s = &r.summary;
    eprintln!("disk3d: {:?}", s.errors);
    assert!(error(s, "disk_vr_rms_over_cs") < 0.2);
    assert!(error(s, "disk_thickness_change") < 0.08);
    for q in ["r10", "r50", "r90"] {
        let (got, want) = (
            error(s, &format!("disk_{q}_change")),
            error(s, &format!("disk_{q}_predicted")),
        );
        assert!((got - want).abs() < 0.04, "{q}: {got} against {want}");
    }
    // Viscosity visibly moves the disk in 4 orbits (its edges are only ≈ H wide): the
    // particles' Σ moved 20% (L1, in annuli of 2 ring spacings) from the start and is
    // closer to the prediction (16%) than to where it started.
    assert!(error(s, "disk_sigma_l1") < error(s, "disk_sigma_l1_start"));
    assert!(
        r.particles.nu.iter().all(|&nu| nu > 0.0),
        "α viscosity is on"
    );
    // The central force and the pair forces are central: angular momentum about z drifts
    // only through the SPH shear stress (measured 4.7e-5).
    assert!(s.conservation.angular_momentum.unwrap() < 1e-3);
}
