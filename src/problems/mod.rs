//! Problem set-ups: each kind builds its initial particles, box and smoothing length from the
//! problem file, and measures its error against its exact solution at the end.

pub mod advection;
pub mod cv;
pub mod cv_disk;
pub mod disk;
pub mod file;
pub mod lattice;
pub mod ring;
pub mod sedov;
pub mod sod;

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::boundary::{BoundaryKind, SimBox, axis_name};
use crate::config::{Config, ProblemKind};
use crate::particles::Particles;

/// What a problem hands the integrator.
pub struct InitialState<const D: usize> {
    pub particles: Particles<D>,
    pub bx: SimBox<D>,
    pub h: f64,
    /// If set, the internal energies are reset after the first density sum so that the
    /// pressure is exactly this value everywhere (a quiet pressure equilibrium).
    pub pressure_equilibrium: Option<f64>,
    /// End time set by the problem itself (used when `time.end` is absent).
    pub t_end: Option<f64>,
    /// Snapshot times the problem asks for, besides `output.interval`.
    pub output_times: Vec<f64>,
    /// A binary's L1 injector after the set-up's own releases (cv problems).
    pub injector: Option<crate::physics::l1_stream::InjectorState>,
}

impl<const D: usize> InitialState<D> {
    /// A state with no pressure reset and no end or snapshot times of its own.
    pub fn new(particles: Particles<D>, bx: SimBox<D>, h: f64) -> Self {
        Self {
            particles,
            bx,
            h,
            pressure_equilibrium: None,
            t_end: None,
            output_times: Vec::new(),
            injector: None,
        }
    }
}

/// The smoothing length: `particles.h`, or `particles.h_factor` × the problem's reference
/// particle spacing.
pub fn smoothing_length(cfg: &Config, reference_spacing: f64) -> f64 {
    cfg.particles
        .h
        .unwrap_or_else(|| cfg.particles.h_factor.unwrap_or(1.2) * reference_spacing)
}

/// Particles on a ring of radius `r` spaced `dr` along it (at least one): the disk's and
/// the spreading ring's rings.
pub(crate) fn ring_count(r: f64, dr: f64) -> usize {
    ((std::f64::consts::TAU * r / dr).round() as usize).max(1)
}

/// The box: the problem's own, or `[domain]`; boundary kinds from `[boundary]` or the
/// problem's defaults.
pub fn make_box<const D: usize>(
    cfg: &Config,
    min: [f64; D],
    max: [f64; D],
    default_kinds: [BoundaryKind; D],
) -> SimBox<D> {
    let (min, max) = match &cfg.domain {
        Some(dom) => (
            std::array::from_fn(|d| dom.min[d]),
            std::array::from_fn(|d| dom.max[d]),
        ),
        None => (min, max),
    };
    let given = [cfg.boundary.x, cfg.boundary.y, cfg.boundary.z];
    let kinds = std::array::from_fn(|d| given[d].unwrap_or(default_kinds[d]));
    SimBox { min, max, kinds }
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    let state = match cfg.problem.kind {
        ProblemKind::Sod => sod::setup(cfg)?,
        ProblemKind::Advection => advection::setup(cfg)?,
        ProblemKind::Sedov => sedov::setup(cfg)?,
        ProblemKind::Ring => ring::setup(cfg)?,
        ProblemKind::Disk => disk::setup(cfg)?,
        ProblemKind::File => file::setup(cfg)?,
        ProblemKind::Cv => cv::setup(cfg)?,
    };
    // A box too small for the kernel: h is what the problem's resolution keys set.
    state
        .bx
        .validate(cfg.particles.kernel.support_factor() * state.h)
        .map_err(|e| anyhow::anyhow!("key `{}`: {e}", crate::limits::h_key(cfg)))?;
    check_initial_state(&state, cfg.particles.kernel)?;
    crate::limits::check_grid(cfg, &state.bx, state.h, &state.particles.pos)?;
    Ok(state)
}

/// Refuses non-physical or misplaced particles, naming the first offender.
pub fn check_initial_state<const D: usize>(
    s: &InitialState<D>,
    kernel: crate::kernel::KernelKind,
) -> Result<()> {
    if s.particles.is_empty() {
        bail!("the problem has no particles");
    }
    check_particles(&s.particles, s.h)?;
    s.bx.validate(kernel.support_factor() * s.h)?;
    s.bx.check_inside(&s.particles.pos, &s.particles.id)?;
    Ok(())
}

/// Refuses a non-physical smoothing length `h` or particle (mass or h not a positive
/// number, internal energy negative or not finite, a position or velocity not finite, an
/// id twice), naming the first offender; the box is not looked at.
pub fn check_particles<const D: usize>(p: &Particles<D>, h: f64) -> Result<()> {
    if !(h > 0.0 && h.is_finite()) {
        bail!("smoothing length h must be > 0, got {h}");
    }
    for i in 0..p.len() {
        if !(p.mass[i] > 0.0 && p.mass[i].is_finite()) {
            bail!("particle {}: mass must be > 0, got {}", p.id[i], p.mass[i]);
        }
        if !(p.u[i] >= 0.0 && p.u[i].is_finite()) {
            bail!(
                "particle {}: internal energy must be ≥ 0, got {}",
                p.id[i],
                p.u[i]
            );
        }
        for d in 0..D {
            if !p.pos[d][i].is_finite() || !p.vel[d][i].is_finite() {
                bail!(
                    "particle {}: non-finite position or velocity along {}",
                    p.id[i],
                    axis_name(d)
                );
            }
        }
    }
    let mut ids = p.id.clone();
    ids.sort_unstable();
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        bail!("particle id {} appears twice", w[0]);
    }
    Ok(())
}

/// The problem's error norms against its exact solution at time `t`.
pub fn errors<const D: usize>(
    cfg: &Config,
    p: &Particles<D>,
    bx: &SimBox<D>,
    h: f64,
    t: f64,
) -> Result<BTreeMap<String, f64>> {
    match cfg.problem.kind {
        ProblemKind::Sod => sod::errors(cfg, p, t),
        ProblemKind::Advection => advection::errors(cfg, p, bx, t),
        ProblemKind::Sedov => sedov::errors(cfg, p, h, t),
        ProblemKind::Ring => ring::errors(cfg, p, t),
        ProblemKind::Disk => disk::errors(cfg, p, t),
        ProblemKind::File => Ok(BTreeMap::new()),
        ProblemKind::Cv => cv::errors(cfg, p, h),
    }
}
