//! One distributed right-hand-side evaluation (paper, Section 2.3), and moving particles to
//! their new owners between steps.
//!
//! **Who evaluates a pair.** Every particle and every boundary image (periodic, mirror) is
//! *located* in the region containing its position ([`Decomposition::owner`], clamped at the
//! box faces). A pair is evaluated by the lower of its partners' location ranks, so each pair
//! of the single-process sweep is evaluated exactly once. Rank r therefore receives, as
//! ghosts, copies of the particles and images located in higher regions that lie closer than
//! the kernel support to r's region (extended to infinity at the box faces, where images
//! lie); they carry the pair class `AWAY` and pair only with particles located on r
//! (`sweep::local::class`). Ghosts of one rank on another are on one side only, as the
//! periodic ghosts of Section 2.2.
//!
//! **What travels, and when.** At the start of an evaluation the owners send the copies
//! (position, velocity, mass, u). Then, stage by stage, "when a particle changes its state":
//! * a rank that has summed stage k over every pair of its copies sends their partial sums
//!   back to the owners (non-blocking), who add them in (with the image's sign flips; mirror
//!   images' sums are dropped, as in a single process);
//! * an owner whose particles have finished stage k (density and pressure; velocity gradient,
//!   viscous stress) sends those values to every rank holding a copy.
//!
//! The sweep goes on with every slab that needs no message meanwhile, so communication
//! overlaps computation; it waits only when no local work is left, and the time it waits is
//! measured per rank.

use std::time::Instant;

use super::comm::{Comm, tag};
use super::decomposition::{Decomposition, coords};
use super::ghosts::{cuboid_distance2, point_cuboid_distance2};
use crate::boundary::{BoundaryKind, SimBox};
use crate::grid::Grid;
use crate::particles::Particles;
use crate::sweep::local::{Elements, Local, REMOTE, class};
use crate::sweep::{
    DENSITY, Exchange, FORCE, GRADIENT, Physics, SweepState, SweepStats, Window, sweep, write_back,
};

/// Figures of one distributed evaluation on one rank.
#[derive(Clone, Copy, Debug, Default)]
pub struct ExchangeStats {
    pub sweep: SweepStats,
    /// Copies this rank sent to other ranks and received from them.
    pub copies_sent: usize,
    pub copies_received: usize,
    /// f64 values sent, all messages of the evaluation.
    pub values_sent: usize,
    pub messages_sent: usize,
    /// Seconds spent waiting for messages (inside the sweep and for the copies).
    pub wait: f64,
    /// Seconds of the whole evaluation.
    pub total: f64,
}

/// The cuboid of `rank`, extended to infinity where it touches the box faces (boundary
/// images outside the box are located in the adjacent region).
fn extended_region(decomp: &Decomposition, rank: usize) -> Cuboid {
    let (mut lo, mut hi) = decomp.region(rank);
    let (blo, bhi) = (decomp.lo(), decomp.hi());
    for d in 0..decomp.dim() {
        if lo[d] <= blo[d] {
            lo[d] = f64::NEG_INFINITY;
        }
        if hi[d] >= bhi[d] {
            hi[d] = f64::INFINITY;
        }
    }
    (lo, hi)
}

/// A cuboid (lo, hi).
type Cuboid = ([f64; 3], [f64; 3]);

fn point<const D: usize>(pos: &[Vec<f64>; D], i: usize) -> [f64; 3] {
    let mut x = [0.0; 3];
    for d in 0..D {
        x[d] = pos[d][i];
    }
    x
}

/// Per rank s, the lower ranks q < s whose extended regions lie closer than `support` to
/// s's: the only ranks that can need a copy of something located in s.
fn lower_neighbours(decomp: &Decomposition, support: f64) -> Vec<Vec<(usize, Cuboid)>> {
    let n = decomp.n_regions();
    let ext: Vec<_> = (0..n).map(|r| extended_region(decomp, r)).collect();
    let s2 = support * support;
    let dim = decomp.dim();
    (0..n)
        .map(|s| {
            (0..s)
                .filter(|&q| cuboid_distance2(ext[q], ext[s], dim) < s2)
                .map(|q| (q, ext[q]))
                .collect()
        })
        .collect()
}

/// Values per copy in the message that creates it: src, flags, sign, pos, vel, mass, u.
const fn copy_len(d: usize) -> usize {
    2 + 3 * d + 2
}

