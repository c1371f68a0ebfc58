//! The `sphdisk analyse …` commands: each reads a run's folder (its problem file, snapshots
//! and time series), measures it against the exact solutions and references of
//! [`crate::analysis`] and the set-ups of [`crate::problems`], and writes its tables,
//! figures and pictures. `analysis/` holds the solutions and norms; this layer the commands.

pub mod cv;
pub mod cv_accretion;
pub mod cv_passage;
pub mod disk;
pub mod hump_phase;
pub mod lightcurve;
pub mod outbursts;
pub mod ring;
pub mod sod;
pub mod superhump;

use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::config::{Config, ProblemKind};

/// The problem file a run saved (`run.toml` in its folder), which must be of `kind`;
/// `what` names that kind in the error ("a shock-tube run").
pub fn run_config(run: &Path, kind: ProblemKind, what: &str) -> Result<Config> {
    if run.is_file() {
        bail!(
            "{}: a file, not a run folder: give the folder {what} wrote (its run.toml names \
             the problem)",
            run.display()
        );
    }
    let cfg = Config::load(&run.join("run.toml"), &[])
        .with_context(|| format!("{}: the run's problem file (run.toml)", run.display()))?;
    if cfg.problem.kind != kind {
        bail!(
            "{}: not {what} (problem.kind = \"{}\")",
            run.display(),
            cfg.problem.kind.name()
        );
    }
    Ok(cfg)
}
