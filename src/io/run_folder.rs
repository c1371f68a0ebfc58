//! Ownership of an output folder: one run at a time holds it (a lock file with its process
//! id, removed when the run ends, taken over when that process is gone), and a fresh run
//! does not write into a folder that holds another run's files unless asked to clear them.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

use crate::io::checkpoint;

/// The lock file's name inside the output folder.
pub const LOCK_FILE: &str = ".sphdisk.lock";

/// Files of a run (and of the analyses of it) directly in its folder.
const RUN_FILES: &[&str] = &[
    "run.toml",
    RUN_ID_FILE,
    "run.log",
    "summary.json",
    "final.csv",
    "final.hdf5",
    "snapshots.json",
    "statistics.csv",
    "lightcurve.csv",
    "monitor.csv",
    "modes.csv",
    "superhump.json",
    "superhump_eccentricity.png",
    "superhump_precession.png",
    "superhump_lightcurve.png",
    "superhump_periodogram.png",
    "sod.png",
    "sod_profile.csv",
    "ring.png",
    "ring_profiles.csv",
    "ring_errors.csv",
    "disk_evolution.csv",
    "cv_evolution.csv",
    "cv.json",
    "lightcurve.png",
    "periodogram.png",
    "lightcurve.json",
];

/// The file holding the identity of the run in a folder (written at its start).
pub const RUN_ID_FILE: &str = "run.id";

/// A new run's identity: a hash of its resolved problem (`config`) and of the moment and
/// process it starts in, as 32 hex digits.
pub fn new_run_id(config: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let start = format!("{nanos}:{}", std::process::id());
    format!(
        "{:016x}{:016x}",
        checkpoint::fnv1a(checkpoint::FNV_OFFSET, config.as_bytes()),
        checkpoint::fnv1a(checkpoint::FNV_OFFSET, start.as_bytes())
    )
}

/// The identity of the run in `dir` (its `run.id`), if it has one.
pub fn read_run_id(dir: &Path) -> Result<Option<String>> {
    let path = dir.join(RUN_ID_FILE);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let id = text.trim();
            if id.is_empty() || id.len() > 64 || !id.bytes().all(|b| b.is_ascii_hexdigit()) {
                bail!("{}: not a run id", path.display());
            }
            Ok(Some(id.to_string()))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
    }
}

/// The exclusive hold of a run on its output folder; the lock file goes when this does
/// (end of the run, an error, a panic that unwinds).
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
}

impl FolderLock {
    /// Locks the existing folder `dir`: fails with one line naming the folder and the
    /// process that holds it; a lock left by a process that no longer runs is taken over.
    pub fn acquire(dir: &Path) -> Result<Self> {
        let path = dir.join(LOCK_FILE);
        for attempt in 0..3 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    let lock = Self { path: path.clone() };
                    write!(f, "{}", std::process::id())
                        .and_then(|_| f.sync_all())
                        .with_context(|| format!("cannot write {}", path.display()))?;
                    return Ok(lock);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = std::fs::read_to_string(&path).unwrap_or_default();
                    match text.trim().parse::<u32>() {
                        Ok(pid) if process_alive(pid) => bail!(
                            "output folder {} is in use by sphdisk process {pid} (lock {}; remove it if no run is there)",
                            dir.display(),
                            path.display()
                        ),
                        // A lock being written this instant is empty; give it a moment.
                        Err(_) if text.is_empty() && attempt == 0 => {
                            std::thread::sleep(std::time::Duration::from_millis(50))
                        }
                        // The holder is gone (killed): take the folder over, unless another
                        // process did so since the lock was read.
                        _ => {
                            if std::fs::read_to_string(&path).unwrap_or_default() == text {
                                let _ = std::fs::remove_file(&path);
                            }
                        }
                    }
                }
                Err(e) => {
                    return Err(e)
                        .with_context(|| format!("cannot lock output folder {}", dir.display()));
                }
            }
        }
        bail!(
            "output folder {} is in use by another sphdisk process (lock {})",
            dir.display(),
            path.display()
        )
    }
}

