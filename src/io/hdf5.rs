//! HDF5 snapshots in SWIFT's layout, written and read with `hdf5-pure` (pure Rust: the
//! default build needs no HDF5 C library, and files open in h5py, yt and swiftsimio).
//!
//! Layout: `/Header` (with `Code = "SWIFT"` as a fixed-length ASCII string, which yt's SWIFT
//! front end requires), `/Units` (cgs factors of the code units), `/Policy`, `/RuntimePars`,
//! `/Parameters` (the problem file flattened to `section:key`), `/HydroScheme` (kernel and
//! smoothing-length convention), `/SubgridScheme`, `/PartType0` (gas) and `/PartType3` (point
//! masses, SWIFT's sink type). Every dataset carries SWIFT's unit-exponent attributes.
//!
//! A snapshot may be split over several files (SWIFT's multi-file convention, one per MPI
//! rank or `output.files_per_snapshot`): `name.0.hdf5`, `name.1.hdf5`, …, each with its own
//! `NumPart_ThisFile` and the shared `NumPart_Total` and `NumFilesPerSnapshot`. A virtual
//! file beside them (SWIFT's, `Header/Virtual` = 1) is read through its parts.
//!
//! `Header/Dimension` is 3 in every file (yt's SWIFT front end needs it for its particle
//! index); the run's dimension is `HydroScheme/Dimension`.
//!
//! Reading accepts SWIFT's plural names and GADGET's singular ones (`Density`,
//! `SmoothingLength`, `InternalEnergy`, `Mass` or the header's `MassTable`).

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use hdf5_pure::{AttrValue, File, FileBuilder, GroupBuilder};

use crate::io::atomic::write_atomic;
use crate::io::snapshot::{PointMassRecord, Snapshot};
use crate::kernel::KernelKind;

/// Number of particle types in SWIFT's header arrays.
const N_TYPES: usize = 7;
/// SWIFT's particle type for sinks, used here for point masses (central star, binary).
const POINT_MASS_TYPE: usize = 3;

/// The code units in cgs (`[units]` in a problem file; 1 when absent).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Units {
    /// Unit mass in grams.
    #[serde(default = "one")]
    pub mass_cgs: f64,
    /// Unit length in centimetres.
    #[serde(default = "one")]
    pub length_cgs: f64,
    /// Unit time in seconds.
    #[serde(default = "one")]
    pub time_cgs: f64,
    /// Mean molecular weight μ of the gas, for the snapshots' `Temperatures`
    /// (T = μ m_p P/(ρ k_B)); default 0.6 (ionised gas of solar composition).
    #[serde(default = "default_mu")]
    pub mean_molecular_weight: f64,
}

fn one() -> f64 {
    1.0
}

fn default_mu() -> f64 {
    0.6
}

/// Proton mass in grams (CODATA 2018).
const PROTON_MASS_G: f64 = 1.672_621_923_69e-24;
/// Boltzmann's constant in erg/K (exact in the SI).
const BOLTZMANN_CGS: f64 = 1.380_649e-16;

impl Default for Units {
    fn default() -> Self {
        Self {
            mass_cgs: 1.0,
            length_cgs: 1.0,
            time_cgs: 1.0,
            mean_molecular_weight: default_mu(),
        }
    }
}

impl Units {
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [
            ("mass_cgs", self.mass_cgs),
            ("length_cgs", self.length_cgs),
            ("time_cgs", self.time_cgs),
            ("mean_molecular_weight", self.mean_molecular_weight),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("key `units.{k}`: must be > 0, got {v}"));
            }
        }
        Ok(())
    }

    /// The cgs factor of a quantity with exponents (mass, length, time).
    fn factor(&self, e: Exponents) -> f64 {
        self.mass_cgs.powf(e.m) * self.length_cgs.powf(e.l) * self.time_cgs.powf(e.t)
    }

    /// Kelvin per code unit of P/ρ (specific energy): T = μ m_p (P/ρ) / k_B.
    pub fn kelvin_per_specific_energy(&self) -> f64 {
        let v = self.length_cgs / self.time_cgs;
        self.mean_molecular_weight * PROTON_MASS_G * v * v / BOLTZMANN_CGS
    }
}

/// What a snapshot file says about the run beyond the particles.
#[derive(Clone, Debug, Default)]
pub struct RunMetadata {
    /// The problem file as run, flattened to dotted keys (`Config::flattened`).
    pub parameters: BTreeMap<String, String>,
    pub units: Units,
    /// Whether every axis is periodic (SWIFT's `PeriodicBoundariesOn`).
    pub periodic: bool,
    /// Whether `units` are physical (`[units]` or a binary's masses and period): then the
    /// gas has `Temperatures` in K.
    pub physical: bool,
}

/// Unit exponents of a dataset: mass, length, time, temperature (current is 0 here).
#[derive(Clone, Copy)]
struct Exponents {
    m: f64,
    l: f64,
    t: f64,
    temp: f64,
}

const fn exps(m: f64, l: f64, t: f64) -> Exponents {
    Exponents { m, l, t, temp: 0.0 }
}

/// Kelvin: U_T (1 K in SWIFT's and sphdisk's units) to the first power.
const KELVIN: Exponents = Exponents {
    m: 0.0,
    l: 0.0,
    t: 0.0,
    temp: 1.0,
};

/// The file names of a snapshot written as `num_files` parts: `base` itself for one file,
/// `stem.k.hdf5` for several (SWIFT's convention).
pub fn part_paths(base: &Path, num_files: usize) -> Vec<PathBuf> {
    if num_files <= 1 {
        return vec![base.to_path_buf()];
    }
    let stem = base
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    (0..num_files)
        .map(|k| base.with_file_name(format!("{stem}.{k}.hdf5")))
        .collect()
}

/// Writes `snap` to `base` (one file) or to `num_files` parts split into contiguous ranges of
/// particles; each file is written atomically.
pub fn write_snapshot(
    base: &Path,
    snap: &Snapshot,
    meta: &RunMetadata,
    num_files: usize,
) -> Result<Vec<PathBuf>> {
    let num_files = num_files.max(1);
    let n = snap.len();
    let paths = part_paths(base, num_files);
    for (k, path) in paths.iter().enumerate() {
        let range = (n * k / num_files)..(n * (k + 1) / num_files);
        let bytes = encode_part(snap, range, k, num_files, meta)
            .with_context(|| format!("cannot encode snapshot {}", path.display()))?;
        write_atomic(path, &bytes)?;
    }
    Ok(paths)
}

