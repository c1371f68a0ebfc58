//! A cataclysmic variable (paper, Section 4): a Roche binary (`[binary]`) whose accretion
//! disk is built by the gas stream from L1 (`[stream]`), at constant h. The run starts with
//! the stream's first release; the box is open (particles leave through the binary's sinks,
//! `physics::mass_transfer`), 2D in the orbital plane or 3D.
//!
//! Figures (`summary.json` `errors`): for a test stream (`stream.width = 0`) its closest
//! approach to the accretor r_min, its launch angle at L1 and its circularisation radius
//! r_circ = j²/GM1 (j the specific angular momentum about the accretor at r_min), each
//! beside the formula of exact-solutions.md 4b; and the disk's radius holding 90% of its
//! mass and its mass fraction.

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::analysis::observer::Surface;
use crate::analysis::roche;
use crate::boundary::BoundaryKind;
use crate::config::Config;
use crate::particles::Particles;
use crate::physics::binary::{Binary, Region};
use crate::physics::eos::Eos;
use crate::physics::mass_transfer::MassTransfer;
use crate::problems::{InitialState, make_box};

/// The default box: the accretor's lobe, L1 and room for the stream and the overflow; the
/// donor's lobe beyond L1 is a sink, so the box ends a little past L1.
fn default_box<const D: usize>(q: f64) -> ([f64; D], [f64; D]) {
    let d = roche::l1_distance(q);
    let mut lo = [0.0; D];
    let mut hi = [0.0; D];
    lo[0] = -d - 0.1;
    hi[0] = 0.7;
    lo[1] = -0.7;
    hi[1] = 0.7;
    if D == 3 {
        lo[2] = -0.3;
        hi[2] = 0.3;
    }
    (lo, hi)
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    let mt = MassTransfer::from_config(cfg).expect("validated: [binary] present");
    if mt.stream.is_none() {
        bail!("table `[stream]`: missing (a cv problem's gas comes through L1)");
    }
    if let Some(s) = &cfg.stream
        && s.start > 0.0
        && cfg.initial_disk.is_none()
    {
        bail!(
            "key `stream.start`: a cv problem's gas all comes through L1, so its stream starts at \
             t = 0 (got {}); a later start needs gas already in place ([initial_disk])",
            s.start
        );
    }
    let h = cfg.particles.h.expect("validated: particles.h present");
    // A disk inside the accretor's Roche lobe must be more than one kernel wide: a support
    // reaching from the white dwarf to L1 resolves neither the stream nor the disk, and
    // every particle would neighbour every other as the stream builds the disk.
    let support = cfg.particles.kernel.support_factor() * h;
    let d_l1 = roche::l1_distance(mt.binary.q);
    if !(support < d_l1) {
        bail!(
            "key `particles.h`: the kernel's support ({}·h = {} a) reaches from the white dwarf \
             past L1 ({d_l1:.4} a away at q = {}); a disk needs h well below {:.4} a",
            cfg.particles.kernel.support_factor(),
            crate::limits::show(support),
            mt.binary.q,
            d_l1 / cfg.particles.kernel.support_factor()
        );
    }
    let (lo, hi) = default_box::<D>(mt.binary.q);
    let bx = make_box(cfg, lo, hi, [BoundaryKind::Open; D]);
    let l1 = roche::l1_point(mt.binary.q);
    for d in 0..D {
        // The key and the value at fault: the lower or the upper face on this axis.
        let (key, face) = if bx.min[d] < l1[d] {
            ("max", bx.max[d])
        } else {
            ("min", bx.min[d])
        };
        if !(bx.min[d] < l1[d] && l1[d] < bx.max[d]) {
            bail!(
                "key `domain.{key}`: the box must hold L1 at ({:.4}, 0{}) where the stream \
                 starts, but its {key} along {} is {face}",
                l1[0],
                if D == 3 { ", 0" } else { "" },
                ["x", "y", "z"][d]
            );
        }
    }
    let mut p = Particles::<D>::new();
    let mut next_id = 0;
    if let Some(disk) = &cfg.initial_disk {
        let stream = mt.stream.expect("checked above");
        let (eos, cooling, u_stream) = (cfg.eos, cfg.cooling, mt.u_inject());
        // An ideal gas starts at the cooling's target temperature where there is one (the
        // disk's, which the stream need not share), else at the stream's; its scale height
        // is that of P/ρ = (γ − 1) u.
        let thermo = move |r: f64| match (eos, cooling) {
            (Eos::Ideal { gamma }, Some(c)) => {
                let u = c.target_u(gamma, r);
                (u, ((gamma - 1.0) * u).sqrt())
            }
            (Eos::Ideal { gamma }, None) => (u_stream, ((gamma - 1.0) * u_stream).sqrt()),
            _ => (0.0, eos.pressure_sound_speed(1.0, 0.0, r).1),
        };
        let n = disk.place(&mt.binary, h, stream.particle_mass, thermo, 0, &mut p);
        next_id = n as u64;
    }
    let mut st = mt.start_state(cfg.particles.seed, next_id);
    // The releases due at t = 0 (none if the stream starts later); the run books them with
    // its initial particles.
    let mut budget = crate::io::summary::MassBudget::default();
    mt.inject(&mut st, &mut p, 0.0, &mut budget, |_| [0.0; D]);
    Ok(InitialState {
        injector: Some(st),
        ..InitialState::new(p, bx, h)
    })
}

