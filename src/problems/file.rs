//! Initial conditions from a CSV file (`[initial] file`), in a box given by `[domain]`, with
//! `particles.h` as the smoothing length. Boundaries default to open.

use std::path::Path;

use anyhow::Result;

use crate::boundary::BoundaryKind;
use crate::config::Config;
use crate::io::csv::read_particles;
use crate::problems::{InitialState, make_box};

pub fn setup<const D: usize>(cfg: &Config) -> Result<InitialState<D>> {
    let init = cfg.initial.as_ref().expect("validated: [initial] present");
    let particles = read_particles::<D>(Path::new(&init.file))?;
    let bx = make_box(cfg, [0.0; D], [1.0; D], [BoundaryKind::Open; D]);
    let h = cfg.particles.h.expect("validated: particles.h present");
    Ok(InitialState::new(particles, bx, h))
}