/// Values per particle of partial sums (stage 1, 2, 3) and finals (stage 1, 2).
const fn partial_len(d: usize, stage: u8) -> usize {
    match stage {
        DENSITY => 3,
        GRADIENT => d * d,
        _ => d + 3,
    }
}

const fn final_len(d: usize, stage: u8) -> usize {
    match stage {
        DENSITY => 3,
        _ => 2 * d * d + 2,
    }
}

/// The messages of one evaluation, as the sweep's [`Exchange`].
struct RankExchange<'c, const D: usize> {
    comm: &'c mut dyn Comm,
    /// Per peer: local indices of this rank's reals it holds copies of (in message order),
    /// their sign and whether their sums come back.
    sent: Vec<Vec<(u32, [f64; D], bool)>>,
    /// Per peer: local indices of the copies received from it, in message order.
    held: Vec<Vec<u32>>,
    export_slab: Vec<bool>,
    import_slab: Vec<bool>,
    export_slabs: Vec<usize>,
    import_slabs: Vec<usize>,
    partials_sent: [bool; 4],
    finals_sent: [bool; 4],
    /// Per stage, per peer: received.
    partials_in: [Vec<bool>; 4],
    finals_in: [Vec<bool>; 4],
    values_sent: usize,
    messages_sent: usize,
}

impl<const D: usize> RankExchange<'_, D> {
    fn all_partials_in(&self, k: u8) -> bool {
        self.partials_in[k as usize].iter().all(|&b| b)
    }

    fn all_finals_in(&self, k: u8) -> bool {
        self.finals_in[k as usize].iter().all(|&b| b)
    }

    fn send(&mut self, dest: usize, tag: u16, data: Vec<f64>) {
        self.values_sent += data.len();
        self.messages_sent += 1;
        self.comm.send(dest, tag, data);
    }

    fn send_partials(&mut self, st: &SweepState<'_, D>, k: u8) {
        for q in 0..self.held.len() {
            if self.held[q].is_empty() {
                continue;
            }
            let mut buf = Vec::with_capacity(self.held[q].len() * partial_len(D, k));
            for &l in &self.held[q] {
                let w = &st.work[l as usize];
                match k {
                    DENSITY => buf.extend([w.rho, w.interactions as f64, w.mu_w]),
                    GRADIENT => buf.extend(w.grad.iter().flatten()),
                    _ => {
                        buf.extend(w.acc);
                        buf.extend([w.du, w.diss, w.vsig]);
                    }
                }
            }
            self.send(q, tag::PARTIALS + k as u16, buf);
        }
        self.partials_sent[k as usize] = true;
    }

    fn take_partials(&mut self, st: &mut SweepState<'_, D>, q: usize, k: u8, buf: &[f64]) {
        let len = partial_len(D, k);
        assert_eq!(
            buf.len(),
            self.sent[q].len() * len,
            "partial sums from rank {q}"
        );
        for (n, &(o, s, back)) in self.sent[q].iter().enumerate() {
            if !back {
                continue;
            }
            let x = &buf[n * len..(n + 1) * len];
            let w = &mut st.work[o as usize];
            match k {
                DENSITY => {
                    w.rho += x[0];
                    w.interactions += x[1] as u32;
                    w.mu_w += x[2];
                }
                GRADIENT => {
                    for a in 0..D {
                        for b in 0..D {
                            w.grad[a][b] += s[a] * s[b] * x[a * D + b];
                        }
                    }
                }
                _ => {
                    for d in 0..D {
                        w.acc[d] += s[d] * x[d];
                    }
                    w.du += x[D];
                    w.diss += x[D + 1];
                    w.vsig = w.vsig.max(x[D + 2]);
                }
            }
        }
        self.partials_in[k as usize][q] = true;
    }

    fn send_finals(&mut self, st: &SweepState<'_, D>, k: u8) {
        for q in 0..self.sent.len() {
            if self.sent[q].is_empty() {
                continue;
            }
            let mut buf = Vec::with_capacity(self.sent[q].len() * final_len(D, k));
            let l = &*st.local;
            for &(o, _, _) in &self.sent[q] {
                let o = o as usize;
                if k == DENSITY {
                    buf.extend([l.rho[o], l.p[o], l.cs[o]]);
                } else {
                    buf.extend(l.vgrad[o].iter().flatten());
                    buf.extend(l.stress[o].iter().flatten());
                    buf.extend([l.nu[o], l.av_scale[o]]);
                }
            }
            self.send(q, tag::FINALS + k as u16, buf);
        }
        self.finals_sent[k as usize] = true;
    }

    fn take_finals(&mut self, st: &mut SweepState<'_, D>, q: usize, k: u8, buf: &[f64]) {
        let len = final_len(D, k);
        assert_eq!(
            buf.len(),
            self.held[q].len() * len,
            "final values from rank {q}"
        );
        let l = &mut *st.local;
        for (n, &c) in self.held[q].iter().enumerate() {
            let c = c as usize;
            let x = &buf[n * len..(n + 1) * len];
            if k == DENSITY {
                (l.rho[c], l.p[c], l.cs[c]) = (x[0], x[1], x[2]);
                (l.vol[c], l.rho_inv[c]) = (l.mass[c] / x[0], 1.0 / x[0]);
            } else {
                let s = l.sign[c];
                for a in 0..D {
                    for b in 0..D {
                        l.vgrad[c][a][b] = s[a] * s[b] * x[a * D + b];
                        l.stress[c][a][b] = s[a] * s[b] * x[D * D + a * D + b];
                    }
                }
                l.nu[c] = x[2 * D * D];
                l.av_scale[c] = x[2 * D * D + 1];
            }
        }
        self.finals_in[k as usize][q] = true;
    }

    /// The next message this rank still needs, in the order the stages need them:
    /// (stage, is_final, peer).
    fn next_needed(&self) -> Option<(u8, bool, usize)> {
        for k in [DENSITY, GRADIENT, FORCE] {
            if let Some(q) = self.partials_in[k as usize].iter().position(|&b| !b) {
                return Some((k, false, q));
            }
            if k != FORCE
                && let Some(q) = self.finals_in[k as usize].iter().position(|&b| !b)
            {
                return Some((k, true, q));
            }
        }
        None
    }

    fn receive(
        &mut self,
        st: &mut SweepState<'_, D>,
        k: u8,
        is_final: bool,
        q: usize,
        block: bool,
    ) -> bool {
        let t = if is_final { tag::FINALS } else { tag::PARTIALS } + k as u16;
        let msg = if block {
            Some(self.comm.recv(q, t))
        } else {
            self.comm.try_recv(q, t)
        };
        match msg {
            Some(buf) if is_final => {
                self.take_finals(st, q, k, &buf);
                true
            }
            Some(buf) => {
                self.take_partials(st, q, k, &buf);
                true
            }
            None => false,
        }
    }
}

