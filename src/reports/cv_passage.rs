//! The stream's passage through the disk's rim, followed particle by particle across a
//! cv run's snapshots (`sphdisk analyse cv`): the overflow as a flux.
//!
//! The paper (Section 4) finds that "about 10 % to 20 % of the stream material flows over
//! and under the disk" and strikes it again nearer the white dwarf. That is a share of the
//! stream's *flow*: of the gas that reaches the rim, how much goes on past it instead of
//! stopping there. One snapshot cannot tell gas passing the rim from gas stopping at it
//! (`cv::overflow_figures` counts where stream gas lies at the rim); the particles' ids
//! can. Every particle released during the run (an id above the first snapshot's largest)
//! is followed from snapshot to snapshot, with R90 the disk's 90%-mass radius of each:
//!
//! - it **arrives** at the first snapshot that finds it within `RIM.1` R90 of the accretor;
//! - it **passes** the rim at the first snapshot within [`SETTLE_ORBITS`] of its arrival
//!   that finds it inside [`PASS_RADIUS`] R90 when the snapshot before had it outside
//!   `RIM.0` R90 (or not yet released), or when it is still on a stream orbit
//!   (eccentricity ≥ `STREAM_ECCENTRICITY`). Gas that stopped at the rim joins the disk and
//!   drifts inward at the viscous speed ~ν/R (10⁻³ a Ω_orb for ν = 7·10⁻⁴): from `RIM.0` to
//!   [`PASS_RADIUS`] R90 takes it tens of orbits, not one snapshot interval. The limit in
//!   time keeps that drift out: in a hot disk (c_s a tenth of v_K) gas that stopped reads
//!   e ≥ 0.3 now and then, and without it would count as passing whenever it drifted
//!   inside [`PASS_RADIUS`] R90 later — a share growing with the run's length;
//! - at that snapshot its height |z| is compared with the disk's own height H(R) there (the
//!   mass-weighted rms z of disk gas in an annulus of width [`H_BIN`] R90 around R): gas
//!   above H came **over or under** the disk, gas within H went **through** its rim (3D);
//! - it **re-impacts** where the first snapshot from its passage on finds it on a
//!   near-circular orbit (eccentricity < `STREAM_ECCENTRICITY`): the radius and azimuth of
//!   the paper's secondary bright region (Figure 5).
//!
//! The passing fraction is the passed mass over the arrived mass, counting the particles
//! that arrived at least [`SETTLE_ORBITS`] before the last snapshot (time to pass); its
//! error is the scatter of the fractions of successive orbits of arrival over √(orbits).
//! A particle caught by no snapshot between its passage and its accretion is missed: the
//! flight from the rim to the re-impact takes ~0.1 orbit, so a run meant for this writes a
//! snapshot every [`MAX_INTERVAL_ORBITS`] orbit or more often (a note says when it does not).
//!
//! What sets the share (paper, Section 4: "the ratio of the heights of the stream and the
//! rim of the disk are unknown") is measured beside it, 3D only: the stream's height as it
//! comes to the rim, the mass-weighted rms z of the stream gas (released during the run, on
//! a stream orbit) at [`APPROACH`] R90, over the rim's, the rms z of disk gas at `RIM` R90,
//! each pooled over the snapshots of the run's second half (the rim settled, the stream's
//! head long gone).

use std::collections::BTreeMap;
use std::f64::consts::TAU;

use serde::Serialize;

use crate::analysis::{standard_error, weighted_quantile};
use crate::io::snapshot::Snapshot;
use crate::reports::cv::{MIN_RIM_PARTICLES, RIM, azimuth_deg};

/// Inside this many R90 a particle from beyond the rim has passed it (module doc): far
/// enough inside the rim that viscous drift cannot carry gas there between snapshots, far
/// enough outside the stream's closest approach (~0.4–0.5 R90) that passing gas is seen
/// before it strikes the disk.
pub const PASS_RADIUS: f64 = 0.75;

/// Width, in R90, of the annuli in which the disk's height H(R) is measured.
pub const H_BIN: f64 = 0.1;

/// Particles that arrived later than this many orbits before the last snapshot are not
/// counted: a passing particle needs ~0.1 orbit to get from the rim to [`PASS_RADIUS`].
/// A particle passes within this time of its arrival or not at all (module doc), so the
/// share does not depend on how long the run goes on after the arrivals.
pub const SETTLE_ORBITS: f64 = 0.25;

