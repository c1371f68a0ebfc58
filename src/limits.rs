//! Bounds on what a run may ask for, derived before anything is allocated: particles
//! (indexed by 32-bit numbers in the neighbour grid), cells of the neighbour grid (from the
//! box and h, in checked 64-bit arithmetic), snapshots per run, files per snapshot, worker
//! threads and the sweep's batch. Each refusal is one line naming the key to change.

use anyhow::{Result, bail};

use crate::boundary::{BoundaryKind, SimBox};
use crate::config::Config;

/// Particles a run may hold: the neighbour grid numbers them with `u32`.
pub const MAX_PARTICLES: u64 = u32::MAX as u64;
/// Cells of the neighbour grid along x (its slabs, each with an entry of the sweep).
pub const MAX_SLABS: u64 = 1 << 26;
/// Cells of the whole neighbour grid (64-bit cell keys, with room to spare).
pub const MAX_GRID_CELLS: u64 = 1 << 60;
/// Snapshots one run may write.
pub const MAX_SNAPSHOTS: u64 = 100_000;
/// Files one snapshot may be split into.
pub const MAX_FILES_PER_SNAPSHOT: usize = 4096;
/// Worker threads per core.
pub const MAX_THREADS_PER_CORE: usize = 16;

/// The particles of a lattice of `counts` per axis (set from `particles.n`), or an error
/// naming the key when there would be more than [`MAX_PARTICLES`].
pub fn lattice_count<const D: usize>(counts: [usize; D]) -> Result<usize> {
    let total = counts
        .iter()
        .try_fold(1u64, |a, &c| a.checked_mul(c as u64))
        .filter(|&t| t <= MAX_PARTICLES);
    match total {
        Some(t) => {
            check_memory::<D>(t, "particles.n")?;
            Ok(t as usize)
        }
        None => {
            let shape: Vec<String> = counts.iter().map(|c| c.to_string()).collect();
            bail!(
                "key `particles.n`: a lattice of {} particles is more than the {MAX_PARTICLES} a run can hold",
                shape.join(" × ")
            )
        }
    }
}

/// The environment variable that sets the memory a run may use (bytes, or with a suffix
/// K, M, G, T: `SPHDISK_MEMORY_LIMIT=64G`), instead of the machine's available memory.
pub const MEMORY_LIMIT_VAR: &str = "SPHDISK_MEMORY_LIMIT";

/// Bytes one particle of a `D`-dimensional run costs, about: its arrays (`Particles`:
/// 3D + D² + 9 numbers, an id and a counter), three times over (the state, the sweep's
/// working copy with ghosts, the copy gathered for outputs), and its share of the
/// neighbour grid's index.
pub fn bytes_per_particle<const D: usize>() -> u64 {
    let arrays = (3 * D + D * D + 9) as u64 * 8 + 12;
    3 * arrays + 64
}

/// The memory a run may use: `SPHDISK_MEMORY_LIMIT` if set, else `MemAvailable` of
/// /proc/meminfo; None where neither is known (then nothing is refused).
pub fn memory_available() -> Result<Option<u64>> {
    if let Ok(text) = std::env::var(MEMORY_LIMIT_VAR) {
        return parse_bytes(&text).map(Some).ok_or_else(|| {
            anyhow::anyhow!(
                "{MEMORY_LIMIT_VAR}: expected bytes, optionally with K, M, G or T (e.g. 64G), got `{text}`"
            )
        });
    }
    let Ok(info) = std::fs::read_to_string("/proc/meminfo") else {
        return Ok(None);
    };
    Ok(info
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))
        .and_then(|rest| rest.trim().strip_suffix("kB"))
        .and_then(|kb| kb.trim().parse::<u64>().ok())
        .map(|kb| kb.saturating_mul(1024)))
}

