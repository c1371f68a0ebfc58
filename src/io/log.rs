//! `run.log`: a line per event of a run (start, snapshots, checkpoints, progress every
//! half minute, end), appended and flushed at once, for batch jobs that run `--quiet`.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};

pub struct RunLog {
    /// None: a log that writes nothing (ranks other than 0 of a distributed run).
    file: Option<std::fs::File>,
    start: Instant,
}

impl RunLog {
    /// Opens (appending to) `run.log` in the output folder.
    pub fn open(dir: &Path) -> Result<Self> {
        let path = dir.join("run.log");
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .with_context(|| format!("cannot open {}", path.display()))?;
        Ok(Self {
            file: Some(file),
            start: Instant::now(),
        })
    }

    /// A log that writes nothing.
    pub fn silent() -> Self {
        Self {
            file: None,
            start: Instant::now(),
        }
    }

    /// Appends one line, prefixed with the wall seconds since the log was opened. A log
    /// that cannot be written must not stop the run: the error is ignored.
    pub fn line(&mut self, msg: &str) {
        let s = self.start.elapsed().as_secs_f64();
        if let Some(f) = &mut self.file {
            let _ = writeln!(f, "[{s:10.2} s] {msg}");
            let _ = f.flush();
        }
    }
}
