//! Guards the disk machinery (point-mass gravity, locally isothermal EOS, α viscosity, the
//! equilibrium set-up balanced against the SPH forces, artificial viscosity measured
//! relative to circular orbits): a 3D Keplerian disk keeps its shape, its noise stays small,
//! and it moves towards what the thin-disk diffusion equation with its own ν(R) predicts.
//!
//! The reference turns as the equilibrium does (pressure-supported at the edges). At the
//! problem's resolution (n = 10) over its 10 orbits the radii enclosing 10/50/90% of the
//! mass end within 0.4 points of the prediction and the disk spreads like α_eff = 0.0117
//! for its α = 0.01 (BENCHMARKS.md); this test runs a coarser disk for 4 orbits.

mod common;
use common::{error, run_problem};
use sphdisk::reports::disk::analyse_disk;

#[test]
fn thin_disk_keeps_its_shape_and_follows_its_viscosity_for_four_orbits() {
    // Coarse (12k particles, h = 0.15 against H = 0.1 at R = 1) and 4 orbits at the inner
    // edge, to stay fast. Measured: rms radial velocity 0.069 c_s (before the orbital-frame
    // artificial viscosity and the balanced start it was 0.2 c_s after 2 orbits and 1 c_s
    // after 5, growing from the inner edge); the radii enclosing 10, 50,
    // 90% of the mass move by −2.0%, −1.1%, +3.3% where the diffusion equation predicts
    // −4.3%, +0.8%, +2.6%. At this resolution the rings' discreteness (one ring per
    // 0.1 = H) and the disk's radial breathing (r50 swings by ±2% over the first orbits, in
    // runs without viscosity too) make a few per cent of scatter; the bars allow it and fail
    // for the old growth, a missing pressure or viscous term, or a wrong vertical gravity
    // (each moves these by tens of per cent). The finer runs are in BENCHMARKS.md.
    let r = run_problem::<3>(
        "disk3d.toml",
        &[
            "particles.n=6",
            "disk.orbits=4",
            "output.interval=6.283185307179586",
        ],
    );
    let s = &r.summary;
    eprintln!("disk3d: {:?}", s.errors);
    // `analyse disk` follows the same figures snapshot by snapshot (one per orbit); its last
    // snapshot is the final state, where it must agree with summary.json.
    let report = analyse_disk(r.dir.path()).expect("analysis runs");
    assert_eq!(report.rows.len(), 4, "one row per orbit");
    let (t_last, last) = report.rows.last().unwrap();
    assert!(
        (t_last - s.t_end).abs() < 1e-9,
        "{t_last} against {}",
        s.t_end
    );
    for (k, v) in last {
        assert!(
            (v - error(s, k)).abs() < 1e-9,
            "{k}: {v} against {}",
            error(s, k)
        );
    }
    assert!(report.file.exists());
    assert!(error(s, "disk_vr_rms_over_cs") < 0.2);
    // No heating beyond the spreading's: the rms thickness grew 1.4% where moving the mass
    // as the prediction does grows it 1.0% (mass moved outwards is thicker; at n = 10 after
    // 10 orbits 2.7% against 2.3%). The bar fails for a disk whose layers puff up (the old
    // 68% in 10 orbits) or collapse.
    let (thick, thick_pred) = (
        error(s, "disk_thickness_change"),
        error(s, "disk_thickness_predicted"),
    );
    assert!(
        (thick - thick_pred).abs() < 0.015,
        "thickness {thick} against {thick_pred}"
    );
    for q in ["r10", "r50", "r90"] {
        let (got, want) = (
            error(s, &format!("disk_{q}_change")),
            error(s, &format!("disk_{q}_predicted")),
        );
        assert!((got - want).abs() < 0.03, "{q}: {got} against {want}");
    }
    // Viscosity visibly moves the disk in 4 orbits (its edges are only ≈ H wide): the
    // particles' Σ moved 20% (L1, in annuli of 2 ring spacings) from the start and is
    // closer to the prediction (13%) than to where it started; so are the enclosed masses
    // M(<R) (measured 0.024 against the prediction, 0.044 against the start).
    assert!(error(s, "disk_sigma_l1") < error(s, "disk_sigma_l1_start"));
    assert!(error(s, "disk_enclosed_mass_l1") < 0.75 * error(s, "disk_enclosed_mass_l1_start"));
    // The α whose diffusion fits the particles' enclosed masses best: 0.0128 measured
    // against the 0.01 given (0.0117 at n = 10 after 10 orbits; 0.005 there without
    // viscosity). The upper bar, 1.6α, fails for a disk whose ν is doubled (α_eff ≈ 0.023)
    // or whose numerical transport doubles; the lower, 0.5α, for one that hardly spreads.
    let alpha_eff = error(s, "disk_alpha_effective");
    assert!((0.005..0.016).contains(&alpha_eff), "α_eff = {alpha_eff}");
    assert!(
        r.particles.nu.iter().all(|&nu| nu > 0.0),
        "α viscosity is on"
    );
    // The central force and the pair forces are central: angular momentum about z drifts
    // only through the SPH shear stress (measured 4.7e-5).
    assert!(s.conservation.angular_momentum.unwrap() < 1e-3);
}