fn encode_part(
    snap: &Snapshot,
    range: std::ops::Range<usize>,
    file_index: usize,
    num_files: usize,
    meta: &RunMetadata,
) -> Result<Vec<u8>> {
    let d = snap.dimension as f64;
    let mut fb = FileBuilder::new();

    // Point masses go with the first file only.
    let point_masses: &[PointMassRecord] = if file_index == 0 {
        &snap.point_masses
    } else {
        &[]
    };
    let mut this_file = [0u64; N_TYPES];
    this_file[0] = range.len() as u64;
    this_file[POINT_MASS_TYPE] = point_masses.len() as u64;
    let mut total = [0u64; N_TYPES];
    total[0] = snap.len() as u64;
    total[POINT_MASS_TYPE] = snap.point_masses.len() as u64;
    let box_size: Vec<f64> = (0..3).map(|a| snap.box_hi[a] - snap.box_lo[a]).collect();

    let mut header = fb.create_group("Header");
    header.set_attr("Code", AttrValue::AsciiString("SWIFT".into()));
    header.set_attr(
        "Producer",
        AttrValue::AsciiString(format!("sphdisk {}", env!("CARGO_PKG_VERSION"))),
    );
    header.set_attr("BoxSize", AttrValue::F64Array(box_size));
    header.set_attr("Shift", AttrValue::F64Array(snap.shift.to_vec()));
    // yt's SWIFT front end builds one periodicity flag per `Header/Dimension` while its
    // particle index reads three, so 1D and 2D files say 3 here (the coordinates are N×3);
    // the hydro dimension is `HydroScheme/Dimension`, where SWIFT writes it too.
    header.set_attr("Dimension", AttrValue::I32Array(vec![3]));
    header.set_attr("Time", AttrValue::F64Array(vec![snap.time]));
    header.set_attr("Step", AttrValue::U64Array(vec![snap.step]));
    header.set_attr("NumPart_ThisFile", AttrValue::U64Array(this_file.to_vec()));
    header.set_attr("NumPart_Total", AttrValue::U64Array(total.to_vec()));
    header.set_attr(
        "NumPart_Total_HighWord",
        AttrValue::U64Array(vec![0; N_TYPES]),
    );
    header.set_attr("MassTable", AttrValue::F64Array(vec![0.0; N_TYPES]));
    header.set_attr(
        "NumFilesPerSnapshot",
        AttrValue::I32Array(vec![num_files as i32]),
    );
    header.set_attr("ThisFile", AttrValue::I32Array(vec![file_index as i32]));
    header.set_attr("Flag_Entropy_ICs", AttrValue::I32Array(vec![0; N_TYPES]));
    header.set_attr("Redshift", AttrValue::F64Array(vec![0.0]));
    header.set_attr("Scale-factor", AttrValue::F64Array(vec![1.0]));
    fb.add_group(header.finish());

    let mut units = fb.create_group("Units");
    let u = meta.units;
    units.set_attr(
        "Unit mass in cgs (U_M)",
        AttrValue::F64Array(vec![u.mass_cgs]),
    );
    units.set_attr(
        "Unit length in cgs (U_L)",
        AttrValue::F64Array(vec![u.length_cgs]),
    );
    units.set_attr(
        "Unit time in cgs (U_t)",
        AttrValue::F64Array(vec![u.time_cgs]),
    );
    units.set_attr("Unit current in cgs (U_I)", AttrValue::F64Array(vec![1.0]));
    units.set_attr(
        "Unit temperature in cgs (U_T)",
        AttrValue::F64Array(vec![1.0]),
    );
    fb.add_group(units.finish());

    let mut policy = fb.create_group("Policy");
    for (k, v) in [
        ("cosmological integration", 0),
        ("hydro", 1),
        ("self-gravity", 0),
        (
            "external potential",
            i32::from(!snap.point_masses.is_empty()),
        ),
    ] {
        policy.set_attr(k, AttrValue::I32Array(vec![v]));
    }
    fb.add_group(policy.finish());

    let mut runtime = fb.create_group("RuntimePars");
    runtime.set_attr(
        "PeriodicBoundariesOn",
        AttrValue::I32Array(vec![i32::from(meta.periodic)]),
    );
    fb.add_group(runtime.finish());

    // SWIFT writes parameters as `Section:key` string attributes.
    let mut params = fb.create_group("Parameters");
    for (k, v) in &meta.parameters {
        params.set_attr(
            &k.replacen('.', ":", 1),
            AttrValue::AsciiString(v.trim_matches('"').to_string()),
        );
    }
    fb.add_group(params.finish());

    let mut hydro = fb.create_group("HydroScheme");
    // The formulation (`[hydro] scheme`, physics::pressure_energy), as the run's parameters
    // name it.
    let scheme = match meta
        .parameters
        .get("hydro.scheme")
        .map(|v| v.trim_matches('"'))
    {
        Some("pressure_energy") => {
            "sphdisk SPH, pressure-energy (Saitoh & Makino 2013; Hopkins 2013), constant h"
        }
        _ => "sphdisk SPH, density-energy (paper Eq. 7), constant h",
    };
    hydro.set_attr("Scheme", AttrValue::AsciiString(scheme.into()));
    let kernel = snap.kernel;
    hydro.set_attr(
        "Kernel function",
        AttrValue::AsciiString(kernel.description().into()),
    );
    hydro.set_attr(
        "Smoothing length convention",
        AttrValue::AsciiString(format!(
            "constant h; kernel support radius {}h ({})",
            kernel.support_factor(),
            kernel.key()
        )),
    );
    hydro.set_attr("Kernel target N_ngb", AttrValue::F64Array(vec![0.0]));
    hydro.set_attr(
        "Dimension",
        AttrValue::I32Array(vec![snap.dimension as i32]),
    );
    fb.add_group(hydro.finish());
    let subgrid = fb.create_group("SubgridScheme");
    fb.add_group(subgrid.finish());

    // Gas.
    let r = range.clone();
    let mut gas = fb.create_group("PartType0");
    let vec3 = |v: &[Vec<f64>; 3]| -> Vec<f64> {
        r.clone()
            .flat_map(|i| [v[0][i], v[1][i], v[2][i]])
            .collect()
    };
    let n = r.len();
    // Densities: mass per length^D (2D: surface density); pressure likewise integrated.
    let vectors = [
        (
            "Coordinates",
            vec3(&snap.pos),
            exps(0.0, 1.0, 0.0),
            "Positions",
        ),
        (
            "Velocities",
            vec3(&snap.vel),
            exps(0.0, 1.0, -1.0),
            "Velocities",
        ),
    ];
    for (name, data, e, desc) in vectors {
        add_dataset(&mut gas, name, &data, Some(&[n as u64, 3]), e, desc, u);
    }
    let scalars: [(&str, &[f64], Exponents, &str); 7] = [
        (
            "Masses",
            &snap.mass[r.clone()],
            exps(1.0, 0.0, 0.0),
            "Masses",
        ),
        (
            "SmoothingLengths",
            &snap.h[r.clone()],
            exps(0.0, 1.0, 0.0),
            "Smoothing lengths h (kernel support 2h)",
        ),
        (
            "Densities",
            &snap.rho[r.clone()],
            exps(1.0, -d, 0.0),
            "Densities by summation (2D: surface density)",
        ),
        (
            "InternalEnergies",
            &snap.u[r.clone()],
            exps(0.0, 2.0, -2.0),
            "Specific internal energies",
        ),
        (
            "Pressures",
            &snap.p[r.clone()],
            exps(1.0, 2.0 - d, -2.0),
            "Pressures (2D: vertically integrated)",
        ),
        (
            "DissipationRates",
            &snap.diss[r.clone()],
            exps(0.0, 2.0, -3.0),
            "Specific viscous dissipation rates",
        ),
        // yt's SWIFT reader asks for the singular name; SWIFT and swiftsimio use the plural.
        (
            "SmoothingLength",
            &snap.h[r.clone()],
            exps(0.0, 1.0, 0.0),
            "Smoothing lengths h (copy under the name yt reads)",
        ),
    ];
    for (name, data, e, desc) in scalars {
        add_dataset(&mut gas, name, data, None, e, desc, u);
    }
    if !snap.alpha.is_empty() {
        add_dataset(
            &mut gas,
            "ViscosityParameters",
            &snap.alpha[r.clone()],
            None,
            exps(0.0, 0.0, 0.0),
            "Artificial-viscosity coefficients α of the switch",
            u,
        );
    }
    if meta.physical {
        // T = μ m_p P/(ρ k_B): P/ρ is c_s² of the isothermal sound speed for every EOS
        // (ideal: (γ−1) u; locally isothermal: c_s(R)²; 2D: the integrated P over Σ).
        let k = u.kelvin_per_specific_energy();
        let temperature: Vec<f64> = r
            .clone()
            .map(|i| {
                if snap.rho[i] > 0.0 {
                    k * snap.p[i] / snap.rho[i]
                } else {
                    0.0
                }
            })
            .collect();
        add_dataset(
            &mut gas,
            "Temperatures",
            &temperature,
            None,
            KELVIN,
            &format!(
                "Temperatures in K: mu m_p P / (rho k_B) with mu = {}",
                u.mean_molecular_weight
            ),
            u,
        );
    }
    let ids = gas.create_dataset("ParticleIDs").with_u64_data(&snap.id[r]);
    ids.set_attr("Description", AttrValue::AsciiString("Unique IDs".into()));
    set_unit_attrs(ids, exps(0.0, 0.0, 0.0), u);
    fb.add_group(gas.finish());

    if !point_masses.is_empty() {
        let mut pm = fb.create_group(&format!("PartType{POINT_MASS_TYPE}"));
        let k = point_masses.len() as u64;
        let pos: Vec<f64> = point_masses.iter().flat_map(|p| p.pos).collect();
        let vel: Vec<f64> = point_masses.iter().flat_map(|p| p.vel).collect();
        let mass: Vec<f64> = point_masses.iter().map(|p| p.mass).collect();
        let ids: Vec<u64> = point_masses.iter().map(|p| p.id).collect();
        let h0 = vec![0.0; point_masses.len()];
        add_dataset(
            &mut pm,
            "Coordinates",
            &pos,
            Some(&[k, 3]),
            exps(0.0, 1.0, 0.0),
            "Positions",
            u,
        );
        add_dataset(
            &mut pm,
            "Velocities",
            &vel,
            Some(&[k, 3]),
            exps(0.0, 1.0, -1.0),
            "Velocities",
            u,
        );
        add_dataset(
            &mut pm,
            "Masses",
            &mass,
            None,
            exps(1.0, 0.0, 0.0),
            "Masses (G M with G = 1)",
            u,
        );
        add_dataset(
            &mut pm,
            "SmoothingLengths",
            &h0,
            None,
            exps(0.0, 1.0, 0.0),
            "Softening (0: none)",
            u,
        );
        let ds = pm.create_dataset("ParticleIDs").with_u64_data(&ids);
        set_unit_attrs(ds, exps(0.0, 0.0, 0.0), u);
        fb.add_group(pm.finish());
    }

    Ok(fb.finish()?)
}

