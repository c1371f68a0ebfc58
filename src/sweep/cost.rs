//! What one pair costs in each loop of the sweep, counted from the code of
//! [`PairBlock`](crate::sweep::pairs::PairBlock) and [`force_pair`](crate::physics::hydro::force_pair):
//! floating-point operations, and bytes loaded or stored by the pair loop. `sphdisk bench`
//! reports these beside its timings, and BENCHMARKS.md's roofline estimate divides them.
//!
//! **Flops:** each +, −, ×, ÷, √, min and max on per-pair data counts one, as the source
//! writes it (a product computed once and reused counts once); negations, comparisons and
//! operations on constants alone (−α, max(β, 1)) count none. Where a branch decides, the
//! count is weighted: 1/2 of pairs approach (the artificial viscosity's Π ≠ 0); the cubic
//! spline's two pieces are both computed for every pair (in SIMD lanes, one selected).
//!
//! **Bytes:** what the pair loop loads or stores, wherever it comes from (registers aside):
//! the [`Pair`] record; the second partner's fields the sum reads and its accumulator (read
//! and written: 2 × its size). The first partner's fields are read, and its terms stored,
//! once for all its pairs (they are consecutive; about 25 per particle here), so they count
//! with the per-particle work. Pair finding: per occupied stencil cell and particle, the
//! cell's range and box and the test of the box against the particle's reach; per candidate
//! tested, its position and pair class read and its index and r² written to the particle's
//! partner list (every candidate is written; the list's length counts the partners); per
//! pair found, the index and r² read back, r written over r² and read again, and the record
//! stored (a group's list is shrunk where it lies, not copied). Sizes are taken from the
//! types themselves, so the counts follow any change of them. Not counted: per-particle
//! work (the first partner's fields and accumulator, zeroing and merging the per-task
//! buffers, the finishing of slabs), and the growth of the per-thread pair vectors.

use std::mem::size_of;

use crate::sweep::local::Local;
use crate::sweep::pairs::{DensitySum, ForceSum, Pair, StencilCell};

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
    /// The pressure–energy formulation (`physics::pressure_energy`): the density sum adds
    /// m u W, the force sum reads u.
    pub pressure_energy: bool,
    /// Candidates tested by pair finding per pair found ([`crate::sweep::pairs::candidates`]).
    pub candidates_per_pair: f64,
    /// Stencil-cell boxes tested by pair finding per pair found (same).
    pub cells_per_pair: f64,
}

