//! A resumed run checks what it reads: a newest checkpoint with a NaN position, a negative
//! mass, a duplicate id, a time past the end, a state that does not parse or a flipped
//! byte in an array is skipped with its cause named in `run.log`, and the run resumes from
//! the older intact checkpoint, ending bit for bit where the uninterrupted run ends. With
//! no intact checkpoint, one line names the newest and its cause.

use std::path::Path;

use sphdisk::io::checkpoint::{self, CheckpointText};
use sphdisk::particles::Particles;

mod common;
use common::problem_file as problem;
use common::{ok, path_str as s, sphdisk_err as sphdisk};

const SETS: [&str; 6] = [
    "--set",
    "particles.n=16",
    "--set",
    "time.end=0.02",
    "--set",
    "output.checkpoint_steps=2",
];

/// The uninterrupted run into `a`, and the same stopped after step 4 into `b`, whose
/// checkpoints are then those of steps 4 and 2.
fn runs(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let (a, b) = (dir.join("a"), dir.join("b"));
    let p = problem("sedov2d.toml");
    ok(&[&["run", &p, "--quiet", "--out", &s(&a)], &SETS[..]].concat());
    ok(&[
        &["run", &p, "--quiet", "--out", &s(&b), "--stop-after", "4"],
        &SETS[..],
    ]
    .concat());
    let names: Vec<String> = checkpoint::list(&b)
        .unwrap()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["ckpt_0000000004.hdf5", "ckpt_0000000002.hdf5"]);
    (a, b)
}

fn copy_run(from: &Path, to: &Path) {
    std::fs::create_dir_all(to.join("checkpoints")).unwrap();
    for sub in ["", "checkpoints"] {
        for e in std::fs::read_dir(from.join(sub)).unwrap() {
            let e = e.unwrap();
            if e.path().is_file() {
                std::fs::copy(e.path(), to.join(sub).join(e.file_name())).unwrap();
            }
        }
    }
}

/// Rewrites the checkpoint of step 4 in `run` (with valid checksums) after `change`.
fn rewrite(run: &Path, change: impl Fn(&mut CheckpointText, &mut Particles<2>)) {
    let path = checkpoint::folder(run).join("ckpt_0000000004.hdf5");
    let (mut text, mut p) = checkpoint::read::<2>(&path).unwrap();
    change(&mut text, &mut p);
    checkpoint::write(run, 4, &text, &mut p).unwrap();
}

/// The state's JSON with `key` set to `value`.
fn with_state(text: &mut CheckpointText, key: &str, value: serde_json::Value) {
    let mut v: serde_json::Value = serde_json::from_str(&text.state_json).unwrap();
    v[key] = value;
    text.state_json = v.to_string();
}

/// Flips one bit in the stored x coordinates of the checkpoint of step 4.
fn flip_a_bit(run: &Path) {
    let path = checkpoint::folder(run).join("ckpt_0000000004.hdf5");
    let (_, p) = checkpoint::read::<2>(&path).unwrap();
    let raw: Vec<u8> = p.pos[0][10..12]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let mut bytes = std::fs::read(&path).unwrap();
    let at = bytes
        .windows(raw.len())
        .position(|w| w == raw.as_slice())
        .expect("x is stored raw");
    bytes[at + 2] ^= 0x01;
    std::fs::write(&path, bytes).unwrap();
}