/// The radius holding `fraction` of the mass of the particles for which `pick` holds, in
/// the orbital plane about the accretor (0 if none).
pub fn mass_radius<const D: usize>(
    p: &Particles<D>,
    fraction: f64,
    pick: impl Fn(usize) -> bool,
) -> f64 {
    let rm: Vec<(f64, f64)> = (0..p.len())
        .filter(|&i| pick(i))
        .map(|i| (p.pos[0][i].hypot(p.pos[1][i]), p.mass[i]))
        .collect();
    crate::analysis::weighted_quantile(rm, fraction).unwrap_or(0.0)
}

/// The stream's first pass, measured on the particles in order of release (ids): from L1
/// inwards to the first minimum of the distance to the accretor. The distance is first
/// averaged over 9 consecutive releases (a nozzle of finite width spreads neighbouring
/// particles across the stream) to find the minimum's place, then a parabola fitted to the
/// raw distances of the 13 releases around it gives its value (an average alone would bias
/// r_min high by the path's curvature). Returns (r_min, the particle nearest that minimum)
/// or None if the stream has not yet turned.
fn first_periastron<const D: usize>(p: &Particles<D>) -> Option<(f64, usize)> {
    const W: usize = 9;
    const FIT: usize = 6;
    let mut order: Vec<usize> = (0..p.len()).collect();
    // Youngest first: the highest id was released last, nearest L1.
    order.sort_by_key(|&i| std::cmp::Reverse(p.id[i]));
    let r: Vec<f64> = order
        .iter()
        .map(|&i| (0..D).map(|d| p.pos[d][i].powi(2)).sum::<f64>().sqrt())
        .collect();
    if r.len() < W + 2 * FIT {
        return None;
    }
    let smooth: Vec<f64> = r
        .windows(W)
        .map(|w| w.iter().sum::<f64>() / W as f64)
        .collect();
    let mut best = (f64::INFINITY, 0);
    let mut turned = false;
    for (k, &s) in smooth.iter().enumerate() {
        if s < best.0 {
            best = (s, k);
        } else if s > best.0 * 1.1 {
            // Receding clearly: the minimum is behind us.
            turned = true;
            break;
        }
    }
    if !turned {
        return None;
    }
    let c = (best.1 + W / 2).clamp(FIT, r.len() - 1 - FIT);
    // Least-squares parabola r = a + b k + c k² over k ∈ [−FIT, FIT] (symmetric sums).
    let (mut s0, mut s2, mut s4, mut t0, mut t1, mut t2) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in -(FIT as i64)..=(FIT as i64) {
        let (kf, rk) = (k as f64, r[(c as i64 + k) as usize]);
        s0 += 1.0;
        s2 += kf * kf;
        s4 += kf.powi(4);
        t0 += rk;
        t1 += kf * rk;
        t2 += kf * kf * rk;
    }
    let b = t1 / s2;
    let cc = (s0 * t2 - s2 * t0) / (s0 * s4 - s2 * s2);
    let a = (t0 - cc * s2) / s0;
    let vertex = if cc > 0.0 {
        a - b * b / (4.0 * cc)
    } else {
        best.0
    };
    Some((vertex.min(best.0), order[c]))
}

