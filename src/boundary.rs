//! Boundaries by ghost particles (paper, Section 2.2): the simulation box, the boundary kind
//! of each axis, the ghosts made for one right-hand-side evaluation, and keeping particles
//! inside the box after a drift.
//!
//! * **periodic**: ghosts on one side only (Figure 2): along the first periodic axis only
//!   images shifted by −L, i.e. only the lexicographically negative shift vectors (see
//!   [`make_ghosts`]). Every periodic pair is then found exactly once, corners included; what
//!   a real particle contributes to such a ghost is folded back into the ghost's owner.
//! * **reflecting**: ghosts on both sides, mirror images of the particles within one support
//!   of each face, with the normal vector components negated. Contributions to pure mirror
//!   ghosts are discarded: the mirrored pair is evaluated on its own.
//! * **open**: no ghosts; particles may leave the box.
//!
//! Ghost quantities are never computed: they are copied from their owners.

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoundaryKind {
    Periodic,
    Reflecting,
    Open,
}

/// The simulation box and the boundary kind of each axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimBox<const D: usize> {
    pub min: [f64; D],
    pub max: [f64; D],
    pub kinds: [BoundaryKind; D],
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Name of axis `d` ("x", "y", "z").
pub fn axis_name(d: usize) -> &'static str {
    AXES[d]
}

impl<const D: usize> SimBox<D> {
    pub fn length(&self, d: usize) -> f64 {
        self.max[d] - self.min[d]
    }

    /// Refuses a box whose closed sides are shorter than two kernel supports: with fewer, a
    /// particle could meet two images of the same neighbour.
    pub fn validate(&self, support: f64) -> Result<()> {
        for d in 0..D {
            let l = self.length(d);
            if !(l > 0.0 && l.is_finite()) {
                bail!(
                    "domain: the box has no positive length along {} (min {}, max {})",
                    AXES[d],
                    self.min[d],
                    self.max[d]
                );
            }
            if self.kinds[d] != BoundaryKind::Open && l < 2.0 * support {
                bail!(
                    "the box is too small for the kernel along {}: length {} < {} \
                     (two kernel supports, support = 2h = {}); use a smaller h or a larger box",
                    AXES[d],
                    l,
                    2.0 * support,
                    support
                );
            }
        }
        Ok(())
    }

    /// Refuses particles outside a periodic or reflecting box, naming the first offender.
    pub fn check_inside(&self, pos: &[Vec<f64>; D], id: &[u64]) -> Result<()> {
        self.check_within(pos, id, false)
    }

    /// As [`check_inside`](Self::check_inside), but the upper faces count as inside: where
    /// a run's own drift may leave a particle (reflected or wrapped to round-off).
    pub fn check_inside_closed(&self, pos: &[Vec<f64>; D], id: &[u64]) -> Result<()> {
        self.check_within(pos, id, true)
    }

    fn check_within(&self, pos: &[Vec<f64>; D], id: &[u64], closed: bool) -> Result<()> {
        for d in 0..D {
            if self.kinds[d] == BoundaryKind::Open {
                continue;
            }
            for (i, &x) in pos[d].iter().enumerate() {
                let below_max = x < self.max[d] || closed && x == self.max[d];
                if !(x >= self.min[d] && below_max) {
                    bail!(
                        "particle {} lies outside the {:?} box along {}: {} = {} not in [{}, {}{}",
                        id[i],
                        self.kinds[d],
                        AXES[d],
                        AXES[d],
                        x,
                        self.min[d],
                        self.max[d],
                        if closed { "]" } else { ")" }
                    );
                }
            }
        }
        Ok(())
    }

    /// After a drift: wraps periodic coordinates, reflects positions and velocities at
    /// reflecting faces. Open axes are left alone.
    pub fn enforce(&self, pos: &mut [Vec<f64>; D], vel: &mut [Vec<f64>; D]) {
        for d in 0..D {
            let (lo, hi, l) = (self.min[d], self.max[d], self.length(d));
            match self.kinds[d] {
                BoundaryKind::Open => {}
                BoundaryKind::Periodic => {
                    for x in pos[d].iter_mut() {
                        if *x < lo || *x >= hi {
                            *x = lo + (*x - lo).rem_euclid(l);
                            if *x >= hi {
                                // rem_euclid may round up to exactly l.
                                *x = lo;
                            }
                        }
                    }
                }
                BoundaryKind::Reflecting => {
                    for (x, v) in pos[d].iter_mut().zip(vel[d].iter_mut()) {
                        if *x < lo {
                            *x = 2.0 * lo - *x;
                            *v = -*v;
                        } else if *x >= hi {
                            *x = (2.0 * hi - *x).min(hi - l * f64::EPSILON);
                            *v = -*v;
                        }
                    }
                }
            }
        }
    }
}

