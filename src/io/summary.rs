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
    /// The largest neighbour grid of the run: its cells (most empty in a sparse box), and
    /// the bytes of its cell index (per occupied cell when sparse).
    #[serde(default)]
    pub peak_grid_cells: u64,
    #[serde(default)]
    pub peak_grid_index_bytes: usize,
    /// Peak resident memory of the process (VmHWM), bytes; 0 where unknown.
    pub peak_rss_bytes: u64,
    pub totals_start: TotalsRecord,
    pub totals_end: TotalsRecord,
    /// What the central mass accreted (present when an accretion radius is set).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accretion: Option<AccretionLedger>,
    /// A binary's mass budget (injected, accreted, returned, escaped, present).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_budget: Option<MassBudgetRecord>,
    /// A binary's geometry and figures (cv problems only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub binary: Option<serde_json::Value>,
    /// The spreading ring's parameters (ring problems only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ring: Option<crate::problems::ring::RingRecord>,
    /// Distributed runs: decomposition, load balance, communication and waiting per rank.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parallel: Option<serde_json::Value>,
    /// Where the step loop's time went: the sweep's stages and everything else.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
}

/// The step loop's wall time split between the sweep (its stages summed over the steps, on
/// this rank or rank 0) and the rest: kicks and drift, external forces, the time step,
/// diagnostics, sinks, injection and output.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Timing {
    /// Seconds in each stage of the sweep.
    pub sweep: crate::sweep::StageTimes,
    pub sweep_seconds: f64,
    /// `wall_seconds` less the sweep.
    pub outside_sweep_seconds: f64,
    /// Their share of `wall_seconds`.
    pub outside_sweep_share: f64,
}

impl Timing {
    /// From the sweep's stage totals and the loop's wall seconds.
    pub fn of(sweep: crate::sweep::StageTimes, wall: f64) -> Self {
        let sweep_seconds = sweep.total();
        let outside = (wall - sweep_seconds).max(0.0);
        Self {
            sweep,
            sweep_seconds,
            outside_sweep_seconds: outside,
            outside_sweep_share: if wall > 0.0 { outside / wall } else { 0.0 },
        }
    }
}

/// Mass, momentum, angular momentum and energy removed by accretion: with it the
/// conservation figures stay exact (particles + accreted = initial).
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct AccretionLedger {
    pub particles: u64,
    pub mass: f64,
    pub momentum: Vec<f64>,
    pub angular_momentum: f64,
    pub kinetic_energy: f64,
    pub internal_energy: f64,
    pub potential_energy: f64,
}

impl AccretionLedger {
    /// The ledger as numbers (particles, mass, L, kinetic, internal, potential, momentum…),
    /// to be summed over ranks.
    pub fn to_values<const D: usize>(&self) -> Vec<f64> {
        let mut v = vec![
            self.particles as f64,
            self.mass,
            self.angular_momentum,
            self.kinetic_energy,
            self.internal_energy,
            self.potential_energy,
        ];
        v.extend((0..D).map(|d| self.momentum.get(d).copied().unwrap_or(0.0)));
        v
    }

    /// Adds a ledger given as [`AccretionLedger::to_values`].
    pub fn add_values<const D: usize>(&mut self, v: &[f64]) {
        if v[0] == 0.0 {
            return;
        }
        if self.momentum.len() != D {
            self.momentum = vec![0.0; D];
        }
        self.particles += v[0] as u64;
        self.mass += v[1];
        self.angular_momentum += v[2];
        self.kinetic_energy += v[3];
        self.internal_energy += v[4];
        self.potential_energy += v[5];
        for d in 0..D {
            self.momentum[d] += v[6 + d];
        }
    }

    /// Removes the particles within `radius` of the centre, books what they carried, and
    /// returns how many went.
    pub fn accrete<const D: usize>(
        &mut self,
        p: &mut crate::particles::Particles<D>,
        radius: f64,
        g: &crate::physics::gravity::PointMass,
    ) -> usize {
        let keep: Vec<bool> = (0..p.len())
            .map(|i| (0..D).map(|d| p.pos[d][i].powi(2)).sum::<f64>() >= radius * radius)
            .collect();
        let gone = keep.iter().filter(|&&k| !k).count();
        if gone == 0 {
            return 0;
        }
        if self.momentum.len() != D {
            self.momentum = vec![0.0; D];
        }
        for i in (0..p.len()).filter(|&i| !keep[i]) {
            let m = p.mass[i];
            let v2: f64 = (0..D).map(|d| p.vel[d][i].powi(2)).sum();
            self.particles += 1;
            self.mass += m;
            for d in 0..D {
                self.momentum[d] += m * p.vel[d][i];
            }
            self.angular_momentum += m * p.angular_momentum_z(i);
            self.kinetic_energy += 0.5 * m * v2;
            self.internal_energy += m * p.u[i];
            self.potential_energy += m * g.potential(&p.position(i));
        }
        p.retain(&keep);
        gone
    }

    /// Adds the ledger to a set of totals (to compare with the start).
    pub fn add_to<const D: usize>(&self, t: &mut crate::particles::Totals<D>) {
        t.mass += self.mass;
        for d in 0..D.min(self.momentum.len()) {
            t.momentum[d] += self.momentum[d];
        }
        t.angular_momentum += self.angular_momentum;
        t.kinetic += self.kinetic_energy;
        t.internal += self.internal_energy;
        t.potential += self.potential_energy;
    }
}