/// `123`, `4K`, `5M`, `6G`, `7T` (powers of 1024; a trailing `B` or `iB` allowed).
fn parse_bytes(text: &str) -> Option<u64> {
    let t = text.trim();
    let t = t
        .strip_suffix("iB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(t);
    let (digits, shift) = match t.chars().last()? {
        'K' | 'k' => (&t[..t.len() - 1], 10),
        'M' | 'm' => (&t[..t.len() - 1], 20),
        'G' | 'g' => (&t[..t.len() - 1], 30),
        'T' | 't' => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    digits.trim().parse::<u64>().ok()?.checked_mul(1 << shift)
}

/// Refuses `particles` particles of a `D`-dimensional run when their estimated memory
/// ([`bytes_per_particle`]) exceeds [`memory_available`], naming `key` (a problem file's
/// key, or a command-line option such as `--n`) and both figures.
pub fn check_memory<const D: usize>(particles: u64, key: &str) -> Result<()> {
    let Some(available) = memory_available()? else {
        return Ok(());
    };
    let need = particles.saturating_mul(bytes_per_particle::<D>());
    let named = if key.starts_with("--") {
        key.to_string()
    } else {
        format!("key `{key}`")
    };
    check_need(
        need as f64,
        available,
        &named,
        &format!("{particles} particles"),
        key,
    )
}

/// Refuses a set-up's `total` particles (counted in f64 before any is made) beyond
/// [`MAX_PARTICLES`] — "`head`: `what` would hold … particles" — or beyond the memory
/// ([`check_memory`], naming `key`).
pub fn check_particle_count<const D: usize>(
    total: f64,
    head: &str,
    what: &str,
    key: &str,
) -> Result<()> {
    if !(total <= MAX_PARTICLES as f64) {
        bail!(
            "{head}: {what} would hold {total:.3e} particles, more than the {MAX_PARTICLES} a run can hold"
        );
    }
    check_memory::<D>(total as u64, key)
}

/// The most particles a `D`-dimensional run may hold here: [`MAX_PARTICLES`], or fewer
/// where the memory ([`memory_available`], at [`bytes_per_particle`]) holds fewer. For
/// set-ups that walk rings or layers before they count their particles: a walk longer than
/// this cannot end in a run.
pub fn particle_budget<const D: usize>() -> Result<f64> {
    let memory = memory_available()?.map_or(f64::INFINITY, |a| {
        a as f64 / bytes_per_particle::<D>() as f64
    });
    Ok(memory.min(MAX_PARTICLES as f64))
}

/// Refuses `need` bytes beyond the `available` limit ([`memory_available`]): "`head`:
/// `what` need about …, more than …: lower `lower`".
pub fn check_need(need: f64, available: u64, head: &str, what: &str, lower: &str) -> Result<()> {
    if need > available as f64 {
        bail!(
            "{head}: {what} need about {}, more than {}: lower {lower}",
            size_text(need),
            memory_source(available)
        );
    }
    Ok(())
}

/// A number as a refusal shows it: plainly, or with an exponent where it is huge or tiny
/// (`1e300`, not its 301 digits).
pub fn show(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e6).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// The largest magnitude (and its inverse the smallest) a set-up's mass scale may take:
/// densities, pressures and momenta are products and squares of it, which must stay within
/// double precision (at 1e300 the summed momentum overflows; at 1e-300 the density
/// underflows and the step fails with no cause named).
pub const MAX_SCALE: f64 = 1e100;

/// Refuses a mass (or transfer rate) `x` of key `key` outside [1/[`MAX_SCALE`],
/// [`MAX_SCALE`]], as one line naming the key.
pub fn check_scale(key: &str, x: f64) -> Result<(), String> {
    if !(1.0 / MAX_SCALE..=MAX_SCALE).contains(&x) {
        return Err(format!(
            "key `{key}`: must lie between 1e-100 and 1e100 (densities and momenta are its \
             products and squares), got {}",
            show(x)
        ));
    }
    Ok(())
}

/// Digits a number of a message may take before [`shorten_numbers`] writes it with an
/// exponent: more than any figure a message means to show in full (a 64-bit count has 20).
const LONGEST_PLAIN_NUMBER: usize = 24;

/// `text` with every number written out in more than [`LONGEST_PLAIN_NUMBER`] characters
/// (Rust writes `1e300` as 301 digits, `1e-300` as 302) shown as [`show`] shows it, so that
/// an error line stays one readable line whatever number it echoes — the solver's own
/// messages and those of the TOML parser alike. Numbers already with an exponent, and
/// digits inside words or paths, are left as they are.
pub fn shorten_numbers(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut copied = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || matches!(b[i - 1], b'.' | b'_')));
        if !starts {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        if j + 1 < b.len() && b[j] == b'.' && b[j + 1].is_ascii_digit() {
            j += 1;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
        }
        let glued = j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_');
        if j - i > LONGEST_PLAIN_NUMBER
            && !glued
            && let Ok(x) = text[i..j].parse::<f64>()
        {
            out.push_str(&text[copied..i]);
            out.push_str(&show(x));
            copied = j;
        }
        i = j;
    }
    out.push_str(&text[copied..]);
    out
}

