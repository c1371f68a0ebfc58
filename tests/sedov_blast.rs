//! Guards the strong-shock regime against the self-similar Sedov–Taylor solution: the shock
//! radius within 5% of ξ0 (E t²/ρ0)^(1/(d+2)) in 2D and 3D, with energy conserved.

mod common;
use common::{error, run_problem};

#[test]
fn sedov_2d_shock_radius() {
    let r = run_problem::<2>("sedov2d.toml", &["particles.n=96", "output.interval=0"]);
    let s = &r.summary;
    eprintln!("sedov 2D: {:?}", s.errors);
    assert!(error(s, "shock_radius_rel") < 0.05);
    assert!(error(s, "isolated_energy_fraction") < 0.01);
    assert!(s.conservation.energy.unwrap() < 1e-3);
}

#[test]
fn sedov_3d_shock_radius() {
    let r = run_problem::<3>("sedov.toml", &["particles.n=32", "output.interval=0"]);
    let s = &r.summary;
    eprintln!("sedov 3D: {:?}", s.errors);
    assert!(error(s, "shock_radius_rel") < 0.05);
    assert!(error(s, "isolated_energy_fraction") < 0.01);
    assert!(s.conservation.energy.unwrap() < 1e-3);
}