fn add_dataset(
    g: &mut GroupBuilder,
    name: &str,
    data: &[f64],
    shape: Option<&[u64]>,
    e: Exponents,
    description: &str,
    units: Units,
) {
    let ds = g.create_dataset(name).with_f64_data(data);
    if let Some(s) = shape {
        ds.with_shape(s);
    }
    ds.set_attr("Description", AttrValue::AsciiString(description.into()));
    set_unit_attrs(ds, e, units);
}

/// SWIFT's per-dataset unit attributes, which swiftsimio reads to attach units: numbers as
/// 1-element arrays, as SWIFT writes them (swiftsimio indexes them `[0]`).
fn set_unit_attrs(ds: &mut hdf5_pure::DatasetBuilder, e: Exponents, units: Units) {
    ds.set_attr("U_M exponent", AttrValue::F32Array(vec![e.m as f32]));
    ds.set_attr("U_L exponent", AttrValue::F32Array(vec![e.l as f32]));
    ds.set_attr("U_t exponent", AttrValue::F32Array(vec![e.t as f32]));
    ds.set_attr("U_I exponent", AttrValue::F32Array(vec![0.0]));
    ds.set_attr("U_T exponent", AttrValue::F32Array(vec![e.temp as f32]));
    ds.set_attr("a-scale exponent", AttrValue::F32Array(vec![0.0]));
    ds.set_attr("h-scale exponent", AttrValue::F32Array(vec![0.0]));
    let f = units.factor(e);
    ds.set_attr(
        "Conversion factor to CGS (not including cosmological corrections)",
        AttrValue::F64Array(vec![f]),
    );
    ds.set_attr(
        "Conversion factor to physical CGS (including cosmological corrections)",
        AttrValue::F64Array(vec![f]),
    );
}

