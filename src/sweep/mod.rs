//! The sweep (paper, Section 2.1 and Figure 1): one right-hand-side evaluation in a single
//! pass along x. Pairs are found slab by slab; the three SPH sums (density → first
//! derivatives → right-hand sides) run on a slab's pairs as soon as every particle they touch
//! has finished the previous sum; a slab's pairs are dropped once its force sum is done. The
//! full pair list never exists: the window holds a few slabs' pairs.
//!
//! A particle's state ("U", "Dens", "1.", "RHS" in Figure 1) is the number of sums finished
//! for its slab. Ghosts finish when their owners do; contributions gathered at periodic ghosts
//! are folded into their owners first. With a periodic x axis the first slabs wait for the
//! last one (the sweep is a ring), which the dependency rules below handle without a special
//! case.
//!
//! Slabs of few particles (a CV disk of a few thousand in a box mostly empty) enter a batch at
//! a time ([`BATCH_PARTICLES_PER_THREAD`], or [`Window::batch_per_thread`]): their pairs are
//! found in parallel, and the blocks ready for the same sum are summed together and merged in
//! slab order — the result of one slab at a time, bit for bit, without leaving all threads
//! but one idle. A block ready before the block before it has its part over the previous
//! slab held until that block's own is merged ([`pairs::Held`]), so no batch changes a bit.

pub mod cost;
pub mod local;
pub mod pairs;
pub mod reference;

use std::time::Instant;

use rayon::prelude::*;

use crate::boundary::SimBox;
use crate::kernel::Kernel;
use crate::particles::Particles;
use crate::physics::artificial_viscosity::{ArtificialViscosity, av_velocity, balsara_factor};
use crate::physics::binary::Binary;
use crate::physics::eos::{Eos, cylindrical_radius};
use crate::physics::gravity::PointMass;
use crate::physics::hydro::PairTerms;
use crate::physics::pressure_energy::{Scheme, smoothed_pressure};
use crate::physics::viscosity::ViscosityModel;
use local::{Local, Work};
use pairs::{BYTES_PER_PAIR, PairBlock};

/// The physics one evaluation needs.
#[derive(Clone, Copy, Debug)]
pub struct Physics<const D: usize> {
    pub kernel: Kernel<D>,
    pub eos: Eos,
    pub av: ArtificialViscosity,
    /// Physical shear viscosity, Eqs. (8)–(10).
    pub viscosity: ViscosityModel,
    /// External central point mass (applied outside the sweep; ν = α c_s H needs its GM).
    /// In a binary, the accretor.
    pub gravity: Option<PointMass>,
    /// A binary: the donor's gravity, and the turning frame the integrator steps in.
    pub binary: Option<Binary>,
    /// β cooling of the internal energy (applied outside the sweep, with the gravity).
    pub cooling: Option<crate::physics::cooling::Cooling>,
    /// The dwarf-nova disk instability: α by the gas's branch, u relaxed to the branch.
    pub outbursts: Option<crate::physics::outbursts::Outbursts>,
    /// The SPH formulation (`physics::pressure_energy`).
    pub scheme: Scheme,
}

impl<const D: usize> Physics<D> {
    /// Everything a problem file switches on, with smoothing length `h`.
    pub fn from_config(cfg: &crate::config::Config, h: f64) -> Self {
        Self {
            kernel: Kernel::<D>::of_kind(cfg.particles.kernel, h),
            eos: cfg.eos,
            av: ArtificialViscosity {
                // Without an energy equation there is no heat to conduct.
                conductivity: if cfg.eos.evolves_energy() {
                    cfg.artificial_viscosity.conductivity
                } else {
                    0.0
                },
                ..cfg.artificial_viscosity
            },
            viscosity: cfg.viscosity,
            gravity: cfg.central_mass(),
            binary: cfg.binary.as_ref().map(Binary::new),
            cooling: cfg.cooling,
            outbursts: cfg.outbursts,
            scheme: cfg.hydro.scheme,
        }
    }