/// A ghost: an image of real particle `owner`, at `pos`, whose vector components are those of
/// the owner multiplied by `sign` (−1 on each mirrored axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ghost<const D: usize> {
    pub owner: u32,
    pub pos: [f64; D],
    pub sign: [f64; D],
    /// Whether contributions computed for this ghost are added to its owner: true when the
    /// image involves a periodic shift (its inverse image does not exist), false for pure
    /// mirrors (the mirrored pair is evaluated separately).
    pub fold: bool,
}

/// One axis's choice for an image: stay, shift by ∓L (periodic), or mirror at a face.
#[derive(Clone, Copy, Debug, PartialEq)]
enum AxisImage {
    Same,
    /// Periodic shift by `k · L`, k = ±1.
    Shift(f64),
    /// Mirror at the face at this coordinate.
    Mirror(f64),
}

/// Makes the ghosts of one evaluation: for every real particle, each image within one
/// support of the box. An image combines per-axis choices (shift on periodic axes, mirror on
/// reflecting ones). Of the periodic shift vectors t only the *lexicographically negative*
/// ones (first non-zero component −1) are made: exactly one of t and −t is, so every
/// periodic pair is found once, in 1, 2 or 3 dimensions and across corners (paper, Figure 2,
/// generalised). Mirror images are made on both faces. The particles are taken in blocks
/// in parallel; the ghosts come out in particle order whatever the threads.
pub fn make_ghosts<const D: usize>(
    bx: &SimBox<D>,
    pos: &[Vec<f64>; D],
    support: f64,
) -> Vec<Ghost<D>> {
    use rayon::prelude::*;
    const BLOCK: usize = 4096;
    let n = pos[0].len();
    let blocks: Vec<Vec<Ghost<D>>> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| images_of(bx, pos, support, b * BLOCK..((b + 1) * BLOCK).min(n)))
        .collect();
    blocks.concat()
}

