//! Guards the sweep (paper, Section 2.1): on random, clustered and periodic particle sets it
//! finds exactly the pairs a brute-force search finds, and its three sums equal a
//! straightforward full-pair-list evaluation (minimum-image distances, no ghosts) to round-off.

use sphdisk::boundary::{BoundaryKind, SimBox};
use sphdisk::kernel::{Kernel, KernelKind};
use sphdisk::particles::Particles;
use sphdisk::physics::artificial_viscosity::{ArtificialViscosity, ConductivitySignal};
use sphdisk::physics::av_switch::SwitchKind;
use sphdisk::physics::eos::Eos;
use sphdisk::physics::pressure_energy::Scheme;
use sphdisk::rng::Rng;
use sphdisk::sweep::local::Local;
use sphdisk::sweep::reference::{brute_force_pairs, full_list_minimum_image};
use sphdisk::sweep::{BATCH_PARTICLES_PER_THREAD, Physics, Window, all_pairs, evaluate};

/// `n` particles in the unit box: uniform, or (clustered) half of them in two tight blobs.
fn random_set<const D: usize>(n: usize, clustered: bool, seed: u64) -> Particles<D> {
    let mut rng = Rng::new(seed);
    let mut p = Particles::new();
    for i in 0..n {
        let pos: [f64; D] = if clustered && i % 2 == 0 {
            let c = if i % 4 == 0 { 0.25 } else { 0.9 };
            std::array::from_fn(|_| (c + 0.04 * rng.normal()).rem_euclid(1.0))
        } else {
            std::array::from_fn(|_| rng.uniform())
        };
        let vel: [f64; D] = std::array::from_fn(|_| rng.normal());
        let m = 0.5 + rng.uniform();
        let u = 1.0 + rng.uniform();
        p.push(i as u64, pos, vel, m, u);
    }
    p
}

fn unit_box<const D: usize>(kinds: [BoundaryKind; D]) -> SimBox<D> {
    SimBox {
        min: [0.0; D],
        max: [1.0; D],
        kinds,
    }
}

fn check_pairs<const D: usize>(p: &Particles<D>, bx: &SimBox<D>, h: f64) {
    check_pairs_with(p, bx, Kernel::<D>::new(h));
}

fn check_pairs_with<const D: usize>(p: &Particles<D>, bx: &SimBox<D>, k: Kernel<D>) {
    let local = Local::build(p, bx, k.support());
    let mut found = all_pairs(&local, &k);
    let mut brute = brute_force_pairs(&local, k.support());
    let n_found = found.len();
    found.sort_unstable();
    found.dedup();
    assert_eq!(found.len(), n_found, "a pair was found twice");
    brute.sort_unstable();
    assert!(!brute.is_empty());
    assert_eq!(found, brute, "sweep pairs differ from brute force");
}

#[test]
fn pairs_equal_brute_force_in_1d_2d_3d_all_boundaries() {
    use BoundaryKind::*;
    for (seed, clustered) in [(1, false), (2, true)] {
        for kind in [Periodic, Reflecting, Open] {
            check_pairs(
                &random_set::<1>(300, clustered, seed),
                &unit_box([kind]),
                0.02,
            );
            check_pairs(
                &random_set::<2>(600, clustered, seed),
                &unit_box([kind; 2]),
                0.04,
            );
            check_pairs(
                &random_set::<3>(1500, clustered, seed),
                &unit_box([kind; 3]),
                0.06,
            );
        }
        check_pairs(
            &random_set::<3>(1500, clustered, seed),
            &unit_box([Periodic, Reflecting, Open]),
            0.07,
        );
        check_pairs(
            &random_set::<2>(800, clustered, seed),
            &unit_box([Reflecting, Periodic]),
            0.05,
        );
    }
}

/// Largest |a − b| over the particles relative to the largest |b|: the sums differ only in
/// the order of their terms, so a few ε times the number of terms (≤ 1e-13 here) is
/// round-off; 1e-10 leaves room without hiding a missing or doubled pair (which shows at
/// the percent level).
fn rel_max_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-300);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

fn check_sums<const D: usize>(p: Particles<D>, bx: &SimBox<D>, h: f64) {
    check_sums_with(p, bx, Kernel::<D>::new(h));
}

fn check_sums_with<const D: usize>(p: Particles<D>, bx: &SimBox<D>, kernel: Kernel<D>) {
    check_sums_av(
        p,
        bx,
        kernel,
        ArtificialViscosity {
            alpha: 1.0,
            beta: 2.0,
            balsara: true,
            ..ArtificialViscosity::default()
        },
    );
}

