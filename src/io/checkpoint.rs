//! Checkpoints: the complete state of a run at the end of a step (every particle array at
//! full precision, the run loop's counters, the problem file as run), so that
//! `sphdisk run --resume` continues bit for bit. One HDF5 file per checkpoint in
//! `<run>/checkpoints/ckpt_<step>.hdf5` with a checksum of every array, written atomically
//! (temporary file, fsync, rename); the newest two are kept, so a run killed while writing
//! still has a complete one.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use hdf5_pure::{AttrValue, File, FileBuilder};

use crate::io::atomic::write_atomic;
use crate::particles::Particles;

/// Checkpoints kept on disk.
pub const KEEP: usize = 2;

/// A checkpoint's content besides the particles: the problem file as run (TOML) and the run
/// loop's state (JSON, whose floats round-trip exactly).
pub struct CheckpointText {
    pub config_toml: String,
    pub state_json: String,
}

pub fn folder(run: &Path) -> PathBuf {
    run.join("checkpoints")
}

/// Particle arrays that checkpoints of earlier versions do not hold: such a checkpoint
/// reads them as zeros (`alpha`, the switch's α, is unused by the runs that wrote it).
const ADDED_LATER: [&str; 1] = ["alpha"];

/// Writes the checkpoint of `step` and removes all but the newest [`KEEP`].
pub fn write<const D: usize>(
    run: &Path,
    step: u64,
    text: &CheckpointText,
    p: &mut Particles<D>,
) -> Result<PathBuf> {
    write_except(run, step, text, p, &[])
}

/// [`write`] without the arrays named in `skip` (tests: a checkpoint of an earlier version).
fn write_except<const D: usize>(
    run: &Path,
    step: u64,
    text: &CheckpointText,
    p: &mut Particles<D>,
    skip: &[&str],
) -> Result<PathBuf> {
    let dir = folder(run);
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(format!("ckpt_{step:010}.hdf5"));
    let mut fb = FileBuilder::new();
    fb.set_attr("Dimension", AttrValue::I32(D as i32));
    fb.set_attr("Step", AttrValue::U64(step));
    // Texts as byte datasets: attributes are limited to 64 KiB, and the state's snapshot
    // list grows with the run.
    fb.create_dataset("Config")
        .with_u8_data(text.config_toml.as_bytes());
    fb.create_dataset("State")
        .with_u8_data(text.state_json.as_bytes());
    let mut g = fb.create_group("Particles");
    g.create_dataset("id").with_u64_data(&p.id);
    g.create_dataset("interactions")
        .with_u32_data(&p.interactions);
    for (name, v) in p.named_arrays_mut() {
        if !skip.contains(&name.as_str()) {
            g.create_dataset(&name).with_f64_data(v);
        }
    }
    fb.add_group(g.finish());
    fb.set_attr(
        "Checksums",
        AttrValue::U64Array(without(checksums(text, p), &checksum_names(p), skip)),
    );
    let bytes = fb
        .finish()
        .with_context(|| format!("cannot encode checkpoint {}", path.display()))?;
    write_atomic(&path, &bytes)?;
    for old in list(run)?.into_iter().skip(KEEP) {
        std::fs::remove_file(&old)
            .with_context(|| format!("cannot remove old checkpoint {}", old.display()))?;
    }
    Ok(path)
}

