//! Shock tube (Sod 1978; any left/right states): equal-mass particles on lattices whose
//! spacings give the two densities, in 1, 2 or 3 dimensions (the tube along x, periodic
//! cross-section by default), checked against the exact Riemann solution.
//!
//! Resolution: `particles.n` particles along x in the left half. The reference spacing for
//! `particles.h_factor` is the x-spacing of the lower-density state (constant h must resolve
//! the sparser side).

use std::collections::BTreeMap;

use anyhow::{Result, bail};

use crate::analysis::riemann::{PrimitiveState, RiemannSolution};
use crate::analysis::{jump_position, x_profile};
use crate::boundary::BoundaryKind;
use crate::config::{Config, SodParams};
use crate::particles::Particles;
use crate::problems::{InitialState, lattice, make_box, smoothing_length};

pub(crate) fn params(cfg: &Config) -> SodParams {
    cfg.sod.clone().unwrap_or_default()
}

pub(crate) fn solution(cfg: &Config) -> Result<RiemannSolution> {
    let s = params(cfg);
    let gamma = match cfg.eos {
        crate::physics::eos::Eos::Ideal { gamma } => gamma,
        _ => bail!("key `eos.kind`: the shock tube needs an ideal gas"),
    };
    let st = |x: &crate::config::StateParams| PrimitiveState {
        rho: x.rho,
        v: x.v,
        p: x.p,
    };
    for (side, x) in [("left", &s.left), ("right", &s.right)] {
        for (key, v) in [("rho", x.rho), ("p", x.p)] {
            if !(v > 0.0 && v.is_finite()) {
                bail!("key `sod.{side}.{key}`: must be > 0, got {v}");
            }
        }
    }
    RiemannSolution::solve(st(&s.left), st(&s.right), gamma).map_err(|e| {
        anyhow::anyhow!("keys `sod.left` and `sod.right`: no exact solution for these states ({e})")
    })
}

/// The left state's lattice: its spacing x0/n and its count across the tube.
fn left_lattice(cfg: &Config) -> (f64, usize) {
    let s = params(cfg);
    let dx = s.x0 / cfg.particles.n.unwrap_or(0) as f64;
    (dx, ((s.width / dx).round() as usize).max(1))
}