/// Fails with the line of [`FolderLock::acquire`] if another running process holds `dir`
/// (for a check before the lock is taken, e.g. before reading a run to resume).
pub fn refuse_if_held(dir: &Path) -> Result<()> {
    let path = dir.join(LOCK_FILE);
    let text = std::fs::read_to_string(&path).unwrap_or_default();
    match text.trim().parse::<u32>() {
        Ok(pid) if pid != std::process::id() && process_alive(pid) => bail!(
            "output folder {} is in use by sphdisk process {pid} (lock {}; remove it if no run is there)",
            dir.display(),
            path.display()
        ),
        _ => Ok(()),
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Whether process `pid` runs (on Linux from /proc; elsewhere every pid counts as running,
/// so a stale lock there is removed by hand). A killed run whose parent has not yet reaped
/// it (a zombie, state `Z` in /proc/PID/stat) no longer runs.
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return true;
    }
    match std::fs::read_to_string(proc.join(pid.to_string()).join("stat")) {
        // "PID (COMM) STATE …": the state follows the last ')' (COMM may hold one).
        Ok(stat) => stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_none_or(|state| state != "Z" && state != "X"),
        Err(_) => proc.join(pid.to_string()).exists(),
    }
}

/// Whether `name` is a file sphdisk writes directly in a run folder: the fixed names,
/// snapshots (`snap_NNNN.hdf5`, `snap_NNNN.k.hdf5`) and temporaries of atomic writes.
fn is_run_file(name: &str) -> bool {
    if RUN_FILES.contains(&name) {
        return true;
    }
    if let Some(rest) = name
        .strip_prefix("snap_")
        .and_then(|r| r.strip_suffix(".hdf5"))
    {
        let mut parts = rest.split('.');
        let digits = |s: Option<&str>| {
            s.is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
        };
        let first = digits(parts.next());
        return match parts.next() {
            None => first,
            k => first && digits(k) && parts.next().is_none(),
        };
    }
    // `.NAME.tmp-PID`, left by a write that was killed.
    if let Some((stem, pid)) = name.strip_prefix('.').and_then(|n| n.rsplit_once(".tmp-")) {
        return pid.bytes().all(|b| b.is_ascii_digit()) && is_run_file(stem);
    }
    false
}

/// The files of an earlier run in `dir` (sorted; checkpoints as `checkpoints/NAME`).
pub fn run_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut found = Vec::new();
    if !dir.is_dir() {
        return Ok(found);
    }
    for e in std::fs::read_dir(dir).with_context(|| format!("cannot list {}", dir.display()))? {
        let e = e.with_context(|| format!("cannot list {}", dir.display()))?;
        if e.file_name().to_str().is_some_and(is_run_file) && e.path().is_file() {
            found.push(e.path());
        }
    }
    let ckpt = checkpoint::folder(dir);
    if ckpt.is_dir() {
        for e in
            std::fs::read_dir(&ckpt).with_context(|| format!("cannot list {}", ckpt.display()))?
        {
            let e = e.with_context(|| format!("cannot list {}", ckpt.display()))?;
            let name = e.file_name();
            let name = name.to_string_lossy();
            let ours = name.starts_with("ckpt_") && name.ends_with(".hdf5")
                || name.starts_with(".ckpt_") && name.contains(".hdf5.tmp-");
            if ours && e.path().is_file() {
                found.push(e.path());
            }
        }
    }
    found.sort();
    Ok(found)
}

/// The process id of a temporary file of an atomic write (`.NAME.tmp-PID`).
fn temporary_pid(name: &str) -> Option<u32> {
    let (_, pid) = name.strip_prefix('.')?.rsplit_once(".tmp-")?;
    pid.parse().ok()
}

