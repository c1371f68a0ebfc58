//! Guards the shock-capturing hydrodynamics against the exact Riemann solution of the Sod
//! tube at t = 0.2: L1 errors that shrink with resolution, the shock and contact where the
//! exact solution puts them, and total energy conserved by the scheme.

mod common;
use common::{error, run_problem};

#[test]
fn sod_1d_converges_and_places_shock_and_contact() {
    let mut last = [f64::INFINITY; 3];
    for n in ["200", "400", "800"] {
        let r = run_problem::<1>(
            "sod.toml",
            &[&format!("particles.n={n}"), "output.interval=0"],
        );
        let s = &r.summary;
        let l1 = [
            error(s, "l1_density"),
            error(s, "l1_velocity"),
            error(s, "l1_pressure"),
        ];
        eprintln!(
            "sod n={n}: L1 rho {:.4e} v {:.4e} p {:.4e}",
            l1[0], l1[1], l1[2]
        );
        // Convergence: every norm must fall as the resolution doubles. SPH with artificial
        // viscosity converges at about first order at discontinuities, so a halving of the
        // spacing lowers the norms by ~1.5–2; requiring a 10% drop is robust yet fails if
        // resolution stops helping.
        for k in 0..3 {
            assert!(
                l1[k] < 0.9 * last[k],
                "L1[{k}] did not fall at n = {n}: {l1:?} vs {last:?}"
            );
        }
        last = l1;
        // The bar: fronts within 2 particle spacings of the exact positions.
        assert!(error(s, "shock_offset_spacings") < 2.0);
        assert!(error(s, "contact_offset_spacings") < 2.0);
        // Energy: KDK is second order and the pair terms conserve energy exactly; the walls
        // are static. 1e-3 is the bar (measured ~2e-6).
        let de = s.conservation.energy.expect("ideal gas");
        assert!(de < 1e-3, "energy drift {de}");
        // The walls push: dP/dt = p_left − p_right = 0.9 until the waves reach them, so the
        // momentum at t = 0.2 is 0.18 (a conservation law with a boundary force).
        let p = s.totals_end.momentum[0];
        assert!((p - 0.18).abs() < 1e-3, "momentum {p}");
    }
    // Absolute accuracy at the finest resolution (measured 0.0047 / 0.0116 / 0.0048).
    assert!(
        last[0] < 0.01 && last[1] < 0.02 && last[2] < 0.01,
        "{last:?}"
    );
}

#[test]
fn sod_3d_matches_the_1d_tube() {
    let r = run_problem::<3>("sod3d.toml", &["particles.n=48", "sod.width=0.11"]);
    let s = &r.summary;
    eprintln!("sod3d: {:?}", s.errors);
    assert!(error(s, "shock_offset_spacings") < 2.0);
    assert!(error(s, "contact_offset_spacings") < 2.0);
    // Coarser than the 1D runs (h is set by the right lattice): L1 of a few 1e-2.
    assert!(error(s, "l1_density") < 0.03);
    assert!(error(s, "l1_pressure") < 0.03);
    let de = s.conservation.energy.expect("ideal gas");
    assert!(de < 1e-3, "energy drift {de}");
    // y and z are periodic and the set-up symmetric: no transverse momentum may appear
    // beyond round-off.
    for d in 1..3 {
        let p = s.totals_end.momentum[d];
        assert!(p.abs() < 1e-12, "transverse momentum {d}: {p}");
    }
}

/// The strong shock (Toro's test 3) and Lax's tube with `problems/strong_shock.toml` and
/// `problems/lax.toml` as they stand (quintic spline, h = 2 spacings): the errors fall at
/// about first order and the fronts stay within a spacing of the exact ones. (With the
/// cubic spline at h = 1.5 spacings the strong shock's L1 stays at 0.047 and its shock lags
/// by a constant distance: 16, 31, 63 spacings at n = 400, 800, 1600.)
#[test]
fn strong_shock_and_lax_converge_with_the_quintic_spline() {
    for file in ["strong_shock.toml", "lax.toml"] {
        let mut last = [f64::INFINITY; 3];
        for n in ["400", "800"] {
            let r = run_problem::<1>(file, &[&format!("particles.n={n}"), "output.interval=0"]);
            let s = &r.summary;
            let l1 = [
                error(s, "l1_density"),
                error(s, "l1_velocity"),
                error(s, "l1_pressure"),
            ];
            eprintln!("{file} n={n}: L1 {l1:?}, {:?}", s.errors);
            // First order halves the norms from n = 400 to 800 (measured 0.50–0.58 of
            // them); 0.75 fails a scheme that stops converging.
            for k in 0..3 {
                assert!(
                    l1[k] < 0.75 * last[k],
                    "{file} L1[{k}] at n = {n}: {l1:?} vs {last:?}"
                );
            }
            last = l1;
            // Measured 0.38–0.63 spacings for the shock, 0.08–0.18 for the contact.
            assert!(error(s, "shock_offset_spacings") < 1.0, "{file} n = {n}");
            assert!(error(s, "contact_offset_spacings") < 0.5, "{file} n = {n}");
            let de = s.conservation.energy.expect("ideal gas");
            assert!(de < 1e-4, "energy drift {de}");
        }
    }
}