/// The ghosts of the particles `range` ([`make_ghosts`]), in order.
fn images_of<const D: usize>(
    bx: &SimBox<D>,
    pos: &[Vec<f64>; D],
    support: f64,
    range: std::ops::Range<usize>,
) -> Vec<Ghost<D>> {
    let mut ghosts: Vec<Ghost<D>> = Vec::new();
    let mut options: [Vec<AxisImage>; D] = std::array::from_fn(|_| Vec::with_capacity(3));
    for i in range {
        for d in 0..D {
            let (lo, hi, x) = (bx.min[d], bx.max[d], pos[d][i]);
            let o = &mut options[d];
            o.clear();
            o.push(AxisImage::Same);
            match bx.kinds[d] {
                BoundaryKind::Open => {}
                BoundaryKind::Periodic => {
                    if x >= hi - support {
                        o.push(AxisImage::Shift(-1.0));
                    }
                    if x < lo + support {
                        o.push(AxisImage::Shift(1.0));
                    }
                }
                BoundaryKind::Reflecting => {
                    if x < lo + support {
                        o.push(AxisImage::Mirror(lo));
                    }
                    if x >= hi - support {
                        o.push(AxisImage::Mirror(hi));
                    }
                }
            }
        }
        if options.iter().all(|o| o.len() == 1) {
            continue;
        }
        // Enumerate the product of the per-axis options.
        let mut choice = [0usize; D];
        'product: loop {
            let mut first_shift = 0.0;
            let mut identity = true;
            let mut g = Ghost {
                owner: i as u32,
                pos: [0.0; D],
                sign: [1.0; D],
                fold: false,
            };
            for d in 0..D {
                let x = pos[d][i];
                g.pos[d] = match options[d][choice[d]] {
                    AxisImage::Same => x,
                    AxisImage::Shift(k) => {
                        identity = false;
                        if first_shift == 0.0 {
                            first_shift = k;
                        }
                        g.fold = true;
                        x + k * bx.length(d)
                    }
                    AxisImage::Mirror(face) => {
                        identity = false;
                        g.sign[d] = -1.0;
                        2.0 * face - x
                    }
                };
            }
            if !identity && first_shift <= 0.0 {
                ghosts.push(g);
            }
            // Next combination.
            let mut d = 0;
            loop {
                if d == D {
                    break 'product;
                }
                choice[d] += 1;
                if choice[d] < options[d].len() {
                    break;
                }
                choice[d] = 0;
                d += 1;
            }
        }
    }
    ghosts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box<const D: usize>(kind: BoundaryKind) -> SimBox<D> {
        SimBox {
            min: [0.0; D],
            max: [1.0; D],
            kinds: [kind; D],
        }
    }

    /// The ghosts come out in particle order, the same on any number of threads: 10 000
    /// particles (three blocks) in a box periodic in x and y and reflecting in z, against
    /// the ghosts of each particle made one at a time.
    #[test]
    fn ghosts_are_in_particle_order_on_any_thread_count() {
        let bx = SimBox::<3> {
            min: [0.0; 3],
            max: [1.0; 3],
            kinds: [
                BoundaryKind::Periodic,
                BoundaryKind::Periodic,
                BoundaryKind::Reflecting,
            ],
        };
        let mut rng = crate::rng::Rng::new(5);
        let pos: [Vec<f64>; 3] =
            std::array::from_fn(|_| (0..10_000).map(|_| rng.uniform()).collect());
        let one_by_one: Vec<Ghost<3>> = (0..10_000)
            .flat_map(|i| images_of(&bx, &pos, 0.1, i..i + 1))
            .collect();
        assert!(one_by_one.len() > 3000, "{}", one_by_one.len());
        for threads in [1, 2, 5] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let g = pool.install(|| make_ghosts(&bx, &pos, 0.1));
            assert_eq!(g.len(), one_by_one.len(), "{threads} threads");
            for (a, b) in g.iter().zip(&one_by_one) {
                assert_eq!(
                    (a.owner, a.pos, a.sign, a.fold),
                    (b.owner, b.pos, b.sign, b.fold),
                    "{threads} threads"
                );
            }
        }
    }

    #[test]
    fn periodic_ghosts_are_one_sided_and_fill_corners() {
        let bx = unit_box::<2>(BoundaryKind::Periodic);
        let pos = [vec![0.95, 0.5, 0.05], vec![0.97, 0.5, 0.5]];
        let g = make_ghosts(&bx, &pos, 0.1);
        // Particle 0 is near the high x and y faces: shifts (−1, 0), (0, −1), (−1, −1).
        // Particle 2 is near the low x face: its shift (+1, 0) is not made, but (−1, 0) of
        // particle 0 covers their pair. No image of particle 1.
        assert_eq!(g.iter().filter(|g| g.owner == 0).count(), 3);
        assert!(
            g.iter()
                .all(|g| g.owner != 1 && g.fold && g.sign == [1.0, 1.0])
        );
        assert!(
            g.iter()
                .filter(|g| g.owner == 0)
                .all(|g| g.pos[0] < 0.0 || g.pos[1] < 0.0)
        );
        assert_eq!(g.iter().filter(|g| g.owner == 2).count(), 0);
    }

    #[test]
    fn anti_diagonal_periodic_corner_gets_a_ghost() {
        // (0.02, 0.98) and (0.99, 0.01) are neighbours across the corner: the image of the
        // second at shift (−1, +1) is lexicographically negative and must exist.
        let bx = unit_box::<2>(BoundaryKind::Periodic);
        let pos = [vec![0.02, 0.99], vec![0.98, 0.01]];
        let g = make_ghosts(&bx, &pos, 0.1);
        assert!(g.iter().any(|g| g.owner == 1
            && (g.pos[0] + 0.01).abs() < 1e-12
            && (g.pos[1] - 1.01).abs() < 1e-12));
        assert!(!g.iter().any(|g| g.owner == 0 && g.pos[0] > 1.0));
    }

    #[test]
    fn reflecting_ghosts_mirror_position_and_sign() {
        let bx = unit_box::<1>(BoundaryKind::Reflecting);
        let pos = [vec![0.02, 0.5, 0.99]];
        let g = make_ghosts(&bx, &pos, 0.1);
        assert_eq!(g.len(), 2);
        assert_eq!(g[0].owner, 0);
        assert!((g[0].pos[0] + 0.02).abs() < 1e-15);
        assert_eq!(g[0].sign, [-1.0]);
        assert!(!g[0].fold);
        assert!((g[1].pos[0] - 1.01).abs() < 1e-15);
    }

    #[test]
    fn enforce_wraps_and_reflects() {
        let mut bx = unit_box::<2>(BoundaryKind::Periodic);
        bx.kinds[1] = BoundaryKind::Reflecting;
        let mut pos = [vec![1.25, -0.25], vec![1.1, -0.1]];
        let mut vel = [vec![1.0, -1.0], vec![1.0, -1.0]];
        bx.enforce(&mut pos, &mut vel);
        assert!((pos[0][0] - 0.25).abs() < 1e-15 && (pos[0][1] - 0.75).abs() < 1e-15);
        assert!((pos[1][0] - 0.9).abs() < 1e-15 && (pos[1][1] - 0.1).abs() < 1e-15);
        assert_eq!(vel[0], vec![1.0, -1.0]);
        assert_eq!(vel[1], vec![-1.0, 1.0]);
    }

    #[test]
    fn too_small_box_is_refused_with_the_axis_named() {
        let bx = unit_box::<3>(BoundaryKind::Periodic);
        let err = bx.validate(0.6).unwrap_err().to_string();
        assert!(
            err.contains("too small") && err.contains("along x"),
            "{err}"
        );
        assert!(bx.validate(0.3).is_ok());
    }

    #[test]
    fn particle_outside_periodic_box_is_named() {
        let bx = unit_box::<1>(BoundaryKind::Periodic);
        let err = bx
            .check_inside(&[vec![0.5, 1.5]], &[7, 8])
            .unwrap_err()
            .to_string();
        assert!(err.contains("particle 8"), "{err}");
    }
}