impl<const D: usize> Exchange<D> for RankExchange<'_, D> {
    fn may_finish(&self, t: usize, k: u8) -> bool {
        !self.export_slab[t] || self.all_partials_in(k)
    }

    fn copies_ready(&self, t: usize, k: u8) -> bool {
        !self.import_slab[t] || k == 0 || k >= FORCE || self.all_finals_in(k)
    }

    fn poll(&mut self, st: &mut SweepState<'_, D>) -> bool {
        let mut changed = false;
        for k in [DENSITY, GRADIENT, FORCE] {
            if !self.partials_sent[k as usize]
                && self.import_slabs.iter().all(|&t| st.pairs_done(t, k))
            {
                self.send_partials(st, k);
            }
            if k != FORCE
                && !self.finals_sent[k as usize]
                && self.export_slabs.iter().all(|&t| st.slab_stage[t] >= k)
            {
                self.send_finals(st, k);
            }
        }
        for k in [DENSITY, GRADIENT, FORCE] {
            for q in 0..self.sent.len() {
                if !self.partials_in[k as usize][q] && self.receive(st, k, false, q, false) {
                    changed = true;
                }
            }
            if k != FORCE {
                for q in 0..self.held.len() {
                    if !self.finals_in[k as usize][q] && self.receive(st, k, true, q, false) {
                        changed = true;
                    }
                }
            }
        }
        changed
    }

    fn wait(&mut self, st: &mut SweepState<'_, D>) {
        match self.next_needed() {
            Some((k, is_final, q)) => {
                if std::env::var_os("SPHDISK_DEBUG_WAIT").is_some() {
                    // Diagnosing a stalled exchange: what this rank waits for, and why.
                    eprintln!(
                        "rank {} waits for {} of stage {k} from rank {q}; sent partials {:?}, \
                         finals {:?}; slab stages {:?}",
                        self.comm.rank(),
                        if is_final { "finals" } else { "partial sums" },
                        self.partials_sent,
                        self.finals_sent,
                        st.slab_stage
                    );
                }
                self.receive(st, k, is_final, q, true);
            }
            None => panic!("distributed sweep: slabs unfinished but no message outstanding"),
        }
    }
}