/// Particles, mass and angular momentum that crossed the simulation's edge one way.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Flow {
    pub particles: u64,
    pub mass: f64,
    /// z-component of the inertial angular momentum about the binary's centre of mass.
    pub angular_momentum: f64,
}

impl Flow {
    pub fn add(&mut self, mass: f64, angular_momentum: f64) {
        self.particles += 1;
        self.mass += mass;
        self.angular_momentum += angular_momentum;
    }

    fn values(&self) -> [f64; 3] {
        [self.particles as f64, self.mass, self.angular_momentum]
    }

    fn add_values(&mut self, v: &[f64]) {
        self.particles += v[0] as u64;
        self.mass += v[1];
        self.angular_momentum += v[2];
    }
}

/// A binary's mass budget: what the L1 stream brought in, and where it left (accreted by
/// the white dwarf, returned into the donor's Roche lobe, escaped). With the particles still
/// present it closes to round-off: injected = present + accreted + returned + escaped.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct MassBudget {
    pub injected: Flow,
    pub accreted: Flow,
    pub returned: Flow,
    pub escaped: Flow,
}

impl MassBudget {
    /// The outflows as numbers, to be summed over ranks (the inflow is rank 0's alone).
    pub fn outflow_values(&self) -> Vec<f64> {
        [self.accreted, self.returned, self.escaped]
            .iter()
            .flat_map(|f| f.values())
            .collect()
    }

    /// Adds outflows given as [`MassBudget::outflow_values`].
    pub fn add_outflow_values(&mut self, v: &[f64]) {
        self.accreted.add_values(&v[0..3]);
        self.returned.add_values(&v[3..6]);
        self.escaped.add_values(&v[6..9]);
    }

    /// Mass that left: accreted + returned + escaped.
    pub fn mass_out(&self) -> f64 {
        self.accreted.mass + self.returned.mass + self.escaped.mass
    }
}

/// The budget as `summary.json` reports it, with the particles still present and the
/// closure of the balance.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MassBudgetRecord {
    #[serde(flatten)]
    pub flows: MassBudget,
    /// Mass (and count) of the particles present at the end.
    pub present: Flow,
    /// (injected + initial − present − out) / injected: round-off only.
    pub residual: f64,
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
    /// |ΔL_z| / |L_z| (2D and 3D); where L_z starts at 0 (a blast from rest), |ΔL_z| over
    /// Σ m |x||v| in the plane at the end. SPH's shear viscosity conserves it only
    /// approximately.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_momentum: Option<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TotalsRecord {
    pub mass: f64,
    pub momentum: Vec<f64>,
    /// Σ m|v|, the scale of momentum drifts.
    #[serde(default)]
    pub momentum_scale: f64,
    pub angular_momentum: f64,
    pub kinetic_energy: f64,
    pub internal_energy: f64,
    pub potential_energy: f64,
    pub energy: f64,
}

impl TotalsRecord {
    /// The totals back in their dimension-typed form (exact: every field is kept).
    pub fn to_totals<const D: usize>(&self) -> crate::particles::Totals<D> {
        crate::particles::Totals {
            mass: self.mass,
            momentum: std::array::from_fn(|d| self.momentum.get(d).copied().unwrap_or(0.0)),
            momentum_scale: self.momentum_scale,
            angular_momentum: self.angular_momentum,
            kinetic: self.kinetic_energy,
            internal: self.internal_energy,
            potential: self.potential_energy,
        }
    }
}

impl<const D: usize> From<&crate::particles::Totals<D>> for TotalsRecord {
    fn from(t: &crate::particles::Totals<D>) -> Self {
        Self {
            mass: t.mass,
            momentum: t.momentum.to_vec(),
            momentum_scale: t.momentum_scale,
            angular_momentum: t.angular_momentum,
            kinetic_energy: t.kinetic,
            internal_energy: t.internal,
            potential_energy: t.potential,
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

/// Writes an analysis' figures to `run/NAME.json` and under the key `key` of the run's
/// `summary.json`, where the run has one (a run still going or stopped has none). Returns
/// the JSON file's path.
pub fn write_analysis<T: Serialize>(
    run: &Path,
    name: &str,
    key: &str,
    figures: &T,
) -> Result<std::path::PathBuf> {
    use anyhow::Context;
    let json = run.join(format!("{name}.json"));
    let mut text = serde_json::to_string_pretty(figures)?;
    text.push('\n');
    write_atomic(&json, text.as_bytes())?;
    let summary = run.join("summary.json");
    if let Ok(old) = std::fs::read_to_string(&summary) {
        let mut v: serde_json::Value = serde_json::from_str(&old)
            .with_context(|| format!("{}: not JSON", summary.display()))?;
        if let Some(obj) = v.as_object_mut() {
            obj.insert(key.into(), serde_json::to_value(figures)?);
            let mut text = serde_json::to_string_pretty(&v)?;
            text.push('\n');
            write_atomic(&summary, text.as_bytes())?;
        }
    }
    Ok(json)
}