/// Reads a snapshot: one file, or all parts of a multi-file snapshot when given `name.hdf5`
/// whose parts are `name.k.hdf5` (or any one part, which names the others).
pub fn read_snapshot(path: &Path) -> Result<Snapshot> {
    let mut first = first_file(path)?;
    let (mut snap, num_files, this_file) = match read_one(&first)? {
        Part::Data(s, n, k) => (*s, n, k),
        Part::Virtual => {
            // SWIFT's virtual file (`scripts/virtual_snapshot.py` writes one) maps the
            // parts' datasets, which this reader does not follow: read the parts.
            let part0 = part_paths(&first, 2).remove(0);
            if !part0.exists() {
                bail!(
                    "{} is a virtual snapshot and its parts ({}, …) are missing",
                    first.display(),
                    part0.display()
                );
            }
            first = part0;
            match read_one(&first)? {
                Part::Data(s, n, k) => (*s, n, k),
                Part::Virtual => bail!("{}: a part is a virtual file", first.display()),
            }
        }
    };
    if num_files > 1 {
        // Find the base name from `stem.k.hdf5` and read the other parts in order.
        let stem = first
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let base_stem = stem
            .strip_suffix(&format!(".{this_file}"))
            .map(str::to_string)
            .unwrap_or(stem);
        let base = first.with_file_name(format!("{base_stem}.hdf5"));
        let parts = part_paths(&base, num_files);
        clear_particles(&mut snap);
        for (k, part) in parts.iter().enumerate() {
            let Part::Data(s, n_files, idx) = read_one(part)? else {
                bail!("{}: a part is a virtual file", part.display());
            };
            if n_files != num_files || idx != k {
                bail!(
                    "{}: part {idx} of {n_files}, expected part {k} of {num_files}",
                    part.display()
                );
            }
            append(&mut snap, *s);
        }
    }
    snap.validate()
        .with_context(|| path.display().to_string())?;
    Ok(snap)
}

/// [`read_snapshot`] for a picture or an analysis, which interpolate with each particle's
/// smoothing length: also refuses an h that is not > 0.
pub fn read_snapshot_with_h(path: &Path) -> Result<Snapshot> {
    let snap = read_snapshot(path)?;
    snap.validate_for_interpolation()
        .with_context(|| path.display().to_string())?;
    Ok(snap)
}

/// The file to open for the snapshot `path`: itself, or the first part `name.0.hdf5` of a
/// multi-file snapshot named `name.hdf5`.
fn first_file(path: &Path) -> Result<PathBuf> {
    if path.exists() {
        return Ok(path.to_path_buf());
    }
    let p0 = part_paths(path, 2).remove(0);
    if !p0.exists() {
        bail!("cannot read snapshot {}: no such file", path.display());
    }
    Ok(p0)
}

/// The first file of a snapshot (the file itself, or part 0 of a multi-file one), opened.
fn open_first(path: &Path) -> Result<(File, PathBuf)> {
    let first = first_file(path)?;
    let bytes = std::fs::read(&first)
        .with_context(|| format!("cannot read snapshot {}", first.display()))?;
    let file = File::from_bytes(bytes)
        .map_err(|e| anyhow::anyhow!("{} is not a readable HDF5 file: {e}", first.display()))?;
    Ok((file, first))
}

/// The physical units of a snapshot: its `/Units` (cgs factors of the code units) with μ
/// from its parameters (`units:mean_molecular_weight`, default 0.6); `None` when the file
/// has no `/Units` or every factor is 1 (a run in G = 1 code units).
pub fn read_units(path: &Path) -> Result<Option<Units>> {
    let (file, first) = open_first(path)?;
    let Ok(group) = file.group("Units") else {
        return Ok(None);
    };
    let attrs = group
        .attrs()
        .map_err(|e| anyhow::anyhow!("{}: cannot read /Units: {e}", first.display()))?;
    let get = |k: &str| attr_f64(&attrs, k).filter(|x| *x > 0.0 && x.is_finite());
    let (Some(mass_cgs), Some(length_cgs), Some(time_cgs)) = (
        get("Unit mass in cgs (U_M)"),
        get("Unit length in cgs (U_L)"),
        get("Unit time in cgs (U_t)"),
    ) else {
        return Ok(None);
    };
    if [mass_cgs, length_cgs, time_cgs] == [1.0; 3] {
        return Ok(None);
    }
    let mu = read_parameters(path)?
        .get("units:mean_molecular_weight")
        .and_then(|v| v.parse::<f64>().ok())
        .filter(|x| *x > 0.0);
    Ok(Some(Units {
        mass_cgs,
        length_cgs,
        time_cgs,
        mean_molecular_weight: mu.unwrap_or_else(default_mu),
    }))
}

/// Whether the snapshot's box is periodic along every axis (SWIFT's
/// `RuntimePars/PeriodicBoundariesOn`; false when absent).
pub fn read_periodic(path: &Path) -> Result<bool> {
    let (file, _) = open_first(path)?;
    let Ok(group) = file.group("RuntimePars") else {
        return Ok(false);
    };
    Ok(group
        .attrs()
        .ok()
        .and_then(|a| attr_f64(&a, "PeriodicBoundariesOn"))
        .is_some_and(|x| x != 0.0))
}

/// The problem file a snapshot was written with: the attributes of its `/Parameters` group,
/// keyed as stored — `section:key` (SWIFT's convention; sphdisk writes the dotted keys of
/// `Config::flattened` with the first `.` made a `:`, so `[binary] q` is `binary:q`) — with
/// string values as they are and numeric ones printed. A file without the group (GADGET
/// initial conditions) gives an empty map. Multi-file snapshots: as [`read_snapshot`], the
/// parameters of the first part.
pub fn read_parameters(path: &Path) -> Result<BTreeMap<String, String>> {
    let (file, first) = open_first(path)?;
    let what = first.display();
    let Ok(group) = file.group("Parameters") else {
        return Ok(BTreeMap::new());
    };
    let attrs = group
        .attrs()
        .map_err(|e| anyhow::anyhow!("{what}: cannot read /Parameters attributes: {e}"))?;
    Ok(attrs
        .iter()
        .filter_map(|(k, v)| {
            let text = match attr_text(v) {
                Some(t) => t,
                None => attr_f64(&HashMap::from([(k.clone(), v.clone())]), k)?.to_string(),
            };
            Some((k.clone(), text))
        })
        .collect())
}

fn clear_particles(s: &mut Snapshot) {
    for v in s.pos.iter_mut().chain(s.vel.iter_mut()) {
        v.clear();
    }
    for v in [
        &mut s.mass,
        &mut s.h,
        &mut s.rho,
        &mut s.u,
        &mut s.p,
        &mut s.diss,
        &mut s.alpha,
    ] {
        v.clear();
    }
    s.id.clear();
    s.point_masses.clear();
}

