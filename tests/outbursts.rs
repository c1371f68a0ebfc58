//! The dwarf-nova instability of `problems/outbursts.toml` (`physics::outbursts`), on a
//! coarse disk (h = 0.03 a, ~800 particles) for a fraction of an orbit:
//! - gas below Σ_max stays on the cold branch exactly: the relaxation replaces compression
//!   and dissipation, so u stays at u_c to round-off while the disk shears and the stream
//!   strikes it;
//! - gas above Σ_max heats towards the hot branch as u_h − u = (u_h − u_c) e^{−Ω t/β}, the
//!   exact solution of du/dt = −(u − u_h) Ω/β at fixed radius;
//! - `analyse outbursts` sees a hot disk cooling as an outburst in the dissipation light
//!   curve.

use std::f64::consts::TAU;

mod common;
use common::run_problem;

const GAMMA: f64 = 5.0 / 3.0;
const CS_COLD: f64 = 0.035;
const CS_HOT: f64 = 0.1;

fn branch_u(cs: f64) -> f64 {
    cs * cs / (GAMMA * (GAMMA - 1.0))
}

#[test]
fn below_sigma_max_the_gas_stays_exactly_on_the_cold_branch() {
    let run = run_problem::<2>(
        "outbursts.toml",
        &[
            "particles.h=0.03",
            "outbursts.sigma_max=1.0",
            "outbursts.sigma_min=0.5",
            &format!("time.end={}", 0.5 * TAU),
        ],
    );
    let p = &run.particles;
    let uc = branch_u(CS_COLD);
    let worst =
        p.u.iter()
            .map(|u| ((u - uc) / uc).abs())
            .fold(0.0, f64::max);
    // du/dt = −(u − u_c) Ω/β is exactly 0 at u = u_c: only round-off of u_c itself.
    assert!(worst < 1e-12, "largest |u − u_c|/u_c = {worst}");
    let monitor = std::fs::read_to_string(run.dir.path().join("monitor.csv")).unwrap();
    let rows = sphdisk::reports::outbursts::parse_monitor(&monitor).unwrap();
    assert!(rows.iter().all(|r| r.hot_mass == 0.0));
    // The stream's particles entered cold too (stream.cs = cs_cold).
    assert!(
        run.summary
            .mass_budget
            .as_ref()
            .unwrap()
            .flows
            .injected
            .particles
            > 0
    );
}

#[test]
fn above_sigma_max_the_gas_heats_on_the_thermal_time() {
    let beta = 2.0;
    let t_end = 0.6;
    let run = run_problem::<2>(
        "outbursts.toml",
        &[
            "particles.h=0.03",
            "outbursts.sigma_max=1e-6",
            "outbursts.sigma_min=1e-7",
            &format!("outbursts.beta={beta}"),
            &format!("time.end={t_end}"),
        ],
    );
    let p = &run.particles;
    let (uc, uh) = (branch_u(CS_COLD), branch_u(CS_HOT));
    // Gas of the initial disk between 0.2 and 0.35 a (away from the edges and the stream's
    // impact), where Ω t/β = 1.0–2.1 at the end: u_h − u has fallen by e^{−1} to e^{−2.1}.
    let gm1 = 1.0 / 1.1;
    let mut worst: f64 = 0.0;
    let mut count = 0;
    for i in 0..p.len() {
        let x = p.position(i);
        let r = x[0].hypot(x[1]);
        if !(0.2..0.35).contains(&r) {
            continue;
        }
        let omega = (gm1 / (r * r * r)).sqrt();
        let exact = uh - (uh - uc) * (-omega * t_end / beta).exp();
        worst = worst.max(((p.u[i] - exact) / (uh - uc)).abs());
        count += 1;
    }
    assert!(count > 100, "{count} particles in the annulus");
    // The exact solution holds at a fixed radius; the gas moves: the pressure rising 8.2×
    // sets the disk's edges expanding and its particles on epicycles of up to 3% in R
    // (measured), so Ω along a path differs by up to 4.5% from Ω at its end, which shifts
    // u by at most 4.5% · (Ω t/β) e^{−Ω t/β} ≤ 1.7% of u_h − u_c (the leapfrog's own error,
    // ~(Ω Δt)²/12 per step, is far smaller). A rate off by 2 would miss by > 20%.
    assert!(worst < 0.02, "largest |u − exact| / (u_h − u_c) = {worst}");
}

#[test]
fn the_analysis_sees_a_hot_disk_cooling_as_an_outburst() {
    // The disk and the stream start on the hot branch (stream.cs = cs_hot) with Σ far below
    // Σ_min everywhere, so the whole disk cools on β/Ω_K = 1.6 orbits at R = 0.3 (β = 60).
    // The cubic spline and the lighter stream keep the cold disk's own light (SPH's
    // transport) low enough at this coarse h for the 1-mag bar: with the problem file's
    // Wendland C4 and 2× stream the cooled disk stays within 1 mag of the hot one here.
    let run = run_problem::<2>(
        "outbursts.toml",
        &[
            "particles.h=0.03",
            "particles.kernel=cubic",
            "stream.particles_per_orbit=16",
            "stream.mass_per_orbit=3.2e-6",
            "stream.cs=0.1",
            "outbursts.sigma_max=1.0",
            "outbursts.sigma_min=0.5",
            "outbursts.beta=60",
            &format!("time.end={}", 10.0 * TAU),
        ],
    );
    let report = sphdisk::reports::outbursts::analyse_outbursts(run.dir.path()).unwrap();
    let f = &report.figures;
    // ν falls by (α_h/α_c)(c_h/c_c)² = 82 as the disk cools: the light from the start is
    // more than 1 mag above the cold disk's (quiescence: the 5% quantile after orbit 2), and
    // one outburst, under way from the first row, declines below the bar within the run.
    assert_eq!(f.outbursts.len(), 1, "{f:#?}");
    let o = &f.outbursts[0];
    assert!(o.start_orbit < 0.05, "{o:?}");
    assert!(o.end_orbit > 1.0 && o.end_orbit < 9.0, "{o:?}");
    assert!(o.peak_mag > 2.0 && o.hot_fraction_max > 0.9, "{o:?}");
    assert!(!o.superoutburst);
    assert!(
        f.notes.iter().any(|n| n.contains("under way")),
        "{:?}",
        f.notes
    );
    assert!(run.dir.path().join("outbursts.png").exists());
    assert!(run.dir.path().join("outbursts.json").exists());
}
