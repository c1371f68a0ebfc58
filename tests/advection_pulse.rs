//! Guards advection: a pulse in pressure equilibrium carried once around a periodic box
//! returns to its initial profile, with an L1 error that falls as the resolution rises, in
//! 1D and 2D; and momentum is conserved per step to round-off.

mod common;
use common::{error, run_problem};

#[test]
fn advection_1d_converges() {
    let mut last = f64::INFINITY;
    for n in ["50", "100", "200"] {
        let r = run_problem::<1>("advection.toml", &[&format!("particles.n={n}")]);
        let l1 = error(&r.summary, "l1_density");
        eprintln!("advection 1D n={n}: L1 = {l1:.4e}");
        // The error is the O(h²) smoothing of the profile (h/Δx fixed at 2, see the problem
        // file): doubling n cuts it by ~4 (measured 3.7–3.9); demand a factor 3, i.e. second
        // order within noise.
        assert!(l1 < last / 3.0, "{l1} vs {last}");
        last = l1;
        let s = &r.summary.conservation;
        assert!(s.momentum_max_per_step < 1e-12, "{s:?}");
        // The pair terms conserve energy exactly; what remains is the O(Δt²) error of the
        // leapfrog with a velocity-dependent predictor (measured 1.4e-8 at n = 50).
        assert!(s.energy.unwrap() < 1e-6, "{s:?}");
    }
}

#[test]
fn advection_2d_converges() {
    let coarse = run_problem::<2>("advection2d.toml", &["particles.n=32", "output.interval=0"]);
    let fine = run_problem::<2>("advection2d.toml", &["particles.n=64", "output.interval=0"]);
    let (a, b) = (
        error(&coarse.summary, "l1_density"),
        error(&fine.summary, "l1_density"),
    );
    eprintln!("advection 2D: L1 n=32 {a:.4e}, n=64 {b:.4e}");
    assert!(b < 0.5 * a, "{b} vs {a}");
    assert!(b < 2e-3);
    assert!(fine.summary.conservation.momentum_max_per_step < 1e-12);
}