fn check_sums_av<const D: usize>(
    p: Particles<D>,
    bx: &SimBox<D>,
    kernel: Kernel<D>,
    av: ArtificialViscosity,
) {
    let phys = Physics::hydro(kernel, Eos::Ideal { gamma: 5.0 / 3.0 }, av);
    check_sums_phys(p, bx, &phys);
}

fn check_sums_phys<const D: usize>(mut p: Particles<D>, bx: &SimBox<D>, phys: &Physics<D>) {
    let phys = *phys;
    let mut reference = p.clone();
    full_list_minimum_image(&mut reference, bx, &phys);
    let stats = evaluate(&mut p, bx, &phys, Window::SWEEP);
    assert!(stats.pairs > 0);
    let tol = 1e-10;
    let dr = rel_max_diff(&p.rho, &reference.rho);
    assert!(dr < tol, "density, {D}D {:?}: {dr}", bx.kinds);
    assert_eq!(p.interactions, reference.interactions);
    for a in 0..D {
        assert!(rel_max_diff(&p.acc[a], &reference.acc[a]) < tol, "acc[{a}]");
        for b in 0..D {
            let d = rel_max_diff(&p.vgrad[a][b], &reference.vgrad[a][b]);
            assert!(d < tol, "vgrad[{a}][{b}] {d}");
        }
    }
    assert!(rel_max_diff(&p.du, &reference.du) < tol, "du");
    assert!(rel_max_diff(&p.diss, &reference.diss) < tol, "dissipation");
    assert!(rel_max_diff(&p.p, &reference.p) < tol, "pressure");
    assert!(rel_max_diff(&p.cs, &reference.cs) < tol, "sound speed");
}

/// The pressure–energy formulation (p̄ = (γ − 1) Σ m u W, physics::pressure_energy) with the
/// velocity-signal conductivity: the sweep's p̄ (the density stage's extra sum, folded at
/// periodic images), accelerations and du/dt equal the full pair list's, and they differ
/// from the density–energy sums (u varies by a factor 2 between particles, so p̄ ≠ (γ−1)ρu).
#[test]
fn pressure_energy_sums_equal_the_full_pair_list() {
    use BoundaryKind::*;
    let av = ArtificialViscosity {
        alpha: 1.0,
        beta: 2.0,
        conductivity: 1.0,
        conductivity_signal: ConductivitySignal::Velocity,
        ..ArtificialViscosity::default()
    };
    fn with_scheme<const D: usize>(h: f64, av: ArtificialViscosity, scheme: Scheme) -> Physics<D> {
        Physics {
            scheme,
            ..Physics::hydro(Kernel::new(h), Eos::Ideal { gamma: 5.0 / 3.0 }, av)
        }
    }
    for (seed, clustered) in [(11, false), (12, true)] {
        check_sums_phys(
            random_set::<1>(300, clustered, seed),
            &unit_box([Periodic]),
            &with_scheme(0.02, av, Scheme::PressureEnergy),
        );
        for kinds in [[Periodic; 2], [Open, Periodic]] {
            let p = random_set::<2>(700, clustered, seed);
            check_sums_phys(
                p.clone(),
                &unit_box(kinds),
                &with_scheme(0.04, av, Scheme::PressureEnergy),
            );
            let (mut a, mut b) = (p.clone(), p);
            evaluate(
                &mut a,
                &unit_box(kinds),
                &with_scheme(0.04, av, Scheme::PressureEnergy),
                Window::SWEEP,
            );
            let de = with_scheme(0.04, av, Scheme::DensityEnergy);
            evaluate(&mut b, &unit_box(kinds), &de, Window::SWEEP);
            assert!(rel_max_diff(&a.p, &b.p) > 0.05);
            // The random velocities' artificial viscosity dominates the accelerations, so
            // they differ less (measured 2.6% and 7.7% of the largest); round-off is 1e-15.
            assert!(rel_max_diff(&a.acc[0], &b.acc[0]) > 0.01);
            assert!(rel_max_diff(&a.du, &b.du) > 0.02);
        }
        check_sums_phys(
            random_set::<3>(1500, clustered, seed),
            &unit_box([Open, Periodic, Periodic]),
            &with_scheme(0.06, av, Scheme::PressureEnergy),
        );
    }
}

#[test]
fn three_sums_equal_full_pair_list_periodic_and_open() {
    use BoundaryKind::*;
    for (seed, clustered) in [(3, false), (4, true)] {
        check_sums(
            random_set::<1>(300, clustered, seed),
            &unit_box([Periodic]),
            0.02,
        );
        check_sums(
            random_set::<2>(700, clustered, seed),
            &unit_box([Periodic; 2]),
            0.04,
        );
        check_sums(
            random_set::<3>(1500, clustered, seed),
            &unit_box([Periodic; 3]),
            0.06,
        );
        check_sums(
            random_set::<2>(700, clustered, seed),
            &unit_box([Open; 2]),
            0.04,
        );
        check_sums(
            random_set::<3>(1500, clustered, seed),
            &unit_box([Open, Periodic, Periodic]),
            0.06,
        );
    }
}

