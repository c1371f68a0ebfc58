//! `sphdisk analyse disk <run>`: how a disk run left its initial equilibrium, snapshot by
//! snapshot: the figures of `summary.json`'s `errors` for a disk ([`errors_from_start`]:
//! the radii enclosing 10/50/90% of the mass against the thin-disk diffusion equation's,
//! Σ's L1 against it, the effective α, the thickness and the radial velocity) at every
//! snapshot's time, as `disk_evolution.csv` in the run folder.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

use crate::config::{Config, ProblemKind};
use crate::io::atomic::write_atomic;
use crate::io::hdf5::read_snapshot_with_h;
use crate::io::snapshot_index::SnapshotIndex;
use crate::problems::disk::{errors_from_start, setup};
use crate::reports::run_config;

/// What the analysis wrote, and the figures at each snapshot's time.
pub struct DiskReport {
    pub file: PathBuf,
    pub rows: Vec<(f64, BTreeMap<String, f64>)>,
}

/// Reads `run.toml` and the snapshots of a disk run and writes `disk_evolution.csv`.
pub fn analyse_disk(run: &Path) -> Result<DiskReport> {
    let cfg = run_config(run, ProblemKind::Disk, "a disk run")?;
    match cfg.problem.dimension {
        2 => analyse::<2>(run, &cfg),
        3 => analyse::<3>(run, &cfg),
        d => bail!("{}: a disk is 2D or 3D, not {d}D", run.display()),
    }
}

fn analyse<const D: usize>(run: &Path, cfg: &Config) -> Result<DiskReport> {
    let start = setup::<D>(cfg)?.particles;
    let index = SnapshotIndex::read(run)?;
    let mut rows = Vec::new();
    for snap in index.snapshots.iter().filter(|s| s.time > 0.0) {
        let p = read_snapshot_with_h(&run.join(&snap.file))?.to_particles::<D>()?;
        rows.push((snap.time, errors_from_start(cfg, &start, &p, snap.time)?));
    }
    if rows.is_empty() {
        bail!(
            "{}: no snapshot after t = 0 (set `output.interval` to follow the disk)",
            run.display()
        );
    }
    let keys: Vec<&String> = rows[0].1.keys().collect();
    let mut csv = String::from("t");
    for k in &keys {
        let _ = write!(csv, ",{k}");
    }
    csv.push('\n');
    for (t, e) in &rows {
        let _ = write!(csv, "{t}");
        for k in &keys {
            let _ = write!(csv, ",{}", e[*k]);
        }
        csv.push('\n');
    }
    let file = run.join("disk_evolution.csv");
    write_atomic(&file, csv.as_bytes())?;
    Ok(DiskReport { file, rows })
}