/// Where the gas that started left of the diaphragm ends: the particles sorted by x, the
/// gap between the last one within the first `n_left` (the left state's count: equal
/// masses) and the next, split in proportion to the volumes m/ρ of the two gases either
/// side (`rho_left`, `rho_right`: at a contact the exact densities each side of it), so
/// that the set-up's lattices give the diaphragm itself. SPH particles move with the gas,
/// and at a contact no gas crosses, so this is the contact's position in mass, immune to
/// how the density is smoothed or binned (a conductivity that smooths u moves it only by
/// moving gas).
pub fn mass_interface<const D: usize>(
    p: &Particles<D>,
    n_left: usize,
    rho_left: f64,
    rho_right: f64,
) -> Option<f64> {
    if n_left == 0 || n_left >= p.len() || !(rho_left > 0.0 && rho_right > 0.0) {
        return None;
    }
    let mut x = p.pos[0].clone();
    let (lo, pivot, _) = x.select_nth_unstable_by(n_left, f64::total_cmp);
    let right = *pivot;
    let left = lo.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let share = (1.0 / rho_left) / (1.0 / rho_left + 1.0 / rho_right);
    Some(left + share * (right - left))
}

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    let s = params(cfg);
    // Refuse states the exact solver cannot handle before building anything.
    solution(cfg)?;
    if !(s.x0 > 0.0 && s.x0 < s.length) {
        bail!("key `sod.x0`: the diaphragm must lie inside (0, sod.length)");
    }
    if !(s.width > 0.0) {
        bail!("key `sod.width`: must be > 0");
    }
    if let Some([lo, hi]) = s.window
        && !(lo < hi && lo.is_finite() && hi.is_finite())
    {
        bail!("key `sod.window`: must be [lo, hi] with lo < hi, got [{lo}, {hi}]");
    }
    let n = cfg.particles.n.unwrap_or(0);
    let (l, r) = (s.left, s.right);
    // Left lattice: cubic, spacing dx.
    let (dx, n_cross_l) = left_lattice(cfg);
    let mass = l.rho * dx.powi(D as i32);
    let width = n_cross_l as f64 * dx;
    // Right lattice: cross-section spacing close to the ideal (m/ρ_R)^(1/D), dividing the
    // width exactly; x-spacing so that the particle mass is the same.
    let ideal = (mass / r.rho).powf(1.0 / D as f64);
    let n_cross_r = ((width / ideal).round() as usize).max(1);
    let dy_r = width / n_cross_r as f64;
    let dx_r = mass / (r.rho * dy_r.powi(D as i32 - 1));
    let n_x_r = right_count(s.x0, s.length, dx_r);
    if n_x_r == 0 {
        bail!("key `particles.n`: too few particles for the right state");
    }
    let mut p = Particles::new();
    let eos = cfg.eos;
    let mut add_block = |lo_x: f64,
                         spacing: [f64; D],
                         counts: [usize; D],
                         st: crate::config::StateParams|
     -> Result<()> {
        let mut lo = [0.0; D];
        lo[0] = lo_x;
        for x in lattice::cuboid(lo, spacing, counts)? {
            let mut v = [0.0; D];
            v[0] = st.v;
            let id = p.len() as u64;
            p.push(id, x, v, mass, eos.internal_energy(st.rho, st.p));
        }
        Ok(())
    };
    let mut counts_l = [n_cross_l; D];
    counts_l[0] = n;
    let mut counts_r = [n_cross_r; D];
    counts_r[0] = n_x_r;
    let mut sp_r = [dy_r; D];
    sp_r[0] = dx_r;
    // Both blocks together within the bound, before either is built.
    let ratio = |e: anyhow::Error| {
        anyhow::anyhow!(
            "{e} (with sod.left.rho / sod.right.rho = {:e} and sod.length = {})",
            l.rho / r.rho,
            s.length
        )
    };
    let both = crate::limits::lattice_count(counts_l).map_err(ratio)? as u64
        + crate::limits::lattice_count(counts_r).map_err(ratio)? as u64;
    crate::limits::check_memory::<D>(both, "particles.n")?;
    if both > crate::limits::MAX_PARTICLES {
        bail!(
            "key `particles.n`: the tube would hold {both} particles, more than the {} a run can hold",
            crate::limits::MAX_PARTICLES
        );
    }
    add_block(0.0, [dx; D], counts_l, l)?;
    add_block(s.x0, sp_r, counts_r, r)?;

    let mut max = [width; D];
    max[0] = s.length;
    let mut kinds = [BoundaryKind::Periodic; D];
    kinds[0] = BoundaryKind::Reflecting;
    let bx = make_box(cfg, [0.0; D], max, kinds);
    let sparse = if l.rho < r.rho { dx } else { dx_r };
    Ok(InitialState::new(p, bx, smoothing_length(cfg, sparse)))
}

/// The right state's count of cells `dx` along x: those that fill `(x0, length)` best
/// while the last cell-centred particle stays inside the tube (off the wall at `length`).
fn right_count(x0: f64, length: f64, dx: f64) -> usize {
    // `as usize` saturates; the bound keeps the count far from overflow.
    let mut k = ((length - x0) / dx).round().clamp(0.0, 1e15) as usize;
    // The last particle as `lattice::cuboid` places it.
    while k > 0 && x0 + (k as f64 - 1.0 + 0.5) * dx >= length {
        k -= 1;
    }
    k
}

/// A discontinuity of the exact solution at time t: its position, the densities on its
/// two sides, and the window `[lo, hi]` that holds it and no other wave (half-way to the
/// neighbouring wave edges, or the tube's ends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Front {
    /// `shock` (the right-moving shock), `left_shock` or `contact`.
    pub name: &'static str,
    pub exact: f64,
    pub rho_left: f64,
    pub rho_right: f64,
    pub lo: f64,
    pub hi: f64,
}

