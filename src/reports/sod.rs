//! `sphdisk analyse sod <run>`: the shock tube's density, velocity, pressure and internal
//! energy against the exact Riemann solution at the final time (`sod.png`, and
//! `sod_profile.csv` with each particle's values beside the exact ones).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};

use crate::config::ProblemKind;
use crate::io::atomic::write_atomic;
use crate::io::hdf5::{read_parameters, read_snapshot_with_h};
use crate::problems::sod::{params, solution};
use crate::render::plot::{PALETTE, Panel, Series, SeriesStyle, plot_panels};
use crate::reports::run_config;

/// Reads `run.toml` and `final.hdf5` of a shock-tube run and writes the plot and the CSV.
pub fn analyse_sod(run: &Path) -> Result<Vec<PathBuf>> {
    let cfg = run_config(run, ProblemKind::Sod, "a shock-tube run")?;
    let fin = run.join("final.hdf5");
    let snap = read_snapshot_with_h(&fin)?;
    // The snapshot must be this tube's: a file copied in from another run is refused, not
    // plotted against a solution it does not follow.
    let kind = read_parameters(&fin)?.get("problem:kind").cloned();
    let dimension = cfg.dimension();
    if snap.dimension != dimension || kind.as_deref().is_some_and(|k| k != "sod") {
        bail!(
            "{}: not a snapshot of this shock tube: {}D{} while run.toml is a {dimension}D \
             \"sod\" run",
            fin.display(),
            snap.dimension,
            kind.map(|k| format!(" \"{k}\"")).unwrap_or_default()
        );
    }
    let s = params(&cfg);
    let sol = solution(&cfg)?;
    let t = snap.time;
    if !(t > 0.0) {
        bail!(
            "{}: final.hdf5 is at t = {t}; nothing to compare",
            run.display()
        );
    }
    // File positions are shifted into [0, L]; the tube's frame is x − shift.
    let x: Vec<f64> = snap.pos[0].iter().map(|x| x - snap.shift[0]).collect();
    let gamma = sol.gamma();
    let mut csv = String::from("x,rho,rho_exact,v,v_exact,p,p_exact,u,u_exact\n");
    let (mut rho, mut vel, mut pre, mut ene) = (vec![], vec![], vec![], vec![]);
    for i in 0..snap.len() {
        let e = sol.sample((x[i] - s.x0) / t);
        let ue = e.p / ((gamma - 1.0) * e.rho);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{}",
            x[i], snap.rho[i], e.rho, snap.vel[0][i], e.v, snap.p[i], e.p, snap.u[i], ue
        );
        rho.push((x[i], snap.rho[i]));
        vel.push((x[i], snap.vel[0][i]));
        pre.push((x[i], snap.p[i]));
        ene.push((x[i], snap.u[i]));
    }
    let (x_lo, x_hi) = (0.0, s.length);
    let exact_curve = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=2000)
            .map(|k| {
                let xx = x_lo + (x_hi - x_lo) * k as f64 / 2000.0;
                (xx, f(xx))
            })
            .collect()
    };
    let sample = |xx: f64| sol.sample((xx - s.x0) / t);
    let panels: Vec<Panel> = [
        ("density ρ", rho, exact_curve(&|xx| sample(xx).rho)),
        ("velocity v_x", vel, exact_curve(&|xx| sample(xx).v)),
        ("pressure p", pre, exact_curve(&|xx| sample(xx).p)),
        (
            "specific internal energy u",
            ene,
            exact_curve(&|xx| {
                let e = sample(xx);
                e.p / ((gamma - 1.0) * e.rho)
            }),
        ),
    ]
    .into_iter()
    .map(|(name, pts, exact)| {
        let (lo, hi) = pts
            .iter()
            .chain(&exact)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.1), b.max(p.1))
            });
        let pad = 0.08 * (hi - lo).max(1e-12);
        Panel {
            title: format!("{name} at t = {t:.3}"),
            x_label: "x".into(),
            y_label: name.split(' ').next_back().unwrap_or(name).into(),
            x_range: (x_lo, x_hi),
            y_range: (lo - pad, hi + pad),
            series: vec![
                Series {
                    label: Some(format!("SPH ({} particles)", snap.len())),
                    points: pts,
                    color: PALETTE[1],
                    style: SeriesStyle::Dots,
                },
                Series {
                    label: Some("exact".into()),
                    points: exact,
                    color: plotters::style::RGBColor(0, 0, 0),
                    style: SeriesStyle::Line,
                },
            ],
        }
    })
    .collect();
    let csv_path = run.join("sod_profile.csv");
    write_atomic(&csv_path, csv.as_bytes())?;
    let png = run.join("sod.png");
    plot_panels(&png, (1800, 450), &panels)?;
    Ok(vec![csv_path, png])
}
