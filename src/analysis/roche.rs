//! Roche geometry of a circular binary (exact-solutions.md, sections 4 and 4b; paper,
//! Section 4): the Roche potential, the inner Lagrangian point L1 and the potential's
//! curvature there. Pure functions of the mass ratio q = M2/M1 (M1 the accretor); nothing
//! here depends on the solver.
//!
//! Units: separation a = 1, G(M1 + M2) = 1, so Ω_orb = 1 and P_orb = 2π; μ = q/(1+q).
//! Frame (the simulation's, and every picture's): the accretor at the origin, the donor at
//! (−1, 0, 0) — on the left, as in the paper's Figures 5 and 6 — and the frame turning
//! counter-clockwise (Ω along +z) about the centre of mass at (−μ, 0, 0).

/// μ = M2/(M1 + M2) = q/(1+q).
pub fn mu(q: f64) -> f64 {
    q / (1.0 + q)
}

/// Position of the centre of mass in the simulation frame.
pub fn centre_of_mass(q: f64) -> [f64; 3] {
    [-mu(q), 0.0, 0.0]
}

/// Position of the donor in the simulation frame.
pub const DONOR: [f64; 3] = [-1.0, 0.0, 0.0];

/// Distances from the accretor and from the donor.
fn distances(x: [f64; 3]) -> (f64, f64) {
    let r1 = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    let r2 = ((x[0] + 1.0).powi(2) + x[1] * x[1] + x[2] * x[2]).sqrt();
    (r1, r2)
}

/// The Roche potential in the turning frame (exact-solutions.md 4b):
/// Φ = −(1−μ)/r1 − μ/r2 − ½ Ω² ((x+μ)² + y²).
pub fn potential(q: f64, x: [f64; 3]) -> f64 {
    let m = mu(q);
    let (r1, r2) = distances(x);
    -(1.0 - m) / r1 - m / r2 - 0.5 * ((x[0] + m).powi(2) + x[1] * x[1])
}

/// The force balance along the line of centres at distance `d` from the accretor towards
/// the donor: (1−μ)/d² − μ/(1−d)² − (d − μ), whose root in (0, 1) is L1.
fn l1_balance(m: f64, d: f64) -> f64 {
    (1.0 - m) / (d * d) - m / ((1.0 - d) * (1.0 - d)) - (d - m)
}

/// Distance of L1 from the accretor (units of a): the root of the quintic
/// (1−μ)/d² − μ/(1−d)² − (d − μ) = 0 between the stars, by bisection to machine precision
/// (the balance falls monotonically from +∞ at d → 0 to −∞ at d → 1). `q` must be > 0.
pub fn l1_distance(q: f64) -> f64 {
    let m = mu(q);
    let (mut lo, mut hi) = (1e-9_f64, 1.0 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if l1_balance(m, mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 4.0 * f64::EPSILON * mid {
            break;
        }
    }
    0.5 * (lo + hi)
}

/// L1 in the simulation frame: (−d, 0, 0).
pub fn l1_point(q: f64) -> [f64; 3] {
    [-l1_distance(q), 0.0, 0.0]
}

/// The Roche potential at L1: the value on the critical surface (both Roche lobes).
pub fn l1_potential(q: f64) -> f64 {
    potential(q, l1_point(q))
}

/// A = (1−μ)/d³ + μ/(1−d)³ at L1 (Lubow & Shu 1975): the potential's second derivatives
/// there are Φ_xx = −(2A+1), Φ_yy = A − 1, Φ_zz = A (Ω = 1).
pub fn l1_a(q: f64) -> f64 {
    let m = mu(q);
    let d = l1_distance(q);
    (1.0 - m) / d.powi(3) + m / (1.0 - d).powi(3)
}

/// Whether `x` lies inside the donor's Roche lobe: on the donor's side of L1 and below the
/// critical potential.
pub fn inside_donor_lobe(q: f64, x: [f64; 3]) -> bool {
    x[0] < -l1_distance(q) && potential(q, x) < l1_potential(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// exact-solutions.md 4b lists d to four digits for q = 0.05 … 0.25.
    #[test]
    fn l1_matches_the_tabulated_roots_and_solves_the_quintic() {
        for (q, d) in [
            (0.05, 0.7687),
            (0.10, 0.7175),
            (0.15, 0.6839),
            (0.20, 0.6586),
            (0.25, 0.6381),
        ] {
            let x = l1_distance(q);
            assert!((x - d).abs() < 6e-5, "q = {q}: {x} against {d}");
            // The root to 1e-8 (issue 13): the balance changes sign within ±1e-9 of it.
            let m = mu(q);
            assert!(l1_balance(m, x - 1e-9) > 0.0 && l1_balance(m, x + 1e-9) < 0.0);
        }
    }

    #[test]
    fn l1_is_a_saddle_of_the_potential() {
        let q = 0.1;
        let l1 = l1_point(q);
        let e = 1e-4;
        let f = |dx: [f64; 3]| potential(q, [l1[0] + dx[0], l1[1] + dx[1], l1[2] + dx[2]]);
        let phi0 = f([0.0; 3]);
        // Along x the potential has a maximum, across (y, z) a minimum.
        let a = l1_a(q);
        let second = |dx| (f(dx) - 2.0 * phi0 + f([-dx[0], -dx[1], -dx[2]])) / (e * e);
        assert!((second([e, 0.0, 0.0]) + 2.0 * a + 1.0).abs() < 1e-4 * a);
        assert!((second([0.0, e, 0.0]) - (a - 1.0)).abs() < 1e-4 * a);
        assert!((second([0.0, 0.0, e]) - a).abs() < 1e-4 * a);
        // And the gradient vanishes (central difference with a step of 1e-6: truncation
        // ~1e-12 Φ''', round-off ~1e-10).
        let g = 1e-6;
        let grad = (f([g, 0.0, 0.0]) - f([-g, 0.0, 0.0])) / (2.0 * g);
        assert!(grad.abs() < 1e-8, "{grad}");
    }

    #[test]
    fn donor_lobe_membership() {
        let q = 0.2;
        assert!(inside_donor_lobe(q, [-1.1, 0.0, 0.0]));
        assert!(!inside_donor_lobe(q, [-0.5, 0.0, 0.0]));
        assert!(!inside_donor_lobe(q, [-1.0, 0.8, 0.0]));
    }
}
