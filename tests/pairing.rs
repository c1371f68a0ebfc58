//! Guards the choice of kernel against the pairing instability (Dehnen & Aly 2012): a
//! jittered 12³ lattice in a periodic box, isothermal, with ~150 neighbours, relaxes under
//! its own pressure forces. With the cubic spline at that neighbour number particles pair up;
//! with Wendland C4 they settle onto a lattice-like arrangement.

use sphdisk::config::Config;
use sphdisk::rng::Rng;
use sphdisk::simulation::{RunOptions, run_with_state};

const K: usize = 12;

/// The problem file of the relaxation with `kernel`, reading `ic.csv` in `dir`.
fn problem(dir: &std::path::Path, kernel: &str) -> std::path::PathBuf {
    let mut rng = Rng::new(3);
    let dx = 1.0 / K as f64;
    let mut csv = String::from("id,x,y,z,vx,vy,vz,m,h,rho,u,p\n");
    let mut id = 0;
    for a in 0..K {
        for b in 0..K {
            for c in 0..K {
                let x: Vec<f64> = [a, b, c]
                    .iter()
                    .map(|&i| {
                        ((i as f64 + 0.5) * dx + 0.3 * dx * (rng.uniform() - 0.5)).rem_euclid(1.0)
                    })
                    .collect();
                let m = 1.0 / (K * K * K) as f64;
                csv.push_str(&format!(
                    "{id},{},{},{},0,0,0,{m},0,1,1,1\n",
                    x[0], x[1], x[2]
                ));
                id += 1;
            }
        }
    }
    std::fs::write(dir.join("ic.csv"), csv).unwrap();
    // h = 1.65 spacings: (4π/3)(2h)³ n ≈ 150 neighbours within the support 2h.
    let toml = format!(
        r#"
[problem]
kind = "file"
dimension = 3
[particles]
h = {h}
kernel = "{kernel}"
[eos]
kind = "isothermal"
cs = 1.0
[artificial_viscosity]
alpha = 1.0
beta = 2.0
[boundary]
x = "periodic"
y = "periodic"
z = "periodic"
[time]
end = 2.0
[output]
interval = 0
[domain]
min = [0.0, 0.0, 0.0]
max = [1.0, 1.0, 1.0]
[initial]
file = "ic.csv"
"#,
        h = 1.65 * dx
    );
    let path = dir.join(format!("{kernel}.toml"));
    std::fs::write(&path, toml).unwrap();
    path
}

/// The share of particles whose nearest neighbour (periodic) is closer than half the
/// lattice spacing, after the relaxation with `kernel`.
fn paired_share(kernel: &str) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let cfg = Config::load(&problem(dir.path(), kernel), &[]).unwrap();
    let out_dir = dir.path().join("run");
    let out = run_with_state::<3>(&cfg, &RunOptions::quiet(&out_dir)).unwrap();
    let p = &out.particles;
    let n = p.len();
    let half = 0.5 / K as f64;
    let paired = (0..n)
        .filter(|&i| {
            (0..n).any(|j| {
                j != i && {
                    let d2: f64 = (0..3)
                        .map(|d| {
                            let x = p.pos[d][i] - p.pos[d][j];
                            let x = x - x.round();
                            x * x
                        })
                        .sum();
                    d2 < half * half
                }
            })
        })
        .count();
    let share = paired as f64 / n as f64;
    eprintln!(
        "{kernel}: {share} of the particles paired, mean neighbours {}",
        out.summary().unwrap().mean_neighbours
    );
    share
}

#[test]
fn wendland_c4_stays_unpaired_where_the_cubic_spline_pairs() {
    // Measured: 42% of the particles within half a spacing of another with the cubic
    // spline, none with Wendland C4 (nearest neighbours at 0.95–0.98 spacings); the
    // jittered start has none (≥ 0.7 spacings).
    let cubic = paired_share("cubic");
    let wendland = paired_share("wendland_c4");
    assert!(cubic > 0.2, "cubic spline: {cubic}");
    assert!(wendland < 0.01, "Wendland C4: {wendland}");
}
