//! Guards the heart of the paper (Section 3.1): the viscously spreading ring, evolved by the
//! physical viscosity of Eqs. (8)–(10) alone, follows the exact Lüst/Pringle solution; the
//! run can be checked from its own output; accretion keeps an exact mass ledger.

mod common;
use common::{error, run_problem};

use sphdisk::reports::ring::analyse_ring;

#[test]
fn ring_follows_the_exact_solution() {
    // n = 32 rings per R0 (4 300 particles), between the resolutions in the
    // closing note (n = 25: 9.8, 2.8, 4.7%; n = 50: 4.2, 2.6, 5.9% at τ = 0.032, 0.064,
    // 0.128; early errors are the kernel smoothing the narrow ring, later ones noise); the
    // bar of 10% fails if the viscous spreading rate is off by more than ~10% (a ring that
    // spreads at 0.8 ν already misses by 15% at τ = 0.128).
    let r = run_problem::<2>("ring.toml", &["particles.n=32"]);
    let s = &r.summary;
    let ring = s.ring.as_ref().expect("summary has the ring entry");
    assert_eq!(
        (ring.mass, ring.r0, ring.nu, ring.gm),
        (1.0, 1.0, 1e-3, 1.0)
    );
    assert!((error(s, "ring_tau") - 0.128).abs() < 1e-12);
    let report = analyse_ring(r.dir.path()).expect("analysis runs");
    let taus: Vec<f64> = report.l1.iter().map(|x| x.0).collect();
    assert_eq!(taus.len(), 3, "{taus:?}");
    for (tau, l1) in &report.l1 {
        eprintln!("ring n=32: tau {tau:.3} L1 {:.2}%", 100.0 * l1);
        assert!(*l1 < 0.10, "tau {tau}: L1 {l1}");
    }
    for f in &report.files {
        assert!(std::fs::metadata(f).unwrap().len() > 0, "{}", f.display());
    }
    // The particles keep to their rings (0.031 R0 apart at the start, further as the
    // ring spreads): most annuli of 0.01 R0 are empty, as the summary records too.
    let (tau_end, empty_end) = *report.empty_annuli.last().unwrap();
    assert!((tau_end - 0.128).abs() < 1e-12);
    assert_eq!(error(s, "ring_empty_annuli"), empty_end);
    for (tau, empty) in &report.empty_annuli {
        eprintln!("ring n=32: tau {tau:.3} empty annuli {:.1}%", 100.0 * empty);
        assert!(*empty > 0.3, "tau {tau}: {empty}");
    }
    // Angular momentum: SPH's shear viscosity conserves it only approximately; measured
    // 3e-4 over the run. 1% would mean a torque error comparable to the viscous torque.
    let dl = s
        .conservation
        .angular_momentum
        .expect("2D run with rotation");
    eprintln!("ring n=32: angular momentum drift {dl:.2e}");
    assert!(dl < 1e-2);
    assert_eq!(s.conservation.mass, 0.0);
}

#[test]
fn jittered_rings_stay_continuous() {
    // Each particle's radius spread across its ring's spacing (n = 25: 0.04 R0, four
    // annuli) with the Wendland C4 kernel: the spreading flow stretches the radii apart
    // but cannot open a gap between particles that start at every radius, so no annulus
    // where the exact Σ exceeds 10% of its peak is empty at any τ (on rings, 82–91% are:
    // BENCHMARKS.md). A regrouping of the particles onto rings would fail this.
    let r = run_problem::<2>(
        "ring.toml",
        &[
            "particles.n=25",
            "particles.kernel=wendland_c4",
            "ring.radial_jitter=1",
        ],
    );
    let report = analyse_ring(r.dir.path()).expect("analysis runs");
    assert_eq!(report.empty_annuli.len(), 3);
    for ((tau, l1), (_, empty)) in report.l1.iter().zip(&report.empty_annuli) {
        eprintln!(
            "jittered ring n=25: tau {tau:.3} L1 {:.2}% empty annuli {:.1}%",
            100.0 * l1,
            100.0 * empty
        );
        assert_eq!(*empty, 0.0, "tau {tau}");
    }
    assert_eq!(error(&r.summary, "ring_empty_annuli"), 0.0);
}

#[test]
fn accretion_ledger_balances_to_round_off() {
    // An accretion radius inside the ring: mass drifts in and is removed; particles plus
    // ledger must add up to the initial mass to round-off.
    let r = run_problem::<2>(
        "ring.toml",
        &[
            "particles.n=20",
            "gravity.accretion_radius=0.6",
            "ring.tau_end=0.064",
        ],
    );
    let s = &r.summary;
    let acc = s.accretion.as_ref().expect("ledger present");
    eprintln!(
        "accreted {} particles, mass {:.4e}",
        acc.particles, acc.mass
    );
    assert!(acc.particles > 0, "nothing reached the accretion radius");
    let total = s.totals_end.mass + acc.mass;
    assert!(
        (total - s.totals_start.mass).abs() < 1e-14 * s.totals_start.mass,
        "{total} vs {}",
        s.totals_start.mass
    );
    assert!(s.conservation.mass < 1e-14);
    assert_eq!(s.particles as u64 + acc.particles, r_initial_count(&r));
}

fn r_initial_count(r: &common::Run<2>) -> u64 {
    let snaps = sphdisk::io::snapshot_index::SnapshotIndex::read(r.dir.path()).unwrap();
    let first = r.dir.path().join(&snaps.snapshots[0].file);
    sphdisk::io::hdf5::read_snapshot(&first).unwrap().len() as u64
}
