//! Straightforward references for the sweep, used by its tests: every pair by brute force,
//! and the three sums from a full pair list with minimum-image distances (no ghosts, no
//! window), written independently of the sweep's bookkeeping.

use crate::boundary::{BoundaryKind, SimBox};
use crate::particles::Particles;
use crate::physics::artificial_viscosity::{av_velocity, balsara_factor};
use crate::physics::eos::cylindrical_radius;
use crate::physics::hydro::{ForceSide, force_pair, gradient_pair};
use crate::physics::pressure_energy::smoothed_pressure;
use crate::sweep::Physics;
use crate::sweep::local::{self, Local};

/// Every (i, j), j < i, of the local set (reals and ghosts, no ghost–ghost pair) closer than
/// the support, by testing all N² pairs.
pub fn brute_force_pairs<const D: usize>(local: &Local<D>, support: f64) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for i in 0..local.len() {
        for j in 0..i {
            if !local::class::pairs(local.class[i], local.class[j]) {
                continue;
            }
            let r2: f64 = (0..D)
                .map(|d| (local.pos[d][i] - local.pos[d][j]).powi(2))
                .sum();
            if r2 < support * support {
                out.push((i as u32, j as u32));
            }
        }
    }
    out
}

/// Separation r_i − r_j under the minimum-image convention on periodic axes.
fn min_image<const D: usize>(bx: &SimBox<D>, parts: &Particles<D>, i: usize, j: usize) -> [f64; D] {
    std::array::from_fn(|d| {
        let mut dx = parts.pos[d][i] - parts.pos[d][j];
        if bx.kinds[d] == BoundaryKind::Periodic {
            let l = bx.length(d);
            dx -= l * (dx / l).round();
        }
        dx
    })
}

/// Density, velocity gradient, acceleration and du/dt from a stored list of all pairs, for
/// boxes whose axes are periodic or open (no mirror walls).
pub fn full_list_minimum_image<const D: usize>(
    parts: &mut Particles<D>,
    bx: &SimBox<D>,
    phys: &Physics<D>,
) {
    assert!(
        bx.kinds.iter().all(|&k| k != BoundaryKind::Reflecting),
        "the reference handles periodic and open axes"
    );
    let n = parts.len();
    let support = phys.kernel.support();
    let mut list = Vec::new();
    for i in 0..n {
        for j in 0..i {
            let dx = min_image(bx, parts, i, j);
            let r = dx.iter().map(|x| x * x).sum::<f64>().sqrt();
            if r < support {
                list.push((i, j, dx, r));
            }
        }
    }
    // Σ m u W without the self term, for the pressure–energy formulation's p̄.
    let mut mu_w = vec![0.0; n];
    for i in 0..n {
        parts.rho[i] = parts.mass[i] * phys.kernel.w0();
        parts.interactions[i] = 0;
    }
    for &(i, j, _, r) in &list {
        let w = phys.kernel.w(r);
        parts.rho[i] += parts.mass[j] * w;
        parts.rho[j] += parts.mass[i] * w;
        mu_w[i] += parts.mass[j] * parts.u[j] * w;
        mu_w[j] += parts.mass[i] * parts.u[i] * w;
        parts.interactions[i] += 1;
        parts.interactions[j] += 1;
    }
    let pe_gamma = phys.pressure_energy_gamma();
    let mut av_scale: Vec<f64> = parts
        .alpha
        .iter()
        .map(|&a| phys.av.alpha_factor(a))
        .collect();
    for i in 0..n {
        let radius = cylindrical_radius(&parts.position(i));
        let (p, cs) = match pe_gamma {
            Some(g) => smoothed_pressure(
                g,
                mu_w[i],
                parts.mass[i],
                parts.u[i],
                phys.kernel.w0(),
                parts.rho[i],
            ),
            None => phys
                .eos
                .pressure_sound_speed(parts.rho[i], parts.u[i], radius),
        };
        parts.p[i] = p;
        parts.cs[i] = cs;
        for a in 0..D {
            for b in 0..D {
                parts.vgrad[a][b][i] = 0.0;
            }
            parts.acc[a][i] = 0.0;
        }
        parts.du[i] = 0.0;
        parts.diss[i] = 0.0;
    }
    for &(i, j, dx, r) in &list {
        let g = gradient_pair(
            &dx,
            phys.kernel.f(r),
            &parts.velocity(i),
            &parts.velocity(j),
        );
        let (si, sj) = (parts.mass[j] / parts.rho[j], parts.mass[i] / parts.rho[i]);
        for a in 0..D {
            for b in 0..D {
                parts.vgrad[a][b][i] += si * g[a][b];
                parts.vgrad[a][b][j] += sj * g[a][b];
            }
        }
    }
    if phys.av.balsara {
        for (i, b) in av_scale.iter_mut().enumerate() {
            let v: [[f64; D]; D] =
                std::array::from_fn(|a| std::array::from_fn(|c| parts.vgrad[a][c][i]));
            *b *= balsara_factor(&v, parts.cs[i], phys.kernel.h());
        }
    }
    let stress: Vec<[[f64; D]; D]> = (0..n)
        .map(|k| {
            let v: [[f64; D]; D] =
                std::array::from_fn(|a| std::array::from_fn(|c| parts.vgrad[a][c][k]));
            let nu = phys.nu(parts.cs[k], cylindrical_radius(&parts.position(k)));
            phys.viscosity.stress(&v, nu)
        })
        .collect();
    let side = |parts: &Particles<D>, k: usize| ForceSide {
        v: parts.velocity(k),
        v_av: av_velocity(
            &phys.av,
            phys.gravity.as_ref(),
            &parts.position(k),
            parts.velocity(k),
        ),
        rho: parts.rho[k],
        rho_inv: 1.0 / parts.rho[k],
        p: parts.p[k],
        cs: parts.cs[k],
        av_scale: av_scale[k],
        stress: stress[k],
        u: parts.u[k],
        y: pe_gamma.map_or(0.0, |g| (g - 1.0) * parts.u[k]),
    };
    for &(i, j, dx, r) in &list {
        let pf = force_pair(
            &dx,
            r,
            phys.kernel.f(r),
            &side(parts, i),
            &side(parts, j),
            &phys.av,
            phys.pair_terms(),
        );
        let (mi, mj) = (parts.mass[i], parts.mass[j]);
        for d in 0..D {
            parts.acc[d][i] += mj * pf.accel[d];
            parts.acc[d][j] -= mi * pf.accel[d];
        }
        parts.du[i] += mj * (pf.work_i + pf.heat_i);
        parts.du[j] += mi * (pf.work_j + pf.heat_j);
        parts.diss[i] += mj * pf.heat_i;
        parts.diss[j] += mi * pf.heat_j;
    }
}