/// `bytes` in GiB, MiB or KiB (two decimals), whichever keeps it at least one.
pub fn size_text(bytes: f64) -> String {
    let (unit, name) = [(30, "GiB"), (20, "MiB"), (10, "KiB")]
        .into_iter()
        .map(|(shift, name)| ((1u64 << shift) as f64, name))
        .find(|&(unit, _)| bytes >= unit)
        .unwrap_or((1.0, "B"));
    format!("{:.2} {name}", bytes / unit)
}

/// What set the limit [`memory_available`] gave, `available` bytes, for messages: the
/// environment variable when it is set, else the machine's free memory.
pub fn memory_source(available: u64) -> String {
    let size = size_text(available as f64);
    if std::env::var_os(MEMORY_LIMIT_VAR).is_some() {
        format!("the {size} that {MEMORY_LIMIT_VAR} allows")
    } else {
        format!("the {size} available (MemAvailable; set {MEMORY_LIMIT_VAR} to change)")
    }
}

/// The key that sets h in `cfg`, for messages.
pub fn h_key(cfg: &Config) -> &'static str {
    if cfg.particles.h.is_some() {
        "particles.h"
    } else {
        "particles.h_factor"
    }
}

/// Refuses a neighbour grid (cells of the kernel support over the box, on open axes over
/// the particles' extent `pos`) with more than [`MAX_SLABS`] slabs or [`MAX_GRID_CELLS`]
/// cells, naming the key that sets h.
pub fn check_grid<const D: usize>(
    cfg: &Config,
    bx: &SimBox<D>,
    h: f64,
    pos: &[Vec<f64>; D],
) -> Result<()> {
    let support = cfg.particles.kernel.support_factor() * h;
    let mut total = Some(1u64);
    let mut along = [0.0f64; D];
    for d in 0..D {
        let extent = if bx.kinds[d] == BoundaryKind::Open {
            let (a, b) = pos[d]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            if a.is_finite() { b - a } else { bx.length(d) }
        } else {
            bx.length(d)
        };
        // Cells along d as `Grid::new` makes them (one more on each side of a closed axis).
        along[d] = (extent / support).floor() + 2.0;
        let cells = if along[d] < 1.8e19 {
            Some(along[d] as u64)
        } else {
            None
        };
        total = total.zip(cells).and_then(|(t, c)| t.checked_mul(c));
    }
    let too_many = !(along[0] <= MAX_SLABS as f64) || total.is_none_or(|t| t > MAX_GRID_CELLS);
    if too_many {
        let total = total.map_or_else(
            || format!("{:.3e}", along.iter().product::<f64>()),
            |t| t.to_string(),
        );
        bail!(
            "key `{}`: h = {h:e} gives a neighbour grid of {total} cells ({:.0} along x) for this box, more than sphdisk allows ({MAX_GRID_CELLS} cells, {MAX_SLABS} along x): raise h or shrink the box",
            h_key(cfg),
            along[0]
        );
    }
    check_pairs(cfg, h, pos)
}

