//! The problem file: its TOML schema, `--set key=value` overrides by dotted key, and the
//! checks that turn bad input into one clear line naming the key or value.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::boundary::BoundaryKind;
use crate::physics::artificial_viscosity::ArtificialViscosity;
use crate::physics::binary::BinaryParams;
use crate::physics::eos::Eos;
use crate::physics::gravity::PointMass;
use crate::physics::l1_stream::StreamParams;
use crate::physics::viscosity::ViscosityModel;

/// A whole problem file. Every table rejects keys it does not know.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub problem: ProblemSection,
    pub particles: ParticlesSection,
    pub eos: Eos,
    /// The SPH formulation: `scheme` = "density_energy" (the paper's, default) or
    /// "pressure_energy" (needs an ideal gas; `physics::pressure_energy`).
    #[serde(default)]
    pub hydro: crate::physics::pressure_energy::HydroSection,
    #[serde(default)]
    pub artificial_viscosity: ArtificialViscosity,
    /// Physical shear viscosity, Eqs. (8)–(10): `nu` or `alpha`, optional `bulk`.
    #[serde(default)]
    pub viscosity: ViscosityModel,
    /// Central point mass: `gm`, optional `softening` and `accretion_radius`.
    pub gravity: Option<PointMass>,
    /// A circular binary (accretor at the origin, donor on the left, turning frame):
    /// `q`, or `m1_msun`, `m2_msun`, `period_days`; `accretor_radius`, `escape_radius`.
    pub binary: Option<BinaryParams>,
    /// Mass transfer through L1 (needs `[binary]`): `particles_per_orbit`,
    /// `mass_per_orbit` or `mdot_msun_per_year`, `cs`, `start`, `stop`.
    pub stream: Option<StreamParams>,
    /// β cooling of the internal energy towards a sound-speed profile (needs an ideal gas
    /// and a central mass): `beta`, `cs0`, `r0`, `q`.
    pub cooling: Option<crate::physics::cooling::Cooling>,
    /// The dwarf-nova disk instability (needs an ideal gas and a central mass, replaces
    /// `[viscosity]` and `[cooling]`): `alpha_cold`, `alpha_hot`, `cs_cold`, `cs_hot`,
    /// `sigma_max`, `sigma_min`, `r0`, `slope`, `beta`, `unstable_branch`, `transport` (`physics::outbursts`).
    pub outbursts: Option<crate::physics::outbursts::Outbursts>,
    /// A disk already in place about a cv problem's accretor: `r_in`, `r_out`, `spacing`
    /// (`problems::cv_disk`).
    pub initial_disk: Option<crate::problems::cv_disk::InitialDisk>,
    #[serde(default)]
    pub boundary: BoundarySection,
    #[serde(default)]
    pub time: TimeSection,
    #[serde(default)]
    pub output: OutputSection,
    #[serde(default)]
    pub sweep: SweepSection,
    /// Overrides the problem's box: `min` and `max`, one entry per dimension.
    pub domain: Option<DomainSection>,
    pub sod: Option<SodParams>,
    pub advection: Option<AdvectionParams>,
    pub sedov: Option<SedovParams>,
    pub ring: Option<RingParams>,
    pub disk: Option<DiskParams>,
    pub initial: Option<InitialFileParams>,
    /// The code units in cgs (`mass_cgs`, `length_cgs`, `time_cgs`), for snapshot metadata.
    pub units: Option<crate::io::hdf5::Units>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ProblemKind {
    /// Shock tube with an exact Riemann solution (any left/right states).
    Sod,
    /// A smooth pulse in pressure equilibrium advected around a periodic box.
    Advection,
    /// Sedov–Taylor point blast.
    Sedov,
    /// Viscously spreading ring around a point mass (Lüst 1952, Pringle 1981).
    Ring,
    /// Keplerian disk (2D or 3D) around a point mass, locally isothermal, in equilibrium.
    Disk,
    /// Particles read from a CSV file (`[initial] file`).
    File,
    /// A cataclysmic variable: a Roche binary (`[binary]`) whose disk the L1 stream
    /// (`[stream]`) builds.
    Cv,
}

