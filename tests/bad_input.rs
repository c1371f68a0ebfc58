//! Guards the command line against bad input: each mistake ends the program with a non-zero
//! exit code and one clear line on stderr naming the key or value at fault — never a panic.

use std::path::Path;

mod common;
use common::problem_file as problem;

/// Runs `sphdisk` with `args` in `dir`; returns (exit code, stderr).
fn sphdisk(dir: &Path, args: &[&str]) -> (i32, String) {
    let (code, _, err) = common::sphdisk_cli(Some(dir), args);
    (code, err)
}

/// Asserts a clean failure whose single line mentions every word in `expect`.
fn assert_fails(dir: &Path, args: &[&str], expect: &[&str]) {
    let (code, err) = sphdisk(dir, args);
    assert_ne!(code, 0, "{args:?} should fail");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one line, got {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for e in expect {
        assert!(err.contains(e), "{args:?}: `{e}` not in: {err}");
    }
}

const FILE_PROBLEM: &str = r#"
[problem]
kind = "file"
dimension = 1
[particles]
h = 0.05
[eos]
kind = "ideal"
gamma = 1.4
[boundary]
x = "periodic"
[time]
end = 0.01
[domain]
min = [0.0]
max = [1.0]
[initial]
file = "ic.csv"
"#;

/// A problem reading particles from `ic.csv`, one of which has the given mass and x.
fn file_problem(dir: &Path, mass: &str, x: &str) -> String {
    let mut csv = String::from("id,x,y,z,vx,vy,vz,m,h,rho,u,p\n");
    for i in 0..40 {
        let (m, xx) = if i == 7 {
            (mass.to_string(), x.to_string())
        } else {
            ("0.025".to_string(), format!("{}", (i as f64 + 0.5) / 40.0))
        };
        csv.push_str(&format!("{i},{xx},0,0,0,0,0,{m},0.05,1,1,1\n"));
    }
    std::fs::write(dir.join("ic.csv"), csv).unwrap();
    let path = dir.join("file.toml");
    std::fs::write(&path, FILE_PROBLEM).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn unknown_key_is_named() {
    let d = tempfile::tempdir().unwrap();
    let p = problem("sod.toml");
    assert_fails(
        d.path(),
        &["run", &p, "--set", "particles.nn=3"],
        &["particles", "nn"],
    );
    let bad = d.path().join("typo.toml");
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace("gamma = 1.4", "gama = 1.4");
    std::fs::write(&bad, text).unwrap();
    assert_fails(
        d.path(),
        &["check", bad.to_str().unwrap()],
        &["eos", "gama"],
    );
}

#[test]
fn a_key_that_does_not_apply_to_the_problem_is_named() {
    let d = tempfile::tempdir().unwrap();
    for (file, set, key) in [
        ("sod.toml", "gravity.gm=1", "gravity.gm"),
        ("sedov.toml", "gravity.gm=1", "gravity.gm"),
        ("ring.toml", "sedov.energy=2", "sedov.energy"),
        ("sod.toml", "disk.r_in=0.5", "disk.r_in"),
        ("sedov.toml", "binary.q=0.1", "binary.q"),
        ("cv2d.toml", "particles.n=100", "particles.n"),
        (
            "ring.toml",
            "output.lightcurve_interval=0.1",
            "output.lightcurve_interval",
        ),
    ] {
        assert_check_and_run_fail(
            d.path(),
            &problem(file),
            &[set],
            &[
                &format!("key `{key}` does not apply"),
                "problem.kind",
                &format!("--set {set}"),
            ],
        );
    }
    // In the file itself: the error names the file and the key.
    let sod = d.path().join("sod_with_gravity.toml");
    let text = std::fs::read_to_string(problem("sod.toml")).unwrap();
    std::fs::write(&sod, format!("{text}\n[gravity]\ngm = 1.0\n")).unwrap();
    let (code, err) = sphdisk(d.path(), &["check", sod.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("sod_with_gravity.toml") && err.contains("key `gravity.gm` does not apply"),
        "{err}"
    );
}

#[test]
fn set_errors_name_the_override_not_the_file() {
    let d = tempfile::tempdir().unwrap();
    let p = problem("sod.toml");
    for (set, words) in [
        ("foo.bar=1", &["--set foo.bar=1", "foo"][..]),
        (
            "particles.h_factor=-2",
            &["--set particles.h_factor=-2", "particles.h_factor"],
        ),
        ("eos.gamma=abc", &["--set eos.gamma=abc", "eos"]),
    ] {
        let (code, err) = sphdisk(d.path(), &["check", &p, "--set", set]);
        assert_ne!(code, 0);
        for w in words {
            assert!(err.contains(w), "`{w}` not in: {err}");
        }
        assert!(!err.contains("sod.toml"), "names the file: {err}");
    }
}

#[test]
fn missing_required_key_is_named() {
    let d = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(problem("sod.toml"))
        .unwrap()
        .replace("end = 0.2", "");
    let f = d.path().join("noend.toml");
    std::fs::write(&f, text).unwrap();
    assert_fails(d.path(), &["check", f.to_str().unwrap()], &["time", "end"]);
}

#[test]
fn negative_or_zero_mass_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let f = file_problem(d.path(), "-1.0", "0.19");
    assert_fails(d.path(), &["run", &f], &["particle 7", "mass", "-1"]);
    let f = file_problem(d.path(), "0", "0.19");
    assert_fails(d.path(), &["run", &f], &["particle 7", "mass"]);
}

/// The artificial-viscosity switch: an unknown name, α_min above α (= α_max), a decay
/// constant of 0, a switch without an α to switch, and a switch's setting without a
/// switch — each one line naming the key.
#[test]
fn switch_settings_are_named() {
    let d = tempfile::tempdir().unwrap();
    let sod = problem("sod.toml");
    let cases: [(&[&str], &str); 4] = [
        (
            &["artificial_viscosity.switch=\"balsara\""],
            "artificial_viscosity.switch",
        ),
        (
            &[
                "artificial_viscosity.switch=\"cullen_dehnen\"",
                "artificial_viscosity.alpha_min=2",
            ],
            "artificial_viscosity.alpha_min",
        ),
        (
            &[
                "artificial_viscosity.switch=\"morris_monaghan\"",
                "artificial_viscosity.switch_decay=0",
            ],
            "artificial_viscosity.switch_decay",
        ),
        (
            &[
                "artificial_viscosity.switch=\"morris_monaghan\"",
                "artificial_viscosity.alpha=0",
            ],
            "artificial_viscosity.alpha",
        ),
    ];
    for (sets, key) in cases {
        let mut args = vec!["check", sod.as_str()];
        for s in sets {
            args.extend(["--set", s]);
        }
        assert_fails(d.path(), &args, &[key]);
    }
    // Without a switch its settings have nothing to act on.
    assert_fails(
        d.path(),
        &["check", &sod, "--set", "artificial_viscosity.alpha_min=0.5"],
        &["artificial_viscosity.alpha_min", "switch"],
    );
}

#[test]
fn hydro_scheme_and_conductivity_signal_are_named() {
    let d = tempfile::tempdir().unwrap();
    let sod = problem("sod.toml");
    assert_fails(
        d.path(),
        &["check", &sod, "--set", "hydro.scheme=\"pressure_entropy\""],
        &["hydro", "scheme", "pressure_entropy"],
    );
    // p̄ smooths (γ − 1) u: an isothermal gas has none.
    assert_fails(
        d.path(),
        &[
            "check",
            &problem("disk3d.toml"),
            "--set",
            "hydro.scheme=\"pressure_energy\"",
        ],
        &["hydro.scheme", "eos.kind"],
    );
    assert_fails(
        d.path(),
        &[
            "check",
            &sod,
            "--set",
            "artificial_viscosity.conductivity_signal=\"sound\"",
        ],
        &["conductivity_signal", "sound"],
    );
}

#[test]
fn unknown_kernel_shock_tube_window_sedov_deposit_and_conductivity_are_named() {
    let d = tempfile::tempdir().unwrap();
    let sod = problem("sod.toml");
    assert_fails(
        d.path(),
        &["check", &sod, "--set", "particles.kernel=\"gauss\""],
        &["particles", "kernel", "gauss"],
    );
    assert_fails(
        d.path(),
        &["check", &sod, "--set", "sod.window=[0.8, 0.2]"],
        &["sod.window"],
    );
    assert_fails(
        d.path(),
        &[
            "check",
            &sod,
            "--set",
            "artificial_viscosity.conductivity=-1",
        ],
        &["artificial_viscosity.conductivity"],
    );
    assert_fails(
        d.path(),
        &[
            "check",
            &problem("sedov2d.toml"),
            "--set",
            "sedov.deposit_radius=0.7",
        ],
        &["sedov.deposit_radius"],
    );
}

#[test]
fn zero_or_negative_smoothing_length_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let p = problem("sod.toml");
    assert_fails(
        d.path(),
        &["check", &p, "--set", "particles.h=0"],
        &["particles.h"],
    );
    assert_fails(
        d.path(),
        &["check", &p, "--set", "particles.h_factor=-1.5"],
        &["particles.h_factor"],
    );
}

#[test]
fn box_too_small_for_the_kernel_is_refused() {
    let d = tempfile::tempdir().unwrap();
    assert_fails(
        d.path(),
        &["check", &problem("sod3d.toml"), "--set", "sod.width=0.03"],
        &["too small", "along y"],
    );
}

#[test]
fn particle_outside_periodic_box_is_named() {
    let d = tempfile::tempdir().unwrap();
    let f = file_problem(d.path(), "0.025", "1.5");
    assert_fails(
        d.path(),
        &["run", &f],
        &["particle 7", "outside", "x = 1.5"],
    );
}

#[test]
fn unreadable_or_malformed_files_are_named() {
    let d = tempfile::tempdir().unwrap();
    assert_fails(
        d.path(),
        &["run", "nowhere.toml"],
        &["cannot read problem file", "nowhere.toml"],
    );
    let f = d.path().join("broken.toml");
    std::fs::write(&f, "[problem\nkind = sod").unwrap();
    assert_fails(d.path(), &["check", f.to_str().unwrap()], &["broken.toml"]);
    let f = d.path().join("kind.toml");
    let text = std::fs::read_to_string(problem("sod.toml"))
        .unwrap()
        .replace("kind = \"sod\"", "kind = \"sodd\"");
    std::fs::write(&f, text).unwrap();
    assert_fails(
        d.path(),
        &["check", f.to_str().unwrap()],
        &["problem.kind", "sodd"],
    );
    let f = file_problem(d.path(), "abc", "0.19");
    assert_fails(d.path(), &["run", &f], &["ic.csv", "line 9", "`m`"]);
}

#[test]
fn a_failed_run_leaves_earlier_outputs_intact() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("summary.json"), "{\"kept\": true}").unwrap();
    let p = problem("sod.toml");
    assert_fails(
        d.path(),
        &[
            "run",
            &p,
            "--out",
            out.to_str().unwrap(),
            "--set",
            "eos.gamma=0.9",
        ],
        &["eos.gamma"],
    );
    assert_eq!(
        std::fs::read_to_string(out.join("summary.json")).unwrap(),
        "{\"kept\": true}"
    );
}