/// The annulus, in R90, where the stream's height on its way to the rim is taken: outside
/// the rim annulus `RIM`, inside the stream's first crossing of 1.5 R90 (module doc).
pub const APPROACH: (f64, f64) = (1.1, 1.4);

/// Longer snapshot intervals (orbits) can miss gas that passes and is accreted or
/// circularised between two snapshots; the figures then carry a note.
pub const MAX_INTERVAL_ORBITS: f64 = 0.05;

/// One particle's history (module doc).
#[derive(Clone, Copy, Debug, Default)]
struct Track {
    mass: f64,
    /// Time of arrival at the rim.
    arrived: Option<f64>,
    /// Outside `RIM.0` R90 at the last snapshot that saw it.
    outside: bool,
    /// Passed: above the disk's H where found (`None`: no H there, or 2D).
    passed: Option<Option<bool>>,
    /// Re-impact radius, its ratio to that snapshot's R90, and azimuth (degrees).
    reimpact: Option<(f64, f64, f64)>,
}

/// Passing fraction of the gas that arrived in one orbit.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PassageWindow {
    pub orbit_start: f64,
    pub orbit_end: f64,
    pub arrived_particles: usize,
    pub arrived_mass: f64,
    pub passed_fraction: f64,
}

/// What the passage of the stream through the rim comes to (module doc); `cv.json` key
/// `passage`.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct PassageFigures {
    /// The longest interval between two snapshots, in orbits.
    pub snapshot_interval_orbits: f64,
    /// Orbits over which the counted particles arrived.
    pub orbits: (f64, f64),
    pub arrived_particles: usize,
    pub arrived_mass: f64,
    /// Passed mass / arrived mass, and its error (None with fewer than two orbits).
    pub passed_fraction: f64,
    pub passed_fraction_error: Option<f64>,
    /// Of the arrived mass, the share that passed above the disk's H (over or under it) and
    /// the share that passed within it (through the rim); 3D only. What is left of the
    /// passed fraction was found where the disk had too few particles to give an H.
    pub over_under_fraction: Option<f64>,
    pub through_fraction: Option<f64>,
    /// Mass-weighted medians of where passed gas re-impacts: radius (a), radius over that
    /// snapshot's R90, azimuth (degrees, turning frame); None if none re-impacted yet.
    pub reimpact_radius: Option<f64>,
    pub reimpact_radius_over_r90: Option<f64>,
    pub reimpact_azimuth_deg: Option<f64>,
    /// Share of the passed mass seen re-impacting.
    pub reimpacted_share: f64,
    /// 3D: the stream's rms height at [`APPROACH`] R90 and the rim's at `RIM` R90 (a), and
    /// their ratio, over the snapshots of the run's second half (module doc); None in 2D or
    /// where those snapshots held no such gas.
    pub stream_height: Option<f64>,
    pub rim_height: Option<f64>,
    pub stream_to_rim_height: Option<f64>,
    pub windows: Vec<PassageWindow>,
}

/// One snapshot's sums for the heights: Σ m z² and Σ m of the approaching stream, and of
/// the disk's rim.
#[derive(Clone, Copy, Debug, Default)]
struct HeightSums {
    time: f64,
    stream: (f64, f64),
    rim: (f64, f64),
}

/// Follows the run's stream particles through its snapshots ([`PassageTracker::feed`] each,
/// in time order, then [`PassageTracker::finish`]).
#[derive(Debug, Default)]
pub struct PassageTracker {
    /// Ids below this were in the first snapshot (the initial disk, releases at t = 0).
    first_stream_id: Option<u64>,
    /// By id: the sums over them come out in the same order every time.
    tracks: BTreeMap<u64, Track>,
    times: Vec<f64>,
    three_d: bool,
    heights: Vec<HeightSums>,
}

impl PassageTracker {
    pub fn new() -> Self {
        Self::default()
    }

