//! What one pair costs in each loop of the sweep, counted from the code of
//! [`PairBlock`](crate::sweep::pairs::PairBlock) and [`force_pair`](crate::physics::hydro::force_pair):
//! floating-point operations, and bytes loaded or stored by the pair loop. `sphdisk bench`
//! reports these beside its timings, and BENCHMARKS.md's roofline estimate divides them.
//!
//! **Flops:** each +, −, ×, ÷, √, min and max on per-pair data counts one, as the source
//! writes it (a product computed once and reused counts once); negations, comparisons and
//! operations on constants alone (−α, max(β, 1)) count none. Where a branch decides, the
//! count is weighted: 1/2 of pairs approach (the artificial viscosity's Π ≠ 0), and 1/2^D of
//! pairs lie within q < 1 of the cubic spline (uniform particles within the support 2h).
//!
//! **Bytes:** what the pair loop loads or stores, wherever it comes from (registers aside):
//! the [`Pair`] record; each partner's fields the sum reads; the two accumulators it
//! updates (read and written: 2 × their size per side). Pair finding: per candidate tested,
//! its position and pair class; per pair found, the record stored, then copied once into
//! the block (read and write). Sizes are taken from the types themselves, so the counts
//! follow any change of them. Not counted: per-particle work (zeroing and merging the
//! per-task buffers, the finishing of slabs), and the growth of the per-task pair vectors.

use std::mem::size_of;

use crate::sweep::local::Local;
use crate::sweep::pairs::{ForceSum, Pair};

/// Fraction of pairs that approach (Π_ij ≠ 0).
pub const APPROACHING: f64 = 0.5;

/// Operations and bytes of one pair in one loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PairCost {
    pub flops: f64,
    pub bytes: f64,
}

impl PairCost {
    /// Flops per byte.
    pub fn intensity(&self) -> f64 {
        self.flops / self.bytes
    }

    /// Pairs per second this loop could reach at `flop_rate` flops/s and `bandwidth` bytes/s
    /// (the roofline: the lower of the two bounds).
    pub fn bound(&self, flop_rate: f64, bandwidth: f64) -> f64 {
        (flop_rate / self.flops).min(bandwidth / self.bytes)
    }
}

impl std::ops::Add for PairCost {
    type Output = PairCost;
    fn add(self, o: PairCost) -> PairCost {
        PairCost {
            flops: self.flops + o.flops,
            bytes: self.bytes + o.bytes,
        }
    }
}

/// The physics that changes what the force loop reads and computes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Setting {
    /// Physical viscosity (Eq. 8): both partners' stress read, the viscous terms computed.
    pub viscous: bool,
    /// The artificial viscosity measures velocities relative to circular orbits: `v_av` read.
    pub orbital: bool,
    /// Artificial conductivity on: u read, the conducted heat computed.
    pub conductivity: bool,
    /// Candidates tested by pair finding per pair found ([`crate::sweep::pairs::candidates`]).
    pub candidates_per_pair: f64,
}

impl Setting {
    /// What `phys` switches on, as the sweep reads it.
    pub fn of<const D: usize>(phys: &crate::sweep::Physics<D>, candidates_per_pair: f64) -> Self {
        Self {
            viscous: phys.viscous(),
            orbital: phys.av.orbital && phys.gravity.is_some(),
            conductivity: phys.av.conductivity > 0.0,
            candidates_per_pair,
        }
    }
}

/// Per-pair costs of pair finding and the three sums.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SweepCost {
    /// Distance tests of the candidates, the kernel (cubic spline), storing the pair.
    pub find: PairCost,
    pub density: PairCost,
    pub gradient: PairCost,
    pub force: PairCost,
}

impl SweepCost {
    pub fn total(&self) -> PairCost {
        self.find + self.density + self.gradient + self.force
    }
}

/// Size of one element of a [`Local`] field, read from the field's type.
fn field<const D: usize, T>(_: impl Fn(&Local<D>) -> &Vec<T>) -> usize {
    size_of::<T>()
}

/// Bytes of one partner's position (D coordinates).
fn position<const D: usize>() -> usize {
    D * field::<D, _>(|l| &l.pos[0])
}