/// The stream's launch angle below the line of centres at L1, in degrees: the mean
/// direction of motion of the particles 0.003–0.01 a from L1 on the accretor's side. There
/// the flow has left the saddle along its unstable direction (Lubow & Shu's angle) but has
/// not yet curved away; a launch speed c_s adds an epicyclic oscillation of relative size
/// ~c_s/(λ ξ) (λ ≈ 3.4 the saddle's growth rate), so the figure is Lubow & Shu's limit for
/// c_s ≲ 1e-3 (the test stream of `problems/roche_stream.toml`).
fn launch_angle<const D: usize>(p: &Particles<D>, q: f64) -> Option<f64> {
    let l1 = roche::l1_point(q);
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0);
    for i in 0..p.len() {
        let (dx, dy) = (p.pos[0][i] - l1[0], p.pos[1][i] - l1[1]);
        let speed = p.vel[0][i].hypot(p.vel[1][i]);
        if dx > 0.0 && (0.003..0.01).contains(&dx.hypot(dy)) && speed > 0.0 {
            sx += p.vel[0][i] / speed;
            sy += p.vel[1][i] / speed;
            n += 1;
        }
    }
    (n >= 5).then(|| (-sy).atan2(sx).to_degrees())
}

/// The binary's figures at the end of a run.
pub fn errors<const D: usize>(
    cfg: &Config,
    p: &Particles<D>,
    h: f64,
) -> Result<BTreeMap<String, f64>> {
    let mt = MassTransfer::from_config(cfg).expect("validated: [binary] present");
    let b = mt.binary;
    let q = b.q;
    let mut e = BTreeMap::new();
    e.insert("l1_distance".into(), roche::l1_distance(q));
    e.insert("stream_r_min_predicted".into(), roche::r_min_fit(q));
    e.insert("stream_r_circ_predicted".into(), roche::r_circ_fit(q));
    e.insert(
        "stream_launch_angle_predicted_deg".into(),
        roche::stream_angle(q).to_degrees(),
    );
    // The stream's own figures need one trajectory sampled in time: a test stream
    // (`stream.width = 0`); in a disk the particles nearest the accretor are disk gas.
    let test_stream = cfg.stream.is_some_and(|s| s.width == 0.0);
    if test_stream && let Some((r_min, i)) = first_periastron(p) {
        e.insert("stream_r_min".into(), r_min);
        let x = p.position(i);
        let v = p.velocity(i);
        // j about the accretor from the velocity relative to it, v + Ω × x.
        let j = x[0] * (v[1] + b.omega * x[0]) - x[1] * (v[0] - b.omega * x[1]);
        e.insert("stream_r_circ".into(), j * j / (1.0 - b.mu));
    }
    if test_stream && let Some(a) = launch_angle(p, q) {
        e.insert("stream_launch_angle_deg".into(), a);
    }
    let disk = |i: usize| is_disk(&b, p, i);
    let total: f64 = p.mass.iter().sum();
    let disk_mass: f64 = (0..p.len()).filter(|&i| disk(i)).map(|i| p.mass[i]).sum();
    e.insert(
        "disk_mass_fraction".into(),
        disk_mass / total.max(f64::MIN_POSITIVE),
    );
    e.insert("disk_radius_90".into(), mass_radius(p, 0.9, disk));
    e.insert("r_circ_over_h".into(), roche::r_circ_fit(q) / h);
    Ok(e)
}

/// Whether particle `i` is disk gas (near-circular orbit about the accretor).
pub fn is_disk<const D: usize>(b: &Binary, p: &Particles<D>, i: usize) -> bool {
    b.region(&p.position(i), &p.velocity(i), 0.0, 0.0) == Region::Disk
}

/// Bins of the disk-mass histogram in R ∈ [0, 1) about the accretor.
pub const DISK_BINS: usize = 1000;

/// Disk mass in `DISK_BINS` annuli of width 1/DISK_BINS (summed over ranks by the caller).
pub fn disk_histogram<const D: usize>(b: &Binary, p: &Particles<D>) -> Vec<f64> {
    let mut hist = vec![0.0; DISK_BINS];
    for i in 0..p.len() {
        if is_disk(b, p, i) {
            let r = p.pos[0][i].hypot(p.pos[1][i]);
            let k = ((r * DISK_BINS as f64) as usize).min(DISK_BINS - 1);
            hist[k] += p.mass[i];
        }
    }
    hist
}

