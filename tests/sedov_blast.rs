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

/// A blast from rest keeps L_z = 0: the pair forces are central, so only round-off
/// (~1e-16 of Σ m|x||v| per step, a few hundred steps) may appear. The summary must say so.
#[test]
fn sedov_2d_reports_its_angular_momentum() {
    let r = run_problem::<2>("sedov2d.toml", &["particles.n=48", "output.interval=0"]);
    let dl = r
        .summary
        .conservation
        .angular_momentum
        .expect("a 2D summary holds conservation.angular_momentum");
    assert!(dl < 1e-12, "ΔL_z / Σ m|x||v| = {dl}");
}

/// With few neighbours (h = 1.5 spacings) and a small source (0.05), particles of the
/// evacuated core lose every neighbour for a while and keep their heat. The summary reports
/// the largest share of the internal energy they held during the run, which is at least
/// the share at the end.
#[test]
fn sedov_isolated_energy_is_its_maximum_over_the_run() {
    let r = run_problem::<2>(
        "sedov2d.toml",
        &[
            "particles.n=64",
            "particles.h_factor=1.5",
            "sedov.deposit_radius=0.05",
            "output.interval=0",
        ],
    );
    let p = &r.particles;
    let total: f64 = (0..p.len()).map(|i| p.mass[i] * p.u[i]).sum();
    let at_end: f64 = (0..p.len())
        .filter(|&i| p.interactions[i] == 0)
        .map(|i| p.mass[i] * p.u[i])
        .sum::<f64>()
        / total;
    let reported = error(&r.summary, "isolated_energy_fraction");
    eprintln!("isolated energy: at the end {at_end}, reported {reported}");
    assert!(reported >= at_end);
    // Measured 0.33 (a third of the heat sits in the isolated core at some step).
    assert!(reported > 0.1, "{reported}");
}

/// Against the exact profile convolved with the kernel (what a perfect SPH density would
/// show, so that the half-way point's own outward bias of a few per cent cancels), the 2D
/// shock radius converges: measured 5.8% at n = 64 and 2.5% at n = 128 (1.2% at 256). A
/// fall to below 0.6 of the coarser figure fails a blast that stops converging, as the
/// deposit in kernel supports did (1.3%, 3.3%, 6.0% at n = 64, 128, 256).
#[test]
fn sedov_2d_converges_against_the_smoothed_exact_profile() {
    let rel = |n: &str| {
        let r = run_problem::<2>(
            "sedov2d.toml",
            &[&format!("particles.n={n}"), "output.interval=0"],
        );
        eprintln!("sedov 2D n = {n}: {:?}", r.summary.errors);
        error(&r.summary, "shock_radius_rel_smoothed")
    };
    let (coarse, fine) = (rel("64"), rel("128"));
    assert!(fine < 0.6 * coarse, "{coarse} → {fine}");
    assert!(fine < 0.04, "{fine}");
}