    /// Hydrodynamics only: no physical viscosity, no gravity.
    pub fn hydro(kernel: Kernel<D>, eos: Eos, av: ArtificialViscosity) -> Self {
        Self {
            kernel,
            eos,
            av,
            viscosity: ViscosityModel::default(),
            gravity: None,
            binary: None,
            cooling: None,
            outbursts: None,
            scheme: Scheme::DensityEnergy,
        }
    }

    /// γ where the pressure–energy formulation is on (an ideal gas), else `None`.
    #[inline]
    pub fn pressure_energy_gamma(&self) -> Option<f64> {
        match (self.scheme, self.eos) {
            (Scheme::PressureEnergy, Eos::Ideal { gamma }) => Some(gamma),
            _ => None,
        }
    }

    /// The switches of the pair functions.
    #[inline]
    pub fn pair_terms(&self) -> PairTerms {
        PairTerms {
            viscous: self.viscous(),
            pressure_energy: self.pressure_energy_gamma().is_some(),
        }
    }

    /// Whether the physical shear viscosity (Eqs. 8–10) acts.
    #[inline]
    pub fn viscous(&self) -> bool {
        self.viscosity.is_on() || self.outbursts.is_some()
    }

    /// ν at an element with sound speed `cs` at cylindrical radius `r`: the two-branch α of
    /// `[outbursts]`, or the `[viscosity]` model.
    #[inline]
    pub fn nu(&self, cs: f64, r: f64) -> f64 {
        let gm = self.gravity.map_or(0.0, |g| g.gm);
        match &self.outbursts {
            Some(o) => o.nu(cs, r, gm),
            None => self.viscosity.nu(cs, r, gm),
        }
    }
}

/// Figures of one evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepStats {
    /// Pairs found (each once).
    pub pairs: u64,
    /// Largest number of pairs held in the window at once.
    pub peak_pairs: usize,
    /// Bytes the window held at its peak.
    pub peak_window_bytes: usize,
    pub ghosts: usize,
    /// Cells of the neighbour grid (most of them empty in a sparse box).
    pub grid_cells: u64,
    /// Bytes of the grid's cell index (dense: one entry per cell; sparse: per occupied cell).
    pub grid_index_bytes: usize,
    pub slabs: usize,
    /// Seconds spent in each part of the evaluation.
    pub times: StageTimes,
}

/// Where an evaluation's time goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageTimes {
    /// Ghosts, grid, copy into cell order.
    pub build: f64,
    pub find_pairs: f64,
    pub density: f64,
    pub gradient: f64,
    pub force: f64,
    /// Folding ghosts, equation of state, copies to ghosts, write-back.
    pub finish: f64,
    /// Waiting for other ranks' messages (distributed runs).
    pub wait: f64,
}

impl StageTimes {
    pub fn add(&mut self, o: &StageTimes) {
        self.build += o.build;
        self.find_pairs += o.find_pairs;
        self.density += o.density;
        self.gradient += o.gradient;
        self.force += o.force;
        self.finish += o.finish;
        self.wait += o.wait;
    }

    /// All parts together: the evaluation's time.
    pub fn total(&self) -> f64 {
        self.build
            + self.find_pairs
            + self.density
            + self.gradient
            + self.force
            + self.finish
            + self.wait
    }

    /// Every part multiplied by `k` (e.g. totals to per-step means).
    pub fn scaled(&self, k: f64) -> StageTimes {
        StageTimes {
            build: self.build * k,
            find_pairs: self.find_pairs * k,
            density: self.density * k,
            gradient: self.gradient * k,
            force: self.force * k,
            finish: self.finish * k,
            wait: self.wait * k,
        }
    }
}

/// How the window holds pairs. A sweep drops a slab's pairs once its force sum is done
/// (the paper's algorithm); `full_list` keeps every pair to the end, the memory behaviour of
/// a stored full pair list, for comparison. `batch_per_thread` is the paper's delay (Section
/// 2.3: delaying a particle's change of state "increases the size of the interaction list
/// and thus acts as a tuning parameter for a size vs. speed tradeoff"): slabs enter the
/// sweep together until they hold this many particles per thread ([`batch_end`]), so that
/// fewer, larger parallel regions run, at the cost of more pairs held at once. Results do
/// not depend on it (blocks are summed and merged in slab order whatever the batch).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub full_list: bool,
    pub batch_per_thread: usize,
}