/// The outer edge of the annulus in which the enclosed disk mass reaches `fraction`.
pub fn histogram_radius(hist: &[f64], fraction: f64) -> f64 {
    let total: f64 = hist.iter().sum();
    let mut acc = 0.0;
    for (k, m) in hist.iter().enumerate() {
        acc += m;
        if total > 0.0 && acc >= fraction * total {
            return (k + 1) as f64 / hist.len() as f64;
        }
    }
    0.0
}

/// Luminosity Σ m ε̇ of the disk, the stream and the spot (module doc of
/// `physics::binary::Region`), for a disk of radius `r_disk`, and what the binary's
/// observer sees of it at time `t` (`analysis::observer`: disk gas through the disk's
/// faces, spot gas through the rim, stream gas isotropically; eclipsed by the donor; face
/// light hidden behind the disk's edge at `rim`).
pub fn luminosities<const D: usize>(
    b: &Binary,
    p: &Particles<D>,
    r_disk: f64,
    rim: f64,
    support: f64,
    t: f64,
) -> [f64; 4] {
    let o = b.observer.direction(b.omega * t / std::f64::consts::TAU);
    let mut l = [0.0; 4];
    for i in 0..p.len() {
        let x = p.position(i);
        let (k, surface) = match b.region(&x, &p.velocity(i), r_disk, support) {
            Region::Disk => (0, Surface::Face),
            Region::Stream => (1, Surface::Isotropic),
            Region::Spot => (2, Surface::Rim),
        };
        let li = p.mass[i] * p.diss[i];
        l[k] += li;
        if li != 0.0 {
            let x3 = std::array::from_fn(|d| if d < D { x[d] } else { 0.0 });
            if surface != Surface::Face || !b.observer.rim_hides(x3, p.cs[i], rim, o) {
                l[3] += li * b.observer.visibility(x3, surface, o);
            }
        }
    }
    l
}

/// Sums over the disk gas with R ∈ [r_lo, r_hi) from which [`DiskModes`] follow (summed
/// over ranks by the caller): Σm, Σm cos φ, Σm sin φ, Σm cos 2φ, Σm sin 2φ, and the
/// mass-weighted osculating eccentricity vector Σm e_x, Σm e_y.
pub fn mode_sums<const D: usize>(b: &Binary, p: &Particles<D>, r_lo: f64, r_hi: f64) -> [f64; 7] {
    let mut s = [0.0; 7];
    for i in 0..p.len() {
        let (x, v) = (p.position(i), p.velocity(i));
        let r = x[0].hypot(x[1]);
        if !(r_lo..r_hi).contains(&r) {
            continue;
        }
        let e = b.eccentricity_vector(&x, &v);
        if (e.iter().map(|c| c * c).sum::<f64>()).sqrt()
            >= crate::physics::binary::STREAM_ECCENTRICITY
        {
            continue;
        }
        let m = p.mass[i];
        let (c, sn) = (x[0] / r, x[1] / r);
        s[0] += m;
        s[1] += m * c;
        s[2] += m * sn;
        s[3] += m * (c * c - sn * sn);
        s[4] += m * 2.0 * c * sn;
        s[5] += m * e[0];
        s[6] += m * e[1];
    }
    s
}

/// The radial window, in units of R90, over which the disk's eccentricity is measured.
///
/// Why the m = 1 amplitude, and why this window: a Kepler ellipse of eccentricity e
/// travelled at its own pace (particles uniform in mean anomaly: a ring in steady motion)
/// has ⟨e^{iφ}⟩ = ⟨cos f⟩ e^{iϖ} = −e e^{iϖ} (the time average of cos f over an orbit is −e),
/// so the mass-weighted amplitude |Σ m e^{iφ}| / Σ m of a ring is its eccentricity and its
/// phase points to apoastron, where the gas lingers. It needs positions only, not the
/// velocities that pressure, viscosity and the tides perturb particle by particle (the
/// osculating eccentricity of a single particle carries its epicyclic noise). The
/// eccentricity of a superhumping disk is excited at the 3:1 resonance near the disk's edge
/// and lives in the outer disk: the inner disk stays circular and, holding much of the
/// mass, would dilute the amplitude by its share; beyond R90 lie the sparse edge and the gas
/// the stream has just shocked, lopsided by construction (it arrives from one side). The
/// window [0.5, 1.0] R90 follows the disk as it grows, so the figure compares across
/// snapshots and runs. Caveats: an eccentric ring that reaches beyond R90 loses part of its
/// apoastron side to the window, which lowers the amplitude; a lopsided distribution of gas
/// on circular orbits reads as eccentricity too (hence the osculating vector beside it); N
/// particles placed at random give an amplitude of about 0.9/√N (the window's particle
/// count is reported).
pub const ECCENTRICITY_WINDOW: (f64, f64) = (0.5, 1.0);