/// Bytes of one partner's velocity.
fn velocity<const D: usize>() -> usize {
    D * field::<D, _>(|l| &l.vel[0])
}

/// Pair finding, per pair found: the distance tests of `candidates_per_pair` candidates,
/// √r², the cubic spline's W and F, the record stored and copied into the block.
pub fn find<const D: usize>(candidates_per_pair: f64) -> PairCost {
    // r² = Σ (x_i − x_j)²: D subtractions, D products, D sums (from 0.0).
    let candidate_flops = 3.0 * D as f64;
    let candidate_bytes = position::<D>() + field::<D, _>(|l| &l.class);
    let inner = 0.5f64.powi(D as i32);
    // q < 1: 1 − 1.5 q² + 0.75 q³ (5 ×, 2 ±) and −3 + 2.25 q (1 ×, 1 +);
    // 1 ≤ q < 2: t = 2 − q, 0.25 t³ (1 −, 3 ×) and −0.75 t²/q (2 ×, 1 ÷).
    let shape = inner * 9.0 + (1.0 - inner) * 7.0;
    // √r², q = r/unit, the two normalisations.
    let pair_flops = 4.0 + shape;
    let pair_bytes = 3 * size_of::<Pair>();
    PairCost {
        flops: candidates_per_pair * candidate_flops + pair_flops,
        bytes: candidates_per_pair * candidate_bytes as f64 + pair_bytes as f64,
    }
}

/// Density, Eq. (5): m_j W and m_i W, added with a count to each partner.
pub fn density<const D: usize>() -> PairCost {
    let reads = 2 * field::<D, _>(|l| &l.mass);
    let acc = 2 * 2 * size_of::<(f64, u32)>();
    PairCost {
        flops: 4.0,
        bytes: (size_of::<Pair>() + reads + acc) as f64,
    }
}

/// Velocity gradient, Eq. (10).
pub fn gradient<const D: usize>() -> PairCost {
    let d = D as f64;
    // dx (D), v_j − v_i (D), (v_j − v_i) f (D), × dx (D²), m/ρ for both (2 ÷), scaled for
    // both (2D²), added to both (2D²).
    let flops = 3.0 * d + 5.0 * d * d + 2.0;
    let side =
        position::<D>() + velocity::<D>() + field::<D, _>(|l| &l.mass) + field::<D, _>(|l| &l.rho);
    let acc = 2 * 2 * size_of::<[[f64; D]; D]>();
    PairCost {
        flops,
        bytes: (size_of::<Pair>() + 2 * side + acc) as f64,
    }
}

/// Forces and du/dt: Eq. (7), Monaghan's Π, optionally the conductivity and Eq. (8).
pub fn force<const D: usize>(s: &Setting) -> PairCost {
    let d = D as f64;
    // dx (D); v_ij·dx (3D); (p_i + p_j)/(ρ_i ρ_j) (3); v_av,ij·dx (3D); the mean α factor
    // (2); Π: w = v·r/r, min(w, 0), v_sig (5), for approaching pairs v_sig,AV and Π (7);
    // coef (2); gv (2); the AV heat (3); accel (D); work_i, work_j (2).
    let mut flops = 8.0 * d + 14.0 + 5.0 + APPROACHING * 7.0;
    // Times the partners' masses (2D + 6) and added to both (2D + 6: acc, du, diss, max v_sig).
    flops += 4.0 * d + 12.0;
    let mut side = position::<D>()
        + velocity::<D>()
        + field::<D, _>(|l| &l.mass)
        + field::<D, _>(|l| &l.rho)
        + field::<D, _>(|l| &l.p)
        + field::<D, _>(|l| &l.cs)
        + field::<D, _>(|l| &l.av_scale);
    if s.orbital {
        side += field::<D, _>(|l| &l.v_av);
    }
    if s.conductivity {
        // ρ̄ (2), v_sig,u (3), the conducted heat (6), added to work_i and work_j (2).
        flops += 13.0;
        side += field::<D, _>(|l| &l.u);
    }
    if s.viscous {
        // g = f dx (D), 1/ρ both (2), v_ij (D); per (a, b): (S_j/ρ_i + S_i/ρ_j) g_b summed (5),
        // S_i v g and S_j v g summed (6); accel (D); both heats (4).
        flops += 3.0 * d + 6.0 + 11.0 * d * d;
        side += field::<D, _>(|l| &l.stress);
    }
    let acc = 2 * 2 * size_of::<ForceSum<D>>();
    PairCost {
        flops,
        bytes: (size_of::<Pair>() + 2 * side + acc) as f64,
    }
}