#[test]
fn bad_viscosity_and_disk_settings_are_named() {
    let d = tempfile::tempdir().unwrap();
    let p = problem("ring.toml");
    assert_fails(
        d.path(),
        &["check", &p, "--set", "viscosity.nu=-1e-3"],
        &["viscosity.nu"],
    );
    assert_fails(
        d.path(),
        &["check", &p, "--set", "viscosity.alpha=-0.1"],
        &["viscosity"],
    );
    assert_fails(
        d.path(),
        &["check", &p, "--set", "gravity.accretion_radius=1.5"],
        &["gravity.accretion_radius", "ring"],
    );
    assert_fails(
        d.path(),
        &[
            "check",
            &p,
            "--set",
            "boundary.x=periodic",
            "--set",
            "domain.min=[-1.0, -1.0]",
            "--set",
            "domain.max=[1.0, 1.0]",
        ],
        &["does not fit"],
    );
    assert_fails(
        d.path(),
        &["check", &p, "--set", "gravity.gm=-1"],
        &["gravity.gm"],
    );
    // A pressure-supported disk edge sharper than about H/2 has κ² < 0.
    let disk = problem("disk3d.toml");
    assert_fails(
        d.path(),
        &["check", &disk, "--set", "disk.inner_width=0.2"],
        &["Rayleigh-unstable", "disk.inner_width"],
    );
    assert_fails(
        d.path(),
        &["check", &disk, "--set", "disk.inner_width=-1"],
        &["disk.inner_width"],
    );
}