impl Window {
    /// The paper's window, with the default batch.
    pub const SWEEP: Self = Self {
        full_list: false,
        batch_per_thread: BATCH_PARTICLES_PER_THREAD,
    };
    /// Every pair kept to the end of the evaluation.
    pub const FULL_LIST: Self = Self {
        full_list: true,
        batch_per_thread: BATCH_PARTICLES_PER_THREAD,
    };

    /// `Sweep` or `FullList`, and the batch where it is not the default (`Sweep/16384`).
    pub fn label(&self) -> String {
        let kind = if self.full_list { "FullList" } else { "Sweep" };
        if self.batch_per_thread == BATCH_PARTICLES_PER_THREAD {
            kind.to_string()
        } else {
            format!("{kind}/{}", self.batch_per_thread)
        }
    }

    /// This window with slabs entering `per_thread` particles per thread at a time.
    pub fn with_batch(self, per_thread: usize) -> Self {
        Self {
            batch_per_thread: per_thread,
            ..self
        }
    }
}

impl Default for Window {
    fn default() -> Self {
        Self::SWEEP
    }
}

/// The three sums, in order. A stage number counts the sums finished.
pub const DENSITY: u8 = 1;
pub const GRADIENT: u8 = 2;
pub const FORCE: u8 = 3;

/// Dependency tables of the slabs, from where ghosts lie relative to their owners.
struct Dependencies {
    /// Slabs holding ghosts of this slab's particles (their pairs must be finished too).
    ghost_slabs: Vec<Vec<usize>>,
    /// Slabs holding owners of ghosts in this slab.
    owner_slabs: Vec<Vec<usize>>,
    /// Local indices of the ghosts whose owner lies in this slab.
    ghosts_of: Vec<Vec<u32>>,
}

impl Dependencies {
    fn new<const D: usize>(local: &Local<D>) -> Self {
        let ns = local.num_slabs();
        let mut dep = Self {
            ghost_slabs: vec![Vec::new(); ns],
            owner_slabs: vec![Vec::new(); ns],
            ghosts_of: vec![Vec::new(); ns],
        };
        // The ghosts with a local owner, and their and their owners' slabs, in order.
        let ghosts: Vec<(u32, usize, usize)> = (0..local.len())
            .into_par_iter()
            .with_min_len(1 << 14)
            .filter(|&k| local.is_ghost[k] && local.owner[k] != local::REMOTE)
            .map(|k| {
                let o = local.owner[k] as usize;
                (k as u32, local.slab_of(k), local.slab_of(o))
            })
            .collect();
        for (k, sg, so) in ghosts {
            dep.ghosts_of[so].push(k);
            if sg != so {
                if !dep.ghost_slabs[so].contains(&sg) {
                    dep.ghost_slabs[so].push(sg);
                }
                if !dep.owner_slabs[sg].contains(&so) {
                    dep.owner_slabs[sg].push(so);
                }
            }
        }
        dep
    }
}