/// With the Morris–Monaghan switch each particle brings its own α (α_ij = ½(α_i + α_j)),
/// through periodic images too; the sweep's sums equal the full pair list's,
/// and they differ from the constant-α sums (the per-particle α is not ignored).
#[test]
fn per_particle_alpha_of_the_switch_equals_the_full_pair_list() {
    use BoundaryKind::*;
    let av = ArtificialViscosity {
        alpha: 1.0,
        beta: 2.0,
        balsara: true,
        switch: SwitchKind::MorrisMonaghan,
        ..ArtificialViscosity::default()
    };
    let with_alpha = |mut p: Particles<2>, seed: u64| {
        let mut rng = Rng::new(seed);
        for a in p.alpha.iter_mut() {
            *a = 0.1 + 0.9 * rng.uniform();
        }
        p
    };
    for kinds in [[Periodic; 2], [Open; 2], [Open, Periodic]] {
        let bx = unit_box(kinds);
        let p = with_alpha(random_set::<2>(700, true, 8), 9);
        check_sums_av(p.clone(), &bx, Kernel::new(0.04), av);
        let mut sw = p.clone();
        let mut constant = p;
        let phys_sw = Physics::hydro(Kernel::new(0.04), Eos::Ideal { gamma: 5.0 / 3.0 }, av);
        let phys_c = Physics::hydro(
            Kernel::new(0.04),
            Eos::Ideal { gamma: 5.0 / 3.0 },
            ArtificialViscosity {
                switch: SwitchKind::None,
                ..av
            },
        );
        evaluate(&mut sw, &bx, &phys_sw, Window::SWEEP);
        evaluate(&mut constant, &bx, &phys_c, Window::SWEEP);
        // α_i averages 0.55 against 1: the viscous heating differs by tens of per cent.
        assert!(rel_max_diff(&sw.diss, &constant.diss) > 0.05);
    }
}

/// Every kernel: the grid and the ghosts take its support (3h for the quintic spline), so
/// the sweep still finds exactly the brute-force pairs and the full pair list's sums.
#[test]
fn every_kernel_finds_the_same_pairs_and_sums() {
    use BoundaryKind::*;
    for kind in KernelKind::ALL {
        let k1 = Kernel::<1>::of_kind(kind, 0.02);
        let k2 = Kernel::<2>::of_kind(kind, 0.04);
        let k3 = Kernel::<3>::of_kind(kind, 0.05);
        for (seed, clustered) in [(5, false), (6, true)] {
            for bk in [Periodic, Reflecting, Open] {
                check_pairs_with(&random_set::<1>(300, clustered, seed), &unit_box([bk]), k1);
                check_pairs_with(
                    &random_set::<2>(600, clustered, seed),
                    &unit_box([bk; 2]),
                    k2,
                );
                check_pairs_with(
                    &random_set::<3>(1200, clustered, seed),
                    &unit_box([bk; 3]),
                    k3,
                );
            }
            check_sums_with(
                random_set::<1>(300, clustered, seed),
                &unit_box([Periodic]),
                k1,
            );
            check_sums_with(
                random_set::<2>(700, clustered, seed),
                &unit_box([Periodic; 2]),
                k2,
            );
            check_sums_with(
                random_set::<3>(1200, clustered, seed),
                &unit_box([Open, Periodic, Periodic]),
                k3,
            );
        }
    }
}

/// Runs `f` in a pool of two threads (the batch is per thread).
fn on_two_threads<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn full_list_window_gives_identical_results_with_more_memory() {
    let bx = unit_box([BoundaryKind::Periodic; 3]);
    let phys = Physics::hydro(
        Kernel::<3>::new(0.03),
        Eos::Isothermal { cs: 1.0 },
        ArtificialViscosity::default(),
    );
    // 40 000 particles in 16 slabs: on two threads each slab holds more than a batch of
    // small slabs (`sweep::BATCH_PARTICLES_PER_THREAD` = 1024 per thread), so slabs enter the
    // sweep one at a time, as in any large run.
    on_two_threads(|| {
        let mut a = random_set::<3>(40_000, false, 9);
        let mut b = a.clone();
        let sa = evaluate(&mut a, &bx, &phys, Window::SWEEP);
        let sb = evaluate(&mut b, &bx, &phys, Window::FULL_LIST);
        assert_eq!(a.acc, b.acc);
        assert_eq!(sa.pairs, sb.pairs);
        assert_eq!(sb.peak_pairs as u64, sb.pairs);
        assert!(
            (sa.peak_pairs as f64) < 0.5 * sb.peak_pairs as f64,
            "window {} vs full {}",
            sa.peak_pairs,
            sb.peak_pairs
        );
    });
}