/// Fails the same way for `check` and for `run` (into `dir/out`), naming every word of
/// `expect` in one line, with exit code 2.
fn assert_check_and_run_fail(dir: &Path, file: &str, sets: &[&str], expect: &[&str]) {
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    for command in ["check", "run"] {
        let mut args = vec![command, file];
        for s in sets {
            args.extend(["--set", s]);
        }
        if command == "run" {
            args.extend(["--quiet", "--out", out]);
        }
        assert_fails(dir, &args, expect);
        let (code, _) = sphdisk(dir, &args);
        assert_eq!(code, 2, "{args:?}: exit code");
    }
    assert!(
        !dir.join("out").join("summary.json").exists(),
        "nothing was run"
    );
}

#[test]
fn bad_binaries_and_streams_are_named() {
    let d = tempfile::tempdir().unwrap();
    let cv = problem("cv2d.toml");
    let stream = problem("roche_stream.toml");
    for q in ["-1", "0"] {
        let set = format!("binary.q={q}");
        assert_check_and_run_fail(d.path(), &cv, &[&set], &["binary.q", "mass ratio"]);
    }
    assert_check_and_run_fail(
        d.path(),
        &cv,
        &["stream.mass_per_orbit=-1"],
        &["stream.mass_per_orbit", "-1"],
    );
    assert_check_and_run_fail(
        d.path(),
        &cv,
        &["binary.limb_darkening=1.5"],
        &["binary.limb_darkening", "[0, 1]", "1.5"],
    );
    // L1 lies 0.7175 a from the accretor at q = 0.1.
    assert_check_and_run_fail(
        d.path(),
        &cv,
        &["binary.accretor_radius=0.9"],
        &["binary.accretor_radius", "Roche lobe", "0.9"],
    );
    assert_check_and_run_fail(
        d.path(),
        &stream,
        &["domain.min=[-0.5, -0.7]", "domain.max=[0.7, 0.7]"],
        &["domain.min", "L1", "-0.5"],
    );
    assert_check_and_run_fail(
        d.path(),
        &stream,
        &["domain.min=[-0.8, -0.7]", "domain.max=[-0.75, 0.7]"],
        &["domain.max", "L1", "-0.75"],
    );
    assert_check_and_run_fail(
        d.path(),
        &stream,
        &["stream.particles_per_orbit=1e300"],
        &["stream.particles_per_orbit", "1e300"],
    );
    // A cv problem's gas all comes through L1: a stream starting later has nothing to run.
    assert_check_and_run_fail(
        d.path(),
        &stream,
        &["stream.start=1.0"],
        &["stream.start", "t = 0"],
    );
    // An initial disk must sit inside the accretor's lobe, outside its radius, at a
    // spacing that does not ask for billions of particles, and only in a cv problem.
    let superhump = problem("superhump.toml");
    assert_check_and_run_fail(
        d.path(),
        &superhump,
        &["initial_disk.r_out=0.9"],
        &["initial_disk.r_out", "L1", "0.9"],
    );
    assert_check_and_run_fail(
        d.path(),
        &superhump,
        &["initial_disk.r_in=0.01"],
        &["initial_disk.r_in", "binary.accretor_radius"],
    );
    assert_check_and_run_fail(
        d.path(),
        &superhump,
        &["particles.h=1e-6", "initial_disk.spacing=1e-6"],
        &["initial_disk.spacing", "particles"],
    );
    assert_check_and_run_fail(
        d.path(),
        &problem("sod.toml"),
        &["initial_disk.r_in=0.1", "initial_disk.r_out=0.3"],
        &["[initial_disk]", "cv problem"],
    );
    // A binary in a 1D problem.
    assert_check_and_run_fail(
        d.path(),
        &cv,
        &["problem.dimension=1"],
        &["binary", "problem.dimension"],
    );
    // [gravity] beside [binary]: the accretor is the central mass.
    assert_check_and_run_fail(d.path(), &cv, &["gravity.gm=1"], &["[gravity]", "[binary]"]);
    // [stream] without [binary]: in a cv problem, and beside a plain central mass.
    let text = std::fs::read_to_string(&cv).unwrap();
    let (head, tail) = text.split_once("[binary]").unwrap();
    let (_, tail) = tail.split_once("[stream]").unwrap();
    let no_binary = d.path().join("no_binary.toml");
    std::fs::write(&no_binary, format!("{head}[stream]{tail}")).unwrap();
    assert_check_and_run_fail(
        d.path(),
        no_binary.to_str().unwrap(),
        &[],
        &["[stream]", "[binary]"],
    );
    assert_check_and_run_fail(
        d.path(),
        &problem("ring.toml"),
        &[
            "stream.particles_per_orbit=100",
            "stream.mass_per_orbit=1e-3",
        ],
        &["[stream]", "[binary]"],
    );
}