fn append(into: &mut Snapshot, s: Snapshot) {
    for a in 0..3 {
        into.pos[a].extend(&s.pos[a]);
        into.vel[a].extend(&s.vel[a]);
    }
    into.id.extend(s.id);
    into.mass.extend(s.mass);
    into.h.extend(s.h);
    into.rho.extend(s.rho);
    into.u.extend(s.u);
    into.p.extend(s.p);
    into.diss.extend(s.diss);
    into.alpha.extend(s.alpha);
    into.point_masses.extend(s.point_masses);
}

fn attr_f64(attrs: &HashMap<String, AttrValue>, key: &str) -> Option<f64> {
    match attrs.get(key)? {
        AttrValue::F64(x) => Some(*x),
        AttrValue::F32(x) => Some(f64::from(*x)),
        AttrValue::I32(x) => Some(f64::from(*x)),
        AttrValue::I64(x) => Some(*x as f64),
        AttrValue::U32(x) => Some(f64::from(*x)),
        AttrValue::U64(x) => Some(*x as f64),
        // SWIFT writes numbers as 1-element arrays.
        AttrValue::F64Array(v) if v.len() == 1 => Some(v[0]),
        AttrValue::F32Array(v) if v.len() == 1 => Some(f64::from(v[0])),
        AttrValue::I32Array(v) if v.len() == 1 => Some(f64::from(v[0])),
        AttrValue::I64Array(v) if v.len() == 1 => Some(v[0] as f64),
        AttrValue::U32Array(v) if v.len() == 1 => Some(f64::from(v[0])),
        AttrValue::U64Array(v) if v.len() == 1 => Some(v[0] as f64),
        _ => None,
    }
}

fn attr_vec(attrs: &HashMap<String, AttrValue>, key: &str) -> Option<Vec<f64>> {
    Some(match attrs.get(key)? {
        AttrValue::F64Array(v) => v.clone(),
        AttrValue::F32Array(v) => v.iter().map(|&x| f64::from(x)).collect(),
        AttrValue::I32Array(v) => v.iter().map(|&x| f64::from(x)).collect(),
        AttrValue::I64Array(v) => v.iter().map(|&x| x as f64).collect(),
        AttrValue::U32Array(v) => v.iter().map(|&x| f64::from(x)).collect(),
        AttrValue::U64Array(v) => v.iter().map(|&x| x as f64).collect(),
        other => vec![attr_f64(
            &HashMap::from([(key.to_string(), other.clone())]),
            key,
        )?],
    })
}

/// What one file holds.
enum Part {
    /// The particles, `NumFilesPerSnapshot` and this file's index.
    Data(Box<Snapshot>, usize, usize),
    /// Nothing but links to the parts (`Header/Virtual` = 1, as SWIFT marks its own).
    Virtual,
}