impl ProblemKind {
    pub fn name(self) -> &'static str {
        match self {
            ProblemKind::Sod => "sod",
            ProblemKind::Advection => "advection",
            ProblemKind::Sedov => "sedov",
            ProblemKind::Ring => "ring",
            ProblemKind::Disk => "disk",
            ProblemKind::File => "file",
            ProblemKind::Cv => "cv",
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemSection {
    pub kind: ProblemKind,
    pub dimension: usize,
    /// Label for outputs; the problem file's stem by default.
    pub name: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesSection {
    /// Resolution: particles along x of the reference state (see each problem).
    pub n: Option<usize>,
    /// Smoothing length in units of the problem's reference particle spacing.
    pub h_factor: Option<f64>,
    /// Smoothing length in code units (overrides `h_factor`).
    pub h: Option<f64>,
    /// The smoothing kernel: "cubic" (the paper's, default), "quintic", "wendland_c2",
    /// "wendland_c4", "wendland_c6".
    #[serde(default)]
    pub kernel: crate::kernel::KernelKind,
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_seed() -> u64 {
    1
}

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySection {
    pub x: Option<BoundaryKind>,
    pub y: Option<BoundaryKind>,
    pub z: Option<BoundaryKind>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSection {
    /// End time (a ring problem derives it from `ring.tau_end` if absent).
    pub end: Option<f64>,
    /// Courant factor: Δt ≤ courant · h / v_sig.
    #[serde(default = "default_courant")]
    pub courant: f64,
    /// Force factor: Δt ≤ force · √(h / |a|).
    #[serde(default = "default_force")]
    pub force: f64,
    /// Energy factor: Δt ≤ energy · u / |du/dt| where u decreases.
    #[serde(default = "default_energy")]
    pub energy: f64,
    /// Viscous factor: Δt ≤ viscous · h² / ν.
    #[serde(default = "default_viscous")]
    pub viscous: f64,
    #[serde(default = "default_max_steps")]
    pub max_steps: u64,
}

impl Default for TimeSection {
    fn default() -> Self {
        Self {
            end: None,
            courant: default_courant(),
            force: default_force(),
            energy: default_energy(),
            viscous: default_viscous(),
            max_steps: default_max_steps(),
        }
    }
}

fn default_courant() -> f64 {
    0.3
}
fn default_force() -> f64 {
    0.25
}
fn default_energy() -> f64 {
    0.3
}
fn default_viscous() -> f64 {
    0.4
}
fn default_max_steps() -> u64 {
    10_000_000
}

/// Default of `output.statistics_steps`.
pub const DEFAULT_STATISTICS_STEPS: u64 = 10;

#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Time between snapshots (HDF5, `snap_NNNN.hdf5`); none if absent or 0.
    pub interval: Option<f64>,
    /// Files each snapshot is split into (SWIFT's multi-file convention); default 1.
    pub files_per_snapshot: Option<usize>,
    /// Write a checkpoint every this many steps (besides one at each snapshot and one
    /// every `checkpoint_wall_seconds`).
    pub checkpoint_steps: Option<u64>,
    /// Wall-clock seconds between checkpoints; default 600. The last two are kept.
    pub checkpoint_wall_seconds: Option<f64>,
    /// Steps between rows of `statistics.csv` (global totals); default
    /// [`DEFAULT_STATISTICS_STEPS`]. Rows are also written at step 0 and at the end.
    pub statistics_steps: Option<u64>,
    /// Time between rows of a binary's `lightcurve.csv` and `monitor.csv`; default
    /// P_orb / 50 = 2π/50.
    pub lightcurve_interval: Option<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSection {
    /// `sweep` (drop pairs as soon as both partners are done) or `full` (keep the whole list,
    /// for memory comparisons).
    #[serde(default)]
    pub window: WindowKind,
    /// Particles per thread that enter the sweep together (default
    /// [`crate::sweep::BATCH_PARTICLES_PER_THREAD`] = 1024): the paper's delay, a size vs.
    /// speed trade-off (`sweep::Window`). Results do not depend on it.
    #[serde(default = "default_batch_per_thread")]
    pub batch_per_thread: u64,
}

impl Default for SweepSection {
    fn default() -> Self {
        Self {
            window: WindowKind::default(),
            batch_per_thread: default_batch_per_thread(),
        }
    }
}

fn default_batch_per_thread() -> u64 {
    crate::sweep::BATCH_PARTICLES_PER_THREAD as u64
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WindowKind {
    #[default]
    Sweep,
    Full,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSection {
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

/// A primitive state (density, velocity along x, pressure).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateParams {
    pub rho: f64,
    pub p: f64,
    #[serde(default)]
    pub v: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SodParams {
    pub left: StateParams,
    pub right: StateParams,
    /// Diaphragm position.
    pub x0: f64,
    /// Tube length: the tube is [0, length] along x.
    pub length: f64,
    /// Cross-section side in 2D/3D (rounded to whole lattice spacings).
    pub width: f64,
    /// The x-range [lo, hi] the error norms cover (default the whole tube): where waves
    /// from the walls, which the exact solution does not know, have not arrived.
    pub window: Option<[f64; 2]>,
}

impl Default for SodParams {
    fn default() -> Self {
        Self {
            left: StateParams {
                rho: 1.0,
                p: 1.0,
                v: 0.0,
            },
            right: StateParams {
                rho: 0.125,
                p: 0.1,
                v: 0.0,
            },
            x0: 0.5,
            length: 1.0,
            width: 0.1,
            window: None,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdvectionParams {
    pub rho0: f64,
    pub p0: f64,
    /// Peak density contrast of the pulse: ρ = ρ0 (1 + amplitude · f).
    pub amplitude: f64,
    /// Gaussian-equivalent width of the pulse (box units).
    pub width: f64,
    /// Velocity component along every axis.
    pub velocity: f64,
    /// Box side (the box is [0, length]^D).
    pub length: f64,
}

impl Default for AdvectionParams {
    fn default() -> Self {
        Self {
            rho0: 1.0,
            p0: 1.0,
            amplitude: 0.5,
            width: 0.1,
            velocity: 1.0,
            length: 1.0,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SedovParams {
    pub energy: f64,
    /// Radius of the region that receives the energy, in box units (default 0.1, the same
    /// at every resolution); the energy is spread with the weights of a cubic spline whose
    /// support is this radius.
    pub deposit_radius: f64,
    pub rho0: f64,
    pub p0: f64,
    /// Box side (the box is [−length/2, length/2]^D).
    pub length: f64,
}

impl Default for SedovParams {
    fn default() -> Self {
        Self {
            energy: 1.0,
            deposit_radius: 0.1,
            rho0: 1.0,
            p0: 1e-6,
            length: 1.0,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RingParams {
    /// Ring mass M.
    pub mass: f64,
    /// Ring radius R0.
    pub r0: f64,
    /// Start at τ0 = 12 ν t0 / R0² (a Gaussian ring of width σ has τ0 = 2σ²/R0²).
    pub tau_start: f64,
    /// End at this τ.
    pub tau_end: f64,
    /// Snapshot (and analysis) times, as τ.
    pub output_tau: Vec<f64>,
    /// Particles are placed where Σ exceeds this fraction of its peak.
    pub cutoff: f64,
    /// Spread of each particle's radius about its ring, as a fraction of the ring spacing
    /// R0/n, in [0, 1]: uniform within ±½ of it (seeded by `particles.seed`). 0 keeps every
    /// particle on its ring; 1 fills the radii between the rings.
    pub radial_jitter: f64,
}

impl Default for RingParams {
    fn default() -> Self {
        Self {
            mass: 1.0,
            r0: 1.0,
            tau_start: 0.016,
            tau_end: 0.128,
            output_tau: vec![0.032, 0.064, 0.128],
            cutoff: 1e-3,
            radial_jitter: 0.0,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DiskParams {
    /// Disk mass (the disk does not self-gravitate; this sets the density scale).
    pub mass: f64,
    /// Inner edge: Σ ∝ R^(−p) / (1 + exp(−(R − r_in)/w)), a smooth step of width
    /// w = `inner_width` H(r_in) centred on r_in.
    pub r_in: f64,
    /// Width of the inner edge in scale heights at r_in. A pressure-supported edge is
    /// Rayleigh-unstable (κ² < 0) where it is sharper than about H/2: the set-up refuses
    /// such an edge.
    pub inner_width: f64,
    /// Outer scale: Σ is further multiplied by exp(−(R/r_out)⁴).
    pub r_out: f64,
    /// Power-law index of Σ.
    pub p: f64,
    /// Particles are placed where Σ exceeds this fraction of its peak.
    pub cutoff: f64,
    /// Vertical extent of the particle layers in scale heights H = c_s/Ω (3D).
    pub layers_h: f64,
    /// Run length in orbits at r_in (used when `time.end` is absent).
    pub orbits: f64,
    /// Start the rings in equilibrium with the SPH forces (one evaluation; in 3D a few
    /// more to relax the layers' heights) instead of the analytic profile's.
    pub balance: bool,
}

impl Default for DiskParams {
    fn default() -> Self {
        Self {
            mass: 0.01,
            r_in: 1.0,
            inner_width: 1.0,
            r_out: 1.6,
            p: 1.0,
            cutoff: 0.02,
            layers_h: 2.5,
            orbits: 10.0,
            balance: true,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialFileParams {
    /// CSV with the `final.csv` header (`id,x,y,z,vx,vy,vz,m,h,rho,u,p`); relative paths are
    /// taken from the problem file's folder.
    pub file: String,
}

/// Levels of a dotted `--set` key (`sod.left.rho` has 3); deeper keys name no setting and
/// would nest tables without bound.
const MAX_KEY_LEVELS: usize = 8;

/// Applies `key=value` to a TOML table, creating intermediate tables. The value is parsed as
/// TOML (number, boolean, array, quoted string); a bare word is taken as a string.
pub fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<()> {
    let (key, raw) = assignment
        .split_once('=')
        .with_context(|| format!("--set expects key=value, got `{assignment}`"))?;
    let key = key.trim();
    let raw = raw.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        bail!("--set: malformed key `{key}`");
    }
    let levels = key.split('.').count();
    if levels > MAX_KEY_LEVELS {
        let shown: String = key.chars().take(40).collect();
        bail!(
            "--set: key `{shown}…` has {levels} levels; problem-file keys have at most {MAX_KEY_LEVELS}"
        );
    }
    let value = match format!("v = {raw}").parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let parts: Vec<&str> = key.split('.').collect();
    let mut cur = table;
    for (n, part) in parts[..parts.len() - 1].iter().enumerate() {
        let entry = cur
            .entry(part.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        cur = match entry {
            toml::Value::Table(t) => t,
            _ => bail!("--set {key}: `{}` is not a table", parts[..=n].join(".")),
        };
    }
    cur.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

impl Config {
    /// Reads a problem file, applies overrides, and checks it. Errors name the file, the
    /// key and the cause.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read problem file {}", path.display()))?;
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let at = e.span().map_or(String::new(), |s| {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let col = before.len() - before.rfind('\n').map_or(0, |k| k + 1) + 1;
                format!("line {line}, column {col}: ")
            });
            anyhow::anyhow!("{}: {at}{}", path.display(), one_line(e.message()))
        })?;
        for o in overrides {
            apply_override(&mut table, o)?;
        }
        let mut cfg = Self::from_table(table).map_err(|e| {
            // An error about a key an override set names the override, not the file.
            let blamed = blamed_override(&format!("{e:#}"), overrides);
            e.context(blamed.unwrap_or_else(|| path.display().to_string()))
        })?;
        if cfg.problem.name.is_none() {
            cfg.problem.name = path.file_stem().map(|s| s.to_string_lossy().into_owned());
        }
        if let Some(init) = &mut cfg.initial {
            let p = Path::new(&init.file);
            if p.is_relative()
                && let Some(dir) = path.parent()
            {
                init.file = dir.join(p).to_string_lossy().into_owned();
            }
        }
        Ok(cfg)
    }

    /// Deserialises and validates a table; unknown keys, missing keys and bad values are
    /// reported with their dotted path.
    pub fn from_table(mut table: toml::Table) -> Result<Self> {
        check_finite("", &table)?;
        whole_numbers_as_integers(&mut table);
        let given = table.clone();
        let cfg: Config =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let path = e.path().to_string();
                // toml appends "\nin `table`"; the dotted path says it already.
                let inner = e.into_inner().to_string();
                let inner = inner.lines().next().unwrap_or("").trim_end();
                if path == "." || path.is_empty() {
                    anyhow::anyhow!("{inner}")
                } else {
                    anyhow::anyhow!("key `{path}`: {inner}")
                }
            })?;
        if let Ok(toml::Value::Table(read)) = toml::Value::try_from(&cfg) {
            check_shapes("", &given, &read)?;
        }
        cfg.validate()?;
        check_applies(&given, cfg.problem.kind)?;
        Ok(cfg)
    }

    /// The central point mass: `[gravity]`, or a binary's accretor.
    pub fn central_mass(&self) -> Option<PointMass> {
        self.gravity.or_else(|| {
            self.binary
                .as_ref()
                .map(|b| crate::physics::binary::Binary::new(b).accretor())
        })
    }

    /// The code units in cgs: `[units]`, or those a binary in physical values defines,
    /// or 1.
    pub fn units(&self) -> crate::io::hdf5::Units {
        self.physical_units().unwrap_or_default()
    }

    /// The physical units of `[units]`, or a binary's from its masses and period; none
    /// when the code units are only G = 1 units (then the cgs factors are 1).
    pub fn physical_units(&self) -> Option<crate::io::hdf5::Units> {
        self.units
            .or_else(|| self.binary.as_ref().and_then(|b| b.physical_units()))
    }

    pub fn dimension(&self) -> usize {
        self.problem.dimension
    }

    pub fn name(&self) -> &str {
        self.problem
            .name
            .as_deref()
            .unwrap_or(self.problem.kind.name())
    }

    fn validate(&self) -> Result<()> {
        let d = self.problem.dimension;
        if !(1..=3).contains(&d) {
            bail!("key `problem.dimension`: must be 1, 2 or 3, got {d}");
        }
        let positive = |key: &str, v: f64| -> Result<()> {
            if !(v > 0.0 && v.is_finite()) {
                bail!("key `{key}`: must be > 0, got {v}");
            }
            Ok(())
        };
        if let Some(h) = self.particles.h {
            positive("particles.h", h)?;
        }
        if let Some(u) = &self.units {
            u.validate().map_err(anyhow::Error::msg)?;
        }
        crate::limits::check_batch("key `sweep.batch_per_thread`", self.sweep.batch_per_thread)?;
        if self.output.files_per_snapshot == Some(0) {
            bail!("key `output.files_per_snapshot`: must be ≥ 1, got 0");
        }
        if let Some(files) = self.output.files_per_snapshot {
            crate::limits::check_files_per_snapshot(files)?;
        }
        if self.output.checkpoint_steps == Some(0) {
            bail!("key `output.checkpoint_steps`: must be ≥ 1, got 0");
        }
        if self.output.statistics_steps == Some(0) {
            bail!("key `output.statistics_steps`: must be ≥ 1, got 0");
        }
        if let Some(w) = self.output.checkpoint_wall_seconds {
            positive("output.checkpoint_wall_seconds", w)?;
        }
        if let Some(f) = self.particles.h_factor {
            positive("particles.h_factor", f)?;
            // h in units of the problem's particle spacing: a support short of the next
            // particle leaves each one alone with itself (h_factor = 1e-6 made a 4096-particle
            // box take 23 s a step, walking 3·10⁷ empty slabs).
            let support = self.particles.kernel.support_factor();
            if f * support < 1.0 {
                bail!(
                    "key `particles.h_factor`: {} leaves each particle without neighbours: the \
                     kernel's support ({support}·h) must reach the next particle, so h_factor \
                     ≥ {}",
                    crate::limits::show(f),
                    1.0 / support
                );
            }
        }
        if self.problem.kind == ProblemKind::Cv {
            if self.particles.h.is_none() {
                bail!("key `particles.h`: missing (a cv problem runs at constant h in units of a)");
            }
        } else if self.problem.kind != ProblemKind::File {
            match self.particles.n {
                None => bail!(
                    "key `particles.n`: missing (the resolution of problem kind `{}`)",
                    self.problem.kind.name()
                ),
                Some(0) => bail!("key `particles.n`: must be > 0, got 0"),
                Some(n) if n as u64 > crate::limits::MAX_PARTICLES => bail!(
                    "key `particles.n`: at most {}, got {n}",
                    crate::limits::MAX_PARTICLES
                ),
                Some(_) => {}
            }
            if self.particles.h.is_none() && self.particles.h_factor.is_none() {
                bail!("key `particles.h_factor`: missing (give particles.h_factor or particles.h)");
            }
        } else if self.particles.h.is_none() {
            bail!("key `particles.h`: missing (a file problem needs the smoothing length)");
        }
        self.eos
            .validate()
            .map_err(|e| anyhow::anyhow!("key `{}", e.replacen(" must", "`: must", 1)))?;
        self.artificial_viscosity
            .validate()
            .map_err(|e| anyhow::anyhow!("key `{}", e.replacen(" must", "`: must", 1)))?;
        if self.hydro.scheme == crate::physics::pressure_energy::Scheme::PressureEnergy
            && !matches!(self.eos, Eos::Ideal { .. })
        {
            bail!(
                "key `hydro.scheme`: \"pressure_energy\" smooths (γ − 1) u and needs eos.kind = \"ideal\""
            );
        }
        match self.time.end {
            Some(end) => positive("time.end", end)?,
            None if matches!(self.problem.kind, ProblemKind::Ring | ProblemKind::Disk) => {}
            None => bail!("key `time.end`: missing"),
        }
        if let Some(g) = &self.gravity {
            g.validate().map_err(|e| anyhow::anyhow!(e))?;
        }
        if let Some(b) = &self.binary {
            if self.gravity.is_some() {
                bail!(
                    "table `[gravity]`: a binary's accretor is the central mass; give [binary] alone"
                );
            }
            b.validate(d).map_err(|e| anyhow::anyhow!(e))?;
        }
        match (&self.stream, &self.binary) {
            (Some(s), Some(b)) => s
                .validate(b.physical_units().is_some())
                .map_err(|e| anyhow::anyhow!(e))?,
            (Some(_), None) => bail!("table `[stream]`: mass transfer through L1 needs [binary]"),
            _ => {}
        }
        if let Some(c) = &self.cooling {
            c.validate(&self.eos, self.central_mass().map(|m| m.gm))
                .map_err(|e| anyhow::anyhow!(e))?;
        }
        if let Some(o) = &self.outbursts {
            o.validate(
                &self.eos,
                self.gravity.is_some() || self.binary.is_some(),
                self.problem.dimension,
            )
            .map_err(|e| anyhow::anyhow!(e))?;
            if self.viscosity.is_on() {
                bail!(
                    "table `[outbursts]`: it sets α by the gas's branch; remove viscosity.alpha / viscosity.nu"
                );
            }
            if self.cooling.is_some() {
                bail!(
                    "table `[outbursts]`: it relaxes u to the branch's temperature itself; remove [cooling]"
                );
            }
        }
        if self.problem.kind == ProblemKind::Cv && self.binary.is_none() {
            bail!("table `[binary]`: missing (problem.kind = \"cv\" needs q or the stars' masses)");
        }
        if let Some(disk) = &self.initial_disk {
            let (Some(b), Some(h), ProblemKind::Cv) =
                (&self.binary, self.particles.h, self.problem.kind)
            else {
                bail!(
                    "table `[initial_disk]`: only a cv problem (with [binary] and particles.h) starts with a disk"
                );
            };
            // The largest of c_s = cs0 (R/r0)^(−q) across the disk: at one of its edges.
            let profile_max = |cs0: f64, r0: f64, q: f64| {
                cs0 * (disk.r_in.max(1e-12) / r0)
                    .powf(-q)
                    .max((disk.r_out / r0).powf(-q))
            };
            let cs_max = match (self.eos, self.cooling) {
                (Eos::Isothermal { cs }, _) => cs,
                (Eos::LocallyIsothermal { cs0, r0, q }, _) => profile_max(cs0, r0, q),
                // An ideal gas starts at the cooling's target (problems/cv.rs).
                (_, Some(c)) => profile_max(c.cs0, c.r0, c.q),
                _ => self.stream.map_or(0.0, |s| s.cs),
            };
            disk.validate(b.mass_ratio(), b.accretor_radius, h, d, cs_max)
                .map_err(|e| anyhow::anyhow!(e))?;
        }
        self.viscosity
            .validate(self.gravity.is_some() || self.binary.is_some())
            .map_err(|e| anyhow::anyhow!(e))?;
        for (k, v) in [
            ("time.courant", self.time.courant),
            ("time.force", self.time.force),
            ("time.energy", self.time.energy),
            ("time.viscous", self.time.viscous),
        ] {
            positive(k, v)?;
            if v > 1.0 {
                bail!("key `{k}`: a step-limiter factor must be ≤ 1, got {v}");
            }
        }
        if let Some(i) = self.output.interval
            && !(i >= 0.0 && i.is_finite())
        {
            bail!("key `output.interval`: must be ≥ 0, got {i}");
        }
        if let Some(i) = self.output.lightcurve_interval
            && !(i > 0.0 && i.is_finite())
        {
            bail!("key `output.lightcurve_interval`: must be > 0, got {i}");
        }
        if let Some(dom) = &self.domain {
            if dom.min.len() != d || dom.max.len() != d {
                bail!("key `domain`: min and max need {d} entries each (problem.dimension = {d})");
            }
            for a in 0..d {
                if !(dom.max[a] > dom.min[a]) {
                    bail!("key `domain`: max must exceed min on every axis");
                }
            }
        }
        if d < 3 && self.boundary.z.is_some() {
            bail!("key `boundary.z`: a {d}D problem has no z axis");
        }
        if d < 2 && self.boundary.y.is_some() {
            bail!("key `boundary.y`: a 1D problem has no y axis");
        }
        let kind = self.problem.kind;
        if kind == ProblemKind::File && self.initial.is_none() {
            bail!(
                "key `initial.file`: missing (problem.kind = \"file\" reads its particles from it)"
            );
        }
        if kind == ProblemKind::File && self.domain.is_none() {
            bail!(
                "key `domain`: missing (problem.kind = \"file\" needs the box: domain.min, domain.max)"
            );
        }
        Ok(())
    }

    /// The key with the largest magnitude among the numbers of the problem (beside
    /// `[units]`, whose cgs factors are large by nature), for a message about an overflow.
    pub fn largest_value(&self) -> Option<(String, f64)> {
        self.flattened()
            .into_iter()
            .filter(|(k, _)| !k.starts_with("units.") && !k.starts_with("particles.seed"))
            .filter_map(|(k, v)| v.parse::<f64>().ok().map(|x| (k, x)))
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
    }

    /// The problem file as it was run (after overrides), flattened to dotted keys.
    pub fn flattened(&self) -> BTreeMap<String, String> {
        let mut out = BTreeMap::new();
        let value = toml::Value::try_from(self).expect("config serialises");
        flatten("", &value, &mut out);
        out
    }
}

/// Refuses a number that is not finite (`nan`, `inf`) anywhere in `t`, naming its key: no
/// setting takes one (leave a key out for its default).
fn check_finite(prefix: &str, t: &toml::Table) -> Result<()> {
    fn walk(key: &str, v: &toml::Value) -> Result<()> {
        match v {
            toml::Value::Float(x) if !x.is_finite() => {
                bail!("key `{key}`: must be a finite number, got {x}")
            }
            toml::Value::Table(t) => check_finite(key, t),
            toml::Value::Array(a) => a.iter().try_for_each(|x| walk(key, x)),
            _ => Ok(()),
        }
    }
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        walk(&key, v)?;
    }
    Ok(())
}

/// Writes every whole number of `t` given as a float (`1e7`, `64.0`) as an integer, up to
/// 2⁵³ where a float holds every integer exactly: TOML has no exponent for integers, and a
/// step count or a resolution is naturally written `time.max_steps = 1e7`, which serde
/// would refuse for an integer key ("invalid type: floating point"). A float key reads the
/// integer back as the same number.
fn whole_numbers_as_integers(t: &mut toml::Table) {
    fn walk(v: &mut toml::Value) {
        match v {
            toml::Value::Float(x) if x.fract() == 0.0 && x.abs() <= 9_007_199_254_740_992.0 => {
                *v = toml::Value::Integer(*x as i64);
            }
            toml::Value::Table(t) => t.iter_mut().for_each(|(_, v)| walk(v)),
            toml::Value::Array(a) => a.iter_mut().for_each(walk),
            _ => {}
        }
    }
    t.iter_mut().for_each(|(_, v)| walk(v));
}

/// Refuses an array in `given` where the schema reads a table (`read`, the configuration
/// serialised back): serde takes `sod.left = [1, 2]` as the fields in order (ρ = 1,
/// p = 2), which nobody means.
fn check_shapes(prefix: &str, given: &toml::Table, read: &toml::Table) -> Result<()> {
    for (k, v) in given {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match (v, read.get(k)) {
            (toml::Value::Array(a), Some(toml::Value::Table(t))) => {
                let fields: Vec<&str> = t.keys().map(String::as_str).collect();
                bail!(
                    "key `{key}`: expected a table {{ {} }}, got an array of {} values",
                    fields.join(", "),
                    a.len()
                );
            }
            (toml::Value::Table(g), Some(toml::Value::Table(r))) => check_shapes(&key, g, r)?,
            _ => {}
        }
    }
    Ok(())
}

/// Keys the problem's kind does not use are errors naming the key: another kind's own
/// table (`sedov.*` on a ring), a central mass where nothing orbits (`gravity.*` on a
/// shock tube, an advected pulse or a blast), a binary, its stream, its disk or its light
/// curve outside a cv problem, and a lattice resolution (`particles.n`, `h_factor`) where
/// the particles come from a file or a stream (they take `particles.h`).
fn check_applies(given: &toml::Table, kind: ProblemKind) -> Result<()> {
    use ProblemKind::*;
    let owner = |table: &str| match table {
        "sod" => Some(Sod),
        "advection" => Some(Advection),
        "sedov" => Some(Sedov),
        "ring" => Some(Ring),
        "disk" => Some(Disk),
        "initial" => Some(File),
        "binary" | "stream" | "initial_disk" => Some(Cv),
        _ => None,
    };
    let first_key = |table: &str| -> String {
        match given.get(table) {
            Some(toml::Value::Table(t)) if !t.is_empty() => {
                format!("{table}.{}", t.keys().next().expect("non-empty"))
            }
            _ => table.to_string(),
        }
    };
    let refuse = |key: String, why: &str| -> Result<()> {
        bail!(
            "key `{key}` does not apply to problem.kind = \"{}\" ({why})",
            kind.name()
        )
    };
    for table in given.keys() {
        if let Some(owner) = owner(table)
            && owner != kind
        {
            return refuse(
                first_key(table),
                &format!("it belongs to problem.kind = \"{}\"", owner.name()),
            );
        }
        if table == "gravity" && matches!(kind, Sod | Advection | Sedov) {
            return refuse(first_key(table), "nothing orbits a central mass there");
        }
    }
    let key_in = |table: &str, key: &str| {
        given
            .get(table)
            .and_then(|t| t.as_table())
            .is_some_and(|t| t.contains_key(key))
    };
    if matches!(kind, Cv | File) {
        for key in ["n", "h_factor"] {
            if key_in("particles", key) {
                let from = if kind == Cv {
                    "the L1 stream"
                } else {
                    "a file"
                };
                return refuse(
                    format!("particles.{key}"),
                    &format!("the particles come from {from}; give particles.h"),
                );
            }
        }
    }
    if kind != Cv && key_in("output", "lightcurve_interval") {
        return refuse(
            "output.lightcurve_interval".into(),
            "only a cv problem writes a light curve",
        );
    }
    Ok(())
}

/// `--set KEY=VALUE` for the override among `overrides` that set the key the error message
/// `msg` names (itself, a key inside it or its table), if one did.
pub fn blamed_override(msg: &str, overrides: &[String]) -> Option<String> {
    named_key(msg).and_then(|key| {
        overrides
            .iter()
            .find(|o| override_touches(o, &key))
            .map(|o| format!("--set {o}"))
    })
}

/// The dotted key an error message names first (`key `a.b``, `table `[a]``, or an
/// unknown top-level `unknown field `a``).
fn named_key(msg: &str) -> Option<String> {
    let after = |marker: &str, end: char| {
        msg.find(marker).and_then(|i| {
            let rest = &msg[i + marker.len()..];
            rest.find(end).map(|j| rest[..j].to_string())
        })
    };
    after("key `", '`')
        .or_else(|| after("table `[", ']'))
        .or_else(|| after("unknown field `", '`'))
}

/// Whether the override `key=value` set `key` itself, a key inside it or the table holding it.
fn override_touches(assignment: &str, key: &str) -> bool {
    let set = assignment
        .split_once('=')
        .map_or(assignment, |x| x.0)
        .trim();
    set == key || set.starts_with(&format!("{key}.")) || key.starts_with(&format!("{set}."))
}

/// Joins a multi-line message into one line.
fn one_line(msg: &str) -> String {
    msg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

fn flatten(prefix: &str, v: &toml::Value, out: &mut BTreeMap<String, String>) {
    match v {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        other => {
            out.insert(prefix.to_string(), other.to_string());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SOD: &str = r#"
        [problem]
        kind = "sod"
        dimension = 1
        [particles]
        n = 100
        h_factor = 1.2
        [eos]
        kind = "ideal"
        gamma = 1.4
        [time]
        end = 0.2
    "#;

    fn load(text: &str, sets: &[&str]) -> Result<Config> {
        let mut t: toml::Table = text.parse()?;
        for s in sets {
            apply_override(&mut t, s)?;
        }
        Config::from_table(t)
    }

    #[test]
    fn set_overrides_dotted_keys_with_typed_values() {
        let c = load(
            SOD,
            &["particles.n=800", "time.end=0.15", "boundary.x=periodic"],
        )
        .unwrap();
        assert_eq!(c.particles.n, Some(800));
        assert_eq!(c.time.end, Some(0.15));
        assert_eq!(c.boundary.x, Some(BoundaryKind::Periodic));
    }

    #[test]
    fn unknown_key_is_named_with_its_path() {
        let e = load(SOD, &["particles.nn=3"]).unwrap_err().to_string();
        assert!(e.contains("particles") && e.contains("nn"), "{e}");
        let e = load(SOD, &["eos.gama=1.4"]).unwrap_err().to_string();
        assert!(e.contains("eos") && e.contains("gama"), "{e}");
    }

    #[test]
    fn whole_numbers_with_an_exponent_or_a_point_are_read_by_integer_keys() {
        // Before: "key `time.max_steps`: invalid type: floating point `1e7`, expected u64".
        let cfg = load(SOD, &["time.max_steps=1e7", "particles.n=64.0"]).unwrap();
        assert_eq!(cfg.time.max_steps, 10_000_000);
        assert_eq!(cfg.particles.n, Some(64));
        // A float key reads them back as the same number; fractions and numbers beyond
        // 2⁵³ stay refused by integer keys.
        let cfg = load(SOD, &["time.end=1e0"]).unwrap();
        assert_eq!(cfg.time.end, Some(1.0));
        for bad in [
            "particles.n=64.5",
            "particles.seed=1e19",
            "particles.n=-1e0",
        ] {
            let e = load(SOD, &[bad]).unwrap_err().to_string();
            assert!(e.contains(bad.split('=').next().unwrap()), "{bad}: {e}");
        }
    }

    #[test]
    fn missing_and_bad_values_are_named() {
        let e = load(&SOD.replace("end = 0.2", ""), &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("time") && e.contains("end"), "{e}");
        let e = load(SOD, &["particles.h_factor=-1"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("particles.h_factor"), "{e}");
        let e = load(SOD, &["eos.gamma=0.5"]).unwrap_err().to_string();
        assert!(e.contains("eos.gamma"), "{e}");
        // The key in backticks, and no stray backtick after the value.
        let e = format!("{:#}", load(SOD, &["eos.gamma=5e-324"]).unwrap_err());
        assert!(
            e.contains("key `eos.gamma`: must be > 1, got 5e-324"),
            "{e}"
        );
        assert!(e.matches('`').count().is_multiple_of(2), "{e}");
        assert!(!e.ends_with('`'), "{e}");
        let e = format!(
            "{:#}",
            load(SOD, &["artificial_viscosity.alpha=9223372036854775807"]).unwrap_err()
        );
        assert!(e.contains("key `artificial_viscosity.alpha`: must"), "{e}");
        assert!(!e.ends_with('`'), "{e}");
        let e = load(SOD, &["sedov.energy=1"]).unwrap_err().to_string();
        assert!(e.contains("key `sedov.energy` does not apply"), "{e}");
        let e = load(SOD, &["boundary.z=open"]).unwrap_err().to_string();
        assert!(e.contains("boundary.z"), "{e}");
        for bad in ["0", "4294967296", "-1"] {
            let e = format!(
                "{:#}",
                load(SOD, &[&format!("sweep.batch_per_thread={bad}")]).unwrap_err()
            );
            assert!(e.contains("sweep.batch_per_thread"), "{bad}: {e}");
        }
        let cfg = load(SOD, &["sweep.batch_per_thread=16384"]).unwrap();
        assert_eq!(cfg.sweep.batch_per_thread, 16384);
        assert_eq!(
            load(SOD, &[]).unwrap().sweep.batch_per_thread,
            crate::sweep::BATCH_PARTICLES_PER_THREAD as u64
        );
    }

    #[test]
    fn a_table_given_as_an_array_is_named() {
        let text = format!("{SOD}\n[sod]\nleft = [1.0, 2.0]\n");
        let e = load(&text, &[]).unwrap_err().to_string();
        assert!(e.contains("sod.left") && e.contains("table"), "{e}");
        let e = load(SOD, &["sod.right=[0.125, 0.1, 0.0]"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("sod.right") && e.contains("array"), "{e}");
        assert!(load(SOD, &["sod.left={ rho = 1.0, p = 2.0 }"]).is_ok());
    }

    #[test]
    fn infinities_and_nans_are_refused_by_key() {
        for (set, key) in [
            ("ring.tau_end=inf", "ring.tau_end"),
            ("sod.left.rho=nan", "sod.left.rho"),
            ("sod.window=[0.1, inf]", "sod.window"),
            ("time.end=-inf", "time.end"),
        ] {
            let e = load(SOD, &[set]).unwrap_err().to_string();
            assert!(e.contains(key) && e.contains("finite"), "{set}: {e}");
        }
    }

    #[test]
    fn a_deeply_dotted_key_is_refused_by_its_depth() {
        let key = vec!["a"; 60_000].join(".");
        let e = load(SOD, &[&format!("{key}=1")]).unwrap_err().to_string();
        assert!(e.contains("--set") && e.contains("60000 levels"), "{e}");
    }

    #[test]
    fn flattened_config_lists_dotted_keys() {
        let f = load(SOD, &[]).unwrap().flattened();
        assert_eq!(f.get("particles.n").map(String::as_str), Some("100"));
        // Defaults are listed too: the snapshots' /HydroScheme reads the formulation here.
        assert_eq!(
            f.get("hydro.scheme").map(String::as_str),
            Some("\"density_energy\"")
        );
        assert_eq!(f.get("eos.gamma").map(String::as_str), Some("1.4"));
    }

    #[test]
    fn outbursts_replace_viscosity_and_cooling() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/outbursts.toml");
        let text = std::fs::read_to_string(path).unwrap();
        assert!(load(&text, &[]).is_ok());
        let e = load(&text, &["viscosity.alpha=0.1"])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("[outbursts]") && e.contains("viscosity.alpha"),
            "{e}"
        );
        let e = load(&text, &["cooling.beta=1", "cooling.cs0=0.05"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("[outbursts]") && e.contains("[cooling]"), "{e}");
        let e = load(&text, &["outbursts.sigma_min=1"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("outbursts.sigma_min"), "{e}");
    }
}