#[test]
fn a_bad_newest_checkpoint_is_skipped_by_name_and_the_older_one_used() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = runs(dir.path());
    type Damage = Box<dyn Fn(&Path)>;
    let cases: Vec<(&str, Damage, &str)> = vec![
        (
            "nan_position",
            Box::new(|r| rewrite(r, |_, p| p.pos[0][7] = f64::NAN)),
            "non-finite position",
        ),
        (
            "negative_mass",
            Box::new(|r| rewrite(r, |_, p| p.mass[3] = -1e-3)),
            "mass must be > 0",
        ),
        (
            "duplicate_id",
            Box::new(|r| {
                rewrite(r, |_, p| {
                    p.id[5] = p.id[6];
                })
            }),
            "appears twice",
        ),
        (
            "far_outside",
            Box::new(|r| rewrite(r, |_, p| p.pos[1][2] = 1e6)),
            "outside",
        ),
        (
            "time_past_end",
            Box::new(|r| rewrite(r, |t, _| with_state(t, "t", 5.0.into()))),
            "outside [0, t_end",
        ),
        (
            "zero_h",
            Box::new(|r| rewrite(r, |t, _| with_state(t, "h", 0.0.into()))),
            "smoothing length",
        ),
        (
            "garbled_state",
            Box::new(|r| rewrite(r, |t, _| t.state_json.insert_str(3, "}{"))),
            "stored run state",
        ),
        (
            "wrong_dimension_box",
            Box::new(|r| {
                rewrite(r, |t, _| {
                    with_state(t, "box_min", serde_json::json!([0.0, 0.0, 0.0]))
                })
            }),
            "not 2-dimensional",
        ),
        ("flipped_bit", Box::new(flip_a_bit), "/Particles/pos0"),
    ];
    for (name, damage, cause) in cases {
        let run = dir.path().join(name);
        copy_run(&b, &run);
        damage(&run);
        let (code, err) = sphdisk(&["run", "--quiet", "--resume", &s(&run)]);
        assert_eq!(code, 0, "{name}: {err}");
        let log = std::fs::read_to_string(run.join("run.log")).unwrap();
        let skip = log
            .lines()
            .find(|l| l.contains("skip checkpoint"))
            .unwrap_or_else(|| panic!("{name}: nothing skipped: {log}"));
        assert!(
            skip.contains("ckpt_0000000004.hdf5") && skip.contains(cause),
            "{name}: {skip}"
        );
        assert!(log.contains("resume from") && log.contains("ckpt_0000000002.hdf5"));
        assert_eq!(
            std::fs::read(a.join("final.csv")).unwrap(),
            std::fs::read(run.join("final.csv")).unwrap(),
            "{name}: the resumed run ends where the uninterrupted one does"
        );
    }
}

#[test]
fn no_intact_checkpoint_is_one_line_naming_the_newest() {
    let dir = tempfile::tempdir().unwrap();
    let (_, b) = runs(dir.path());
    flip_a_bit(&b);
    let older = checkpoint::folder(&b).join("ckpt_0000000002.hdf5");
    let (text, mut p) = checkpoint::read::<2>(&older).unwrap();
    p.mass[0] = f64::NAN;
    // Written as step 2 again: the newest two stay those of steps 4 and 2.
    checkpoint::write(&b, 2, &text, &mut p).unwrap();
    let (code, err) = sphdisk(&["run", "--quiet", "--resume", &s(&b)]);
    assert_ne!(code, 0);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ")
            && err.contains("no usable checkpoint")
            && err.contains("ckpt_0000000004.hdf5")
            && err.contains("checksum"),
        "{err}"
    );
}

#[test]
fn a_checkpoint_of_another_run_is_refused_and_never_fallen_back_to() {
    let dir = tempfile::tempdir().unwrap();
    let (_, b) = runs(dir.path());
    // Another run of the same problem, stopped at step 6: checkpoints of steps 6 and 4.
    let other = dir.path().join("other");
    ok(&[
        &[
            "run",
            &problem("sedov2d.toml"),
            "--quiet",
            "--out",
            &s(&other),
            "--stop-after",
            "6",
        ],
        &SETS[..],
    ]
    .concat());
    let foreign = |step: u64| checkpoint::folder(&other).join(format!("ckpt_{step:010}.hdf5"));
    // Its newest checkpoint copied into b's folder: refused by name, nothing resumed.
    let run = dir.path().join("newest_foreign");
    copy_run(&b, &run);
    let into = checkpoint::folder(&run).join("ckpt_0000000006.hdf5");
    std::fs::copy(foreign(6), &into).unwrap();
    let (code, err) = sphdisk(&["run", "--quiet", "--resume", &s(&run)]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("ckpt_0000000006.hdf5") && err.contains("another run"),
        "{err}"
    );
    assert!(!run.join("summary.json").exists(), "nothing was resumed");
    // b's own newest damaged and its older one replaced by the other run's: the fallback
    // does not cross runs.
    let run = dir.path().join("older_foreign");
    copy_run(&b, &run);
    flip_a_bit(&run);
    let older = checkpoint::folder(&run).join("ckpt_0000000002.hdf5");
    std::fs::copy(foreign(4), &older).unwrap();
    let (code, err) = sphdisk(&["run", "--quiet", "--resume", &s(&run)]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("no usable checkpoint"), "{err}");
    assert!(!run.join("summary.json").exists(), "nothing was resumed");
}