/// Removes the temporaries of atomic writes (`.NAME.tmp-PID`, in `dir` and its checkpoint
/// folder) whose process no longer runs: what a write killed half-way leaves. Called by a
/// run that holds the folder, before it writes; returns how many went.
pub fn remove_stale_temporaries(dir: &Path) -> Result<usize> {
    let mut removed = 0;
    for folder in [dir.to_path_buf(), checkpoint::folder(dir)] {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name();
            let Some(pid) = name.to_str().and_then(temporary_pid) else {
                continue;
            };
            if pid != std::process::id() && !process_alive(pid) && e.path().is_file() {
                std::fs::remove_file(e.path())
                    .with_context(|| format!("cannot remove {}", e.path().display()))?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// Refuses a fresh run into `dir` if it holds another run's files; one line names the
/// folder, a few of the files and the ways on.
pub fn refuse_if_used(dir: &Path) -> Result<()> {
    let files = run_files(dir)?;
    if files.is_empty() {
        return Ok(());
    }
    let names: Vec<String> = files
        .iter()
        .take(3)
        .map(|f| {
            f.strip_prefix(dir)
                .unwrap_or(f)
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let more = if files.len() > 3 { ", …" } else { "" };
    bail!(
        "output folder {} holds another run's files ({}{more}): continue it with --resume {}, choose a different --out, or give --force to replace it",
        dir.display(),
        names.join(", "),
        dir.display()
    )
}

/// Removes the files of an earlier run from `dir` (and its checkpoint folder if that is
/// then empty); files sphdisk does not write stay.
pub fn clear(dir: &Path) -> Result<()> {
    for f in run_files(dir)? {
        std::fs::remove_file(&f).with_context(|| format!("cannot remove {}", f.display()))?;
    }
    let ckpt = checkpoint::folder(dir);
    if ckpt.is_dir() && std::fs::read_dir(&ckpt).is_ok_and(|mut d| d.next().is_none()) {
        std::fs::remove_dir(&ckpt).with_context(|| format!("cannot remove {}", ckpt.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_files_are_told_from_other_files() {
        for name in [
            "run.toml",
            "summary.json",
            "snap_0003.hdf5",
            "snap_0003.12.hdf5",
            ".summary.json.tmp-4242",
            ".snap_0001.hdf5.tmp-7",
        ] {
            assert!(is_run_file(name), "{name}");
        }
        for name in [
            "notes.txt",
            "snap_.hdf5",
            "snap_00a1.hdf5",
            "snap_0001.2.3.hdf5",
            "my_summary.json",
            ".notes.txt.tmp-1",
            ".run.toml.tmp-x",
        ] {
            assert!(!is_run_file(name), "{name}");
        }
    }

    #[test]
    fn a_held_lock_is_refused_and_released_when_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let lock = FolderLock::acquire(dir.path()).unwrap();
        let text = std::fs::read_to_string(dir.path().join(LOCK_FILE)).unwrap();
        assert_eq!(text, std::process::id().to_string());
        let e = format!("{:#}", FolderLock::acquire(dir.path()).unwrap_err());
        assert!(e.contains(&std::process::id().to_string()), "{e}");
        assert!(e.contains(&dir.path().display().to_string()), "{e}");
        drop(lock);
        assert!(!dir.path().join(LOCK_FILE).exists());
        FolderLock::acquire(dir.path()).unwrap();
    }

    #[test]
    fn a_stale_lock_is_taken_over() {
        // A process that has ended: its pid is free (Linux keeps pids unused for a while).
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(LOCK_FILE), pid.to_string()).unwrap();
        let _lock = FolderLock::acquire(dir.path()).unwrap();
        let text = std::fs::read_to_string(dir.path().join(LOCK_FILE)).unwrap();
        assert_eq!(text, std::process::id().to_string());
    }

    #[test]
    fn the_lock_of_a_killed_but_unreaped_run_is_taken_over() {
        // A child that has exited but is not waited for stays a zombie with its /proc
        // entry: a run killed while its parent (a shell, a batch system) has not yet reaped
        // it. Its lock must not block the next run.
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        let stat = format!("/proc/{pid}/stat");
        let t0 = std::time::Instant::now();
        while !std::fs::read_to_string(&stat)
            .unwrap_or_default()
            .rsplit_once(')')
            .is_some_and(|(_, r)| r.trim_start().starts_with('Z'))
        {
            assert!(t0.elapsed().as_secs() < 10, "child never exited");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(LOCK_FILE), pid.to_string()).unwrap();
        let lock = FolderLock::acquire(dir.path());
        child.wait().unwrap();
        let _lock = lock.unwrap();
        let text = std::fs::read_to_string(dir.path().join(LOCK_FILE)).unwrap();
        assert_eq!(text, std::process::id().to_string());
    }

    #[test]
    fn temporaries_of_dead_processes_are_removed_and_others_kept() {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let me = std::process::id();
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(checkpoint::folder(d)).unwrap();
        let stale = [
            format!(".summary.json.tmp-{dead}"),
            format!("checkpoints/.ckpt_0000000004.hdf5.tmp-{dead}"),
        ];
        let kept = [
            format!(".run.toml.tmp-{me}"),
            ".notes.tmp-x".to_string(),
            "notes.txt".to_string(),
        ];
        for f in stale.iter().chain(&kept) {
            std::fs::write(d.join(f), "x").unwrap();
        }
        assert_eq!(remove_stale_temporaries(d).unwrap(), 2);
        for f in &stale {
            assert!(!d.join(f).exists(), "{f}");
        }
        for f in &kept {
            assert!(d.join(f).exists(), "{f}");
        }
        assert_eq!(remove_stale_temporaries(d).unwrap(), 0);
    }

    #[test]
    fn clear_removes_only_run_files() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(checkpoint::folder(d)).unwrap();
        for f in [
            "run.toml",
            "summary.json",
            "snap_0000.hdf5",
            "checkpoints/ckpt_0000000005.hdf5",
        ] {
            std::fs::write(d.join(f), "x").unwrap();
        }
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        assert!(refuse_if_used(d).is_err());
        clear(d).unwrap();
        refuse_if_used(d).unwrap();
        let left: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(left, ["notes.txt"]);
    }
}
