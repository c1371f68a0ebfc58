//! Guards the disk machinery (point-mass gravity, locally isothermal EOS, α viscosity, the
//! equilibrium set-up): a 3D Keplerian disk starts in equilibrium and stays where it started
//! for two orbits at its inner edge — its viscous time there is 10⁴, 1600 times longer.
//!
//! Known and open (issue 3): over longer runs non-axisymmetric motions grow by about 2× per
//! orbit (rms v_R from 0.006 c_s after one orbit to 1.4 c_s after ten), with or without
//! viscosity, in 2D and 3D, and in a nearly inviscid ring too; so this test stops at two
//! orbits, where the growth has not started to matter.

mod common;
use common::{error, run_problem};

#[test]
fn thin_disk_starts_in_equilibrium_for_two_orbits() {
    // Coarse (15k particles, 2 orbits) to stay fast. Measured: the radii enclosing 10, 50,
    // 90% of the mass move by +3.8%, −0.2%, +1.7% (the kernel-smoothed inner edge settles
    // by less than one ring spacing, 0.1), the rms thickness by 3.3%, and the rms radial
    // velocity is 0.19 c_s (epicyclic wobble of the rings). A wrong viscous force, a missing
    // pressure term or a wrong vertical gravity moves these by tens of per cent.
    let r = run_problem::<3>("disk3d.toml", &["particles.n=6", "disk.orbits=2"]);
    let s = &r.summary;
    eprintln!("disk3d: {:?}", s.errors);
    assert!(error(s, "disk_r10_change").abs() < 0.06);
    assert!(error(s, "disk_r50_change").abs() < 0.02);
    assert!(error(s, "disk_r90_change").abs() < 0.04);
    assert!(error(s, "disk_thickness_change") < 0.08);
    assert!(error(s, "disk_vr_rms_over_cs") < 0.4);
    assert!(
        r.particles.nu.iter().all(|&nu| nu > 0.0),
        "α viscosity is on"
    );
    // The central force is radial: angular momentum about z drifts only through the SPH
    // shear stress (measured 4e-5).
    assert!(s.conservation.angular_momentum.unwrap() < 1e-3);
}
