//! `summary.json`: the figures of one run. Scripts rely on these keys: extend, never rename.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Result;
use serde::{Deserialize, Serialize};

use crate::io::atomic::write_atomic;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub problem: String,
    pub dimension: usize,
    pub particles: usize,
    pub steps: u64,
    pub t_end: f64,
    pub wall_seconds: f64,
    /// particles × steps / wall seconds.
    pub particle_updates_per_second: f64,
    /// Neighbour pairs evaluated (each once per step) / wall seconds.
    pub pairs_per_second: f64,
    /// Largest number of pairs the sweep's window held at once.
    pub peak_pair_window: usize,
    pub threads: usize,
    pub ranks: usize,
    pub conservation: Conservation,
    /// Problem-specific error norms against the exact solution.
    pub errors: BTreeMap<String, f64>,
    // Beyond the contract: figures that help read the above.
    pub smoothing_length: f64,
    pub kernel: String,
    pub mean_neighbours: f64,
    pub ghosts: usize,
    pub peak_window_bytes: usize,
    /// Peak resident memory of the process (VmHWM), bytes; 0 where unknown.
    pub peak_rss_bytes: u64,
    pub totals_start: TotalsRecord,
    pub totals_end: TotalsRecord,
}

/// Relative drifts, end against start.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Conservation {
    pub mass: f64,
    /// |ΔP| / Σ m|v|.
    pub momentum: f64,
    /// |ΔE| / |E| with E = kinetic + internal (null for an isothermal gas, whose energy is
    /// not conserved).
    pub energy: Option<f64>,
    /// Largest single-step momentum drift |ΔP| / Σ m|v|.
    pub momentum_max_per_step: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TotalsRecord {
    pub mass: f64,
    pub momentum: Vec<f64>,
    pub kinetic_energy: f64,
    pub internal_energy: f64,
    pub energy: f64,
}

impl<const D: usize> From<&crate::particles::Totals<D>> for TotalsRecord {
    fn from(t: &crate::particles::Totals<D>) -> Self {
        Self {
            mass: t.mass,
            momentum: t.momentum.to_vec(),
            kinetic_energy: t.kinetic,
            internal_energy: t.internal,
            energy: t.energy(),
        }
    }
}

impl Summary {
    pub fn write(&self, path: &Path) -> Result<()> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        write_atomic(path, text.as_bytes())
    }

    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)?;
        Ok(serde_json::from_str(&text)?)
    }
}

/// Peak resident set size of this process from /proc (Linux); 0 elsewhere.
pub fn peak_rss_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}
