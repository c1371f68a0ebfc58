//! `sphdisk render` on a run folder: every snapshot of the run (from `snapshots.json`) as a
//! numbered PNG frame, all with one colour range so that the frames make a movie.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::io::hdf5::read_snapshot;
use crate::render::image::{RenderOptions, common_range, draw_png, render_field};
use crate::simulation::SnapshotIndex;

/// Renders every snapshot of the run in `run` into `out/frame_NNNN.png` with a colour range
/// fixed over all of them (unless `opts.range` fixes it already); returns the frames written.
pub fn render_run(run: &Path, opts: &RenderOptions, out: &Path) -> Result<Vec<PathBuf>> {
    let index = SnapshotIndex::read(run)?;
    if index.snapshots.is_empty() {
        bail!(
            "{}: the run wrote no snapshots (set output.interval)",
            run.display()
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
    // Fields first (one range for all), then pictures.
    let mut fields = Vec::with_capacity(index.snapshots.len());
    for entry in &index.snapshots {
        let snap = read_snapshot(&run.join(&entry.file))?.in_run_frame();
        let (field, frame) =
            render_field(&snap, opts).with_context(|| format!("rendering {}", entry.file))?;
        fields.push((snap, field, frame));
    }
    let mut fixed = opts.clone();
    if fixed.range.is_none() {
        let all: Vec<&[f64]> = fields.iter().map(|(_, f, _)| f.as_slice()).collect();
        fixed.range = Some(common_range(&all, opts.scale));
    }
    let mut written = Vec::new();
    for (k, (snap, field, frame)) in fields.iter().enumerate() {
        let path = out.join(format!("frame_{k:04}.png"));
        draw_png(snap, field, frame, &fixed, &path)?;
        written.push(path);
    }
    Ok(written)
}