/// All four loops for `setting`.
pub fn sweep_cost<const D: usize>(setting: &Setting) -> SweepCost {
    SweepCost {
        find: find::<D>(setting.candidates_per_pair),
        density: density::<D>(),
        gradient: gradient::<D>(),
        force: force::<D>(setting),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::pairs::BYTES_PER_PAIR;

    /// The byte counts are the sizes of the records and fields they name: a change of any
    /// of them (a pair record of f32, a packed accumulator) must show here and in
    /// BENCHMARKS.md's roofline table.
    #[test]
    fn bytes_are_the_sizes_of_what_the_loops_touch() {
        let f = size_of::<f64>();
        assert_eq!(BYTES_PER_PAIR, size_of::<Pair>());
        assert_eq!(size_of::<Pair>(), 2 * size_of::<u32>() + 3 * f);
        assert_eq!(size_of::<Pair>(), 32);
        assert_eq!(size_of::<ForceSum<3>>(), 6 * f);
        assert_eq!(size_of::<(f64, u32)>(), 16);

        // Density: the record, m_i and m_j, (ρ, count) read and written for both.
        assert_eq!(density::<3>().bytes, (32 + 2 * f + 2 * 2 * 16) as f64);
        assert_eq!(density::<3>().bytes, 112.0);
        // Gradient: x, v, m, ρ of both; the 3×3 gradient read and written for both.
        assert_eq!(
            gradient::<3>().bytes,
            (32 + 2 * 8 * f + 2 * 2 * 9 * f) as f64
        );
        assert_eq!(gradient::<3>().bytes, 448.0);
        assert_eq!(gradient::<3>().flops, 56.0);
        // Force, the bench's hydro: x, v, m, ρ, p, c_s, α factor of both; a, du, diss, v_sig.
        let hydro = Setting::default();
        assert_eq!(
            force::<3>(&hydro).bytes,
            (32 + 2 * 11 * f + 2 * 2 * 6 * f) as f64
        );
        assert_eq!(force::<3>(&hydro).bytes, 400.0);
        assert_eq!(force::<3>(&hydro).flops, 70.5);
        // disk3d: plus v_av (3) and the stress (9) of both.
        let disk = Setting {
            viscous: true,
            orbital: true,
            ..hydro
        };
        assert_eq!(
            force::<3>(&disk).bytes,
            (32 + 2 * 23 * f + 2 * 2 * 6 * f) as f64
        );
        assert_eq!(force::<3>(&disk).bytes, 592.0);
        assert_eq!(force::<3>(&disk).flops, 184.5);
        let cond = Setting {
            conductivity: true,
            ..hydro
        };
        assert_eq!(force::<3>(&cond).bytes - force::<3>(&hydro).bytes, 16.0);
        // Pair finding: x and the class byte per candidate; the record stored, read, written.
        assert_eq!(find::<3>(0.0).bytes, (3 * 32) as f64);
        assert_eq!(
            find::<3>(1.0).bytes - find::<3>(0.0).bytes,
            (3 * f + 1) as f64
        );
        assert_eq!(find::<3>(1.0).flops - find::<3>(0.0).flops, 9.0);
        assert_eq!(find::<3>(0.0).flops, 4.0 + 0.125 * 9.0 + 0.875 * 7.0);
    }

    #[test]
    fn roofline_bound_is_the_lower_of_the_two() {
        let c = PairCost {
            flops: 10.0,
            bytes: 100.0,
        };
        assert_eq!(c.intensity(), 0.1);
        assert_eq!(c.bound(1e9, 1e10), 1e8);
        assert_eq!(c.bound(1e8, 1e10), 1e7);
        let t = sweep_cost::<3>(&Setting::default()).total();
        assert!(t.bytes > 0.0 && t.flops > 0.0);
    }
}
