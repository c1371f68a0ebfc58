//! Guards `sphdisk render` as users call it: a snapshot to one PNG, a run folder to one frame
//! per snapshot, and clear one-line errors for what cannot be drawn.

use std::path::Path;

mod common;
use common::problem_file as problem;

fn sphdisk(args: &[&str]) -> (i32, String, String) {
    common::sphdisk_cli(None, args)
}

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|b| b.starts_with(b"\x89PNG\r\n\x1a\n"))
}

#[test]
fn snapshot_and_run_folder_render_to_pngs() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("blast");
    let run_s = run.to_string_lossy().into_owned();
    let (code, _, err) = sphdisk(&[
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &run_s,
        "--set",
        "particles.n=24",
        "--set",
        "output.interval=0.04",
    ]);
    assert_eq!(code, 0, "{err}");
    let png = dir.path().join("one.png");
    let (code, out, err) = sphdisk(&[
        "render",
        &run.join("final.hdf5").to_string_lossy(),
        "--quantity",
        "density",
        "--resolution",
        "64",
        "--out",
        &png.to_string_lossy(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("64 × 64 pixels"), "{out}");
    assert!(is_png(&png));

    let frames = dir.path().join("frames");
    let (code, out, err) = sphdisk(&[
        "render",
        &run_s,
        "--quantity",
        "temperature",
        "--resolution",
        "48",
        "--out",
        &frames.to_string_lossy(),
    ]);
    assert_eq!(code, 0, "{err}");
    // Snapshots at t = 0, 0.04, 0.08.
    assert!(out.contains("wrote 3 frames"), "{out}");
    for k in 0..3 {
        assert!(is_png(&frames.join(format!("frame_{k:04}.png"))));
    }
}

#[test]
fn what_cannot_be_drawn_fails_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("tube");
    let (code, _, err) = sphdisk(&[
        "run",
        &problem("sod.toml"),
        "--quiet",
        "--out",
        &run.to_string_lossy(),
        "--set",
        "particles.n=50",
    ]);
    assert_eq!(code, 0, "{err}");
    let cases: [(&[&str], &str); 4] = [
        (&["render", "final.hdf5"], "1D"),
        (
            &["render", "final.hdf5", "--quantity", "pressure-ish"],
            "unknown quantity",
        ),
        (&["render", "nope.hdf5"], "no such file"),
        (&["render", "final.hdf5", "--range", "1"], "--range"),
    ];
    for (args, expect) in cases {
        let args: Vec<String> = args
            .iter()
            .map(|a| {
                if a.ends_with(".hdf5") {
                    run.join(a).to_string_lossy().into_owned()
                } else {
                    a.to_string()
                }
            })
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, _, err) = sphdisk(&args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(expect), "{args:?}: `{expect}` not in {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn a_snapshot_with_bad_particles_is_refused_naming_the_file_and_the_field() {
    use sphdisk::io::hdf5::{RunMetadata, read_parameters, read_snapshot, write_snapshot};
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("blast");
    let run_s = run.to_string_lossy().into_owned();
    let (code, _, err) = sphdisk(&[
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &run_s,
        "--set",
        "particles.n=16",
    ]);
    assert_eq!(code, 0, "{err}");
    let good = run.join("final.hdf5");
    let meta = RunMetadata {
        parameters: read_parameters(&good).unwrap(),
        units: Default::default(),
        periodic: false,
        physical: false,
    };
    type Spoil = fn(&mut sphdisk::io::snapshot::Snapshot);
    let spoils: [(&str, Spoil, &str); 5] = [
        ("nan_x", |s| s.pos[0][3] = f64::NAN, "Coordinates"),
        ("neg_mass", |s| s.mass[5] = -1.0, "Masses"),
        ("zero_h", |s| s.h[2] = 0.0, "SmoothingLengths"),
        ("inf_rho", |s| s.rho[7] = f64::INFINITY, "Densities"),
        ("twin", |s| s.id[1] = s.id[0], "ParticleIDs"),
    ];
    for (name, spoil, field) in spoils {
        let mut snap = read_snapshot(&good).unwrap();
        spoil(&mut snap);
        let bad = run.join(format!("snap_{name}.hdf5"));
        write_snapshot(&bad, &snap, &meta, 1).unwrap();
        let file = bad.to_string_lossy().into_owned();
        let png = dir.path().join(format!("{name}.png"));
        let png = png.to_string_lossy();
        let from_out = dir.path().join(name).to_string_lossy().into_owned();
        let cases: [&[&str]; 2] = [
            &["render", &file, "--resolution", "32", "--out", &png],
            &[
                "run",
                &problem("sedov2d.toml"),
                "--quiet",
                "--out",
                &from_out,
                "--set",
                "particles.n=16",
                "--from",
                &file,
            ],
        ];
        // `--from` takes h from the problem (GADGET files have none): h = 0 passes there.
        let refused = if name == "zero_h" { 1 } else { 2 };
        for args in &cases[..refused] {
            let (code, _, err) = sphdisk(args);
            assert_eq!(code, 2, "{name}: {args:?}: {err}");
            assert_eq!(err.lines().count(), 1, "{err}");
            assert!(
                err.starts_with("error: ") && err.contains(&file) && err.contains(field),
                "{name}: {err}"
            );
        }
    }
    // `analyse` reads the same way: a spoilt final.hdf5 of a shock tube.
    let tube = dir.path().join("tube");
    let (code, _, err) = sphdisk(&[
        "run",
        &problem("sod.toml"),
        "--quiet",
        "--out",
        &tube.to_string_lossy(),
        "--set",
        "particles.n=40",
    ]);
    assert_eq!(code, 0, "{err}");
    let fin = tube.join("final.hdf5");
    let mut snap = read_snapshot(&fin).unwrap();
    snap.pos[0][4] = f64::NAN;
    write_snapshot(&fin, &snap, &meta, 1).unwrap();
    let (code, _, err) = sphdisk(&["analyse", "sod", &tube.to_string_lossy()]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("final.hdf5") && err.contains("Coordinates"),
        "{err}"
    );
}

#[test]
fn nothing_in_the_frame_is_refused_naming_the_file() {
    use sphdisk::io::hdf5::{RunMetadata, read_parameters, read_snapshot, write_snapshot};
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("blast");
    let run_s = run.to_string_lossy().into_owned();
    let (code, _, err) = sphdisk(&[
        "--threads",
        "1",
        "run",
        &problem("sedov2d.toml"),
        "--quiet",
        "--out",
        &run_s,
        "--set",
        "particles.n=12",
    ]);
    assert_eq!(code, 0, "{err}");
    let good = run.join("final.hdf5");
    let meta = RunMetadata {
        parameters: read_parameters(&good)
            .unwrap()
            .into_iter()
            .map(|(k, v)| (k.replacen(':', ".", 1), v))
            .collect(),
        units: Default::default(),
        periodic: false,
        physical: false,
    };
    // A snapshot without particles: it used to be drawn blank over the box with the
    // invented colour range 1e-4 .. 1.
    let mut empty = read_snapshot(&good).unwrap();
    for v in empty.pos.iter_mut().chain(empty.vel.iter_mut()) {
        v.clear();
    }
    for v in [
        &mut empty.mass,
        &mut empty.h,
        &mut empty.rho,
        &mut empty.u,
        &mut empty.p,
        &mut empty.diss,
    ] {
        v.clear();
    }
    empty.id.clear();
    let none = run.join("none.hdf5");
    write_snapshot(&none, &empty, &meta, 1).unwrap();
    let none_s = none.to_string_lossy().into_owned();
    let png = dir.path().join("x.png");
    let png_s = png.to_string_lossy().into_owned();
    let good_s = good.to_string_lossy().into_owned();
    let far: [&[&str]; 3] = [
        &["render", &none_s, "--out", &png_s],
        // Every particle outside the requested frame, or in 3D outside the slice.
        &[
            "render", &good_s, "--xlim", "100,101", "--ylim", "100,101", "--out", &png_s,
        ],
        &[
            "render", &run_s, "--xlim", "100,101", "--ylim", "100,101", "--out", &png_s,
        ],
    ];
    let expect = [
        (none_s.as_str(), "no particles"),
        (good_s.as_str(), "none of its"),
        (run_s.as_str(), "none of its"),
    ];
    for (args, (file, why)) in far.iter().zip(expect) {
        let (code, out, err) = sphdisk(args);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with("error: ") && err.contains(file) && err.contains(why),
            "{args:?}: {err}"
        );
        assert!(!png.exists(), "{args:?} drew {}", png.display());
    }
    // The frame that holds the blast still draws.
    let (code, _, err) = sphdisk(&[
        "render", &good_s, "--xlim", "0,1", "--ylim", "0,1", "--out", &png_s,
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(is_png(&png));
}
