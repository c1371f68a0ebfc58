//! `snapshots.json`: the snapshots a run has written, with their time and step, so that
//! `render`, the `analyse` commands and other tools find each snapshot's time without
//! opening it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

/// Snapshots written so far, listed in `snapshots.json` (file, time, step) so that tools
/// can find each snapshot's time.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct SnapshotIndex {
    pub snapshots: Vec<SnapshotEntry>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SnapshotEntry {
    /// The snapshot's name; with `files` > 1 its parts are `snap_NNNN.k.hdf5`.
    pub file: String,
    pub time: f64,
    pub step: u64,
    #[serde(default = "one_file")]
    pub files: usize,
}

fn one_file() -> usize {
    1
}

impl SnapshotIndex {
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("snapshots.json");
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "cannot read {} (a run folder lists its snapshots there)",
                path.display()
            )
        })?;
        serde_json::from_str(&text)
            .with_context(|| format!("{} is not a snapshot index", path.display()))
    }
}

/// The snapshots of the run in `run`, in time order, as (file, time): those
/// `snapshots.json` lists, and `final.hdf5` when it is later than the last of them (a run
/// whose end time is not a snapshot time, or one without snapshots). Empty when there are
/// neither.
pub fn snapshots_with_final(run: &Path) -> Result<Vec<(String, f64)>> {
    let index = SnapshotIndex::read(run)?;
    let mut files: Vec<(String, f64)> = index
        .snapshots
        .iter()
        .map(|s| (s.file.clone(), s.time))
        .collect();
    let last_t = files.last().map_or(f64::NEG_INFINITY, |f| f.1);
    let path = run.join("final.hdf5");
    if path.exists() {
        // read_snapshot's errors name the file.
        let snap = crate::io::hdf5::read_snapshot(&path)?;
        if snap.time > last_t + 1e-9 * last_t.abs().max(1.0) {
            files.push(("final.hdf5".into(), snap.time));
        }
    }
    Ok(files)
}

/// The snapshot file behind `input`: the file itself, or the first snapshot a run folder
/// lists (`None` when it lists none).
pub fn snapshot_of(input: &Path) -> Result<Option<PathBuf>> {
    if !input.is_dir() {
        return Ok(Some(input.to_path_buf()));
    }
    let index = SnapshotIndex::read(input)?;
    Ok(index.snapshots.first().map(|first| input.join(&first.file)))
}