/// Refuses a kernel support `support_factor · h` that would hold more neighbour pairs than
/// the memory has room for ([`memory_available`]), naming the key that sets h: before, an h
/// many times the particle spacing (`particles.h_factor = 1e300`) filled the memory with
/// pairs until the system killed the run. The particles are binned in cells one support
/// wide (the neighbour grid's); a particle's candidates are those of the 3^D cells around
/// its own, an upper bound on its neighbours (a thin disk under a wide support is a 2D
/// distribution in 3D cells, so no uniform share of them is assumed). The sweep holds the
/// pairs of about three slabs (the paper's window): the most candidate pairs in three
/// neighbouring slabs, with the particles' own memory ([`bytes_per_particle`]), must fit.
/// (`disk3d.toml`, 55 916 particles, checked: at `h_factor = 4` 1.83 GiB estimated against
/// a measured peak of 1.16 GiB; at 8, 11.0 GiB against 8.8–10.2 GiB — the estimate is the
/// right size, not a margin.)
pub fn check_pairs<const D: usize>(cfg: &Config, h: f64, pos: &[Vec<f64>; D]) -> Result<()> {
    use std::collections::HashMap;
    let Some(available) = memory_available()? else {
        return Ok(());
    };
    let n = pos[0].len();
    let support = cfg.particles.kernel.support_factor() * h;
    if n == 0 || !(support > 0.0 && support.is_finite()) {
        return Ok(());
    }
    let lo: [f64; D] =
        std::array::from_fn(|d| pos[d].iter().copied().fold(f64::INFINITY, f64::min));
    let cell = |i: usize| -> [i64; D] {
        std::array::from_fn(|d| ((pos[d][i] - lo[d]) / support).floor() as i64)
    };
    let mut counts: HashMap<[i64; D], u64> = HashMap::new();
    for i in 0..n {
        *counts.entry(cell(i)).or_insert(0) += 1;
    }
    // Candidates (ordered, self included) of each slab along x.
    let mut per_slab: HashMap<i64, f64> = HashMap::new();
    for (c, &k) in &counts {
        let mut around = 0u64;
        for o in 0..3usize.pow(D as u32) {
            let mut nb = *c;
            let mut rest = o;
            for x in nb.iter_mut() {
                *x += (rest % 3) as i64 - 1;
                rest /= 3;
            }
            around += counts.get(&nb).copied().unwrap_or(0);
        }
        *per_slab.entry(c[0]).or_insert(0.0) += k as f64 * around as f64;
    }
    let window = per_slab
        .keys()
        .map(|&s| {
            (s - 1..=s + 1)
                .map(|t| per_slab.get(&t).copied().unwrap_or(0.0))
                .sum::<f64>()
        })
        .fold(0.0, f64::max);
    let pairs = window / 2.0;
    let need = pairs * crate::sweep::pairs::BYTES_PER_PAIR as f64
        + (n as u64).saturating_mul(bytes_per_particle::<D>()) as f64;
    let most = counts.values().copied().max().unwrap_or(0);
    check_need(
        need,
        available,
        &format!("key `{}`", h_key(cfg)),
        &format!(
            "{n} particles and up to {pairs:.3e} neighbour pairs in the sweep's window (h = {h:.3e}: up to {most} particles in a cell one support wide)"
        ),
        h_key(cfg),
    )
}

/// Refuses more than [`MAX_SNAPSHOTS`] snapshots of `output.interval` up to `t_end`.
pub fn check_snapshot_count(interval: f64, t_end: f64) -> Result<u64> {
    let count = (t_end / interval * (1.0 + 1e-12)).floor();
    if !(count <= MAX_SNAPSHOTS as f64) {
        bail!(
            "key `output.interval`: {interval:e} up to time.end = {t_end:e} gives {count:.3e} snapshots, more than the {MAX_SNAPSHOTS} a run may write: raise output.interval or lower time.end"
        );
    }
    Ok(count as u64)
}

/// Refuses more than [`MAX_FILES_PER_SNAPSHOT`] files per snapshot.
pub fn check_files_per_snapshot(files: usize) -> Result<()> {
    if files > MAX_FILES_PER_SNAPSHOT {
        bail!("key `output.files_per_snapshot`: at most {MAX_FILES_PER_SNAPSHOT}, got {files}");
    }
    Ok(())
}

/// Refuses a batch of the sweep (`sweep::Window::batch_per_thread`) of no particles or of
/// more than a run may hold ([`MAX_PARTICLES`]), naming `what` asked for it (the key
/// `sweep.batch_per_thread` or the option `--batch`).
pub fn check_batch(what: &str, batch: u64) -> Result<()> {
    if !(1..=MAX_PARTICLES).contains(&batch) {
        bail!("{what}: must be between 1 and {MAX_PARTICLES}, got {batch}");
    }
    Ok(())
}

