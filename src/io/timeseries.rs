//! Time series written during a run, a row at a time (FargoCPT's monitor files, Phantom's
//! `.ev`, SWIFT's `statistics.txt`): for every run `statistics.csv` (global totals every
//! `output.statistics_steps` steps, at step 0 and at the end); for a binary, `lightcurve.csv` (the luminosity L = Σ mᵢ ε̇ᵢ of the dissipated
//! energy, split into disk, stream and bright-spot regions), `monitor.csv` (the disk's
//! radius and mass, and the mass budget) and `modes.csv` (the disk's eccentricity, m = 1
//! and m = 2 modes and longitude of periastron). Rows are appended and flushed at once; a resumed
//! run first drops the rows written after its checkpoint, so the files continue as if the
//! run had never stopped.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// One CSV file with a fixed header, appended row by row.
pub struct Series {
    path: PathBuf,
    file: Option<std::fs::File>,
}

impl Series {
    /// Opens `name` in `dir` for a run at time `t`: a new file with `header` when `fresh`,
    /// otherwise the existing one without its rows later than `t` (first column).
    pub fn open(dir: &Path, name: &str, header: &str, fresh: bool, t: f64) -> Result<Self> {
        let path = dir.join(name);
        let mut keep = format!("{header}\n");
        if !fresh && let Ok(old) = std::fs::read_to_string(&path) {
            for line in old.lines().skip(1) {
                let first = line.split(',').next().and_then(|c| c.parse::<f64>().ok());
                if first.is_some_and(|x| x <= t) {
                    keep.push_str(line);
                    keep.push('\n');
                }
            }
        }
        crate::io::atomic::write_atomic(&path, keep.as_bytes())?;
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .with_context(|| format!("cannot open {}", path.display()))?;
        Ok(Self {
            path,
            file: Some(file),
        })
    }

    /// A series that writes nothing (ranks other than 0).
    pub fn silent() -> Self {
        Self {
            path: PathBuf::new(),
            file: None,
        }
    }

    /// Appends one row of numbers (full precision).
    pub fn row(&mut self, values: &[f64]) -> Result<()> {
        let Some(f) = &mut self.file else {
            return Ok(());
        };
        let line: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        writeln!(f, "{}", line.join(","))
            .and_then(|_| f.flush())
            .with_context(|| format!("cannot write {}", self.path.display()))
    }
}

/// The rows as the run finally had them: wherever the time `t` does not increase (a
/// resumed run writing again from its checkpoint), the earlier rows from that time on are
/// dropped.
pub fn supersede<T>(rows: impl IntoIterator<Item = T>, t: impl Fn(&T) -> f64) -> Vec<T> {
    let mut kept: Vec<T> = Vec::new();
    for r in rows {
        while kept.last().is_some_and(|last| t(last) >= t(&r)) {
            kept.pop();
        }
        kept.push(r);
    }
    kept
}

/// Parses the text of a series written by [`Series`]: the header must be `header`; each
/// row has one number per column (`allow_nan`: NaN cells, for values a row may lack — but
/// never in the first column, the time; never infinities). A last line without its newline that does not parse is a row a running
/// simulation is still writing and is left out. Errors do not name the file.
pub fn parse_series(text: &str, header: &str, allow_nan: bool) -> anyhow::Result<Vec<Vec<f64>>> {
    let mut lines = text.lines().enumerate();
    let first = match lines.next() {
        Some((_, h)) => h.trim_start_matches('\u{feff}').trim(),
        None => anyhow::bail!("empty file; expected the header `{header}`"),
    };
    if first != header {
        anyhow::bail!("header is `{first}`, expected `{header}`");
    }
    let names: Vec<&str> = header.split(',').collect();
    let unfinished_last = !text.ends_with('\n');
    let total = text.lines().count();
    let mut rows = Vec::new();
    for (k, line) in lines {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        match parse_row(line, &names, allow_nan) {
            Ok(row) => rows.push(row),
            Err(_) if unfinished_last && k + 1 == total => {}
            Err(e) => anyhow::bail!("line {}: {e}", k + 1),
        }
    }
    Ok(rows)
}

fn parse_row(line: &str, names: &[&str], allow_nan: bool) -> anyhow::Result<Vec<f64>> {
    let cells: Vec<&str> = line.split(',').map(str::trim).collect();
    if cells.len() != names.len() {
        anyhow::bail!("{} cells, expected {}", cells.len(), names.len());
    }
    cells
        .iter()
        .zip(names)
        .enumerate()
        .map(|(i, (cell, name))| {
            let x: f64 = cell
                .parse()
                .map_err(|_| anyhow::anyhow!("column {name}: `{cell}` is not a number"))?;
            if x.is_infinite() || (x.is_nan() && !(allow_nan && i > 0)) {
                anyhow::bail!("column {name}: {x} is not a finite number");
            }
            Ok(x)
        })
        .collect()
}

/// Header of `statistics.csv`: time, step, time step, particles, their mass, what the
/// central mass accreted (mass; a binary's accretor included), energies (kinetic,
/// internal, potential in the external field, total), momentum and Σ m (x v_y − y v_x),
/// summed over every rank's particles (unused momentum components 0).
pub const STATISTICS_HEADER: &str = "t,step,dt,particles,mass,accreted_mass,kinetic_energy,internal_energy,potential_energy,total_energy,px,py,pz,angular_momentum";

/// Header of `lightcurve.csv`: Σ m ε̇ in all, in the disk, the stream and the bright spot
/// (`physics::binary::Region`), and what an observer at `binary.inclination` sees of it
/// (`analysis::observer`: foreshortened, the spot only from the rim's side facing the
/// observer, eclipsed by the donor).
pub const LIGHTCURVE_HEADER: &str = "t,orbit,l_total,l_disk,l_stream,l_spot,l_observed";
/// Header of `modes.csv`: the disk's m = 1 and m = 2 modes and mean eccentricity in the
/// window [0.5, 1.0) R90 (`problems::cv::DiskModes`), the longitude of periastron in the
/// turning frame and in the inertial frame (whose slope is the precession rate).
pub const MODES_HEADER: &str = "t,orbit,r_disk,window_mass,m1,m1_phase_deg,m2,m2_phase_deg,e,periastron_deg,periastron_inertial_deg";
/// Header of `monitor.csv`; `hot_mass` is the mass on the hot branch of `[outbursts]` (0
/// without it).
pub const MONITOR_HEADER: &str =
    "t,orbit,particles,mass,disk_mass,r_disk,injected,accreted,returned,escaped,hot_mass";
