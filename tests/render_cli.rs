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
