//! Per-particle CSV: the final state (`final.csv`), snapshots, and initial conditions read
//! back. sphdisk writes the header `id,x,y,z,vx,vy,vz,m,h,rho,u,p` (coordinates beyond the
//! dimension 0) and reads any file whose header names x[, y, z], m and u.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::io::atomic::write_atomic;
use crate::particles::Particles;

pub const HEADER: &str = "id,x,y,z,vx,vy,vz,m,h,rho,u,p";

/// Writes the particles (with smoothing length `h`) to `path`, atomically.
pub fn write_particles<const D: usize>(path: &Path, p: &Particles<D>, h: f64) -> Result<()> {
    let mut s = String::with_capacity(p.len() * 160);
    s.push_str(HEADER);
    s.push('\n');
    for i in 0..p.len() {
        let _ = write!(s, "{}", p.id[i]);
        for d in 0..3 {
            let _ = write!(s, ",{}", if d < D { p.pos[d][i] } else { 0.0 });
        }
        for d in 0..3 {
            let _ = write!(s, ",{}", if d < D { p.vel[d][i] } else { 0.0 });
        }
        let _ = writeln!(s, ",{},{},{},{},{}", p.mass[i], h, p.rho[i], p.u[i], p.p[i]);
    }
    write_atomic(path, s.as_bytes())
}

/// The columns initial conditions need in `D` dimensions (the rest are optional).
pub fn required_columns(d: usize) -> Vec<&'static str> {
    let mut c = ["x", "y", "z"][..d].to_vec();
    c.extend(["m", "u"]);
    c
}

/// Initial conditions from a CSV whose header names its columns, in any order: x[, y, z]
/// (up to the dimension), m and u are required; id (default: the row's number from 0),
/// vx[, vy, vz] (default 0) and rho are read when present; other columns (h, p, z of a 2D
/// file, …) are ignored. Errors name the file, line and column, and a missing column.
pub fn read_particles<const D: usize>(path: &Path) -> Result<Particles<D>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read initial conditions {}", path.display()))?;
    let mut lines = text.lines().enumerate();
    let (_, header) = lines
        .next()
        .with_context(|| format!("{}: empty file", path.display()))?;
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    let find = |name: &str| cols.iter().position(|c| *c == name);
    let col = |name: &str| -> Result<usize> {
        find(name).with_context(|| {
            format!(
                "{}: header has no column `{name}` (a {D}D file needs {}; id, {} and rho are optional)",
                path.display(),
                required_columns(D).join(", "),
                ["vx", "vy", "vz"][..D].join(", ")
            )
        })
    };
    let axes = ["x", "y", "z"];
    let vaxes = ["vx", "vy", "vz"];
    let cx: Vec<usize> = (0..D).map(|d| col(axes[d])).collect::<Result<_>>()?;
    let cm = col("m")?;
    let cu = col("u")?;
    let ci = find("id");
    let cv: Vec<Option<usize>> = (0..D).map(|d| find(vaxes[d])).collect();
    // Written by sphdisk: the density at output time, useful to analyses.
    let crho = find("rho");
    let mut p = Particles::new();
    for (ln, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != cols.len() {
            bail!(
                "{}: line {}: {} fields, header has {}",
                path.display(),
                ln + 1,
                fields.len(),
                cols.len()
            );
        }
        let num = |c: usize| -> Result<f64> {
            fields[c].parse::<f64>().map_err(|_| {
                anyhow::anyhow!(
                    "{}: line {}: column `{}` is not a number: `{}`",
                    path.display(),
                    ln + 1,
                    cols[c],
                    fields[c]
                )
            })
        };
        let id: u64 = match ci {
            None => p.len() as u64,
            Some(ci) => fields[ci].parse().map_err(|_| {
                anyhow::anyhow!(
                    "{}: line {}: id `{}` is not a non-negative integer",
                    path.display(),
                    ln + 1,
                    fields[ci]
                )
            })?,
        };
        let mut pos = [0.0; D];
        let mut vel = [0.0; D];
        for d in 0..D {
            pos[d] = num(cx[d])?;
            if let Some(c) = cv[d] {
                vel[d] = num(c)?;
            }
        }
        p.push(id, pos, vel, num(cm)?, num(cu)?);
        if let Some(c) = crho {
            *p.rho.last_mut().expect("just pushed") = num(c)?;
        }
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_then_read_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.csv");
        let mut p = Particles::<2>::new();
        p.push(5, [0.1, 0.2], [1.0, -1.0], 0.3, 2.5);
        p.push(9, [1.0 / 3.0, 0.7], [0.0, 0.5], 0.4, 1.5);
        write_particles(&path, &p, 0.05).unwrap();
        let q = read_particles::<2>(&path).unwrap();
        assert_eq!(q.id, p.id);
        assert_eq!(q.pos, p.pos);
        assert_eq!(q.vel, p.vel);
        assert_eq!(q.mass, p.mass);
        assert_eq!(q.u, p.u);
    }

    #[test]
    fn bad_number_names_line_and_column() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.csv");
        std::fs::write(&path, format!("{HEADER}\n0,0.1,0,0,0,0,0,abc,0.1,1,1,1\n")).unwrap();
        let e = read_particles::<1>(&path).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("`m`"), "{e}");
    }

    #[test]
    fn fewer_columns_by_header_names() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.csv");
        // Columns in any order, without id or velocities: ids count rows, velocities 0.
        std::fs::write(&path, "m, y,x,u\n0.5,0.2,0.1,1.5\n0.25,0.4,0.3,2\n").unwrap();
        let p = read_particles::<2>(&path).unwrap();
        assert_eq!(p.id, [0, 1]);
        assert_eq!(p.pos, [vec![0.1, 0.3], vec![0.2, 0.4]]);
        assert_eq!(p.vel, [vec![0.0; 2], vec![0.0; 2]]);
        assert_eq!(p.mass, [0.5, 0.25]);
        assert_eq!(p.u, [1.5, 2.0]);
        // A missing required column is named, with what the file needs.
        std::fs::write(&path, "x,y,u\n0.1,0.2,1\n").unwrap();
        let e = read_particles::<2>(&path).unwrap_err().to_string();
        assert!(
            e.contains("no column `m`") && e.contains("x, y, m, u"),
            "{e}"
        );
        let e = read_particles::<3>(&dir.path().join("p.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no column `z`"), "{e}");
    }
}