#[test]
fn values_that_pass_validation_are_bounded_before_anything_is_allocated() {
    // Each of these panicked (capacity overflow, index out of bounds) or aborted on an
    // allocation; now `check` and `run` refuse it naming the key.
    let d = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str], &[&str]); 8] = [
        (
            "sod.toml",
            &["time.end=1e308"],
            &["output.interval", "snapshots"],
        ),
        (
            "sod.toml",
            &["output.interval=1e-300"],
            &["output.interval", "snapshots"],
        ),
        (
            "sedov.toml",
            &["particles.n=2097153"],
            &["particles.n", "2097153 × 2097153"],
        ),
        ("sod3d.toml", &["particles.n=2097153"], &["particles.n"]),
        (
            "sod.toml",
            &["particles.h_factor=1e-308"],
            &["particles.h_factor", "without neighbours", "≥ 0.5"],
        ),
        (
            "sod.toml",
            &["particles.h=1e-300"],
            &["particles.h", "neighbour grid"],
        ),
        (
            "disk3d.toml",
            &["particles.h_factor=1e-308"],
            &["particles.h_factor", "without neighbours", "≥ 0.5"],
        ),
        (
            "sod.toml",
            &["output.files_per_snapshot=1000000000"],
            &["output.files_per_snapshot", "4096"],
        ),
    ];
    for (file, sets, expect) in cases {
        assert_check_and_run_fail(d.path(), &problem(file), sets, expect);
    }
    // Threads: at most 16 per core, for every command.
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let many = (16 * cores + 1).to_string();
    let p = problem("sod.toml");
    for command in [
        &["check", &p][..],
        &["run", &p, "--quiet", "--out", "out"][..],
    ] {
        let args = [&["--threads", &many][..], command].concat();
        assert_fails(d.path(), &args, &["--threads", &many]);
    }
}