#[test]
fn a_finished_run_is_extended_with_new_end_and_interval() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("tube");
    let r = s(&run);
    let sets = [
        "--set",
        "particles.n=40",
        "--set",
        "time.end=0.02",
        "--set",
        "output.interval=0.01",
    ];
    ok(&[
        &["run", &problem("sod.toml"), "--quiet", "--out", &r][..],
        &sets[..],
    ]
    .concat());
    let snaps = |run: &Path| -> Vec<f64> {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(run.join("snapshots.json")).unwrap())
                .unwrap();
        v["snapshots"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["time"].as_f64().unwrap())
            .collect()
    };
    assert_eq!(snaps(&run), [0.0, 0.01, 0.02]);
    ok(&[
        "run",
        "--quiet",
        "--resume",
        &r,
        "--set",
        "time.end=0.03",
        "--set",
        "output.interval=0.005",
    ]);
    let t: Vec<f64> = snaps(&run);
    assert_eq!(t.len(), 5, "{t:?}");
    assert!(
        (t[3] - 0.025).abs() < 1e-12 && (t[4] - 0.03).abs() < 1e-12,
        "{t:?}"
    );
    for k in 0..5 {
        assert!(run.join(format!("snap_{k:04}.hdf5")).exists());
    }
    let toml = std::fs::read_to_string(run.join("run.toml")).unwrap();
    assert!(
        toml.contains("end = 0.03") && toml.contains("interval = 0.005"),
        "{toml}"
    );
    let summary = std::fs::read_to_string(run.join("summary.json")).unwrap();
    assert!(summary.contains("\"t_end\": 0.03"), "{summary}");
    // What the particles are cannot change mid-run: named, nothing run.
    let (code, err) = sphdisk(&["run", "--quiet", "--resume", &r, "--set", "particles.n=80"]);
    assert_eq!(code, 2, "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("particles.n") && err.contains("resumed"),
        "{err}"
    );
    // An end before the checkpoint's time is named too.
    let (code, err) = sphdisk(&["run", "--quiet", "--resume", &r, "--set", "time.end=0.01"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("time.end"), "{err}");
}

#[test]
fn a_bad_override_is_named_as_the_override_not_as_the_checkpoints() {
    // Before: "no usable checkpoint to resume from in …/checkpoints: …/ckpt_…: configuration:
    // key `sweep.batch_per_thread`: …", after trying every checkpoint with the override,
    // as if the checkpoints were at fault.
    let d = tempfile::tempdir().unwrap();
    let (_, b) = runs(d.path());
    let cases: [(&str, &[&str]); 4] = [
        (
            "sweep.batch_per_thread=0",
            &["--set sweep.batch_per_thread=0:", "sweep.batch_per_thread"],
        ),
        (
            "eos.gamma=2",
            &["--set eos.gamma:", "cannot change when a run is resumed"],
        ),
        (
            "time.end=1e-300",
            &["--set time.end=1e-300:", "before the checkpoint's time"],
        ),
        (
            "output.interval=1e-300",
            &["--set output.interval=1e-300:", "snapshots"],
        ),
    ];
    for (set, expect) in cases {
        let (code, err) = sphdisk(&["run", "--resume", &s(&b), "--quiet", "--set", set]);
        assert_eq!(code, 2, "{set}: {err}");
        assert_eq!(err.lines().count(), 1, "{set}: {err}");
        assert!(!err.contains("no usable checkpoint"), "{set}: {err}");
        for e in expect {
            assert!(err.contains(e), "{set}: `{e}` not in: {err}");
        }
    }
    // Both checkpoints are still there and resumable.
    assert_eq!(checkpoint::list(&b).unwrap().len(), 2);
    ok(&["run", "--resume", &s(&b), "--quiet"]);
}