/// 64-bit FNV-1a of `bytes`, continuing from `hash`.
pub(crate) fn fnv1a(hash: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(hash, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

pub(crate) const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// The names of what [`checksums`] covers, in its order.
fn checksum_names<const D: usize>(p: &mut Particles<D>) -> Vec<String> {
    let mut names = vec![
        "Config".to_string(),
        "State".into(),
        "/Particles/id".into(),
        "/Particles/interactions".into(),
    ];
    names.extend(
        p.named_arrays_mut()
            .into_iter()
            .map(|(n, _)| format!("/Particles/{n}")),
    );
    names
}

/// FNV-1a of the raw (little-endian) bytes of the texts and of every particle array, in
/// the order of [`checksum_names`]: stored with each checkpoint, checked on reading.
fn checksums<const D: usize>(text: &CheckpointText, p: &mut Particles<D>) -> Vec<u64> {
    let mut out = vec![
        fnv1a(FNV_OFFSET, text.config_toml.as_bytes()),
        fnv1a(FNV_OFFSET, text.state_json.as_bytes()),
        p.id.iter()
            .fold(FNV_OFFSET, |h, v| fnv1a(h, &v.to_le_bytes())),
        p.interactions
            .iter()
            .fold(FNV_OFFSET, |h, v| fnv1a(h, &v.to_le_bytes())),
    ];
    for (_, v) in p.named_arrays_mut() {
        out.push(v.iter().fold(FNV_OFFSET, |h, x| fnv1a(h, &x.to_le_bytes())));
    }
    out
}

/// `values` (one per name of `names`) less those of the particle arrays named in `skip`.
fn without<T: Clone>(values: Vec<T>, names: &[String], skip: &[&str]) -> Vec<T> {
    values
        .into_iter()
        .zip(names)
        .filter(|(_, n)| {
            !skip
                .iter()
                .any(|s| n.strip_prefix("/Particles/") == Some(*s))
        })
        .map(|(v, _)| v)
        .collect()
}

/// The checkpoints of a run, newest first.
pub fn list(run: &Path) -> Result<Vec<PathBuf>> {
    let dir = folder(run);
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(&dir)
        .with_context(|| format!("cannot list {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("ckpt_") && n.ends_with(".hdf5"))
        })
        .collect();
    found.sort();
    found.reverse();
    Ok(found)
}

/// The dimension a checkpoint was written in.
pub fn dimension(path: &Path) -> Result<usize> {
    let f = open(path)?;
    let attrs = f
        .root()
        .attrs()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    match attrs.get("Dimension") {
        Some(AttrValue::I32(d)) if (1..=3).contains(d) => Ok(*d as usize),
        _ => bail!(
            "{}: not an sphdisk checkpoint (no Dimension)",
            path.display()
        ),
    }
}

fn open(path: &Path) -> Result<File> {
    let bytes = std::fs::read(path)
        .with_context(|| format!("cannot read checkpoint {}", path.display()))?;
    File::from_bytes(bytes)
        .map_err(|e| anyhow::anyhow!("{} is not a readable checkpoint: {e}", path.display()))
}

/// Reads a checkpoint written by [`write`] in dimension `D`.
pub fn read<const D: usize>(path: &Path) -> Result<(CheckpointText, Particles<D>)> {
    let what = path.display();
    let f = open(path)?;
    let text_attr = |k: &str| -> Result<String> {
        let bytes = f
            .dataset(k)
            .and_then(|d| d.read_u8())
            .map_err(|_| anyhow::anyhow!("{what}: not an sphdisk checkpoint (no {k})"))?;
        String::from_utf8(bytes).with_context(|| format!("{what}: {k} is not text"))
    };
    if dimension(path)? != D {
        bail!("{what}: checkpoint is not {D}D");
    }
    let text = CheckpointText {
        config_toml: text_attr("Config")?,
        state_json: text_attr("State")?,
    };
    let g = f
        .group("Particles")
        .map_err(|e| anyhow::anyhow!("{what}: no particles: {e}"))?;
    let err = |name: &str, e: hdf5_pure::Error| anyhow::anyhow!("{what}: /Particles/{name}: {e}");
    let id = g
        .dataset("id")
        .and_then(|d| d.read_u64())
        .map_err(|e| err("id", e))?;
    let interactions = g
        .dataset("interactions")
        .and_then(|d| d.read_u32())
        .map_err(|e| err("interactions", e))?;
    let mut p = Particles::<D>::new();
    let n = id.len();
    p.id = id;
    p.interactions = interactions;
    let mut absent: Vec<&str> = Vec::new();
    for (name, v) in p.named_arrays_mut() {
        if let Some(&later) = ADDED_LATER.iter().find(|&&a| a == name)
            && g.dataset(&name).is_err()
        {
            // A checkpoint of an earlier version.
            absent.push(later);
            *v = vec![0.0; n];
            continue;
        }
        *v = g
            .dataset(&name)
            .and_then(|d| d.read_f64())
            .map_err(|e| err(&name, e))?;
        if v.len() != n {
            bail!(
                "{what}: /Particles/{name} has {} entries for {n} particles",
                v.len()
            );
        }
    }
    if p.interactions.len() != n {
        bail!("{what}: /Particles/interactions has the wrong length");
    }
    // Checkpoints written before checksums were stored have none to compare.
    let attrs = f
        .root()
        .attrs()
        .map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    match attrs.get("Checksums") {
        None => {}
        Some(AttrValue::U64Array(stored)) => {
            let all_names = checksum_names(&mut p);
            let found = without(checksums(&text, &mut p), &all_names, &absent);
            let names = without(all_names.clone(), &all_names, &absent);
            if stored.len() != found.len() {
                bail!(
                    "{what}: {} checksums stored for {} arrays (the file is corrupt)",
                    stored.len(),
                    found.len()
                );
            }
            if let Some(k) = (0..found.len()).find(|&k| stored[k] != found[k]) {
                bail!(
                    "{what}: {} does not match its checksum (the file is corrupt)",
                    names[k]
                );
            }
        }
        Some(_) => bail!("{what}: Checksums is not a list of 64-bit checksums"),
    }
    Ok((text, p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn particles() -> Particles<2> {
        let mut p = Particles::new();
        for i in 0..20u64 {
            let x = i as f64 / 7.0;
            p.push(i + 100, [x, x.sin()], [x.cos(), 0.1], 0.01, 1.5 + x);
        }
        for (k, (_, v)) in p.named_arrays_mut().into_iter().enumerate() {
            for (i, x) in v.iter_mut().enumerate() {
                *x += (k * 31 + i) as f64 * std::f64::consts::PI * 1e-3;
            }
        }
        p.interactions
            .iter_mut()
            .enumerate()
            .for_each(|(i, k)| *k = i as u32);
        p
    }

    fn text() -> CheckpointText {
        CheckpointText {
            config_toml: "[problem]\nkind = \"sod\"\n".into(),
            state_json: "{\"t\":0.1}".into(),
        }
    }

    #[test]
    fn checkpoint_restores_every_array_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let mut p = particles();
        let path = write(dir.path(), 7, &text(), &mut p).unwrap();
        let (t, mut q) = read::<2>(&path).unwrap();
        assert_eq!(t.config_toml, text().config_toml);
        assert_eq!(t.state_json, text().state_json);
        assert_eq!(q.id, p.id);
        assert_eq!(q.interactions, p.interactions);
        for ((a, x), (b, y)) in p.named_arrays_mut().into_iter().zip(q.named_arrays_mut()) {
            assert_eq!(a, b);
            let xb: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
            let yb: Vec<u64> = y.iter().map(|v| v.to_bits()).collect();
            assert_eq!(xb, yb, "array {a}");
        }
    }

    /// A checkpoint of an earlier version, without `alpha`, resumes with α = 0 and its
    /// checksums still checked; any other missing array is an error naming it.
    #[test]
    fn a_checkpoint_without_the_later_arrays_reads_them_as_zero() {
        let dir = tempfile::tempdir().unwrap();
        let mut p = particles();
        let path = write_except(dir.path(), 7, &text(), &mut p, &["alpha"]).unwrap();
        let (_, q) = read::<2>(&path).unwrap();
        assert_eq!(q.alpha, vec![0.0; p.len()]);
        assert_eq!(q.u, p.u);
        assert_eq!(q.vgrad[1][0], p.vgrad[1][0]);
        // The stored checksums still cover the rest: corrupt u and it is named.
        let mut bytes = std::fs::read(&path).unwrap();
        let needle: Vec<u8> = p.u[3].to_le_bytes().to_vec();
        let at = bytes
            .windows(8)
            .position(|w| w == needle.as_slice())
            .unwrap();
        bytes[at] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        let e = format!("{:#}", read::<2>(&path).err().unwrap());
        assert!(e.contains("/Particles/u") && e.contains("checksum"), "{e}");
        let path = write_except(dir.path(), 8, &text(), &mut p, &["mass"]).unwrap();
        let e = format!("{:#}", read::<2>(&path).err().unwrap());
        assert!(e.contains("/Particles/mass"), "{e}");
    }

    #[test]
    fn only_the_newest_two_are_kept() {
        let dir = tempfile::tempdir().unwrap();
        let mut p = particles();
        for step in [5, 10, 15, 20] {
            write(dir.path(), step, &text(), &mut p).unwrap();
        }
        let names: Vec<String> = list(dir.path())
            .unwrap()
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["ckpt_0000000020.hdf5", "ckpt_0000000015.hdf5"]);
    }

    #[test]
    fn a_flipped_byte_in_an_array_fails_its_checksum_by_name() {
        let dir = tempfile::tempdir().unwrap();
        let mut p = particles();
        let path = write(dir.path(), 3, &text(), &mut p).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        // The raw bytes of the masses, found in the file; one bit of one of them flipped.
        let raw: Vec<u8> = p.mass[4..6].iter().flat_map(|m| m.to_le_bytes()).collect();
        let at = bytes
            .windows(raw.len())
            .position(|w| w == raw.as_slice())
            .expect("the masses are stored raw");
        bytes[at + 3] ^= 0x10;
        std::fs::write(&path, &bytes).unwrap();
        let e = format!("{:#}", read::<2>(&path).err().unwrap());
        assert!(
            e.contains("/Particles/mass") && e.contains("checksum"),
            "{e}"
        );
        assert!(e.contains("ckpt_0000000003.hdf5"), "{e}");
    }

    #[test]
    fn wrong_dimension_and_truncation_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let mut p = particles();
        let path = write(dir.path(), 1, &text(), &mut p).unwrap();
        let e = format!("{:#}", read::<3>(&path).err().unwrap());
        assert!(e.contains("not 3D"), "{e}");
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() / 3]).unwrap();
        let e = format!("{:#}", read::<2>(&path).err().unwrap());
        assert!(e.contains("ckpt_0000000001.hdf5"), "{e}");
    }
}