    /// Takes one snapshot (in the run's frame) with its disk mask (`cv::disk_mask`: true
    /// where the orbit's eccentricity is below `STREAM_ECCENTRICITY`) and R90 (None: no
    /// disk, nothing arrives or passes).
    pub fn feed(&mut self, s: &Snapshot, disk: &[bool], r90: Option<f64>) {
        self.times.push(s.time);
        let first = *self
            .first_stream_id
            .get_or_insert_with(|| s.id.iter().max().map_or(0, |m| m + 1));
        self.three_d |= s.dimension == 3;
        let Some(r90) = r90.filter(|r| *r > 0.0) else {
            return;
        };
        let heights = disk_heights(s, disk, r90);
        if s.dimension == 3 {
            self.heights.push(height_sums(s, disk, r90, first));
        }
        for i in (0..s.len()).filter(|&i| s.id[i] >= first) {
            let x = [s.pos[0][i], s.pos[1][i], s.pos[2][i]];
            let r = x[0].hypot(x[1]);
            let t = self.tracks.entry(s.id[i]).or_insert(Track {
                mass: s.mass[i],
                outside: true,
                ..Track::default()
            });
            if t.arrived.is_none() && r <= RIM.1 * r90 {
                t.arrived = Some(s.time);
            }
            let in_time = t
                .arrived
                .is_none_or(|a| s.time - a <= SETTLE_ORBITS * TAU * (1.0 + 1e-9));
            if t.passed.is_none() && in_time && r < PASS_RADIUS * r90 && (t.outside || !disk[i]) {
                t.arrived.get_or_insert(s.time);
                let above = if s.dimension == 3 {
                    let k = (r / (H_BIN * r90)) as usize;
                    heights.get(k).copied().flatten().map(|h| x[2].abs() > h)
                } else {
                    None
                };
                t.passed = Some(above);
            }
            if t.passed.is_some() && t.reimpact.is_none() && disk[i] {
                t.reimpact = Some((r, r / r90, azimuth_deg(x[0], x[1])));
            }
            t.outside = r >= RIM.0 * r90;
        }
    }