/// A contact at rest (t = 0.5), three ways. The paper's density–energy form: the largest
/// |p − p*|/p* by the contact is 1.19 at n = 200. Price's (2008) conductivity with its
/// pressure signal brings it to 0.073, but the heat it conducts expands the dense side: the
/// gas that started on the left ends 2.5 spacings further right (measured). The problem
/// file's pressure–energy form with the velocity-signal conductivity meets the bars
/// at n = 200 and 400: blip below 5% (measured 0.05–0.06%) and the gas's edge within 0.1
/// spacing of the diaphragm (measured 0.008 and 0.015). Total energy stays conserved
/// (every pair exchanges heat and work antisymmetrically; measured 1e-6, 3e-7 and 2e-9).
#[test]
fn a_stationary_contact_keeps_its_pressure_and_its_place() {
    let run = |n: &str, sets: &[&str]| {
        let n = format!("particles.n={n}");
        let mut all = vec![n.as_str(), "output.interval=0"];
        all.extend_from_slice(sets);
        let r = run_problem::<1>("stationary_contact.toml", &all);
        let s = &r.summary;
        eprintln!("stationary contact {all:?}: {:?}", s.errors);
        let de = s.conservation.energy.expect("ideal gas");
        assert!(de < 1e-5, "energy drift {de}");
        (
            error(s, "contact_pressure_blip"),
            error(s, "contact_mass_offset_spacings"),
        )
    };
    let paper = [
        "hydro.scheme=density_energy",
        "particles.kernel=cubic",
        "particles.h_factor=1.5",
        "artificial_viscosity.conductivity=0",
    ];
    let (without, _) = run("200", &paper);
    let mut conducting = paper.to_vec();
    conducting.extend([
        "artificial_viscosity.conductivity=1.0",
        "artificial_viscosity.conductivity_signal=pressure",
    ]);
    let (with, moved) = run("200", &conducting);
    assert!(without > 0.5, "{without}");
    assert!(with < 0.1 * without, "with {with}, without {without}");
    assert!(moved > 1.0, "the conducted heat moves the gas: {moved}");
    for n in ["200", "400"] {
        let (blip, drift) = run(n, &[]);
        assert!(blip < 0.05, "pressure–energy blip {blip} at n = {n}");
        assert!(
            drift < 0.1,
            "pressure–energy drift {drift} spacings at n = {n}"
        );
    }
}

/// Sod with the pressure–energy formulation and the velocity-signal conductivity, at the
/// problem file's kernel and h: as accurate as the density–energy form (L1 ρ measured
/// 9.10e-3 vs 9.11e-3 at n = 400, 4.68e-3 vs 4.70e-3 at 800; 10% allows for the two
/// schemes' different errors at the contact) with the blip below the 5% (measured
/// 1.2% and 0.45%, against 7.9% and 8.3%), and total energy conserved.
#[test]
fn sod_with_pressure_energy_is_as_accurate_without_the_blip() {
    for n in ["400", "800"] {
        let n = format!("particles.n={n}");
        let de = run_problem::<1>("sod.toml", &[n.as_str(), "output.interval=0"]);
        let pe = run_problem::<1>(
            "sod.toml",
            &[
                n.as_str(),
                "output.interval=0",
                "hydro.scheme=pressure_energy",
                "artificial_viscosity.conductivity=1",
                "artificial_viscosity.conductivity_signal=velocity",
            ],
        );
        let (d, p) = (&de.summary, &pe.summary);
        eprintln!(
            "sod {n}: density–energy {:?}\npressure–energy {:?}",
            d.errors, p.errors
        );
        let (l1_de, l1_pe) = (error(d, "l1_density"), error(p, "l1_density"));
        assert!(l1_pe < 1.1 * l1_de, "{l1_pe} vs {l1_de}");
        assert!(error(p, "contact_pressure_blip") < 0.05);
        assert!(error(d, "contact_pressure_blip") > 0.05);
        // KDK's truncation error, as for density–energy (measured 5.4e-6 and 2.2e-6).
        assert!(p.conservation.energy.expect("ideal gas") < 1e-4);
    }
}