/// Refuses more than [`MAX_THREADS_PER_CORE`] worker threads per core of `cores`, naming
/// the command-line option (`--threads`, `--with-threads`) that asked for them.
pub fn check_threads(option: &str, threads: usize, cores: usize) -> Result<()> {
    let max = MAX_THREADS_PER_CORE * cores.max(1);
    if threads > max {
        bail!(
            "{option}: {threads} is more than {max} ({MAX_THREADS_PER_CORE} per core of the {cores} here)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_counts_are_checked_before_they_overflow() {
        assert_eq!(lattice_count([3, 4, 5]).unwrap(), 60);
        for counts in [[2_097_153usize; 3], [usize::MAX, 2, 1], [65_536, 65_536, 1]] {
            let e = lattice_count(counts).unwrap_err().to_string();
            assert!(e.contains("particles.n"), "{e}");
        }
    }

    #[test]
    fn numbers_are_shown_with_an_exponent_only_where_huge_or_tiny() {
        assert_eq!(show(1e300), "1e300");
        assert_eq!(show(-2e-7), "-2e-7");
        assert_eq!(show(50.0), "50");
        assert_eq!(show(0.0), "0");
        assert_eq!(show(f64::NAN), "NaN");
    }

    #[test]
    fn long_numbers_in_messages_are_shortened_and_the_rest_left_alone() {
        let huge = format!("got {}, and -{} with {}", 1e300, 1e300, 1e-300);
        assert!(huge.len() > 900);
        assert_eq!(shorten_numbers(&huge), "got 1e300, and -1e300 with 1e-300");
        let tail = format!("`{}`", 2.5e-200);
        assert_eq!(shorten_numbers(&tail), "`2.5e-200`");
        for kept in [
            "a lattice of 4294967295 particles at t = 0.30000000000000004",
            "count 18446744073709551615 in /runs/run_1234567890123456789012345678/x.h5",
            "dt = 2.510032514109954e-17, v2 1.5",
            "",
        ] {
            assert_eq!(shorten_numbers(kept), kept);
        }
    }

    #[test]
    fn sizes_are_written_in_the_largest_unit_that_keeps_them_at_least_one() {
        assert_eq!(size_text(3.0 * (1u64 << 30) as f64), "3.00 GiB");
        assert_eq!(size_text((1u64 << 20) as f64), "1.00 MiB");
        assert_eq!(size_text(1536.0), "1.50 KiB");
        assert_eq!(size_text(12.0), "12.00 B");
    }

    #[test]
    fn memory_sizes_parse_with_suffixes() {
        assert_eq!(parse_bytes("123"), Some(123));
        assert_eq!(parse_bytes("4K"), Some(4096));
        assert_eq!(parse_bytes("2GiB"), Some(2 << 30));
        assert_eq!(parse_bytes("1T"), Some(1 << 40));
        assert_eq!(parse_bytes("lots"), None);
        assert_eq!(parse_bytes("99999999999T"), None);
        // 10⁹ particles in 3D are hundreds of GiB: more than any test machine has.
        assert!(bytes_per_particle::<3>() * 1_000_000_000 > 500 << 30);
    }

    #[test]
    fn snapshot_counts_files_and_threads_are_bounded() {
        assert_eq!(check_snapshot_count(0.05, 0.2).unwrap(), 4);
        for (iv, end) in [(0.05, 1e308), (1e-300, 0.2), (f64::MIN_POSITIVE, 1.0)] {
            let e = check_snapshot_count(iv, end).unwrap_err().to_string();
            assert!(e.contains("output.interval"), "{e}");
        }
        check_files_per_snapshot(4).unwrap();
        let e = check_files_per_snapshot(1_000_000_000)
            .unwrap_err()
            .to_string();
        assert!(e.contains("output.files_per_snapshot"), "{e}");
        check_threads("--threads", 32, 2).unwrap();
        let e = check_threads("--threads", 100_000, 2)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--threads") && e.contains("100000"), "{e}");
    }
}