/// The exact solution's shocks (where p* exceeds the state ahead by more than 1e-6 of it)
/// and its contact (where ρ*_L and ρ*_R differ by more than 1e-6 of the larger), in the
/// tube [0, length] with the diaphragm at x0, at t > 0. Waves weaker than that bound no
/// window.
pub fn fronts(sol: &RiemannSolution, x0: f64, length: f64, t: f64) -> Vec<Front> {
    let w = sol.wave_speeds();
    let (l, r) = (sol.left(), sol.right());
    // A wave is there where p* differs from the state it runs into by more than 1e-6 of it.
    let wave = |p_ahead: f64| (sol.p_star() - p_ahead).abs() > 1e-6 * p_ahead;
    let (rl, rs) = (sol.rho_star_left(), sol.rho_star_right());
    let contact = (rl - rs).abs() > 1e-6 * rl.max(rs);
    let mut edges = Vec::new();
    if wave(l.p) {
        edges.extend([w.left_head, w.left_tail]);
    }
    if contact {
        edges.push(w.contact);
    }
    if wave(r.p) {
        edges.extend([w.right_tail, w.right_head]);
    }
    let edges: Vec<f64> = edges.iter().map(|s| x0 + s * t).collect();
    // Half-way to the nearest distinct wave edge on either side (or the tube's end).
    let window = |x: f64| {
        let gap = 1e-9 * length;
        let below = edges
            .iter()
            .copied()
            .filter(|&e| e < x - gap)
            .fold(0.0, f64::max);
        let above = edges
            .iter()
            .copied()
            .filter(|&e| e > x + gap)
            .fold(length, f64::min);
        let lo = if below > 0.0 { 0.5 * (below + x) } else { 0.0 };
        let hi = if above < length {
            0.5 * (above + x)
        } else {
            length
        };
        (lo, hi)
    };
    let mut out = Vec::new();
    let mut push = |name, exact: f64, rho_left, rho_right| {
        if exact > 0.0 && exact < length {
            let (lo, hi) = window(exact);
            out.push(Front {
                name,
                exact,
                rho_left,
                rho_right,
                lo,
                hi,
            });
        }
    };
    if wave(l.p) && sol.p_star() > l.p {
        push("left_shock", x0 + w.left_head * t, l.rho, rl);
    }
    if contact {
        push("contact", x0 + w.contact * t, rl, rs);
    }
    if wave(r.p) && sol.p_star() > r.p {
        push("shock", x0 + w.right_head * t, rs, r.rho);
    }
    out
}

/// Each front of [`fronts`] measured in an x-binned density profile: the crossing of the
/// mid-value of its jump within its window ([`jump_position`]), as (front, position).
pub fn measure_fronts(
    sol: &RiemannSolution,
    x0: f64,
    length: f64,
    t: f64,
    profile: &[(f64, f64)],
) -> Vec<(Front, f64)> {
    fronts(sol, x0, length, t)
        .into_iter()
        .filter_map(|f| {
            jump_position(profile, f.lo, f.hi, f.rho_left, f.rho_right, f.exact).map(|x| (f, x))
        })
        .collect()
}