/// What a distributed evaluation adds to the sweep (paper, Section 2.3): other ranks'
/// contributions to this rank's particles, and the values of the copies of other ranks'
/// particles, which change "when a particle changes its state". The single-process sweep
/// uses [`NoExchange`].
pub trait Exchange<const D: usize> {
    /// Whether slab `t` may finish stage `stage` now (its reals' sums are complete).
    fn may_finish(&self, t: usize, stage: u8) -> bool;
    /// Whether the copies of other ranks' particles in slab `t` hold their values after
    /// stage `stage` (so that the next sum may use them).
    fn copies_ready(&self, t: usize, stage: u8) -> bool;
    /// Sends what has become ready and takes in what has arrived, without waiting; true if
    /// that changed anything the sweep waits for.
    fn poll(&mut self, st: &mut SweepState<'_, D>) -> bool;
    /// Waits for the next message the sweep needs; called only when no local work is left.
    fn wait(&mut self, st: &mut SweepState<'_, D>);
}

/// The sweep's state as an [`Exchange`] sees it.
pub struct SweepState<'a, const D: usize> {
    pub local: &'a mut Local<D>,
    pub work: &'a mut [Work<D>],
    /// Sums finished per slab (the slab's particles' state).
    pub slab_stage: &'a [u8],
    /// Sums done per pair block.
    pub pair_stage: &'a [u8],
}

impl<const D: usize> SweepState<'_, D> {
    /// Whether every pair of slab `t`'s particles has had sum `k` (blocks `t` and `t + 1`).
    pub fn pairs_done(&self, t: usize, k: u8) -> bool {
        self.pair_stage[t] >= k && (t + 1 >= self.pair_stage.len() || self.pair_stage[t + 1] >= k)
    }
}

/// No other ranks.
pub struct NoExchange;

impl<const D: usize> Exchange<D> for NoExchange {
    fn may_finish(&self, _: usize, _: u8) -> bool {
        true
    }
    fn copies_ready(&self, _: usize, _: u8) -> bool {
        true
    }
    fn poll(&mut self, _: &mut SweepState<'_, D>) -> bool {
        false
    }
    fn wait(&mut self, _: &mut SweepState<'_, D>) {
        unreachable!("the single-process sweep never waits")
    }
}

/// Evaluates density, velocity gradient, accelerations and du/dt of every real particle by
/// one sweep, writing them into `parts`.
pub fn evaluate<const D: usize>(
    parts: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
    window: Window,
) -> SweepStats {
    let clock = Instant::now();
    let mut local = Local::build(parts, bx, phys.kernel.support());
    local.set_alpha_factors(&parts.alpha, &phys.av);
    let build = clock.elapsed().as_secs_f64();
    let (work, mut stats) = sweep(&mut local, phys, window, &mut NoExchange);
    stats.times.build += build;
    let c = Instant::now();
    write_back(parts, &local, work);
    stats.times.finish += c.elapsed().as_secs_f64();
    stats
}

