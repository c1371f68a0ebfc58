//! Regular particle lattices: cell-centred points filling a cuboid, the quiet start every
//! set-up uses.

/// Points `lo + (i + ½) · spacing` of an `n[0] × … × n[D−1]` lattice, x slowest; a
/// lattice of more particles than a run can hold is refused (naming `particles.n`) before
/// anything is allocated.
pub fn cuboid<const D: usize>(
    lo: [f64; D],
    spacing: [f64; D],
    n: [usize; D],
) -> anyhow::Result<Vec<[f64; D]>> {
    let total = crate::limits::lattice_count(n)?;
    let mut out = Vec::with_capacity(total);
    for mut k in 0..total {
        let mut idx = [0usize; D];
        for d in (0..D).rev() {
            idx[d] = k % n[d];
            k /= n[d];
        }
        out.push(std::array::from_fn(|d| {
            lo[d] + (idx[d] as f64 + 0.5) * spacing[d]
        }));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_fills_the_cuboid_cell_centred() {
        let pts = cuboid([0.0, 1.0], [0.5, 0.25], [2, 4]).unwrap();
        assert_eq!(pts.len(), 8);
        assert_eq!(pts[0], [0.25, 1.125]);
        assert_eq!(pts[7], [0.75, 1.875]);
    }
}