    /// The figures (None if no particle arrived early enough to be counted), with a note
    /// for a coarse snapshot interval pushed to `notes`.
    pub fn finish(self, notes: &mut Vec<String>) -> Option<PassageFigures> {
        let t_last = *self.times.last()?;
        let interval = self
            .times
            .windows(2)
            .map(|w| (w[1] - w[0]) / TAU)
            .fold(0.0, f64::max);
        let cutoff = t_last - SETTLE_ORBITS * TAU;
        let counted: Vec<(f64, &Track)> = self
            .tracks
            .values()
            .filter_map(|t| t.arrived.filter(|&a| a <= cutoff).map(|a| (a, t)))
            .collect();
        if counted.is_empty() {
            notes.push(format!(
                "no stream gas reached the rim ({:.2} R90) by {SETTLE_ORBITS} orbit before the last snapshot: no passage figures",
                RIM.1
            ));
            return None;
        }
        // (A relative margin: snapshots written every 0.05 orbit come out a rounding above it.)
        if interval > MAX_INTERVAL_ORBITS * (1.0 + 1e-6) {
            notes.push(format!(
                "snapshots up to {interval:.3} orbit apart (passage figures want ≤ {MAX_INTERVAL_ORBITS}): gas that passes the rim and is accreted between two snapshots is missed, and its height is taken after it struck the disk"
            ));
        }
        // Sums start from +0: an empty f64 `sum()` is −0, which would read "-0.0".
        let mass = |pick: &dyn Fn(&Track) -> bool| -> f64 {
            counted
                .iter()
                .filter(|(_, t)| pick(t))
                .fold(0.0, |acc, (_, t)| acc + t.mass)
        };
        let arrived_mass = mass(&|_| true);
        let passed_mass = mass(&|t| t.passed.is_some());
        let (first, last) = counted
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(a, _)| {
                (lo.min(a), hi.max(a))
            });
        let (o0, o1) = (first / TAU, last / TAU);
        // Whole orbits of arrival, counted back from the last counted arrival. Arrivals come
        // at snapshot times and a window's edges fall on snapshot times too, so membership
        // is decided half a snapshot interval past each edge: round-off in the times cannot
        // move a snapshot's arrivals across it.
        let n_windows = ((o1 - o0 + 1e-9).floor() as usize).max(1);
        let half = 0.5 * interval;
        let windows: Vec<PassageWindow> = (0..n_windows)
            .rev()
            .filter_map(|k| {
                let end = o1 - k as f64;
                let start = end - 1.0;
                let inside: Vec<&Track> = counted
                    .iter()
                    .filter(|(a, _)| {
                        let o = a / TAU;
                        o <= end + half && (o > start + half || k + 1 == n_windows)
                    })
                    .map(|(_, t)| *t)
                    .collect();
                let m = inside.iter().fold(0.0, |acc, t| acc + t.mass);
                let p = inside
                    .iter()
                    .filter(|t| t.passed.is_some())
                    .fold(0.0, |acc, t| acc + t.mass);
                (m > 0.0).then(|| PassageWindow {
                    orbit_start: if k + 1 == n_windows { o0 } else { start },
                    orbit_end: end,
                    arrived_particles: inside.len(),
                    arrived_mass: m,
                    passed_fraction: p / m,
                })
            })
            .collect();
        let fractions: Vec<f64> = windows.iter().map(|w| w.passed_fraction).collect();
        let error = (fractions.len() >= 2).then(|| standard_error(&fractions));
        let re: Vec<(f64, (f64, f64, f64))> = counted
            .iter()
            .filter_map(|(_, t)| t.reimpact.map(|r| (t.mass, r)))
            .collect();
        let re_mass = re.iter().fold(0.0, |acc, (m, _)| acc + m);
        let az: Vec<(f64, f64)> = re.iter().map(|&(m, r)| (r.2, m)).collect();
        let (stream_height, rim_height) =
            pooled_heights(&self.heights, 0.5 * (self.times[0] + t_last));
        Some(PassageFigures {
            snapshot_interval_orbits: interval,
            orbits: (o0, o1),
            arrived_particles: counted.len(),
            arrived_mass,
            passed_fraction: passed_mass / arrived_mass,
            passed_fraction_error: error,
            over_under_fraction: self
                .three_d
                .then(|| mass(&|t| t.passed == Some(Some(true))) / arrived_mass),
            through_fraction: self
                .three_d
                .then(|| mass(&|t| t.passed == Some(Some(false))) / arrived_mass),
            reimpact_radius: weighted_quantile(re.iter().map(|&(m, r)| (r.0, m)).collect(), 0.5),
            reimpact_radius_over_r90: weighted_quantile(
                re.iter().map(|&(m, r)| (r.1, m)).collect(),
                0.5,
            ),
            reimpact_azimuth_deg: crate::reports::cv::circular_median_deg(&az),
            reimpacted_share: if passed_mass > 0.0 {
                re_mass / passed_mass
            } else {
                0.0
            },
            stream_height,
            rim_height,
            stream_to_rim_height: stream_height.zip(rim_height).map(|(s, r)| s / r),
            windows,
        })
    }
}

/// The disk's height H in annuli of width [`H_BIN`] R90 out to `RIM.1` R90: the
/// mass-weighted rms z of its gas (None where fewer than `MIN_RIM_PARTICLES` lie).
fn disk_heights(s: &Snapshot, disk: &[bool], r90: f64) -> Vec<Option<f64>> {
    let n = (RIM.1 / H_BIN).ceil() as usize + 1;
    let mut acc = vec![(0.0, 0.0, 0usize); n];
    for i in (0..s.len()).filter(|&i| disk[i]) {
        let k = (s.pos[0][i].hypot(s.pos[1][i]) / (H_BIN * r90)) as usize;
        if let Some(a) = acc.get_mut(k) {
            a.0 += s.mass[i] * s.pos[2][i].powi(2);
            a.1 += s.mass[i];
            a.2 += 1;
        }
    }
    acc.into_iter()
        .map(|(mz2, m, c)| (c >= MIN_RIM_PARTICLES && m > 0.0).then(|| (mz2 / m).sqrt()))
        .collect()
}

/// This snapshot's [`HeightSums`]: stream gas (id ≥ `first`, not on a disk orbit) at
/// [`APPROACH`] R90, disk gas at `RIM` R90.
fn height_sums(s: &Snapshot, disk: &[bool], r90: f64, first: u64) -> HeightSums {
    let mut h = HeightSums {
        time: s.time,
        ..HeightSums::default()
    };
    for i in 0..s.len() {
        let r = s.pos[0][i].hypot(s.pos[1][i]) / r90;
        let mz2 = s.mass[i] * s.pos[2][i].powi(2);
        let sums = if disk[i] && (RIM.0..=RIM.1).contains(&r) {
            &mut h.rim
        } else if !disk[i] && s.id[i] >= first && (APPROACH.0..=APPROACH.1).contains(&r) {
            &mut h.stream
        } else {
            continue;
        };
        sums.0 += mz2;
        sums.1 += s.mass[i];
    }
    h
}