/// Evaluates the right-hand sides of this rank's particles `parts` (those it owns), with the
/// other ranks of `comm` doing theirs at the same time: copies exchanged, the sweep run with
/// messages at each change of state, the results written into `parts`. External gravity is
/// added by the caller.
pub fn evaluate<const D: usize>(
    comm: &mut dyn Comm,
    decomp: &Decomposition,
    parts: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
    window: Window,
) -> ExchangeStats {
    let clock = Instant::now();
    let me = comm.rank();
    let nr = comm.size();
    assert_eq!(decomp.n_regions(), nr, "one region per rank");
    let support = phys.kernel.support();
    let s2 = support * support;
    let lower = lower_neighbours(decomp, support);

    // This rank's reals and their boundary images; where each is located, who needs it.
    let mut elems = Elements::reals_and_images(parts, bx, support, |_| 0);
    let n_real = elems.n_real;
    let mut keep = vec![true; elems.len()];
    let mut outgoing: Vec<Vec<f64>> = vec![Vec::new(); nr];
    let mut sent_src: Vec<Vec<(u32, [f64; D], bool)>> = vec![Vec::new(); nr];
    for k in 0..elems.len() {
        let mine = &elems;
        let x = point(&mine.pos, k);
        let at = decomp.owner(x);
        let real = k < n_real;
        let image = if real { 0 } else { class::IMAGE };
        let mut here = at == me;
        let mut emit = |q: usize| {
            let out = &mut outgoing[q];
            out.push(mine.src[k] as f64);
            out.push(if real || mine.fold[k] { 1.0 } else { 0.0 } + if real { 0.0 } else { 2.0 });
            out.extend(mine.sign[k]);
            out.extend((0..D).map(|d| mine.pos[d][k]));
            out.extend((0..D).map(|d| mine.vel[d][k]));
            out.extend([mine.mass[k], mine.u[k]]);
            sent_src[q].push((mine.src[k], mine.sign[k], real || mine.fold[k]));
        };
        if at != me {
            emit(at);
        }
        for &(q, ref ext) in &lower[at] {
            if point_cuboid_distance2(x, *ext, decomp.dim()) < s2 {
                if q == me {
                    here = true;
                } else {
                    emit(q);
                }
            }
        }
        let cls = if at == me {
            image
        } else if at > me {
            image | class::AWAY
        } else {
            class::NO_PAIR
        };
        // Reals always stay (their sums are accumulated here); images only if needed here.
        keep[k] = real || here;
        elems.class[k] = cls;
    }
    elems.retain(&keep);
    let mut values_sent = 0;
    let mut messages_sent = 0;
    let copies_sent: usize = sent_src.iter().map(Vec::len).sum();
    for (q, out) in outgoing.into_iter().enumerate() {
        if q != me {
            values_sent += out.len();
            messages_sent += 1;
            comm.send(q, tag::ELEMENTS, out);
        }
    }
    let wait_clock = Instant::now();
    let mut held_elems: Vec<std::ops::Range<usize>> = vec![0..0; nr];
    let first_received = elems.len();
    let cl = copy_len(D);
    for q in 0..nr {
        if q == me {
            continue;
        }
        let buf = comm.recv(q, tag::ELEMENTS);
        let start = elems.len();
        for c in buf.chunks_exact(cl) {
            let flags = c[1] as u8;
            let sign: [f64; D] = std::array::from_fn(|d| c[2 + d]);
            let pos: [f64; D] = std::array::from_fn(|d| c[2 + D + d]);
            let vel: [f64; D] = std::array::from_fn(|d| c[2 + 2 * D + d]);
            let at = decomp.owner({
                let mut x = [0.0; 3];
                x[..D].copy_from_slice(&pos);
                x
            });
            let image = if flags & 2 != 0 { class::IMAGE } else { 0 };
            let cls = if at == me { image } else { image | class::AWAY };
            elems.push(
                pos,
                vel,
                c[2 + 3 * D],
                c[3 + 3 * D],
                sign,
                flags & 1 != 0,
                cls,
                REMOTE,
            );
        }
        held_elems[q] = start..elems.len();
    }
    let mut wait = wait_clock.elapsed().as_secs_f64();
    let copies_received = elems.len() - first_received;

    // Reals first, in store order, as `Local::from_elements` expects (reals always stay).
    debug_assert!(
        elems.src[..n_real]
            .iter()
            .enumerate()
            .all(|(i, &s)| s as usize == i)
    );
    let open = SimBox::<D> {
        min: [0.0; D],
        max: [1.0; D],
        kinds: [BoundaryKind::Open; D],
    };
    let grid = Grid::new(&open, support, &elems.pos);
    let mut local = Local::from_elements(elems, grid);
    local.set_alpha_factors(&parts.alpha, &phys.av);

    let mut local_of_elem = vec![0u32; local.len()];
    for (k, &e) in local.element.iter().enumerate() {
        local_of_elem[e as usize] = k as u32;
    }
    let local_of_real = &local.real_at;
    let ns = local.num_slabs();
    let mut export_slab = vec![false; ns];
    let mut import_slab = vec![false; ns];
    let sent: Vec<Vec<(u32, [f64; D], bool)>> = sent_src
        .into_iter()
        .map(|v| {
            v.into_iter()
                .map(|(s, sign, back)| {
                    let o = local_of_real[s as usize];
                    export_slab[local.slab_of(o as usize)] = true;
                    (o, sign, back)
                })
                .collect()
        })
        .collect();
    let held: Vec<Vec<u32>> = held_elems
        .iter()
        .map(|r| {
            r.clone()
                .map(|e| {
                    let k = local_of_elem[e];
                    import_slab[local.slab_of(k as usize)] = true;
                    k
                })
                .collect()
        })
        .collect();
    let pick = |f: &[bool]| (0..ns).filter(|&t| f[t]).collect::<Vec<_>>();
    let (export_slabs, import_slabs) = (pick(&export_slab), pick(&import_slab));
    let mut ex = RankExchange::<D> {
        partials_in: std::array::from_fn(|_| sent.iter().map(Vec::is_empty).collect()),
        finals_in: std::array::from_fn(|_| held.iter().map(Vec::is_empty).collect()),
        sent,
        held,
        export_slab,
        import_slab,
        export_slabs,
        import_slabs,
        partials_sent: [false; 4],
        finals_sent: [false; 4],
        values_sent,
        messages_sent,
        comm,
    };
    let (work, sweep_stats) = sweep(&mut local, phys, window, &mut ex);
    assert!(
        ex.partials_sent[FORCE as usize] && ex.next_needed().is_none(),
        "distributed sweep ended with messages outstanding"
    );
    wait += sweep_stats.times.wait;
    write_back(parts, &local, work);
    ExchangeStats {
        sweep: SweepStats {
            ghosts: local.num_ghosts(),
            ..sweep_stats
        },
        copies_sent,
        copies_received,
        values_sent: ex.values_sent,
        messages_sent: ex.messages_sent,
        wait,
        total: clock.elapsed().as_secs_f64(),
    }
}