/// The sweep over a built working set: the three sums slab by slab (module documentation),
/// with `ex` supplying what other ranks contribute. Returns the accumulators.
pub fn sweep<const D: usize>(
    local: &mut Local<D>,
    phys: &Physics<D>,
    window: Window,
    ex: &mut dyn Exchange<D>,
) -> (Vec<Work<D>>, SweepStats) {
    let clock = Instant::now();
    set_av_velocities(local, phys);
    let mut work = crate::memory::filled_vec(local.len(), Work::<D>::default());
    let deps = Dependencies::new(local);
    let ns = local.num_slabs();
    let mut blocks: Vec<Option<PairBlock>> = (0..ns).map(|_| None).collect();
    let mut pair_stage = vec![0u8; ns];
    let mut slab_stage = vec![0u8; ns];
    let mut stats = SweepStats {
        ghosts: local.num_ghosts(),
        slabs: ns,
        grid_cells: local.grid.num_cells_u64(),
        grid_index_bytes: local.cells.bytes(),
        ..Default::default()
    };
    let mut times = StageTimes {
        build: clock.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let lap = |t: &mut f64, since: Instant| *t += since.elapsed().as_secs_f64();
    let mut live_pairs = 0usize;
    // Block sums' parts waiting for the block before them (`PairBlock::scatter`).
    let mut held = pairs::Held::default();

    let pairs_done = |pair_stage: &[u8], s: usize, k: u8| {
        pair_stage[s] >= k && (s + 1 >= ns || pair_stage[s + 1] >= k)
    };

    // Slabs touched but not yet finished (small: the window, plus the first slabs of a
    // periodic x axis that wait for the last).
    let mut pending: Vec<usize> = Vec::new();
    // Slabs enter a batch at a time: one slab, or several of few particles together, so that
    // every thread has pairs to find and sum (`batch_end`). The blocks of a batch — and every
    // block ready for the same sum at once — are summed in parallel and merged in slab order
    // (`PairBlock::scatter`): the same result as one block after another.
    let mut s = 0;
    loop {
        if s < ns {
            let end = batch_end(local, s, window.batch_per_thread);
            let c = Instant::now();
            let found: Vec<PairBlock> = (s..end)
                .into_par_iter()
                .with_min_len(1)
                .map(|t| PairBlock::find(local, &phys.kernel, t))
                .collect();
            lap(&mut times.find_pairs, c);
            let c = Instant::now();
            let refs: Vec<&PairBlock> = found.iter().collect();
            PairBlock::density(
                &refs,
                local,
                phys.pressure_energy_gamma().is_some(),
                &mut work,
                (&pair_stage, &mut held),
            );
            lap(&mut times.density, c);
            for (t, block) in (s..end).zip(found) {
                stats.pairs += block.len() as u64;
                live_pairs += block.len();
                blocks[t] = Some(block);
                pair_stage[t] = DENSITY;
                pending.push(t);
            }
            stats.peak_pairs = stats.peak_pairs.max(live_pairs);
            s = end;
        } else {
            s = ns + 1;
        }
        // Advance every block and slab as far as the dependencies allow.
        loop {
            let mut progress = false;
            for &t in &pending {
                let next = slab_stage[t] + 1;
                if next > FORCE {
                    continue;
                }
                let ready = pairs_done(&pair_stage, t, next)
                    && deps.ghost_slabs[t]
                        .iter()
                        .all(|&g| pairs_done(&pair_stage, g, next))
                    && deps.owner_slabs[t].iter().all(|&o| slab_stage[o] >= next)
                    && ex.may_finish(t, next);
                if ready {
                    let c = Instant::now();
                    finish_slab(local, &mut work, &deps, phys, t, next);
                    lap(&mut times.finish, c);
                    slab_stage[t] = next;
                    progress = true;
                }
            }
            // The blocks ready for their next sum (it depends on the slabs' stages only, which
            // this pass does not change), by sum, in slab order (`pending` is ascending). A
            // block may become ready before the block before it (whose previous slab waits
            // for a wall's mirror images or, on a periodic x axis, for the last slab); the
            // sums still merge every particle's terms in slab order (`PairBlock::scatter`).
            let (mut for_gradient, mut for_force) = (Vec::new(), Vec::new());
            for &t in &pending {
                let next = pair_stage[t] + 1;
                if next > FORCE {
                    continue;
                }
                let ready = slab_stage[t] >= next - 1
                    && (t == 0 || slab_stage[t - 1] >= next - 1)
                    && ex.copies_ready(t, next - 1)
                    && (t == 0 || ex.copies_ready(t - 1, next - 1));
                if ready {
                    if next == GRADIENT {
                        for_gradient.push(t);
                    } else {
                        for_force.push(t);
                    }
                }
            }
            if !for_gradient.is_empty() {
                let refs: Vec<&PairBlock> = for_gradient
                    .iter()
                    .map(|&t| blocks[t].as_ref().expect("live block"))
                    .collect();
                let c = Instant::now();
                PairBlock::gradient(&refs, local, &mut work, (&pair_stage, &mut held));
                lap(&mut times.gradient, c);
                for &t in &for_gradient {
                    pair_stage[t] = GRADIENT;
                }
                progress = true;
            }
            if !for_force.is_empty() {
                let refs: Vec<&PairBlock> = for_force
                    .iter()
                    .map(|&t| blocks[t].as_ref().expect("live block"))
                    .collect();
                let c = Instant::now();
                PairBlock::force(&refs, local, phys, &mut work, (&pair_stage, &mut held));
                lap(&mut times.force, c);
                for &t in &for_force {
                    pair_stage[t] = FORCE;
                    if !window.full_list {
                        live_pairs -= blocks[t].as_ref().map_or(0, PairBlock::len);
                        blocks[t] = None;
                    }
                }
                progress = true;
            }
            let mut st = SweepState {
                local,
                work: &mut work,
                slab_stage: &slab_stage,
                pair_stage: &pair_stage,
            };
            if ex.poll(&mut st) {
                progress = true;
            }
            pending.retain(|&t| slab_stage[t] < FORCE || pair_stage[t] < FORCE);
            if !progress {
                // Nothing local left to do: wait for other ranks, or go on to the next slab.
                if s > ns && !pending.is_empty() {
                    let c = Instant::now();
                    ex.wait(&mut st);
                    lap(&mut times.wait, c);
                    continue;
                }
                break;
            }
        }
        if s > ns {
            break;
        }
    }
    assert!(
        slab_stage.iter().all(|&s| s == FORCE),
        "sweep left slabs unfinished: a dependency cycle"
    );
    assert!(held.is_empty(), "sweep left a block's sum unmerged");
    stats.peak_window_bytes = stats.peak_pairs * BYTES_PER_PAIR;
    stats.times = times;
    (work, stats)
}

/// Slabs enter the sweep together until they hold this many particles per thread (the
/// default of [`Window::batch_per_thread`], `[sweep] batch_per_thread`): a slab holding more
/// enters alone, so the window of a large run stays the paper's (a few slabs' pairs); slabs
/// of few particles — a CV disk of a few thousand, most slabs nearly empty — enter several at
/// a time, so that every thread has pairs to find and sum.
pub const BATCH_PARTICLES_PER_THREAD: usize = 1024;

/// The end of the batch of slabs entering the sweep from slab `s`, `per_thread` particles
/// for each of this pool's threads.
fn batch_end<const D: usize>(local: &Local<D>, s: usize, per_thread: usize) -> usize {
    let want = per_thread.saturating_mul(rayon::current_num_threads().max(1));
    batch_of(|t| local.slab_range(t).len(), local.num_slabs(), s, want)
}

/// The end of the batch from slab `s` of `ns` slabs holding `len(t)` particles each: slabs
/// are added until they hold `want` particles (at least one slab).
fn batch_of(len: impl Fn(usize) -> usize, ns: usize, s: usize, want: usize) -> usize {
    let (mut end, mut count) = (s, 0);
    while end < ns && (end == s || count < want) {
        count += len(end);
        end += 1;
    }
    end
}

/// A slab has finished stage `stage` for all its particles: fold the periodic ghosts' part
/// into their owners, complete the owners' quantities, and copy them to every ghost.
fn finish_slab<const D: usize>(
    local: &mut Local<D>,
    work: &mut [Work<D>],
    deps: &Dependencies,
    phys: &Physics<D>,
    t: usize,
    stage: u8,
) {
    let ghosts = &deps.ghosts_of[t];
    for &g in ghosts {
        let g = g as usize;
        if local.fold[g] {
            let o = local.owner[g] as usize;
            let (wg, s) = (work[g], local.sign[g]);
            let wo = &mut work[o];
            match stage {
                DENSITY => {
                    wo.rho += wg.rho;
                    wo.mu_w += wg.mu_w;
                    wo.interactions += wg.interactions;
                }
                GRADIENT => {
                    for a in 0..D {
                        for b in 0..D {
                            wo.grad[a][b] += s[a] * s[b] * wg.grad[a][b];
                        }
                    }
                }
                _ => {
                    for d in 0..D {
                        wo.acc[d] += s[d] * wg.acc[d];
                    }
                    wo.du += wg.du;
                    wo.diss += wg.diss;
                    wo.vsig = wo.vsig.max(wg.vsig);
                }
            }
        }
    }
    finish_reals(local, work, phys, local.slab_range(t), stage);
    for &g in ghosts {
        let g = g as usize;
        let o = local.owner[g] as usize;
        match stage {
            DENSITY => {
                local.rho[g] = local.rho[o];
                local.vol[g] = local.mass[g] / local.rho[g];
                local.rho_inv[g] = local.rho_inv[o];
                local.p[g] = local.p[o];
                local.cs[g] = local.cs[o];
            }
            GRADIENT => {
                let s = local.sign[g];
                let flip = |m: &[[f64; D]; D]| -> [[f64; D]; D] {
                    std::array::from_fn(|a| std::array::from_fn(|b| s[a] * s[b] * m[a][b]))
                };
                local.vgrad[g] = flip(&local.vgrad[o]);
                local.stress[g] = flip(&local.stress[o]);
                local.nu[g] = local.nu[o];
                local.av_scale[g] = local.av_scale[o];
            }
            _ => {}
        }
    }
}

/// Completes the quantities of stage `stage` of the reals in `range` (in parallel: each
/// particle reads only its own sums and state).
fn finish_reals<const D: usize>(
    local: &mut Local<D>,
    work: &[Work<D>],
    phys: &Physics<D>,
    range: std::ops::Range<usize>,
    stage: u8,
) {
    const GRAIN: usize = 512;
    let (start, end) = (range.start, range.end);
    let is_ghost = &local.is_ghost[start..end];
    let pos = &local.pos;
    let radius = |k: usize| cylindrical_radius::<D>(&std::array::from_fn(|d| pos[d][k]));
    let work = &work[start..end];
    match stage {
        DENSITY => {
            let w0 = phys.kernel.w0();
            let (mass, u) = (&local.mass[start..end], &local.u[start..end]);
            local.rho[start..end]
                .par_iter_mut()
                .zip(local.vol[start..end].par_iter_mut())
                .zip(local.rho_inv[start..end].par_iter_mut())
                .zip(local.p[start..end].par_iter_mut())
                .zip(local.cs[start..end].par_iter_mut())
                .enumerate()
                .with_min_len(GRAIN)
                .for_each(|(o, ((((rho_k, vol_k), inv_k), p_k), cs_k))| {
                    if is_ghost[o] {
                        return;
                    }
                    let rho = work[o].rho + mass[o] * w0;
                    let (p, cs) = match phys.pressure_energy_gamma() {
                        Some(gamma) => {
                            smoothed_pressure(gamma, work[o].mu_w, mass[o], u[o], w0, rho)
                        }
                        None => {
                            // Only the locally isothermal gas needs the radius (a `hypot`).
                            let r = if phys.eos.needs_radius() {
                                radius(start + o)
                            } else {
                                0.0
                            };
                            phys.eos.pressure_sound_speed(rho, u[o], r)
                        }
                    };
                    (*rho_k, *p_k, *cs_k) = (rho, p, cs);
                    (*vol_k, *inv_k) = (mass[o] / rho, 1.0 / rho);
                });
        }
        GRADIENT => {
            let h = phys.kernel.h();
            let cs = &local.cs[start..end];
            local.vgrad[start..end]
                .par_iter_mut()
                .zip(local.av_scale[start..end].par_iter_mut())
                .zip(local.nu[start..end].par_iter_mut())
                .zip(local.stress[start..end].par_iter_mut())
                .enumerate()
                .with_min_len(GRAIN)
                .for_each(|(o, (((vgrad, av_scale), nu_k), stress))| {
                    if is_ghost[o] {
                        return;
                    }
                    *vgrad = work[o].grad;
                    if phys.av.balsara {
                        *av_scale *= balsara_factor(vgrad, cs[o], h);
                    }
                    if phys.viscous() {
                        let nu = phys.nu(cs[o], radius(start + o));
                        *nu_k = nu;
                        *stress = phys.viscosity.stress(vgrad, nu);
                    }
                });
        }
        _ => {}
    }
}

/// With `artificial_viscosity.orbital`, every element's velocity relative to its circular
/// orbit, once per evaluation (positions and velocities are fixed during it, copies
/// included), rather than twice per pair.
fn set_av_velocities<const D: usize>(local: &mut Local<D>, phys: &Physics<D>) {
    local.v_av.clear();
    if phys.av.orbital && phys.gravity.is_some() {
        let v_av: Vec<[f64; D]> = (0..local.len())
            .into_par_iter()
            .map(|k| {
                av_velocity(
                    &phys.av,
                    phys.gravity.as_ref(),
                    &local.position(k),
                    local.velocity(k),
                )
            })
            .collect();
        local.v_av = v_av;
    }
}

/// Copies the finished quantities of this rank's reals from the working set into `parts`, in
/// parallel over blocks of the store: each task writes one block of every array, reading
/// each particle's working-set record once. The accumulators then go to `memory`'s pool
/// for the next evaluation.
pub fn write_back<const D: usize>(parts: &mut Particles<D>, local: &Local<D>, work: Vec<Work<D>>) {
    const BLOCK: usize = 4096;
    let at = &local.real_at;
    debug_assert_eq!(at.len(), parts.len());
    // The store's f64 arrays, in this order: rho, p, cs, du, diss, vsig, nu, acc[a],
    // vgrad[a][b]; cut into blocks, one row of blocks per task.
    let mut columns: Vec<std::slice::ChunksMut<'_, f64>> = vec![
        parts.rho.chunks_mut(BLOCK),
        parts.p.chunks_mut(BLOCK),
        parts.cs.chunks_mut(BLOCK),
        parts.du.chunks_mut(BLOCK),
        parts.diss.chunks_mut(BLOCK),
        parts.vsig.chunks_mut(BLOCK),
        parts.nu.chunks_mut(BLOCK),
    ];
    columns.extend(parts.acc.iter_mut().map(|v| v.chunks_mut(BLOCK)));
    columns.extend(
        parts
            .vgrad
            .iter_mut()
            .flatten()
            .map(|v| v.chunks_mut(BLOCK)),
    );
    let mut rows: Vec<(Vec<&mut [f64]>, &mut [u32])> = Vec::new();
    for inter in parts.interactions.chunks_mut(BLOCK) {
        let row = columns.iter_mut().map(|c| c.next().expect("equal lengths"));
        rows.push((row.collect(), inter));
    }
    rows.into_par_iter()
        .enumerate()
        .for_each(|(t, (mut row, inter))| {
            for o in 0..inter.len() {
                let k = at[t * BLOCK + o] as usize;
                let w = &work[k];
                let cs = local.cs[k];
                let scalars = [
                    local.rho[k],
                    local.p[k],
                    cs,
                    w.du,
                    w.diss,
                    w.vsig.max(2.0 * cs),
                    local.nu[k],
                ];
                for (c, x) in scalars.into_iter().enumerate() {
                    row[c][o] = x;
                }
                let g = &local.vgrad[k];
                for a in 0..D {
                    row[7 + a][o] = w.acc[a];
                    for b in 0..D {
                        row[7 + D + a * D + b][o] = g[a][b];
                    }
                }
                inter[o] = w.interactions;
            }
        });
    crate::memory::keep_vec(work);
}

