//! `sphdisk render` on a run folder: every snapshot of the run (from `snapshots.json`, and
//! the final state when it is later) as a numbered PNG frame, all with one frame and one
//! colour range so that the frames make a movie, and all
//! with the same overlay (`RenderOptions::roche_q`: a binary's Roche lobes); and the frames
//! assembled into an animated GIF ([`write_gif`]) that any browser or viewer plays.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::io::hdf5::read_snapshot_with_h;
use crate::io::snapshot_index::snapshots_with_final;
use crate::render::image::{
    RenderOptions, common_range, default_extent, draw_png, nothing_to_draw, render_field,
};
use crate::render::interpolate::Extent;

/// Renders every snapshot of the run in `run` — those `snapshots.json` lists and the final
/// state when it is later ([`snapshots_with_final`]) — into `out/frame_NNNN.png`, all with
/// one frame (`opts.frame`, or the smallest holding every snapshot's [`default_extent`]) and one
/// colour range (`opts.range`, or [`common_range`] over all of them), and the rest of
/// `opts` — the Roche lobes of `opts.roche_q` included — for every frame; returns the
/// frames written.
pub fn render_run(run: &Path, opts: &RenderOptions, out: &Path) -> Result<Vec<PathBuf>> {
    let files = snapshots_with_final(run)?;
    if files.is_empty() {
        bail!(
            "{}: the run wrote no snapshots (set output.interval)",
            run.display()
        );
    }
    let mut snaps = Vec::with_capacity(files.len());
    for (file, _) in &files {
        snaps.push((file, read_snapshot_with_h(&run.join(file))?.in_run_frame()));
    }
    let mut fixed = opts.clone();
    if fixed.frame.is_none() {
        let mut frame: Option<Extent> = None;
        for (file, snap) in &snaps {
            let e = default_extent(snap, opts).with_context(|| format!("framing {file}"))?;
            frame = Some(frame.map_or(e, |f| f.union(&e)));
        }
        fixed.frame = frame;
    }
    // Fields first (one range for all), then pictures.
    let mut fields = Vec::with_capacity(snaps.len());
    for (file, snap) in snaps {
        let (field, frame, reached) =
            render_field(&snap, &fixed).with_context(|| format!("rendering {file}"))?;
        fields.push((snap, field, frame, reached));
    }
    // A frame some snapshots leave empty is drawn in the others' range; none reached at all
    // leaves no range to draw with.
    if fields.iter().all(|f| f.3 == 0) {
        let (snap, _, frame, _) = &fields[fields.len() - 1];
        let (last, _) = &files[files.len() - 1];
        return Err(nothing_to_draw(snap, &fixed, frame)).with_context(|| {
            format!(
                "{}: all {} snapshots would be blank; the last, {last}",
                run.display(),
                files.len()
            )
        });
    }
    let fields: Vec<_> = fields.into_iter().map(|(s, f, fr, _)| (s, f, fr)).collect();
    std::fs::create_dir_all(out).with_context(|| format!("cannot create {}", out.display()))?;
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

/// The PNG `frames` (all of one size, as [`render_run`] writes them) as an animated GIF at
/// `fps` frames per second, looping, at `path`. Each frame gets its own 256-colour palette
/// (NeuQuant, the GIF encoder's quantiser).
pub fn write_gif(frames: &[PathBuf], path: &Path, fps: u32) -> Result<()> {
    use image::codecs::gif::{GifEncoder, Repeat};
    use image::{Delay, Frame};
    if frames.is_empty() {
        bail!("no frames to assemble into {}", path.display());
    }
    if !(1..=50).contains(&fps) {
        bail!("--fps: must lie between 1 and 50, got {fps}");
    }
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot write {}", path.display()))?;
    let mut enc = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    enc.set_repeat(Repeat::Infinite)?;
    let mut size = None;
    for f in frames {
        let img = image::open(f)
            .with_context(|| format!("cannot read frame {}", f.display()))?
            .to_rgba8();
        let dims = img.dimensions();
        if *size.get_or_insert(dims) != dims {
            bail!(
                "{}: {}×{} pixels, the first frame {}×{}",
                f.display(),
                dims.0,
                dims.1,
                size.unwrap().0,
                size.unwrap().1
            );
        }
        let delay = Delay::from_numer_denom_ms(1000, fps);
        enc.encode_frame(Frame::from_parts(img, 0, 0, delay))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::hdf5::{RunMetadata, Units, write_snapshot};
    use crate::io::snapshot::Snapshot;
    use crate::io::snapshot_index::{SnapshotEntry, SnapshotIndex};
    use crate::render::interpolate::{Quantity, View};
    use crate::render::overlay::mass_ratio_of;

    /// A run folder of a q = 0.2 binary with two snapshots of a small ring about the
    /// accretor, box (−1.5, −1) … (0.5, 1), as a 2D run writes them.
    fn binary_run(dir: &Path) {
        let meta = RunMetadata {
            parameters: [("binary.q".to_string(), "0.2".to_string())].into(),
            units: Units::default(),
            periodic: false,
            physical: false,
        };
        let mut index = SnapshotIndex::default();
        for k in 0..2 {
            let mut s = Snapshot {
                dimension: 2,
                time: k as f64,
                box_hi: [2.0, 2.0, 1.0],
                shift: [1.5, 1.0, 0.0],
                ..Snapshot::default()
            };
            for i in 0..200 {
                let phi = std::f64::consts::TAU * (i as f64 + 0.1 * k as f64) / 200.0;
                let r = 0.2 + 0.1 * (i % 5) as f64 / 5.0;
                s.pos[0].push(1.5 + r * phi.cos());
                s.pos[1].push(1.0 + r * phi.sin());
                s.pos[2].push(0.0);
                for v in &mut s.vel {
                    v.push(0.0);
                }
                s.id.push(i);
                s.mass.push(1e-3);
                s.h.push(0.05);
                s.rho.push(1.0);
                s.u.push(1.0);
                s.p.push(1.0);
                s.diss.push(0.0);
            }
            let file = format!("snap_{k:04}.hdf5");
            write_snapshot(&dir.join(&file), &s, &meta, 1).unwrap();
            index.snapshots.push(SnapshotEntry {
                file,
                time: s.time,
                step: k,
                files: 1,
            });
        }
        std::fs::write(
            dir.join("snapshots.json"),
            serde_json::to_string(&index).unwrap(),
        )
        .unwrap();
    }

    #[test]
    fn frames_of_a_binary_run_carry_the_roche_lobes() {
        let dir = tempfile::tempdir().unwrap();
        binary_run(dir.path());
        let q = mass_ratio_of(dir.path()).unwrap();
        assert_eq!(q, Some(0.2));
        let mut opts = RenderOptions::new(Quantity::Density, View::FaceOn);
        opts.resolution = (48, 48);
        let plain = render_run(dir.path(), &opts, &dir.path().join("plain")).unwrap();
        opts.roche_q = q;
        let roche = render_run(dir.path(), &opts, &dir.path().join("roche")).unwrap();
        assert_eq!(plain.len(), 2);
        assert_eq!(roche.len(), 2);
        for (a, b) in plain.iter().zip(&roche) {
            assert_ne!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
        }
    }

    /// The GIF holds every frame, in order, at the frames' size, with the delay of the
    /// frame rate, and each frame's pixels are the PNG's within the palette's quantisation.
    #[test]
    fn the_frames_play_as_an_animated_gif() {
        use image::AnimationDecoder;
        let dir = tempfile::tempdir().unwrap();
        binary_run(dir.path());
        let mut opts = RenderOptions::new(Quantity::Density, View::FaceOn);
        opts.resolution = (64, 64);
        let frames = render_run(dir.path(), &opts, &dir.path().join("f")).unwrap();
        let gif = dir.path().join("movie.gif");
        write_gif(&frames, &gif, 4).unwrap();
        let dec = image::codecs::gif::GifDecoder::new(std::fs::File::open(&gif).unwrap()).unwrap();
        let played = dec.into_frames().collect_frames().unwrap();
        assert_eq!(played.len(), frames.len());
        for (g, png) in played.iter().zip(&frames) {
            let png = image::open(png).unwrap().to_rgba8();
            assert_eq!(g.buffer().dimensions(), png.dimensions());
            assert_eq!(g.delay().numer_denom_ms(), (250, 1));
            // Mean absolute difference per channel, of 255: a 256-colour palette of a
            // picture with a colour map, axes and text stays within a few levels.
            let diff: f64 = g
                .buffer()
                .as_raw()
                .iter()
                .zip(png.as_raw())
                .map(|(a, b)| (*a as f64 - *b as f64).abs())
                .sum::<f64>()
                / png.as_raw().len() as f64;
            assert!(diff < 4.0, "{diff}");
        }
        // The two snapshots differ (the ring turned), and so do their frames in the GIF.
        assert_ne!(played[0].buffer().as_raw(), played[1].buffer().as_raw());
        assert!(
            write_gif(&frames, &gif, 0)
                .unwrap_err()
                .to_string()
                .contains("--fps")
        );
        assert!(write_gif(&[], &gif, 5).is_err());
    }

    #[test]
    fn frames_include_the_final_state_when_it_is_later() {
        let dir = tempfile::tempdir().unwrap();
        binary_run(dir.path());
        let mut opts = RenderOptions::new(Quantity::Density, View::FaceOn);
        opts.resolution = (32, 32);
        let two = render_run(dir.path(), &opts, &dir.path().join("two")).unwrap();
        assert_eq!(two.len(), 2);
        // A final state at t = 2, after the last snapshot (t = 1): one more frame.
        let mut last = crate::io::hdf5::read_snapshot(&dir.path().join("snap_0001.hdf5")).unwrap();
        last.time = 2.0;
        let meta = RunMetadata::default();
        write_snapshot(&dir.path().join("final.hdf5"), &last, &meta, 1).unwrap();
        let files = snapshots_with_final(dir.path()).unwrap();
        let times: Vec<f64> = files.iter().map(|f| f.1).collect();
        assert_eq!(times, [0.0, 1.0, 2.0]);
        assert_eq!(files[2].0, "final.hdf5");
        let three = render_run(dir.path(), &opts, &dir.path().join("three")).unwrap();
        assert_eq!(three.len(), 3);
        // A final state at the last snapshot's time adds nothing.
        last.time = 1.0;
        write_snapshot(&dir.path().join("final.hdf5"), &last, &meta, 1).unwrap();
        assert_eq!(snapshots_with_final(dir.path()).unwrap().len(), 2);
    }
}