/// The stream's and the rim's rms heights pooled over the snapshots from `since` on (None
/// where those snapshots held no such gas).
fn pooled_heights(sums: &[HeightSums], since: f64) -> (Option<f64>, Option<f64>) {
    let (mut stream, mut rim) = ((0.0, 0.0), (0.0, 0.0));
    for h in sums.iter().filter(|h| h.time >= since) {
        stream = (stream.0 + h.stream.0, stream.1 + h.stream.1);
        rim = (rim.0 + h.rim.0, rim.1 + h.rim.1);
    }
    let rms = |(mz2, m): (f64, f64)| (m > 0.0).then(|| (mz2 / m).sqrt());
    (rms(stream), rms(rim))
}

/// `cv_passage.csv`: a row per orbit of arrival.
pub fn windows_csv(windows: &[PassageWindow]) -> String {
    let mut s =
        String::from("orbit_start,orbit_end,arrived_particles,arrived_mass,passed_fraction\n");
    for w in windows {
        s.push_str(&format!(
            "{:.4},{:.4},{},{:.6e},{:.6}\n",
            w.orbit_start, w.orbit_end, w.arrived_particles, w.arrived_mass, w.passed_fraction
        ));
    }
    s
}

impl PassageFigures {
    /// The line `analyse cv` prints.
    pub fn summary_line(&self) -> String {
        let pct =
            |v: Option<f64>| v.map_or("–".to_string(), |v| format!("{:.1}%", 100.0 * v.abs()));
        format!(
            "the stream's passage through the rim (arrivals over orbits {:.2}–{:.2}, {} particles, snapshots ≤ {:.3} orbit apart): {:.1}%{} passes the rim instead of stopping there — over or under the disk {}, through it {}; re-impact at R = {} a ({} R90), azimuth {}° ({:.0}% of the passed gas seen re-impacting){}",
            self.orbits.0,
            self.orbits.1,
            self.arrived_particles,
            self.snapshot_interval_orbits,
            100.0 * self.passed_fraction,
            self.passed_fraction_error
                .map_or(String::new(), |e| format!(" ± {:.1}%", 100.0 * e)),
            pct(self.over_under_fraction),
            pct(self.through_fraction),
            self.reimpact_radius
                .map_or("–".into(), |v| format!("{v:.3}")),
            self.reimpact_radius_over_r90
                .map_or("–".into(), |v| format!("{v:.2}")),
            self.reimpact_azimuth_deg
                .map_or("–".into(), |v| format!("{v:.0}")),
            100.0 * self.reimpacted_share,
            match (self.stream_height, self.rim_height) {
                (Some(st), Some(rim)) => format!(
                    "; the stream comes to the rim at {:.2} of its height (rms z {st:.4} a at {}–{} R90 against the rim's {rim:.4} a, the run's second half)",
                    st / rim,
                    APPROACH.0,
                    APPROACH.1
                ),
                _ => String::new(),
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::binary::{Binary, BinaryParams};
    use crate::reports::cv::disk_mask;

    /// One particle: id, position, inertial velocity about the accretor, mass.
    type Part = (u64, [f64; 3], [f64; 2], f64);

    /// A 3D snapshot at `orbit` of `parts`, velocities written in the turning frame.
    fn snapshot(b: &Binary, orbit: f64, parts: &[Part]) -> Snapshot {
        let n = parts.len();
        let mut s = Snapshot {
            dimension: 3,
            time: orbit * TAU,
            pos: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            vel: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            ..Snapshot::default()
        };
        for (i, &(id, x, u, m)) in parts.iter().enumerate() {
            s.id.push(id);
            s.mass.push(m);
            for k in 0..3 {
                s.pos[k][i] = x[k];
            }
            s.vel[0][i] = u[0] + b.omega * x[1];
            s.vel[1][i] = u[1] - b.omega * x[0];
        }
        s
    }

    /// Gas at radius `r`, azimuth `phi` (degrees), height `z` on a circular Kepler orbit.
    fn circular(b: &Binary, id: u64, r: f64, phi: f64, z: f64) -> Part {
        let (sn, c) = phi.to_radians().sin_cos();
        let vk = ((1.0 - b.mu) / r).sqrt();
        (id, [r * c, r * sn, z], [-vk * sn, vk * c], 1e-6)
    }

    /// Gas at radius `r`, azimuth `phi`, height `z` falling straight in (eccentricity 1).
    fn infalling(id: u64, r: f64, phi: f64, z: f64) -> Part {
        let (sn, c) = phi.to_radians().sin_cos();
        (id, [r * c, r * sn, z], [-0.5 * c, -0.5 * sn], 1e-6)
    }

    /// Rings at the centres of the H annuli (R90 = 0.5), three particles a column at
    /// z = 0, ±0.02 (rms 0.0163), 24 a ring.
    fn disk(b: &Binary) -> Vec<Part> {
        let mut parts = Vec::new();
        for k in 1..10 {
            let r = 0.05 * k as f64 + 0.025;
            for j in 0..24 {
                for z in [-0.02, 0.0, 0.02] {
                    parts.push(circular(b, parts.len() as u64, r, 15.0 * j as f64, z));
                }
            }
        }
        parts
    }

    /// q = 0.1, its disk ([`disk`]) and the first id a stream particle gets.
    fn setup() -> (Binary, Vec<Part>, u64) {
        let b = Binary::new(&BinaryParams::with_q(0.1));
        let base = disk(&b);
        let first = base.len() as u64;
        (b, base, first)
    }

    /// The tracker fed with snapshots of the stages (orbit, particles) in order, R90 = 0.5:
    /// its figures and notes.
    fn track(b: &Binary, stages: &[(f64, Vec<Part>)]) -> (Option<PassageFigures>, Vec<String>) {
        let mut t = PassageTracker::new();
        for (orbit, parts) in stages {
            let s = snapshot(b, *orbit, parts);
            t.feed(&s, &disk_mask(b, &s), Some(0.5));
        }
        let mut notes = Vec::new();
        (t.finish(&mut notes), notes)
    }

    /// Ten stream particles pass the rim (four over the disk, four under it, two through
    /// its midplane) and re-impact at R = 0.275 a, azimuth 30°; ten stop at the rim and
    /// drift inward slowly; a disk particle that was there from the start moves far inward
    /// and is not counted. The tracker finds the halves, the routes and the re-impact.
    #[test]
    fn the_tracker_tells_gas_passing_the_rim_from_gas_stopping_there() {
        let (b, base, first) = setup();
        // Orbit 0.05: twenty stream particles beyond the rim (R = 0.6 > 1.1 R90).
        let mut p1 = base.clone();
        p1.extend((0..20).map(|k| infalling(first + k, 0.6, 200.0, 0.0)));
        // Orbit 0.10: passers inside 0.75 R90, stoppers circular at the rim; an old disk
        // particle thrown inward.
        let mut p2 = base.clone();
        p2[0] = infalling(0, 0.325, 100.0, 0.0);
        for k in 0..10 {
            let z = [0.1, 0.1, 0.1, 0.1, -0.1, -0.1, -0.1, -0.1, 0.0, 0.0][k as usize];
            p2.push(infalling(first + k, 0.325, 150.0, z));
        }
        p2.extend((10..20).map(|k| circular(&b, first + k, 0.48, 190.0, 0.0)));
        // Orbit 0.40: passers circular at 0.275 a, 30°; stoppers 0.01 a further in.
        let mut p3 = base.clone();
        p3.extend((0..10).map(|k| circular(&b, first + k, 0.275, 30.0, 0.0)));
        p3.extend((10..20).map(|k| circular(&b, first + k, 0.47, 190.0, 0.0)));
        let stages = [(0.0, base), (0.05, p1), (0.10, p2), (0.40, p3)];
        let (f, notes) = track(&b, &stages);
        let f = f.expect("twenty arrivals");
        assert_eq!(f.arrived_particles, 20);
        // Exact: the figures are ratios of equal masses.
        assert!((f.passed_fraction - 0.5).abs() < 1e-12, "{f:?}");
        assert!((f.over_under_fraction.unwrap() - 0.4).abs() < 1e-12);
        assert!((f.through_fraction.unwrap() - 0.1).abs() < 1e-12);
        assert!((f.reimpact_radius.unwrap() - 0.275).abs() < 1e-12);
        assert!((f.reimpact_radius_over_r90.unwrap() - 0.55).abs() < 1e-12);
        assert!((f.reimpact_azimuth_deg.unwrap() - 30.0).abs() < 1e-9);
        assert_eq!(f.reimpacted_share, 1.0);
        // The stream was at 1.1–1.4 R90 only at orbit 0.05, in the run's first half.
        assert_eq!((f.stream_height, f.stream_to_rim_height), (None, None));
        assert!(f.rim_height.is_some());
        // Snapshots 0.3 orbit apart are too coarse for the figures to be trusted blindly.
        assert!(
            notes.iter().any(|n| n.contains("0.300 orbit apart")),
            "{notes:?}"
        );
        // The CSV has a row per window with the header's five columns.
        let csv = windows_csv(&f.windows);
        assert!(csv.lines().all(|l| l.split(',').count() == 5));
        assert_eq!(csv.lines().count(), 1 + f.windows.len());
    }

    /// Gas that stopped at the rim and, much later, reads eccentric there (a hot disk's
    /// turbulence) and then is found inside 0.75 R90 has not passed the rim: a passage
    /// counts only within SETTLE_ORBITS of the arrival. Ten particles arrive at orbit 0.05
    /// and sit circular at the rim until orbit 1.0, when they read eccentric (infalling) at
    /// 0.48 a, and at orbit 1.05 are inside 0.75 R90; ten more pass at once (orbit 0.1).
    #[test]
    fn gas_that_stopped_does_not_pass_later() {
        let (b, base, first) = setup();
        let with = |stoppers: &dyn Fn(u64) -> Part, passers: &dyn Fn(u64) -> Part| {
            let mut p = base.clone();
            p.extend((0..10).map(|k| stoppers(first + k)));
            p.extend((10..20).map(|k| passers(first + k)));
            p
        };
        let arriving = |id| infalling(id, 0.6, 200.0, 0.0);
        let at_rim = |id| circular(&b, id, 0.48, 190.0, 0.0);
        let passed = |id| circular(&b, id, 0.275, 30.0, 0.0);
        let stages: Vec<(f64, Vec<Part>)> = vec![
            (0.0, base.clone()),
            (0.05, with(&arriving, &arriving)),
            (0.1, with(&at_rim, &|id| infalling(id, 0.325, 150.0, 0.1))),
            (0.3, with(&at_rim, &passed)),
            (1.0, with(&|id| infalling(id, 0.48, 190.0, 0.0), &passed)),
            (1.05, with(&|id| circular(&b, id, 0.3, 150.0, 0.0), &passed)),
        ];
        let f = track(&b, &stages).0.expect("twenty arrivals");
        assert_eq!(f.arrived_particles, 20);
        // Exact: ratios of equal masses.
        assert!((f.passed_fraction - 0.5).abs() < 1e-12, "{f:?}");
    }

    /// The arrival windows hold whole orbits of snapshots, the same in a run ending at
    /// orbit 3 and one ending at orbit 6: a particle arrives (and stops) at every snapshot,
    /// 0.05 orbit apart, so each window but the first holds exactly 20 arrivals, whatever
    /// the round-off of the snapshot times at the windows' edges.
    #[test]
    fn arrival_windows_hold_whole_orbits_of_snapshots() {
        let (b, base, first) = setup();
        for last in [3.0, 6.0] {
            let mut parts = base.clone();
            let n = (last / 0.05f64).round() as u64;
            let stages: Vec<(f64, Vec<Part>)> = (0..=n)
                .map(|k| {
                    if k > 0 {
                        parts.push(circular(&b, first + k, 0.48, 190.0, 0.0));
                    }
                    (k as f64 * 0.05, parts.clone())
                })
                .collect();
            let f = track(&b, &stages).0.expect("arrivals");
            let counts: Vec<usize> = f.windows.iter().map(|w| w.arrived_particles).collect();
            assert_eq!(counts.iter().sum::<usize>(), f.arrived_particles);
            assert!(counts[1..].iter().all(|&c| c == 20), "{last}: {counts:?}");
            assert_eq!(counts.len(), last as usize - 1, "{last}: {counts:?}");
        }
    }

    /// A stream that stops at the rim passes nothing: every share reads +0, not the −0 an
    /// empty float sum gives (written "-0.0" to cv.json and "-0.0%" to the summary).
    #[test]
    fn a_stream_stopping_at_the_rim_passes_a_positive_zero() {
        let (b, base, first) = setup();
        let mut p1 = base.clone();
        p1.extend((0..10).map(|k| infalling(first + k, 0.6, 200.0, 0.0)));
        let mut p2 = base.clone();
        p2.extend((0..10).map(|k| circular(&b, first + k, 0.48, 190.0, 0.0)));
        let mut p3 = base.clone();
        p3.extend((0..10).map(|k| circular(&b, first + k, 0.47, 190.0, 0.0)));
        let stages = [(0.0, base), (0.05, p1), (0.1, p2), (0.4, p3)];
        let f = track(&b, &stages).0.expect("ten arrivals");
        assert_eq!(f.arrived_particles, 10);
        for share in [
            f.passed_fraction,
            f.over_under_fraction.unwrap(),
            f.through_fraction.unwrap(),
        ] {
            assert!(share == 0.0 && share.is_sign_positive(), "{f:?}");
        }
        assert!(
            f.windows
                .iter()
                .all(|w| w.passed_fraction.is_sign_positive())
        );
    }

    /// The stream's height at its approach against the rim's: the rms z of stream gas at
    /// 1.1–1.4 R90, pooled over the run's second half, over the rms z of the disk's gas at
    /// 0.9–1.1 R90. Stream gas in the first half, beyond 1.4 R90, on a disk orbit, or from
    /// the first snapshot is left out.
    #[test]
    fn the_stream_is_measured_against_the_rim_as_it_approaches() {
        let (b, base, first) = setup();
        // Four particles arrive (and are gone by orbit 0.25), so there are figures.
        let mut p1 = base.clone();
        p1.extend((0..4).map(|k| infalling(first + k, 0.6, 200.0, 0.0)));
        // First half (orbit 0.05 < 0.2): a thick stream at 1.25 R90, not counted.
        p1.extend((4..8).map(|k| infalling(first + k, 0.625, 200.0, 0.05)));
        let mut p2 = base.clone();
        p2.extend((0..4).map(|k| circular(&b, first + k, 0.48, 190.0, 0.0)));
        // Second half: the stream at ±z at 1.25 R90, and gas that must be left out.
        let second = |z: f64| {
            let mut p = base.clone();
            p.extend((0..4).map(|k| {
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                infalling(first + 10 + k, 0.625, 200.0, sign * z)
            }));
            p.push(infalling(first + 20, 0.8, 200.0, 0.3)); // 1.6 R90
            p.push(circular(&b, first + 21, 0.6, 200.0, 0.03)); // a disk orbit
            p
        };
        let stages = [
            (0.0, base.clone()),
            (0.05, p1),
            (0.1, p2),
            (0.25, second(0.01)),
            (0.4, second(0.02)),
        ];
        let f = track(&b, &stages).0.expect("four arrivals");
        // Exact, from the positions: equal masses, z² of 1e-4 and 4e-4 four times each; the
        // rim ring (R = 0.475) has columns at z = 0, ±0.02.
        let stream = (0.5f64 * (1e-4 + 4e-4)).sqrt();
        let rim = (0.0008f64 / 3.0).sqrt();
        assert!((f.stream_height.unwrap() - stream).abs() < 1e-15, "{f:?}");
        assert!((f.rim_height.unwrap() - rim).abs() < 1e-15, "{f:?}");
        assert!((f.stream_to_rim_height.unwrap() - stream / rim).abs() < 1e-12);
        assert!(
            f.summary_line()
                .contains(&format!("{:.2} of its height", stream / rim))
        );
    }

    /// Gas that has not yet had SETTLE_ORBITS to pass is not counted, and a run whose
    /// stream never reaches a disk gives no figures but a note.
    #[test]
    fn late_arrivals_are_not_counted_and_no_arrival_gives_a_note() {
        let (b, base, first) = setup();
        let mut p1 = base.clone();
        p1.push(circular(&b, first, 0.48, 190.0, 0.0));
        let (f, notes) = track(&b, &[(0.0, base), (0.1, p1)]);
        assert_eq!(f, None);
        assert!(
            notes[0].contains("no stream gas reached the rim"),
            "{notes:?}"
        );
    }
}