impl Setting {
    /// What `phys` switches on, as the sweep reads it.
    /// `tested` and `pairs`: what pair finding tested over a working set, and the pairs it
    /// found there.
    pub fn of<const D: usize>(
        phys: &crate::sweep::Physics<D>,
        tested: crate::sweep::pairs::Tested,
        pairs: u64,
    ) -> Self {
        let per_pair = |n: u64| n as f64 / pairs.max(1) as f64;
        Self {
            viscous: phys.viscous(),
            orbital: phys.av.orbital && phys.gravity.is_some(),
            conductivity: phys.av.conductivity > 0.0,
            pressure_energy: phys.pressure_energy_gamma().is_some(),
            candidates_per_pair: per_pair(tested.candidates),
            cells_per_pair: per_pair(tested.cells),
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

/// Pair finding, per pair found: the box tests of `cells_per_pair` stencil cells, the
/// distance tests of `candidates_per_pair` candidates, √r², the cubic spline's W and F, the
/// record stored.
pub fn find<const D: usize>(candidates_per_pair: f64, cells_per_pair: f64) -> PairCost {
    // Per axis: lo − x, x − hi, their max, the max with 0, e², added to d² (6).
    let cell_flops = 6.0 * D as f64;
    let cell_bytes = size_of::<StencilCell<D>>();
    // r² = Σ (x_i − x_j)²: D subtractions, D products, D sums (from 0.0).
    let candidate_flops = 3.0 * D as f64;
    // x and the class read; r² written and read back (the loop of distances, then the one
    // picking the partners); the index and r² written to the partner list.
    let listed = size_of::<u32>() + size_of::<f64>();
    let candidate_bytes =
        position::<D>() + field::<D, _>(|l| &l.class) + 2 * size_of::<f64>() + listed;
    // Both pieces, for every pair (two pairs at a time in SIMD lanes, each lane selecting
    // its piece: `Kernel::w_and_f_two`): q < 1: 1 − 1.5 q² + 0.75 q³ (5 ×, 2 ±) and
    // −3 + 2.25 q (1 ×, 1 +); 1 ≤ q < 2: t = 2 − q, 0.25 t³ (1 −, 3 ×) and −0.75 t²/q
    // (2 ×, 1 ÷).
    let shape = 9.0 + 7.0;
    // √r², q = r/unit, the two normalisations.
    let pair_flops = 4.0 + shape;
    // The index and r² read back, r written and read, the record stored.
    let pair_bytes = listed + 2 * size_of::<f64>() + size_of::<Pair>();
    PairCost {
        flops: cells_per_pair * cell_flops + candidates_per_pair * candidate_flops + pair_flops,
        bytes: cells_per_pair * cell_bytes as f64
            + candidates_per_pair * candidate_bytes as f64
            + pair_bytes as f64,
    }
}

/// Density, Eq. (5): m_j W and m_i W, added with a count to each partner; with the
/// pressure–energy formulation also m u W (u of both, two products, two sums more).
pub fn density<const D: usize>(s: &Setting) -> PairCost {
    let mass = field::<D, _>(|l| &l.mass);
    if s.pressure_energy {
        let u = field::<D, _>(|l| &l.u);
        let acc = 2 * size_of::<DensitySum>();
        return PairCost {
            flops: 8.0,
            bytes: (size_of::<Pair>() + mass + u + acc) as f64,
        };
    }
    let acc = 2 * size_of::<(f64, u32)>();
    PairCost {
        flops: 4.0,
        bytes: (size_of::<Pair>() + mass + acc) as f64,
    }
}

/// Velocity gradient, Eq. (10).
pub fn gradient<const D: usize>() -> PairCost {
    let d = D as f64;
    // dx (D), v_j − v_i (D), (v_j − v_i) f (D), × dx (D²), scaled by m/ρ for both (2D²;
    // m/ρ is stored per particle with ρ), added to both (2D²).
    let flops = 3.0 * d + 5.0 * d * d;
    let side = position::<D>() + velocity::<D>() + field::<D, _>(|l| &l.vol);
    let acc = 2 * size_of::<[[f64; D]; D]>();
    PairCost {
        flops,
        bytes: (size_of::<Pair>() + side + acc) as f64,
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
    if s.conductivity || s.pressure_energy {
        side += field::<D, _>(|l| &l.u);
    }
    if s.conductivity {
        // ρ̄ (2), v_sig,u (3), the conducted heat (6), added to work_i and work_j (2).
        flops += 13.0;
    }
    if s.pressure_energy {
        // y = (γ − 1) u_j (1; the first partner's once per particle). Its pressure part,
        // u_i u_j (1), the two weights (2 ÷), their sum (1), f v·r (1), both works (2), costs
        // what Eq. (7)'s (7) does.
        flops += 1.0;
    }
    if s.viscous {
        // g = f dx (D), S_i g and S_j g (4D²), v_ij (D); per axis S_j g/ρ_i + S_i g/ρ_j
        // added to accel (4) and v_ij·S_i g, v_ij·S_j g summed (4); both heats (4). 1/ρ
        // is stored per particle with ρ.
        flops += 10.0 * d + 4.0 + 4.0 * d * d;
        side += field::<D, _>(|l| &l.stress) + field::<D, _>(|l| &l.rho_inv);
    }
    let acc = 2 * size_of::<ForceSum<D>>();
    PairCost {
        flops,
        bytes: (size_of::<Pair>() + side + acc) as f64,
    }
}

/// All four loops for `setting`.
pub fn sweep_cost<const D: usize>(setting: &Setting) -> SweepCost {
    SweepCost {
        find: find::<D>(setting.candidates_per_pair, setting.cells_per_pair),
        density: density::<D>(setting),
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

        // Density: the record, m_j, (ρ, count) of j read and written (i's once per particle).
        let hydro = Setting::default();
        assert_eq!(density::<3>(&hydro).bytes, (32 + f + 2 * 16) as f64);
        assert_eq!(density::<3>(&hydro).bytes, 72.0);
        // Pressure–energy: u_j too, (ρ, Σ m u W, count) of j read and written.
        let pe = Setting {
            pressure_energy: true,
            ..hydro
        };
        assert_eq!(size_of::<DensitySum>(), 24);
        assert_eq!(density::<3>(&pe).bytes, (32 + 2 * f + 2 * 24) as f64);
        assert_eq!(density::<3>(&pe).flops, 8.0);
        // Its force sum reads u_j and forms y = (γ − 1) u_j.
        assert_eq!(force::<3>(&pe).bytes - force::<3>(&hydro).bytes, 8.0);
        assert_eq!(force::<3>(&pe).flops - force::<3>(&hydro).flops, 1.0);
        // With the conductivity as well, u is read once.
        let both = Setting {
            conductivity: true,
            ..pe
        };
        assert_eq!(force::<3>(&both).bytes - force::<3>(&hydro).bytes, 8.0);
        // Gradient: x, v, m/ρ of j; j's 3×3 gradient read and written.
        assert_eq!(gradient::<3>().bytes, (32 + 7 * f + 2 * 9 * f) as f64);
        assert_eq!(gradient::<3>().bytes, 232.0);
        assert_eq!(gradient::<3>().flops, 54.0);
        // Force, the bench's hydro: x, v, m, ρ, p, c_s, α factor of j; j's a, du, diss, v_sig.
        assert_eq!(force::<3>(&hydro).bytes, (32 + 11 * f + 2 * 6 * f) as f64);
        assert_eq!(force::<3>(&hydro).bytes, 216.0);
        assert_eq!(force::<3>(&hydro).flops, 70.5);
        // disk3d: plus v_av (3), the stress (9) and 1/ρ of j.
        let disk = Setting {
            viscous: true,
            orbital: true,
            ..hydro
        };
        assert_eq!(force::<3>(&disk).bytes, (32 + 24 * f + 2 * 6 * f) as f64);
        assert_eq!(force::<3>(&disk).bytes, 320.0);
        assert_eq!(force::<3>(&disk).flops, 140.5);
        let cond = Setting {
            conductivity: true,
            ..hydro
        };
        assert_eq!(force::<3>(&cond).bytes - force::<3>(&hydro).bytes, 8.0);
        // Pair finding: x and the class byte per candidate read, r² written and read back,
        // its index and r² written;
        // per pair the index and r² read back, r written and read, the record stored;
        // per stencil cell its range (two indices) and box (two corners), 18 flops in 3D.
        assert_eq!(find::<3>(0.0, 0.0).bytes, (4 + 8 + 2 * 8 + 32) as f64);
        assert_eq!(
            find::<3>(1.0, 0.0).bytes - find::<3>(0.0, 0.0).bytes,
            (3 * f + 1 + 2 * f + 4 + 8) as f64
        );
        assert_eq!(find::<3>(1.0, 0.0).flops - find::<3>(0.0, 0.0).flops, 9.0);
        // Per pair: √r², q, the two normalisations, and both pieces of the spline (9 + 7
        // flops) in every dimension, as the lanes compute them.
        assert_eq!(find::<3>(0.0, 0.0).flops, 4.0 + 9.0 + 7.0);
        assert_eq!(find::<2>(0.0, 0.0).flops, find::<3>(0.0, 0.0).flops);
        assert_eq!(
            find::<3>(0.0, 1.0).bytes - find::<3>(0.0, 0.0).bytes,
            (2 * size_of::<usize>() + 6 * f) as f64
        );
        assert_eq!(find::<3>(0.0, 1.0).bytes - find::<3>(0.0, 0.0).bytes, 64.0);
        assert_eq!(find::<3>(0.0, 1.0).flops - find::<3>(0.0, 0.0).flops, 18.0);
        assert_eq!(find::<2>(0.0, 1.0).flops - find::<2>(0.0, 0.0).flops, 12.0);
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