/// L1 norms (volume-weighted) of ρ, v_x and p against the exact solution (over `sod.window`
/// if set), and the positions of the shocks and the contact ([`measure_fronts`] on the
/// x-binned density): `shock_position` (the right-moving shock), `left_shock_position`,
/// `contact_position`, each with its exact value and its distance from it in particle
/// spacings (`*_offset_spacings`): at a shock the post-shock spacing, at the contact the
/// sparser side's. At the contact also `contact_pressure_blip`: the largest |p − p*| / p*
/// within its window, and `contact_mass_position` ([`mass_interface`]: where the left
/// gas ends) with `contact_mass_offset_spacings`.
pub fn errors<const D: usize>(
    cfg: &Config,
    p: &Particles<D>,
    t: f64,
) -> Result<BTreeMap<String, f64>> {
    let s = params(cfg);
    let sol = solution(cfg)?;
    let exact = |i: usize| sol.sample((p.pos[0][i] - s.x0) / t);
    let [lo, hi] = s.window.unwrap_or([f64::NEG_INFINITY, f64::INFINITY]);
    let inside = |i: usize| (lo..=hi).contains(&p.pos[0][i]);
    // Volume-weighted as `analysis::l1_norm`, over the window's particles.
    let l1 = |err: &dyn Fn(usize) -> f64| {
        let (mut num, mut den) = (0.0, 0.0);
        for i in (0..p.len()).filter(|&i| inside(i)) {
            let v = p.mass[i] / p.rho[i];
            num += v * err(i).abs();
            den += v;
        }
        num / den
    };
    let mut e = BTreeMap::new();
    e.insert("l1_density".into(), l1(&|i| p.rho[i] - exact(i).rho));
    e.insert("l1_velocity".into(), l1(&|i| p.vel[0][i] - exact(i).v));
    e.insert("l1_pressure".into(), l1(&|i| p.p[i] - exact(i).p));

    let mass = p.mass[0];
    let bin = (mass / p.rho.iter().cloned().fold(0.0, f64::max)).powf(1.0 / D as f64);
    let profile = x_profile(p, bin);
    for (f, x) in measure_fronts(&sol, s.x0, s.length, t, &profile) {
        let rho_spacing = match f.name {
            "contact" => f.rho_left.min(f.rho_right),
            _ => f.rho_left.max(f.rho_right),
        };
        let spacing = (mass / rho_spacing).powf(1.0 / D as f64);
        e.insert(format!("{}_position", f.name), x);
        e.insert(format!("{}_position_exact", f.name), f.exact);
        e.insert(
            format!("{}_offset_spacings", f.name),
            (x - f.exact).abs() / spacing,
        );
    }
    if let Some(f) = fronts(&sol, s.x0, s.length, t)
        .into_iter()
        .find(|f| f.name == "contact")
    {
        let (_, n_cross) = left_lattice(cfg);
        let n_left = cfg.particles.n.unwrap_or(0) * n_cross.pow(D as u32 - 1);
        if let Some(x) = mass_interface(p, n_left, f.rho_left, f.rho_right) {
            let spacing = (mass / f.rho_left.min(f.rho_right)).powf(1.0 / D as f64);
            e.insert("contact_mass_position".into(), x);
            e.insert(
                "contact_mass_offset_spacings".into(),
                (x - f.exact).abs() / spacing,
            );
        }
        let ps = sol.p_star();
        let blip = (0..p.len())
            .filter(|&i| (f.lo..=f.hi).contains(&p.pos[0][i]))
            .map(|i| (p.p[i] - ps).abs() / ps)
            .fold(0.0, f64::max);
        e.insert("contact_pressure_blip".into(), blip);
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `problems/sod.toml` with `sets` and `particles.n = n`, set up in 1D (with every check of a
    /// set-up: particles inside the box, the box against the kernel).
    fn set_up(n: usize, sets: &[&str]) -> Result<InitialState<1>> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/sod.toml");
        let mut sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        sets.push(format!("particles.n={n}"));
        let cfg = Config::load(&path, &sets)?;
        crate::problems::setup::<1>(&cfg)
    }

    #[test]
    fn every_resolution_from_1_to_1000_sets_up_inside_the_tube() {
        // With h from `h_factor`, a coarse tube is refused only where the kernel does not
        // fit the box (4h > 1, n < 24), by that message, or where the right state gets no
        // particle (n ≤ 4), naming the key.
        for n in 1..=1000 {
            match set_up(n, &[]) {
                Ok(_) => assert!(n >= 24, "n = {n}"),
                Err(e) => {
                    let e = format!("{e:#}");
                    let kernel = e.contains("too small for the kernel");
                    let few = n <= 4 && e.contains("particles.n");
                    assert!(n < 24 && (kernel || few), "n = {n}: {e}");
                }
            }
        }
        // With a small fixed h every n sets up that gives the right state a particle.
        for n in 1..=1000 {
            match set_up(n, &["particles.h=0.001"]) {
                Ok(_) => assert!(n > 4, "n = {n}"),
                Err(e) => {
                    let e = format!("{e:#}");
                    assert!(n <= 4 && e.contains("particles.n"), "n = {n}: {e}");
                }
            }
        }
    }

    /// The exact density in bins of width `bin` over [0, 1] (the value at each bin centre),
    /// and the same averaged over ±`smooth` bins (a symmetric smoothing, which leaves the
    /// mid-value crossing of an isolated jump in place).
    fn exact_profiles(
        sol: &RiemannSolution,
        t: f64,
        bin: f64,
        smooth: usize,
    ) -> [Vec<(f64, f64)>; 2] {
        let n = (1.0 / bin).round() as usize;
        let raw: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let x = (k as f64 + 0.5) * bin;
                (x, sol.sample((x - 0.5) / t).rho)
            })
            .collect();
        let smoothed = (smooth..n - smooth)
            .map(|k| {
                let mean = raw[k - smooth..=k + smooth]
                    .iter()
                    .map(|p| p.1)
                    .sum::<f64>()
                    / (2 * smooth + 1) as f64;
                (raw[k].0, mean)
            })
            .collect();
        [raw, smoothed]
    }

    fn riemann(l: (f64, f64, f64), r: (f64, f64, f64)) -> RiemannSolution {
        let st = |(rho, v, p)| PrimitiveState { rho, v, p };
        RiemannSolution::solve(st(l), st(r), 1.4).unwrap()
    }

    #[test]
    fn fronts_are_found_on_exact_profiles_whichever_way_the_density_jumps() {
        // Sod (ρ falls across contact and shock), Lax (ρ rises across the contact onto the
        // post-shock plateau) and the strong shock (the same, a 10× rise, contact and shock
        // 0.047 apart), each at a time when the waves are well inside [0, 1].
        let cases = [
            ("sod", riemann((1.0, 0.0, 1.0), (0.125, 0.0, 0.1)), 0.2),
            (
                "lax",
                riemann((0.445, 0.698, 3.528), (0.5, 0.0, 0.571)),
                0.14,
            ),
            (
                "strong",
                riemann((1.0, 0.0, 1000.0), (1.0, 0.0, 0.01)),
                0.012,
            ),
        ];
        let bin = 1e-3;
        for (name, sol, t) in cases {
            let f = fronts(&sol, 0.5, 1.0, t);
            let names: Vec<&str> = f.iter().map(|f| f.name).collect();
            assert_eq!(names, ["contact", "shock"], "{name}");
            for (k, profile) in exact_profiles(&sol, t, bin, 5).iter().enumerate() {
                let found = measure_fronts(&sol, 0.5, 1.0, t, profile);
                assert_eq!(found.len(), 2, "{name}");
                for (front, x) in found {
                    // Bins straddling a step put the interpolated crossing half-way between
                    // their centres: within half a bin of the step. One bin is the bound.
                    assert!(
                        (x - front.exact).abs() <= bin,
                        "{name} ({}): {} at {x}, exact {}",
                        ["raw", "smoothed"][k],
                        front.name,
                        front.exact
                    );
                }
            }
        }
    }

    #[test]
    fn fronts_of_other_patterns() {
        // Two shocks (colliding streams): both shocks, no contact (ρ*_L = ρ*_R).
        let collide = riemann((1.0, 1.0, 1.0), (1.0, -1.0, 1.0));
        let names: Vec<&str> = fronts(&collide, 0.5, 1.0, 0.1)
            .iter()
            .map(|f| f.name)
            .collect();
        assert_eq!(names, ["left_shock", "shock"]);
        // A stationary contact: no wave but the contact, with the whole tube as its window.
        let contact = riemann((1.0, 0.0, 1.0), (0.125, 0.0, 1.0));
        let f = fronts(&contact, 0.5, 1.0, 0.2);
        assert_eq!(f.len(), 1);
        assert_eq!(
            (f[0].name, f[0].exact, f[0].lo, f[0].hi),
            ("contact", 0.5, 0.0, 1.0)
        );
        // Two rarefactions (the 123 problem): nothing to measure.
        let fans = riemann((1.0, -2.0, 0.4), (1.0, 2.0, 0.4));
        assert!(fronts(&fans, 0.5, 1.0, 0.15).is_empty());
    }

    /// The mass interface is the left gas's edge, whatever the order of the store and
    /// however the density is smoothed: on the set-up it lies between the lattices; move
    /// the left gas and it moves with it.
    #[test]
    fn the_mass_interface_follows_the_left_gas() {
        let mut s = set_up(200, &[]).unwrap().particles;
        let n_left = 200;
        let edge = |p: &Particles<1>| {
            let l = (0..n_left).map(|i| p.pos[0][i]).fold(f64::MIN, f64::max);
            let r = (n_left..p.len())
                .map(|i| p.pos[0][i])
                .fold(f64::MAX, f64::min);
            (l, r)
        };
        // Sod's states, (ρ_L, ρ_R) = (1, 0.125): the gap between the lattices is split 1 : 8.
        let x = mass_interface(&s, n_left, 1.0, 0.125).unwrap();
        let (l, r) = edge(&s);
        assert!((x - (l + (r - l) / 9.0)).abs() < 1e-15);
        // On the set-up it is the diaphragm itself, to round-off (the gap's midpoint lies
        // (Δx_R − Δx_L)/4 to the right: 0.22 of the sparse spacing).
        assert!((x - 0.5).abs() < 1e-12, "{x}");
        // Compress the right gas towards the wall and push the left gas 0.03 after it.
        for i in 0..s.len() {
            let x = &mut s.pos[0][i];
            *x = if i < n_left {
                *x + 0.03
            } else {
                0.53 + (*x - 0.5) * 0.9
            };
        }
        s.pos[0].reverse();
        let moved = mass_interface(&s, n_left, 1.0, 0.125).unwrap();
        assert!((moved - x - 0.03).abs() < 0.01, "{moved} {x}");
        assert_eq!(mass_interface(&s, 0, 1.0, 0.125), None);
        assert_eq!(mass_interface(&s, s.len(), 1.0, 0.125), None);
    }

    #[test]
    fn the_right_state_keeps_its_density_and_the_particles_their_mass() {
        for n in [100, 101, 300, 800] {
            let s = set_up(n, &[]).unwrap();
            let p = &s.particles;
            assert!(p.mass.iter().all(|&m| m == p.mass[0]), "n = {n}");
            // Right of the diaphragm: particle spacing m / ρ_R, the sod.toml value 0.125.
            let mut right: Vec<f64> = p.pos[0].iter().copied().filter(|&x| x > 0.5).collect();
            right.sort_by(f64::total_cmp);
            let spacing = right[1] - right[0];
            assert!((p.mass[0] / spacing / 0.125 - 1.0).abs() < 1e-12, "n = {n}");
            assert!(*right.last().unwrap() < 1.0, "n = {n}");
        }
    }
}