/// The disk's non-axisymmetric state in a radial window ([`ECCENTRICITY_WINDOW`]
/// explains the choice): the m = 1 and m = 2 Fourier amplitudes of its
/// mass |Σ m e^{imφ}|/Σ m with their phases, and the mean osculating eccentricity vector.
/// For gas on one Kepler ellipse of eccentricity e the m = 1 amplitude is e and its phase
/// points to apoastron; the eccentricity vector points to periastron.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiskModes {
    pub mass: f64,
    pub m1: f64,
    /// Phase of the m = 1 mode (the apoastron's azimuth), degrees in [0, 360).
    pub m1_phase_deg: f64,
    pub m2: f64,
    /// Phase of the m = 2 mode, degrees in [0, 180).
    pub m2_phase_deg: f64,
    /// |mass-weighted mean osculating eccentricity vector|.
    pub e: f64,
    /// Its azimuth: the longitude of periastron in the turning frame, degrees in [0, 360).
    pub periastron_deg: f64,
}

impl DiskModes {
    /// From [`mode_sums`]; None without mass.
    pub fn from_sums(s: &[f64; 7]) -> Option<Self> {
        if !(s[0] > 0.0) {
            return None;
        }
        let deg = |y: f64, x: f64, m: f64| (y.atan2(x).to_degrees() / m).rem_euclid(360.0 / m);
        Some(Self {
            mass: s[0],
            m1: s[1].hypot(s[2]) / s[0],
            m1_phase_deg: deg(s[2], s[1], 1.0),
            m2: s[3].hypot(s[4]) / s[0],
            m2_phase_deg: deg(s[4], s[3], 2.0),
            e: s[5].hypot(s[6]) / s[0],
            periastron_deg: deg(s[6], s[5], 1.0),
        })
    }
}