/// Reads one file.
fn read_one(path: &Path) -> Result<Part> {
    let what = path.display();
    let bytes = std::fs::read(path).with_context(|| format!("cannot read snapshot {what}"))?;
    let file = File::from_bytes(bytes)
        .map_err(|e| anyhow::anyhow!("{what} is not a readable HDF5 file: {e}"))?;
    let header = file
        .group("Header")
        .map_err(|_| anyhow::anyhow!("{what}: no /Header group (not a SWIFT or GADGET snapshot)"))?
        .attrs()
        .map_err(|e| anyhow::anyhow!("{what}: cannot read /Header attributes: {e}"))?;
    if attr_f64(&header, "Virtual") == Some(1.0) {
        return Ok(Part::Virtual);
    }
    let box_size = attr_vec(&header, "BoxSize").unwrap_or_else(|| vec![1.0]);
    if box_size.is_empty() {
        bail!("{what}: Header/BoxSize holds no value");
    }
    let box_size: Vec<f64> = (0..3)
        .map(|a| box_size.get(a).copied().unwrap_or(box_size[0]))
        .collect();
    let shift = attr_vec(&header, "Shift").unwrap_or_else(|| vec![0.0; 3]);
    let num_files = attr_f64(&header, "NumFilesPerSnapshot").unwrap_or(1.0);
    if !(1.0..=crate::limits::MAX_FILES_PER_SNAPSHOT as f64).contains(&num_files) {
        bail!(
            "{what}: Header/NumFilesPerSnapshot = {num_files} is not between 1 and {}",
            crate::limits::MAX_FILES_PER_SNAPSHOT
        );
    }
    let num_files = num_files as usize;
    let this_file = attr_f64(&header, "ThisFile").unwrap_or(0.0);
    if !(0.0..num_files as f64).contains(&this_file) {
        bail!("{what}: Header/ThisFile = {this_file} is not a part of {num_files}");
    }
    let this_file = this_file as usize;
    let mass_table = attr_vec(&header, "MassTable").unwrap_or_default();

    let gas = file
        .group("PartType0")
        .map_err(|_| anyhow::anyhow!("{what}: no /PartType0 group (no gas particles)"))?;
    let names = gas
        .datasets()
        .map_err(|e| anyhow::anyhow!("{what}: cannot list /PartType0: {e}"))?;
    let find = |alts: &[&'static str]| -> Option<&'static str> {
        alts.iter().find(|a| names.iter().any(|n| n == *a)).copied()
    };
    let read_f64 = |alts: &[&'static str]| -> Result<Option<Vec<f64>>> {
        let Some(name) = find(alts) else {
            return Ok(None);
        };
        let ds = gas
            .dataset(name)
            .map_err(|e| anyhow::anyhow!("{what}: /PartType0/{name}: {e}"))?;
        Ok(Some(ds.read_f64().map_err(|e| {
            anyhow::anyhow!("{what}: cannot read /PartType0/{name}: {e}")
        })?))
    };
    let coords = read_f64(&["Coordinates"])?
        .with_context(|| format!("{what}: /PartType0 has no Coordinates"))?;
    // Coordinates are N×3 (SWIFT, GADGET); the unused ones of 1D and 2D runs are zero.
    if coords.len() % 3 != 0 {
        bail!("{what}: /PartType0/Coordinates is not N×3");
    }
    let n = coords.len() / 3;
    // The hydro dimension: `HydroScheme/Dimension` (sphdisk, SWIFT), else the header's.
    let hydro_dimension = file
        .group("HydroScheme")
        .ok()
        .and_then(|g| g.attrs().ok())
        .and_then(|a| attr_f64(&a, "Dimension"));
    let dimension = match hydro_dimension.or_else(|| attr_f64(&header, "Dimension")) {
        Some(d) => d as usize,
        None => 3,
    };
    if !(1..=3).contains(&dimension) {
        bail!("{what}: the dimension is {dimension}, expected 1, 2 or 3");
    }
    let split = |v: &[f64]| -> [Vec<f64>; 3] {
        std::array::from_fn(|a| (0..v.len() / 3).map(|i| v[3 * i + a]).collect())
    };
    let column = |alts: &[&'static str], label: &str| -> Result<Option<Vec<f64>>> {
        let v = read_f64(alts)?;
        if let Some(v) = &v
            && v.len() != n
        {
            bail!("{what}: {label} has {} entries for {n} particles", v.len());
        }
        Ok(v)
    };
    let vel = match read_f64(&["Velocities", "Velocity"])? {
        Some(v) if v.len() == 3 * n => split(&v),
        Some(_) => bail!("{what}: /PartType0/Velocities is not N×3"),
        None => std::array::from_fn(|_| vec![0.0; n]),
    };
    let mass = match column(&["Masses", "Mass"], "Masses")? {
        Some(m) => m,
        None => match mass_table.first() {
            Some(&m) if m > 0.0 => vec![m; n],
            _ => bail!("{what}: no /PartType0/Masses and no MassTable entry for gas"),
        },
    };
    let ids = match find(&["ParticleIDs", "ParticleID"]) {
        Some(name) => gas
            .dataset(name)
            .and_then(|d| d.read_u64())
            .map_err(|e| anyhow::anyhow!("{what}: cannot read /PartType0/{name}: {e}"))?,
        None => (0..n as u64).collect(),
    };
    if ids.len() != n {
        bail!(
            "{what}: ParticleIDs has {} entries for {n} particles",
            ids.len()
        );
    }
    let zeros = || vec![0.0; n];
    let snap = Snapshot {
        dimension,
        time: attr_f64(&header, "Time").unwrap_or(0.0),
        step: attr_f64(&header, "Step").unwrap_or(0.0) as u64,
        box_lo: [0.0; 3],
        box_hi: std::array::from_fn(|a| box_size[a]),
        shift: std::array::from_fn(|a| shift.get(a).copied().unwrap_or(0.0)),
        id: ids,
        pos: split(&coords),
        vel,
        mass,
        h: column(&["SmoothingLengths", "SmoothingLength"], "SmoothingLengths")?
            .unwrap_or_else(zeros),
        rho: column(&["Densities", "Density"], "Densities")?.unwrap_or_else(zeros),
        u: column(&["InternalEnergies", "InternalEnergy"], "InternalEnergies")?
            .unwrap_or_else(zeros),
        p: column(&["Pressures", "Pressure"], "Pressures")?.unwrap_or_else(zeros),
        diss: column(&["DissipationRates"], "DissipationRates")?.unwrap_or_else(zeros),
        alpha: column(&["ViscosityParameters"], "ViscosityParameters")?.unwrap_or_default(),
        point_masses: read_point_masses(&file, path)?,
        kernel: read_kernel(&file),
    };
    Ok(Part::Data(Box::new(snap), num_files, this_file))
}

/// A string attribute's text, without trailing NULs and blanks; None for other types.
fn attr_text(v: &AttrValue) -> Option<String> {
    match v {
        AttrValue::AsciiString(s) | AttrValue::String(s) => Some(s),
        AttrValue::AsciiStringSized { value, .. } | AttrValue::StringSized { value, .. } => {
            Some(value)
        }
        _ => None,
    }
    .map(|s| s.trim_end_matches('\0').trim().to_string())
}

/// The run's kernel: `/HydroScheme` `Kernel function` (the description written from
/// [`Snapshot::kernel`]), else `/Parameters` `particles:kernel`, else the cubic spline
/// (files of other codes that name none).
fn read_kernel(file: &File) -> KernelKind {
    let text = |group: &str, key: &str| -> Option<String> {
        attr_text(file.group(group).ok()?.attrs().ok()?.get(key)?)
    };
    text("HydroScheme", "Kernel function")
        .and_then(|d| KernelKind::ALL.into_iter().find(|k| k.description() == d))
        .or_else(|| text("Parameters", "particles:kernel").and_then(|k| KernelKind::from_key(&k)))
        .unwrap_or_default()
}

fn read_point_masses(file: &File, path: &Path) -> Result<Vec<PointMassRecord>> {
    let Ok(g) = file.group(&format!("PartType{POINT_MASS_TYPE}")) else {
        return Ok(Vec::new());
    };
    let what = path.display();
    let read = |name: &str| -> Result<Vec<f64>> {
        g.dataset(name).and_then(|d| d.read_f64()).map_err(|e| {
            anyhow::anyhow!("{what}: cannot read /PartType{POINT_MASS_TYPE}/{name}: {e}")
        })
    };
    let pos = read("Coordinates")?;
    let vel = read("Velocities")?;
    let mass = read("Masses")?;
    let ids = g
        .dataset("ParticleIDs")
        .and_then(|d| d.read_u64())
        .map_err(|e| anyhow::anyhow!("{what}: point-mass IDs: {e}"))?;
    if pos.len() != 3 * mass.len() || vel.len() != pos.len() || ids.len() != mass.len() {
        bail!("{what}: /PartType{POINT_MASS_TYPE} datasets disagree in length");
    }
    Ok((0..mass.len())
        .map(|k| PointMassRecord {
            id: ids[k],
            pos: [pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]],
            vel: [vel[3 * k], vel[3 * k + 1], vel[3 * k + 2]],
            mass: mass[k],
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn sample(n: usize, dimension: usize) -> Snapshot {
        let mut rng = Rng::new(7);
        let mut col = || (0..n).map(|_| rng.uniform()).collect::<Vec<f64>>();
        Snapshot {
            dimension,
            time: 0.125,
            step: 42,
            box_lo: [0.0; 3],
            box_hi: [2.0, 4.0, 1.0],
            shift: [1.0, 2.0, 0.0],
            id: (0..n as u64).map(|i| 3 * i + 5).collect(),
            pos: [col(), col(), col()],
            vel: [col(), col(), col()],
            mass: col(),
            h: col(),
            rho: col(),
            u: col(),
            p: col(),
            diss: col(),
            alpha: col(),
            point_masses: vec![PointMassRecord {
                id: u64::MAX,
                pos: [0.5, 0.25, 0.0],
                vel: [0.0, 1.0, 0.0],
                mass: 0.75,
            }],
            kernel: KernelKind::Cubic,
        }
    }

    fn meta() -> RunMetadata {
        RunMetadata {
            parameters: BTreeMap::from([
                ("eos.gamma".to_string(), "1.4".to_string()),
                ("problem.kind".to_string(), "\"sod\"".to_string()),
            ]),
            units: Units {
                mass_cgs: 2e33,
                length_cgs: 7e10,
                time_cgs: 1e3,
                mean_molecular_weight: 0.6,
            },
            periodic: true,
            physical: true,
        }
    }

    #[test]
    fn snapshot_round_trips_every_field_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snap.hdf5");
        let mut snap = sample(257, 3);
        // The kernel travels too (pictures spread particles with it).
        snap.kernel = KernelKind::WendlandC4;
        write_snapshot(&path, &snap, &meta(), 1).unwrap();
        let back = read_snapshot(&path).unwrap();
        assert_eq!(back, snap);
    }

    #[test]
    fn multi_file_snapshot_reads_back_whole_from_any_name() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("snap_0003.hdf5");
        let snap = sample(100, 2);
        let paths = write_snapshot(&base, &snap, &meta(), 3).unwrap();
        assert_eq!(paths.len(), 3);
        assert!(!base.exists(), "parts only, no single file");
        assert_eq!(read_snapshot(&base).unwrap(), snap);
        assert_eq!(read_snapshot(&paths[2]).unwrap(), snap);
    }

    #[test]
    fn a_virtual_file_beside_the_parts_reads_the_parts() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("snap_0002.hdf5");
        let snap = sample(60, 2);
        write_snapshot(&base, &snap, &meta(), 2).unwrap();
        // What SWIFT's virtual file holds besides its mapped datasets: the header, marked.
        let mut fb = FileBuilder::new();
        let mut h = fb.create_group("Header");
        h.set_attr("Virtual", AttrValue::I32Array(vec![1]));
        h.set_attr("NumFilesPerSnapshot", AttrValue::I32Array(vec![1]));
        fb.add_group(h.finish());
        std::fs::write(&base, fb.finish().unwrap()).unwrap();
        assert_eq!(read_snapshot(&base).unwrap(), snap);
        // Without its parts it says so.
        let lone = dir.path().join("lone.hdf5");
        std::fs::copy(&base, &lone).unwrap();
        let e = format!("{:#}", read_snapshot(&lone).unwrap_err());
        assert!(
            e.contains("virtual snapshot") && e.contains("lone.0.hdf5"),
            "{e}"
        );
    }

    #[test]
    fn temperatures_in_kelvin_only_with_physical_units() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snap.hdf5");
        let snap = sample(30, 3);
        let m = meta();
        write_snapshot(&path, &snap, &m, 1).unwrap();
        let f = File::open(&path).unwrap();
        let t = f.dataset("PartType0/Temperatures").unwrap();
        // μ m_p v²/k_B with v = 7e10 cm / 1e3 s: 0.6 · 1.67262e-24 · 4.9e15 / 1.380649e-16.
        let k = m.units.kelvin_per_specific_energy();
        assert!((k / (0.6 * 1.672_621_923_69e-24 * 4.9e15 / 1.380_649e-16) - 1.0).abs() < 1e-15);
        let expect: Vec<f64> = (0..30).map(|i| k * snap.p[i] / snap.rho[i]).collect();
        assert_eq!(t.read_f64().unwrap(), expect);
        let a = t.attrs().unwrap();
        assert_eq!(a["U_T exponent"], AttrValue::F32Array(vec![1.0]));
        assert_eq!(a["U_L exponent"], AttrValue::F32Array(vec![0.0]));
        assert_eq!(
            attr_f64(
                &a,
                "Conversion factor to CGS (not including cosmological corrections)"
            ),
            Some(1.0)
        );
        // G = 1 units: no kelvin, no field.
        let plain = RunMetadata {
            physical: false,
            ..meta()
        };
        write_snapshot(&path, &snap, &plain, 1).unwrap();
        let f = File::open(&path).unwrap();
        assert!(f.dataset("PartType0/Temperatures").is_err());
    }

    #[test]
    fn the_hydro_scheme_names_the_formulation() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snap.hdf5");
        for (scheme, expect) in [
            (None, "density-energy"),
            (Some("\"density_energy\""), "density-energy"),
            (Some("\"pressure_energy\""), "pressure-energy"),
        ] {
            let mut m = meta();
            if let Some(s) = scheme {
                m.parameters.insert("hydro.scheme".into(), s.into());
            }
            write_snapshot(&path, &sample(10, 1), &m, 1).unwrap();
            let f = File::open(&path).unwrap();
            let hydro = f.group("HydroScheme").unwrap().attrs().unwrap();
            let text = attr_text(hydro.get("Scheme").unwrap()).unwrap();
            assert!(text.contains(expect), "{scheme:?}: {text}");
        }
    }

    #[test]
    fn header_carries_swift_metadata() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snap.hdf5");
        write_snapshot(&path, &sample(10, 2), &meta(), 1).unwrap();
        let f = File::open(&path).unwrap();
        let h = f.group("Header").unwrap().attrs().unwrap();
        assert_eq!(h["Code"], AttrValue::AsciiString("SWIFT".into()));
        // yt needs 3 here for its particle index; the hydro dimension is the scheme's.
        assert_eq!(attr_f64(&h, "Dimension"), Some(3.0));
        let hydro = f.group("HydroScheme").unwrap().attrs().unwrap();
        assert_eq!(attr_f64(&hydro, "Dimension"), Some(2.0));
        assert_eq!(attr_vec(&h, "BoxSize").unwrap(), vec![2.0, 4.0, 1.0]);
        let units = f.group("Units").unwrap().attrs().unwrap();
        assert_eq!(attr_f64(&units, "Unit length in cgs (U_L)"), Some(7e10));
        let params = f.group("Parameters").unwrap().attrs().unwrap();
        assert_eq!(params["eos:gamma"], AttrValue::AsciiString("1.4".into()));
        assert_eq!(params["problem:kind"], AttrValue::AsciiString("sod".into()));
        // 2D density is a surface density: mass per length², in cgs 2e33 / 7e10².
        let rho = f.dataset("PartType0/Densities").unwrap().attrs().unwrap();
        assert_eq!(attr_f64(&rho, "U_L exponent"), Some(-2.0));
        let c = attr_f64(
            &rho,
            "Conversion factor to CGS (not including cosmological corrections)",
        )
        .unwrap();
        assert!((c / (2e33 / 4.9e21) - 1.0).abs() < 1e-12);
        let coords = f.dataset("PartType0/Coordinates").unwrap();
        assert_eq!(coords.shape().unwrap(), vec![10, 3]);
    }

    #[test]
    fn numbers_are_one_element_arrays_as_swift_writes_them() {
        // swiftsimio reads every number of /Header, /Units and the datasets' unit
        // attributes as `value[0]`: a scalar attribute raises IndexError there.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("snap.hdf5");
        write_snapshot(&path, &sample(10, 2), &meta(), 1).unwrap();
        let f = File::open(&path).unwrap();
        let one = |v: &AttrValue| {
            matches!(v, AttrValue::F64Array(a) if a.len() == 1)
                || matches!(v, AttrValue::F32Array(a) if a.len() == 1)
                || matches!(v, AttrValue::I32Array(a) if a.len() == 1)
                || matches!(v, AttrValue::U64Array(a) if a.len() == 1)
        };
        let h = f.group("Header").unwrap().attrs().unwrap();
        for k in [
            "Dimension",
            "Time",
            "NumFilesPerSnapshot",
            "ThisFile",
            "Scale-factor",
        ] {
            assert!(one(&h[k]), "Header/{k}: {:?}", h[k]);
        }
        let units = f.group("Units").unwrap().attrs().unwrap();
        assert_eq!(units.len(), 5);
        for (k, v) in &units {
            assert!(one(v), "Units/{k}: {v:?}");
        }
        let ds = f.dataset("PartType0/Densities").unwrap().attrs().unwrap();
        for k in [
            "U_M exponent",
            "U_L exponent",
            "U_t exponent",
            "a-scale exponent",
        ] {
            assert!(one(&ds[k]), "Densities {k}: {:?}", ds[k]);
        }
        assert_eq!(ds["U_L exponent"], AttrValue::F32Array(vec![-2.0]));
    }

    #[test]
    fn parameters_read_back_as_section_colon_key() {
        let dir = tempfile::tempdir().unwrap();
        let base = dir.path().join("snap.hdf5");
        let mut m = meta();
        m.parameters
            .insert("binary.q".to_string(), "0.15".to_string());
        write_snapshot(&base, &sample(20, 3), &m, 2).unwrap();
        // A multi-file snapshot by its base name: the first part's parameters.
        let p = read_parameters(&base).unwrap();
        assert_eq!(p.get("binary:q").map(String::as_str), Some("0.15"));
        assert_eq!(p.get("problem:kind").map(String::as_str), Some("sod"));
        assert_eq!(p.get("eos:gamma").map(String::as_str), Some("1.4"));
        assert_eq!(p.len(), 3);
        // No /Parameters group: nothing; no file: an error.
        let mut fb = FileBuilder::new();
        let h = fb.create_group("Header");
        fb.add_group(h.finish());
        let bare = dir.path().join("bare.hdf5");
        std::fs::write(&bare, fb.finish().unwrap()).unwrap();
        assert!(read_parameters(&bare).unwrap().is_empty());
        assert!(read_parameters(&dir.path().join("nope.hdf5")).is_err());
    }

    #[test]
    fn truncated_foreign_and_missing_files_are_named_errors() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("snap.hdf5");
        write_snapshot(&good, &sample(50, 3), &meta(), 1).unwrap();
        let bytes = std::fs::read(&good).unwrap();
        let cut = dir.path().join("cut.hdf5");
        std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
        let e = format!("{:#}", read_snapshot(&cut).unwrap_err());
        assert!(e.contains("cut.hdf5"), "{e}");

        let text = dir.path().join("text.hdf5");
        std::fs::write(&text, "id,x\n1,2\n").unwrap();
        let e = format!("{:#}", read_snapshot(&text).unwrap_err());
        assert!(e.contains("not a readable HDF5 file"), "{e}");

        let mut fb = FileBuilder::new();
        fb.create_dataset("temperature").with_f64_data(&[1.0]);
        let foreign = dir.path().join("foreign.h5");
        std::fs::write(&foreign, fb.finish().unwrap()).unwrap();
        let e = format!("{:#}", read_snapshot(&foreign).unwrap_err());
        assert!(e.contains("no /Header group"), "{e}");

        let e = format!(
            "{:#}",
            read_snapshot(&dir.path().join("nope.hdf5")).unwrap_err()
        );
        assert!(e.contains("no such file"), "{e}");
    }

    /// A corrupted header whose BoxSize is an empty array (found by tests/fuzz.rs) is a named
    /// error, not an index out of bounds.
    #[test]
    fn an_empty_box_size_is_a_named_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("empty_box.hdf5");
        let mut fb = FileBuilder::new();
        let mut h = fb.create_group("Header");
        h.set_attr("BoxSize", AttrValue::F64Array(Vec::new()));
        fb.add_group(h.finish());
        let mut g = fb.create_group("PartType0");
        g.create_dataset("Coordinates")
            .with_f64_data(&[0.1, 0.2, 0.3])
            .with_shape(&[1, 3]);
        fb.add_group(g.finish());
        std::fs::write(&path, fb.finish().unwrap()).unwrap();
        let e = format!("{:#}", read_snapshot(&path).unwrap_err());
        assert!(e.contains("BoxSize") && e.contains("empty_box.hdf5"), "{e}");
    }

    #[test]
    fn gadget_style_singular_names_and_mass_table_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ics.hdf5");
        let mut fb = FileBuilder::new();
        let mut h = fb.create_group("Header");
        h.set_attr("BoxSize", AttrValue::F64(2.0));
        h.set_attr(
            "MassTable",
            AttrValue::F64Array(vec![0.5, 0.0, 0.0, 0.0, 0.0, 0.0]),
        );
        h.set_attr(
            "NumPart_ThisFile",
            AttrValue::I32Array(vec![2, 0, 0, 0, 0, 0]),
        );
        fb.add_group(h.finish());
        let mut g = fb.create_group("PartType0");
        g.create_dataset("Coordinates")
            .with_f32_data(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
            .with_shape(&[2, 3]);
        g.create_dataset("Velocity")
            .with_f32_data(&[0.0; 6])
            .with_shape(&[2, 3]);
        g.create_dataset("InternalEnergy")
            .with_f32_data(&[1.5, 2.5]);
        g.create_dataset("ParticleIDs").with_u32_data(&[7, 9]);
        fb.add_group(g.finish());
        std::fs::write(&path, fb.finish().unwrap()).unwrap();
        let s = read_snapshot(&path).unwrap();
        assert_eq!(s.dimension, 3);
        assert_eq!(s.mass, vec![0.5, 0.5]);
        assert_eq!(s.id, vec![7, 9]);
        assert_eq!(s.u, vec![1.5, 2.5]);
        assert_eq!(s.box_hi, [2.0; 3]);
        assert!((s.pos[1][1] - 0.5).abs() < 1e-7);
    }
}