/// The batch (`[sweep] batch_per_thread`, the paper's delay) trades memory for fewer parallel
/// regions and changes no result: one slab at a time, the default, a few slabs at a time and
/// every slab in one batch give the same accelerations, energies and densities to the bit,
/// while the window grows with the batch. With a periodic x axis the first slabs wait for the
/// last, and by a reflecting wall the mirror images wait for their owners: there a block
/// becomes ready before the block before it, at a point that depends on the batch, and its
/// terms must still be merged after that block's (a reflecting wall gave 157 accelerations
/// that differed at round-off, batch 4 096 against 1, when they were merged as they came).
#[test]
fn the_batch_changes_the_window_and_no_result() {
    use BoundaryKind::{Open, Periodic, Reflecting};
    for kinds in [
        [Periodic; 3],
        [Reflecting, Periodic, Periodic],
        [Open, Reflecting, Periodic],
    ] {
        batch_changes_no_result(unit_box(kinds));
    }
}

fn batch_changes_no_result(bx: SimBox<3>) {
    let phys = Physics::hydro(
        Kernel::<3>::new(0.03),
        Eos::Ideal { gamma: 5.0 / 3.0 },
        ArtificialViscosity::default(),
    );
    on_two_threads(|| {
        let base = random_set::<3>(40_000, false, 5);
        let run = |batch: usize| {
            let mut p = base.clone();
            let st = evaluate(&mut p, &bx, &phys, Window::SWEEP.with_batch(batch));
            (p, st)
        };
        let (a, sa) = run(1);
        let mut peaks = vec![sa.peak_pairs];
        for batch in [BATCH_PARTICLES_PER_THREAD, 4096, 1 << 30] {
            let (b, sb) = run(batch);
            // Compared whole, to the bit (a failure names the field, not 40 000 values).
            assert!(a.acc == b.acc, "batch {batch}: accelerations differ");
            assert!(a.du == b.du, "batch {batch}: du/dt differs");
            assert!(a.rho == b.rho, "batch {batch}: densities differ");
            assert!(
                a.vgrad == b.vgrad,
                "batch {batch}: velocity gradients differ"
            );
            assert_eq!(sa.pairs, sb.pairs, "batch {batch}");
            peaks.push(sb.peak_pairs);
        }
        // 40 000 particles in 16 slabs of ~2 500 on two threads: batches of one slab (for 1
        // and 1 024 per thread: a slab holds more than 2 × 1 024), of four (until they hold
        // 2 × 4 096), and of all sixteen.
        assert_eq!(peaks[0], peaks[1], "{peaks:?}");
        assert!(peaks[1] < peaks[2] && peaks[2] < peaks[3], "{peaks:?}");
        assert_eq!(
            peaks[3] as u64, sa.pairs,
            "one batch holds every pair: {peaks:?}"
        );
    });
}

/// A mostly empty open box (a dense clump and a few particles far out, as a binary's disk
/// and its escaping gas): the grid index is sparse, and the pairs and sums are still exactly
/// those of brute force and of the full pair list.
#[test]
fn sparse_grid_of_a_mostly_empty_box_finds_the_same_pairs_and_sums() {
    let mut rng = Rng::new(11);
    let mut p = Particles::<3>::new();
    for i in 0..1200 {
        let far = i % 100 == 0;
        let pos: [f64; 3] = std::array::from_fn(|_| {
            if far {
                0.5 + 0.5 * (2.0 * rng.uniform() - 1.0)
            } else {
                0.5 + 0.01 * rng.normal()
            }
        });
        let vel: [f64; 3] = std::array::from_fn(|_| rng.normal());
        p.push(i as u64, pos, vel, 1.0, 1.0 + rng.uniform());
    }
    let bx = unit_box([BoundaryKind::Open; 3]);
    let h = 0.004;
    let local = Local::build(&p, &bx, Kernel::<3>::new(h).support());
    assert!(local.cells.is_sparse(), "the grid of this box is sparse");
    assert!(
        local.cells.bytes() < 100 * p.len(),
        "index {} bytes for {} particles",
        local.cells.bytes(),
        p.len()
    );
    check_pairs(&p, &bx, h);
    check_sums(p, &bx, h);
}