/// `n` particles of mass `mass` on one Kepler ellipse about the accretor (semi-major axis
/// `a`, eccentricity `e`, periastron at turning-frame azimuth `varpi`), uniform in mean
/// anomaly (a ring in steady motion), each with its Kepler velocity written in the turning
/// frame: the reference against which the disk's mode measures are checked.
pub fn kepler_ring<const D: usize>(
    b: &Binary,
    a: f64,
    e: f64,
    varpi: f64,
    n: usize,
    mass: f64,
) -> Particles<D> {
    let gm = 1.0 - b.mu;
    let mut p = Particles::new();
    for k in 0..n {
        let mean = std::f64::consts::TAU * (k as f64 + 0.5) / n as f64;
        let (xy, u) = crate::analysis::kepler_point(gm, a, e, varpi, mean);
        let mut x = [0.0; D];
        let mut v = [0.0; D];
        x[..2].copy_from_slice(&xy);
        // Turning frame: subtract Ω × x.
        v[0] = u[0] + b.omega * x[1];
        v[1] = u[1] - b.omega * x[0];
        p.push(k as u64, x, v, mass, 0.0);
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::binary::BinaryParams;

    /// problems/overflow3d_cool.toml: an ideal gas with cooling starts its disk at the
    /// cooling's target u₀(R), its columns as tall as P/ρ = (γ − 1) u₀ makes them
    /// (H = √((γ − 1) u₀)/Ω_K; the adiabatic sound speed would make them √γ taller), while
    /// the stream's first releases carry the stream's own, cooler u.
    #[test]
    fn an_ideal_gas_disk_starts_at_the_cooling_target_and_the_stream_cooler() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems")
            .join("overflow3d_cool.toml");
        let cfg = Config::load(&path, &["particles.h=0.04".to_string()]).unwrap();
        let (Eos::Ideal { gamma }, Some(c), Some(s)) = (cfg.eos, cfg.cooling, cfg.stream) else {
            panic!("overflow3d_cool.toml: an ideal gas, [cooling] and [stream]");
        };
        let init = setup::<3>(&cfg).unwrap();
        let p = &init.particles;
        let b = Binary::new(cfg.binary.as_ref().unwrap());
        let gm = b.accretor().gm;
        let dx = cfg.initial_disk.unwrap().spacing(0.04);
        let u_stream = s.cs * s.cs / (gamma * (gamma - 1.0));
        let (mut disk, mut stream) = (0, 0);
        // Per ring (keyed by R to 1e-6): its radius and the tallest |z|.
        let mut rings: BTreeMap<i64, (f64, f64)> = BTreeMap::new();
        for i in 0..p.len() {
            let r = p.pos[0][i].hypot(p.pos[1][i]);
            if r < 0.5 {
                disk += 1;
                let u0 = c.target_u(gamma, r);
                assert!((p.u[i] - u0).abs() <= 1e-12 * u0, "u {} u0 {u0}", p.u[i]);
                let e = rings.entry((r * 1e6).round() as i64).or_insert((r, 0.0));
                e.1 = e.1.max(p.pos[2][i].abs());
            } else {
                stream += 1;
                assert!((p.u[i] - u_stream).abs() <= 1e-12 * u_stream);
                assert!(p.u[i] < 0.5 * c.target_u(gamma, r));
            }
        }
        assert!(disk > 1000 && stream >= 1, "{disk} disk, {stream} stream");
        // The top particle of each column sits at H Φ⁻¹((n − ½)/n), n = round(√(2π) H/Δ):
        // exact but for the quantile's 1.2e-9 and round-off.
        for (r, z_top) in rings.values() {
            let hz = ((gamma - 1.0) * c.target_u(gamma, *r)).sqrt() / (gm / r.powi(3)).sqrt();
            let n = ((2.0 * std::f64::consts::PI).sqrt() * hz / dx)
                .round()
                .max(1.0);
            let want = hz * crate::problems::cv_disk::normal_quantile((n - 0.5) / n);
            assert!((z_top - want).abs() < 1e-8 * hz, "R {r}: {z_top} vs {want}");
        }
    }

    #[test]
    fn an_eccentric_ring_reads_its_eccentricity_and_periastron() {
        let b = Binary::new(&BinaryParams::with_q(0.1));
        for (e, varpi_deg) in [(0.05, 30.0), (0.2, 250.0)] {
            let ring = kepler_ring::<2>(&b, 0.4, e, f64::to_radians(varpi_deg), 2000, 1e-6);
            let m = DiskModes::from_sums(&mode_sums(&b, &ring, 0.0, 1.0)).unwrap();
            // ⟨e^{iφ}⟩ over the mean anomaly is −e e^{iϖ} exactly; 2000 samples of a
            // smooth periodic function converge far below 1e-9.
            assert!((m.m1 - e).abs() < 1e-9, "m1 {} for e {e}", m.m1);
            assert!((m.m1_phase_deg - (varpi_deg + 180.0).rem_euclid(360.0)).abs() < 1e-6);
            // Every particle's osculating vector is the ellipse's.
            assert!((m.e - e).abs() < 1e-9);
            assert!((m.periastron_deg - varpi_deg).abs() < 1e-6);
            // An ellipse's m = 2 amplitude is second order in e: ⟨cos 2f⟩ = … = O(e²).
            assert!(m.m2 < e * e + 1e-9);
            assert!((m.mass - 2000.0 * 1e-6).abs() < 1e-15);
        }
        // The window leaves out what lies outside it: an apoastron beyond r_hi.
        let ring = kepler_ring::<2>(&b, 0.4, 0.2, 0.0, 2000, 1e-6);
        let inner = DiskModes::from_sums(&mode_sums(&b, &ring, 0.0, 0.4)).unwrap();
        assert!(inner.mass < 0.6 * 2000.0 * 1e-6);
        assert!(DiskModes::from_sums(&mode_sums(&b, &ring, 0.9, 1.0)).is_none());
    }
}