/// Moves every particle of `parts` whose position lies in another rank's region to that
/// rank, with all its state (so that the next kick and time step are the same as if it had
/// stayed). Returns how many particles this rank sent away.
pub fn migrate<const D: usize>(
    comm: &mut dyn Comm,
    decomp: &Decomposition,
    parts: &mut Particles<D>,
) -> usize {
    let me = comm.rank();
    let nr = comm.size();
    let owners = decomp.owners(&coords(parts));
    let keep: Vec<bool> = owners.iter().map(|&o| o == me).collect();
    let mut out: Vec<Vec<f64>> = vec![Vec::new(); nr];
    for (i, &o) in owners.iter().enumerate() {
        if o != me {
            parts.state_of(i, &mut out[o]);
        }
    }
    let moved = keep.iter().filter(|&&k| !k).count();
    for (q, m) in out.into_iter().enumerate() {
        if q != me {
            comm.send(q, tag::MIGRATE, m);
        }
    }
    if moved > 0 {
        parts.retain(&keep);
    }
    for q in 0..nr {
        if q != me {
            let buf = comm.recv(q, tag::MIGRATE);
            parts.push_states(&buf);
        }
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::comm::ThreadComm;
    use crate::kernel::Kernel;
    use crate::physics::artificial_viscosity::ArtificialViscosity;
    use crate::physics::eos::Eos;
    use crate::physics::pressure_energy::Scheme;
    use crate::physics::viscosity::ViscosityModel;
    use crate::rng::Rng;

    /// A jittered lattice of `n` per axis in `bx` with random velocities and energies.
    fn lattice<const D: usize>(bx: &SimBox<D>, n: usize, seed: u64) -> Particles<D> {
        let mut rng = Rng::new(seed);
        let mut p = Particles::new();
        let total = n.pow(D as u32);
        for k in 0..total {
            let mut c = k;
            let pos: [f64; D] = std::array::from_fn(|d| {
                let i = c % n;
                c /= n;
                let dx = bx.length(d) / n as f64;
                bx.min[d] + (i as f64 + 0.5 + 0.3 * (rng.uniform() - 0.5)) * dx
            });
            let vel: [f64; D] = std::array::from_fn(|_| rng.normal() * 0.3);
            p.push(
                k as u64,
                pos,
                vel,
                1.0 + 0.5 * rng.uniform(),
                1.0 + rng.uniform(),
            );
            // Each particle's own α for the switch (another rank's reach it with the
            // gradient stage's exchange).
            p.alpha[k] = 0.1 + 0.9 * rng.uniform();
        }
        p
    }

    /// The state after one evaluation on `n` ranks (in-process), by particle id.
    fn distributed<const D: usize>(
        p: &Particles<D>,
        bx: &SimBox<D>,
        phys: &Physics<D>,
        n: usize,
    ) -> Vec<Particles<D>> {
        let decomp = Decomposition::for_particles(n, bx, p, &[]);
        ThreadComm::run(n, |c| {
            let owners: Vec<bool> = (0..p.len())
                .map(|i| decomp.owner(point(&p.pos, i)) == c.rank())
                .collect();
            let mut mine = p.clone();
            mine.retain(&owners);
            evaluate(c, &decomp, &mut mine, bx, phys, Window::SWEEP);
            mine
        })
    }

    /// Compares every rank's results with the single-process sweep's, by id. Each quantity
    /// is compared relative to its rms over all particles: the sums are the same pairs
    /// added in another order, so the difference is round-off (≈1e-16 per term times the
    /// ~10–100 terms), far below the 1e-12 bar of issue 4.
    fn assert_same<const D: usize>(solo: &Particles<D>, ranks: &[Particles<D>]) {
        let n: usize = ranks.iter().map(Particles::len).sum();
        assert_eq!(n, solo.len(), "every particle on exactly one rank");
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
        let mut fields: Vec<(String, Vec<f64>, f64)> = Vec::new();
        let mut add = |name: &str, v: &Vec<f64>| fields.push((name.to_string(), v.clone(), rms(v)));
        add("rho", &solo.rho);
        add("p", &solo.p);
        add("du", &solo.du);
        add("diss", &solo.diss);
        add("vsig", &solo.vsig);
        for d in 0..D {
            add(&format!("acc{d}"), &solo.acc[d]);
            for b in 0..D {
                add(&format!("vgrad{d}{b}"), &solo.vgrad[d][b]);
            }
        }
        let index: std::collections::HashMap<u64, usize> =
            solo.id.iter().enumerate().map(|(i, &id)| (id, i)).collect();
        for r in ranks {
            for i in 0..r.len() {
                let j = index[&r.id[i]];
                assert_eq!(
                    r.interactions[i], solo.interactions[j],
                    "interactions of {}",
                    r.id[i]
                );
                let mine: Vec<f64> = {
                    let mut v = vec![r.rho[i], r.p[i], r.du[i], r.diss[i], r.vsig[i]];
                    for d in 0..D {
                        v.push(r.acc[d][i]);
                        for b in 0..D {
                            v.push(r.vgrad[d][b][i]);
                        }
                    }
                    v
                };
                for ((name, v, scale), x) in fields.iter().zip(mine) {
                    assert!(
                        (x - v[j]).abs() <= 1e-12 * scale.max(1e-300),
                        "{name} of particle {}: {x} vs {} (rms {scale})",
                        r.id[i],
                        v[j]
                    );
                }
            }
        }
    }

    fn physics<const D: usize>(h: f64) -> Physics<D> {
        Physics {
            kernel: Kernel::new(h),
            eos: Eos::Ideal { gamma: 5.0 / 3.0 },
            av: ArtificialViscosity {
                alpha: 1.0,
                beta: 2.0,
                balsara: true,
                switch: crate::physics::av_switch::SwitchKind::MorrisMonaghan,
                ..ArtificialViscosity::default()
            },
            viscosity: ViscosityModel {
                nu: Some(0.01),
                alpha: None,
                bulk: 0.5,
            },
            gravity: None,
            binary: None,
            cooling: None,
            outbursts: None,
            scheme: Scheme::DensityEnergy,
        }
    }

    fn check<const D: usize>(bx: SimBox<D>, n: usize, h: f64, ranks: &[usize]) {
        check_with(bx, n, h, ranks, Scheme::DensityEnergy);
    }

    fn check_with<const D: usize>(
        bx: SimBox<D>,
        n: usize,
        h: f64,
        ranks: &[usize],
        scheme: Scheme,
    ) {
        let p = lattice(&bx, n, 7);
        let phys = Physics {
            scheme,
            ..physics::<D>(h)
        };
        let mut solo = p.clone();
        crate::sweep::evaluate(&mut solo, &bx, &phys, Window::SWEEP);
        for &nr in ranks {
            assert_same(&solo, &distributed(&p, &bx, &phys, nr));
        }
    }

    #[test]
    fn ranks_reproduce_the_single_process_sums_in_1d_with_walls() {
        let bx = SimBox {
            min: [0.0],
            max: [1.0],
            kinds: [BoundaryKind::Reflecting],
        };
        check(bx, 200, 0.012, &[1, 2, 3, 4, 7]);
    }

    #[test]
    fn ranks_reproduce_the_single_process_sums_in_a_periodic_2d_box() {
        let bx = SimBox {
            min: [0.0, -0.5],
            max: [1.0, 0.5],
            kinds: [BoundaryKind::Periodic; 2],
        };
        check(bx, 40, 0.04, &[1, 2, 3, 4, 5]);
    }

    #[test]
    fn ranks_reproduce_the_single_process_pressure_energy_sums() {
        // p̄ adds Σ m u W to the density stage's partial sums sent between ranks.
        let bx = SimBox {
            min: [0.0, -0.5],
            max: [1.0, 0.5],
            kinds: [BoundaryKind::Periodic, BoundaryKind::Reflecting],
        };
        check_with(bx, 40, 0.04, &[1, 2, 3, 4], Scheme::PressureEnergy);
    }

    #[test]
    fn ranks_reproduce_the_single_process_sums_with_mixed_walls_in_2d() {
        let bx = SimBox {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
            kinds: [BoundaryKind::Reflecting, BoundaryKind::Periodic],
        };
        check(bx, 36, 0.04, &[2, 3, 4]);
    }

    #[test]
    fn ranks_reproduce_the_single_process_sums_in_3d() {
        let bx = SimBox {
            min: [0.0; 3],
            max: [1.0; 3],
            kinds: [
                BoundaryKind::Periodic,
                BoundaryKind::Reflecting,
                BoundaryKind::Open,
            ],
        };
        check(bx, 14, 0.09, &[2, 3, 4]);
    }

    #[test]
    fn migration_moves_every_particle_to_the_region_holding_it_with_its_state() {
        let out = ThreadComm::run(3, |c| {
            let decomp = Decomposition::new(
                &crate::domain::TreeShape::uniform([3, 1, 1]),
                1,
                [0.0; 3],
                [3.0, 0.0, 0.0],
            );
            let mut p = Particles::<1>::new();
            // Every rank starts with one particle in each region.
            for k in 0..3 {
                let id = (c.rank() * 3 + k) as u64;
                p.push(id, [k as f64 + 0.5], [id as f64], 1.0, 0.1 * id as f64);
                let i = p.len() - 1;
                p.rho[i] = 10.0 + id as f64;
                p.interactions[i] = id as u32;
            }
            migrate(c, &decomp, &mut p);
            p
        });
        for (r, p) in out.iter().enumerate() {
            assert_eq!(p.len(), 3);
            for i in 0..3 {
                let id = p.id[i];
                assert!((p.pos[0][i] - (r as f64 + 0.5)).abs() < 1e-15);
                assert_eq!(p.vel[0][i], id as f64);
                assert_eq!(p.rho[i], 10.0 + id as f64);
                assert_eq!(p.interactions[i], id as u32);
                assert_eq!(p.u[i], 0.1 * id as f64);
            }
        }
    }
}
