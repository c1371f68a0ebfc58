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