/// rayon's environment variable is bounded as `--threads` is (before, RAYON_NUM_THREADS=
/// 100000 started a hundred thousand threads).
#[test]
fn too_many_threads_from_the_environment_are_refused_naming_the_variable() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let many = (16 * cores + 1).to_string();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(["check", &problem("sod.toml")])
        .env("RAYON_NUM_THREADS", &many)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: RAYON_NUM_THREADS") && err.contains(&many),
        "{err}"
    );
    // --threads, where given, is what counts.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(["--threads", "1", "check", &problem("sod.toml")])
        .env("RAYON_NUM_THREADS", &many)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn a_run_larger_than_the_memory_is_refused_naming_the_key() {
    let d = tempfile::tempdir().unwrap();
    // 1500³ = 3.4·10⁹ particles: within the 2³² a run can index, but terabytes.
    assert_check_and_run_fail(
        d.path(),
        &problem("sedov.toml"),
        &["particles.n=1500"],
        &["particles.n", "GiB", "SPHDISK_MEMORY_LIMIT"],
    );
    // The limit set by hand: 10⁵ particles of a tube in 1 MiB do not fit, 900 do.
    let run = |sets: &[&str]| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"));
        cmd.args(["check", &problem("sod.toml")]);
        for s in sets {
            cmd.args(["--set", s]);
        }
        let out = cmd.env("SPHDISK_MEMORY_LIMIT", "1M").output().unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (code, err) = run(&["particles.n=100000"]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    // The limit named as what set it, in a unit that shows it (before: "more than the
    // 0.00 GiB available (MemAvailable; …)" for a limit set by hand).
    assert!(
        err.contains("particles.n")
            && err.contains("the 1.00 MiB that SPHDISK_MEMORY_LIMIT allows")
            && !err.contains("MemAvailable")
            && !err.contains("0.00"),
        "{err}"
    );
    let (code, err) = run(&[]);
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn nonsense_that_used_to_pass_is_named() {
    let d = tempfile::tempdir().unwrap();
    let sod = problem("sod.toml");
    let cases: [(&str, &[&str], &[&str]); 9] = [
        // An array where a table { rho, p, v } belongs was read as ρ = 1, p = 2.
        ("sod.toml", &["sod.left=[1, 2]"], &["sod.left", "table"]),
        // Infinities and NaN: named by key, not by what they do to particle 0.
        (
            "ring.toml",
            &["ring.tau_end=inf"],
            &["ring.tau_end", "finite"],
        ),
        (
            "advection.toml",
            &["advection.width=inf"],
            &["advection.width"],
        ),
        (
            "advection.toml",
            &["advection.velocity=nan"],
            &["advection.velocity"],
        ),
        (
            "sedov2d.toml",
            &["sedov.deposit_radius=inf"],
            &["sedov.deposit_radius"],
        ),
        // Values whose energies overflow: the largest one is named.
        (
            "advection.toml",
            &["advection.velocity=1e300"],
            &["advection.velocity", "overflow"],
        ),
        // A step limiter so small the run would take ~10³⁰⁰ steps: named at once.
        (
            "sod.toml",
            &["time.courant=1e-300"],
            &["time.max_steps", "time.courant"],
        ),
        // An end so early that E t² underflows: the exact blast of the end-of-run errors
        // had a shock radius of 0 and integrated 0/0 for hours (found by tests/fuzz.rs).
        (
            "sedov.toml",
            &["time.end=1e-300"],
            &["time.end", "shock radius"],
        ),
        (
            "sedov2d.toml",
            &["time.end=5e-324"],
            &["time.end", "shock radius"],
        ),
    ];
    for (file, sets, expect) in cases {
        let out = d.path().join("out");
        let _ = std::fs::remove_dir_all(&out);
        let mut args = vec!["run", &sod, "--quiet", "--out", "out"];
        let p = problem(file);
        args[1] = &p;
        for s in sets {
            args.extend(["--set", s]);
        }
        assert_refused_in_time(d.path(), &args, expect);
    }
}

/// A clean refusal within 20 s (a hang fails): exit 2, one `error:` line holding every word
/// of `expect`.
fn assert_refused_in_time(dir: &Path, args: &[&str], expect: &[&str]) {
    let (code, err) = common::sphdisk_within(dir, args, 20.0);
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert_eq!(code, 2, "{args:?}: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one line, got {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    for e in expect {
        assert!(err.contains(e), "{args:?}: `{e}` not in: {err}");
    }
}

#[test]
fn analyse_sod_refuses_what_is_not_this_shock_tube_naming_the_file() {
    let d = tempfile::tempdir().unwrap();
    let run = |file: &str, out: &str, sets: &[&str]| {
        let p = problem(file);
        let mut args = vec!["--threads", "1", "run", &p, "--quiet", "--out", out];
        for s in sets {
            args.extend(["--set", s]);
        }
        let (code, err) = sphdisk(d.path(), &args);
        assert_eq!(code, 0, "{file}: {err}");
    };
    run("sod.toml", "tube", &["particles.n=40"]);
    run("sedov2d.toml", "blast", &["particles.n=12"]);
    // The blast's final.hdf5 copied into the tube's folder: run.toml says "sod", the file
    // is a 2D blast; it used to be plotted against the tube's solution with exit 0.
    let tube = d.path().join("tube");
    let mixed = d.path().join("mixed");
    std::fs::create_dir(&mixed).unwrap();
    for f in ["run.toml", "snapshots.json"] {
        std::fs::copy(tube.join(f), mixed.join(f)).unwrap();
    }
    std::fs::copy(d.path().join("blast/final.hdf5"), mixed.join("final.hdf5")).unwrap();
    assert_refused_in_time(
        d.path(),
        &["analyse", "sod", "mixed"],
        &["mixed/final.hdf5", "2D \"sedov\"", "1D \"sod\""],
    );
    assert!(!mixed.join("sod.png").exists());
    // Another problem's folder, by its run.toml; a snapshot given for the folder.
    assert_refused_in_time(
        d.path(),
        &["analyse", "sod", "blast"],
        &["blast", "not a shock-tube run", "sedov"],
    );
    assert_refused_in_time(
        d.path(),
        &["analyse", "sod", "tube/final.hdf5"],
        &["tube/final.hdf5", "not a run folder"],
    );
    // The tube itself still analyses.
    let (code, err) = sphdisk(d.path(), &["analyse", "sod", "tube"]);
    assert_eq!(code, 0, "{err}");
    assert!(tube.join("sod.png").exists());
}

#[test]
fn analyse_ring_refuses_an_edited_summary_or_snapshot_naming_it() {
    use sphdisk::io::hdf5::{RunMetadata, read_parameters, read_snapshot, write_snapshot};
    let d = tempfile::tempdir().unwrap();
    let p = problem("ring.toml");
    let (code, err) = sphdisk(
        d.path(),
        &[
            "--threads",
            "1",
            "run",
            &p,
            "--quiet",
            "--out",
            "ring",
            "--set",
            "particles.n=12",
            "--set",
            "ring.tau_end=0.02",
            "--set",
            "ring.output_tau=[0.018]",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let ring = d.path().join("ring");
    let (code, err) = sphdisk(d.path(), &["analyse", "ring", "ring"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(ring.join("summary.json")).unwrap();
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap();
    // Each used to loop forever in the plot (mass 0, r0 = 1e308), panic (r0 < 0, ν < 0,
    // τ_start < 0, spacing 0) or print an L1 error of NaN (spacing 1e300).
    let edits: [(&str, f64); 10] = [
        ("mass", 0.0),
        ("mass", -1.0),
        ("r0", 1e308),
        ("r0", -1.0),
        ("nu", -1.0),
        ("nu", 0.0),
        ("tau_start", -1.0),
        ("spacing", 0.0),
        ("spacing", 1e-300),
        ("spacing", 1e300),
    ];
    for (k, (key, value)) in edits.into_iter().enumerate() {
        let edited = d.path().join(format!("e{k}"));
        std::fs::create_dir(&edited).unwrap();
        for e in std::fs::read_dir(&ring).unwrap() {
            let e = e.unwrap();
            if e.path().is_file() {
                std::fs::copy(e.path(), edited.join(e.file_name())).unwrap();
            }
        }
        let mut s = summary.clone();
        s["ring"][key] = serde_json::json!(value);
        std::fs::write(edited.join("summary.json"), s.to_string()).unwrap();
        let dir = format!("e{k}");
        assert_refused_in_time(
            d.path(),
            &["analyse", "ring", &dir],
            &[&format!("{dir}/summary.json"), &format!("`ring.{key}`")],
        );
    }
    // No summary; a summary without its ring entry.
    let bare = d.path().join("bare");
    std::fs::create_dir(&bare).unwrap();
    assert_refused_in_time(
        d.path(),
        &["analyse", "ring", "bare"],
        &["bare", "summary.json"],
    );
    let mut s = summary.clone();
    s.as_object_mut().unwrap().remove("ring");
    std::fs::write(bare.join("summary.json"), s.to_string()).unwrap();
    assert_refused_in_time(
        d.path(),
        &["analyse", "ring", "bare"],
        &["bare", "summary.json", "`ring`"],
    );
    // A NaN coordinate in a snapshot: refused naming the file and the field.
    let snap_path = ring.join("snap_0001.hdf5");
    let mut snap = read_snapshot(&snap_path).unwrap();
    snap.pos[1][3] = f64::NAN;
    let meta = RunMetadata {
        parameters: read_parameters(&snap_path)
            .unwrap()
            .into_iter()
            .map(|(k, v)| (k.replacen(':', ".", 1), v))
            .collect(),
        units: Default::default(),
        periodic: false,
        physical: false,
    };
    write_snapshot(&snap_path, &snap, &meta, 1).unwrap();
    assert_refused_in_time(
        d.path(),
        &["analyse", "ring", "ring"],
        &["ring/snap_0001.hdf5", "Coordinates"],
    );
}

/// `sphdisk check FILE --set …` with the memory limit `limit`, killed after a minute (a set-up
/// that loops or fills the memory fails the test rather than hanging it): (exit code or
/// None where killed, stderr).
fn check_within_a_minute(file: &str, sets: &[&str], limit: &str) -> (Option<i32>, String) {
    use std::io::Read;
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"));
    cmd.args(["check", &problem(file)]);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let mut child = cmd
        .env("SPHDISK_MEMORY_LIMIT", limit)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let start = std::time::Instant::now();
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if start.elapsed() > std::time::Duration::from_secs(60) {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    (code, reader.join().unwrap())
}

#[test]
fn set_ups_count_their_particles_and_pairs_before_making_them() {
    // An h_factor whose support stops short of the next particle (before: 1e-6 ran a
    // 4096-particle box at 23 s a step, every particle its own only neighbour).
    let d = tempfile::tempdir().unwrap();
    for file in ["advection2d.toml", "ring.toml", "sedov2d.toml"] {
        assert_check_and_run_fail(
            d.path(),
            &problem(file),
            &["particles.h_factor=1e-6"],
            &["particles.h_factor", "without neighbours"],
        );
    }
    // Before: the first two panicked (capacity overflow: a scale height of inf or 1e300
    // ring spacings), the ring's r0 looped for ever on a surface density of 0 or inf, a
    // ring of 3000 rings per r0 and a disk of 60 filled the memory, and an h of 8 ring
    // spacings (3 700 particles in a support) took 120 s and 10 GiB to check — at 1e300
    // the system killed it. The 2 GiB limit stands for a machine's memory.
    let cases: [(&str, &[&str], &[&str]); 11] = [
        (
            "disk3d.toml",
            &["eos.q=1e300"],
            &["eos.cs0", "eos.q", "H/R"],
        ),
        (
            "disk3d.toml",
            &["eos.q=-1e300"],
            &["eos.cs0", "eos.q", "H/R"],
        ),
        (
            "disk3d.toml",
            &["disk.layers_h=1e300"],
            &["disk.layers_h", "particles"],
        ),
        (
            "disk3d.toml",
            &["particles.n=60"],
            &["particles.n", "SPHDISK_MEMORY_LIMIT"],
        ),
        (
            "ring.toml",
            &["ring.r0=1e300"],
            &["ring.r0", "surface density"],
        ),
        (
            "ring.toml",
            &["ring.r0=1e-300"],
            &["ring.r0", "surface density"],
        ),
        (
            "ring.toml",
            &["particles.n=3000"],
            &["particles.n", "SPHDISK_MEMORY_LIMIT"],
        ),
        // 10⁹ rings per r0 (4·10⁹ radii to walk) and a disk spacing of 6e-9 (10⁹ radii).
        (
            "ring.toml",
            &["particles.n=1000000000"],
            &["particles.n", "ring at r0"],
        ),
        (
            "disk3d.toml",
            &["particles.n=100000000"],
            &["particles.n", "radii"],
        ),
        (
            "disk3d.toml",
            &["particles.h_factor=8"],
            &[
                "particles.h_factor",
                "neighbour pairs",
                "SPHDISK_MEMORY_LIMIT",
            ],
        ),
        (
            "disk3d.toml",
            &["particles.h_factor=1e300"],
            &["particles.h_factor", "neighbour pairs"],
        ),
    ];
    for (file, sets, expect) in cases {
        let (code, err) = check_within_a_minute(file, sets, "2G");
        assert_eq!(code, Some(2), "{file} {sets:?}: {err}");
        assert!(!err.contains("panicked"), "{file} {sets:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{file} {sets:?}: {err}");
        for e in expect {
            assert!(err.contains(e), "{file} {sets:?}: `{e}` not in: {err}");
        }
    }
    // The files as they are pass the same checks under the same limit.
    for file in ["disk3d.toml", "ring.toml", "cv2d.toml"] {
        let (code, err) = check_within_a_minute(file, &[], "2G");
        assert_eq!(code, Some(0), "{file}: {err}");
    }
}

#[test]
fn masses_beyond_double_precision_and_a_kernel_wider_than_the_lobe_are_named() {
    // Before: a ring or disk of mass 1e300 ran and wrote `momentum: null` (the sum
    // overflowed); 1e-300 failed later as "every particle was accreted" (ring), "non-finite
    // position" (disk) or "time step is 0" naming time.max_steps (stream); an h of 1e5 a
    // ran a CV whose every particle neighbours every other; a cooling target of 1e300 made
    // the first step's internal energy NaN.
    let d = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str], &[&str]); 7] = [
        ("ring.toml", &["ring.mass=1e300"], &["ring.mass", "1e100"]),
        ("ring.toml", &["ring.mass=1e-300"], &["ring.mass", "1e-100"]),
        ("disk3d.toml", &["disk.mass=1e300"], &["disk.mass"]),
        ("disk3d.toml", &["disk.mass=1e-300"], &["disk.mass"]),
        (
            "cv2d.toml",
            &["stream.mass_per_orbit=1e-300"],
            &["stream.mass_per_orbit"],
        ),
        ("cv2d.toml", &["particles.h=1e5"], &["particles.h", "L1"]),
        // Before: "particle 0 has internal energy NaN …: reduce time.courant or time.energy".
        (
            "cv2d_cooling.toml",
            &["cooling.cs0=1e300"],
            &["cooling.cs0", "orbital speed"],
        ),
    ];
    for (file, sets, expect) in cases {
        assert_check_and_run_fail(d.path(), &problem(file), sets, expect);
    }
}

#[test]
fn huge_and_tiny_numbers_in_an_error_line_are_written_with_an_exponent() {
    // Before: Rust writes 1e300 as its 301 digits and 1e-300 as 302, in the solver's
    // messages and the TOML parser's alike; the line ran to 400–760 characters.
    let d = tempfile::tempdir().unwrap();
    let cases: [(&str, &[&str], &str); 5] = [
        ("cv2d.toml", &["binary.q=1e-300"], "got 1e-300"),
        (
            "cv2d.toml",
            &["binary.accretor_radius=-1e300"],
            "got -1e300",
        ),
        ("disk3d.toml", &["particles.n=1e300"], "`1e300`"),
        (
            "sod.toml",
            &["particles.h_factor=1e300"],
            "2.0000000000000002e298",
        ),
        ("outbursts.toml", &["outbursts.cs_hot=1e-300"], "1e-300"),
    ];
    for (file, sets, shown) in cases {
        let mut args = vec!["check".to_string(), problem(file)];
        for s in sets {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = sphdisk(d.path(), &args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(shown), "{args:?}: `{shown}` not in: {err}");
        // The echoed override and the message's own words: well under 300 characters.
        assert!(err.len() < 300, "{args:?}: {} characters: {err}", err.len());
    }
}