/// Every pair the sweep's blocks find, as (i, j) local indices, slab by slab (for tests and
/// diagnostics; the sweep itself never holds them all).
pub fn all_pairs<const D: usize>(local: &Local<D>, kernel: &Kernel<D>) -> Vec<(u32, u32)> {
    (0..local.num_slabs())
        .flat_map(|s| {
            PairBlock::find(local, kernel, s)
                .pairs()
                .map(|p| (p.i, p.j))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small slabs enter together until they hold the batch's particles; a slab holding as
    /// many alone enters alone; the last batch ends at the last slab.
    #[test]
    fn small_slabs_enter_together_and_large_ones_alone() {
        let sizes = [100, 100, 3000, 50, 50, 50, 600, 700];
        let len = |t: usize| sizes[t];
        let ns = sizes.len();
        let mut ends = Vec::new();
        let mut s = 0;
        while s < ns {
            s = batch_of(len, ns, s, 512);
            ends.push(s);
        }
        // 100 + 100 < 512 takes the 3000 too; 50 × 3 < 512 takes the 600; 700 alone.
        assert_eq!(ends, [3, 7, 8]);
        assert_eq!(batch_of(len, ns, 2, 512), 3);
        assert_eq!(batch_of(len, ns, 7, 1), 8);
    }
}
