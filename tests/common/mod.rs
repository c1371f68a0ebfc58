//! Shared by the physics validations: run a problem file from `problems/` with overrides,
//! quietly, into a temporary folder.

use std::path::Path;

use sphdisk::config::Config;
use sphdisk::io::summary::Summary;
use sphdisk::simulation::{RunOptions, run_with_state};

#[allow(dead_code)]
pub struct Run<const D: usize> {
    pub summary: Summary,
    pub particles: sphdisk::particles::Particles<D>,
    pub dir: tempfile::TempDir,
}

#[allow(dead_code)]
pub fn run_problem<const D: usize>(file: &str, sets: &[&str]) -> Run<D> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(file);
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let cfg = Config::load(&path, &sets).expect("problem file loads");
    assert_eq!(cfg.dimension(), D, "dimension of {file}");
    let dir = tempfile::tempdir().expect("temporary folder");
    let opts = RunOptions::quiet(dir.path());
    let out = run_with_state::<D>(&cfg, &opts).expect("run succeeds");
    Run {
        summary: out.summary().expect("run finishes").clone(),
        particles: out.particles,
        dir,
    }
}

#[allow(dead_code)]
pub fn error(s: &Summary, key: &str) -> f64 {
    *s.errors
        .get(key)
        .unwrap_or_else(|| panic!("summary has no errors.{key}: {:?}", s.errors))
}

/// The path of a problem file in `problems/`, as a string for command lines.
#[allow(dead_code)]
pub fn problem_file(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Runs the `sphdisk` binary with `args` (in `dir` if given); returns (exit code, stdout,
/// stderr).
#[allow(dead_code)]
pub fn sphdisk_cli(dir: Option<&Path>, args: &[&str]) -> (i32, String, String) {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"));
    cmd.args(args);
    if let Some(d) = dir {
        cmd.current_dir(d);
    }
    let out = cmd.output().expect("sphdisk starts");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A path as a command-line argument.
#[allow(dead_code)]
pub fn path_str(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// Runs the `sphdisk` binary with `args`; returns (exit code, stderr).
#[allow(dead_code)]
pub fn sphdisk_err(args: &[&str]) -> (i32, String) {
    let (code, _, err) = sphdisk_cli(None, args);
    (code, err)
}

/// Runs the `sphdisk` binary with `args` and asserts that it succeeds.
#[allow(dead_code)]
pub fn ok(args: &[&str]) {
    let (code, err) = sphdisk_err(args);
    assert_eq!(code, 0, "{args:?}: {err}");
}

/// Every particle's state in `b` (from several ranks) equals the state in `a` (one rank), matched by id, to 1e-12 of
/// each quantity's rms (the bar of issue 4): the same pairs are summed in another order,
/// so the differences are round-off.
#[allow(dead_code)]
pub fn assert_same_state<const D: usize>(
    a: &sphdisk::particles::Particles<D>,
    b: &mut sphdisk::particles::Particles<D>,
    what: &str,
) {
    assert_eq!(a.len(), b.len(), "{what}: particle count");
    let mut a = a.clone();
    let index: std::collections::HashMap<u64, usize> =
        a.id.iter().enumerate().map(|(i, &id)| (id, i)).collect();
    let order: Vec<usize> = b.id.iter().map(|id| index[id]).collect();
    assert_eq!(a.interactions.len(), b.interactions.len());
    for (k, &j) in order.iter().enumerate() {
        assert_eq!(
            a.interactions[j], b.interactions[k],
            "{what}: interactions of {}",
            b.id[k]
        );
    }
    let ids = b.id.clone();
    let (aa, bb) = (a.named_arrays_mut(), b.named_arrays_mut());
    let mut worst = 0.0f64;
    for ((name, x), (_, y)) in aa.iter().zip(bb.iter()) {
        let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
        for (k, &j) in order.iter().enumerate() {
            let d = (x[j] - y[k]).abs() / rms.max(1e-300);
            worst = worst.max(d);
            assert!(
                d <= 1e-12,
                "{what}: {name} of particle {}: {} vs {} (rms {rms})",
                ids[k],
                x[j],
                y[k]
            );
        }
    }
    eprintln!("{what}: largest difference {worst:.1e} of the rms");
}

/// [`sphdisk_cli`] that fails the test when the command runs past `limit` seconds (a hang)
/// instead of waiting for it; returns (exit code, stderr).
#[allow(dead_code)]
pub fn sphdisk_within(dir: &Path, args: &[&str], limit: f64) -> (i32, String) {
    let err_path = dir.join(".stderr");
    let err_file = std::fs::File::create(&err_path).unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_sphdisk"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::null())
        .stderr(err_file)
        .spawn()
        .expect("sphdisk starts");
    let t0 = std::time::Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().unwrap() {
            break st;
        }
        if t0.elapsed().as_secs_f64() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{args:?}: still running after {limit} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let err = std::fs::read_to_string(&err_path).unwrap_or_default();
    std::fs::remove_file(&err_path).unwrap();
    (status.code().unwrap_or(-1), err)
}
