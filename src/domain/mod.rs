//! Domain decomposition for distributed runs (paper, Sections 2.3–2.4 and Figure 3), in pure
//! Rust and without MPI: which cuboid of the box each rank owns, where the cuts lie so that
//! every rank carries the same load, which particles a rank must hold as ghosts of its
//! neighbours, and how the load is measured between steps.
//!
//! * [`decomposition`]: the dimensional tree of cuts (slices along x, each cut independently
//!   along y, and in 3D along z), its shape, the weighted-quantile cuts, ownership, and moving
//!   the cuts between steps;
//! * [`ghosts`]: the ranks and particles a rank exchanges across its region's faces, with the
//!   one-sided rule that evaluates every cross-boundary pair exactly once;
//! * [`balance`]: load statistics, the paper's sequence of load measures (particle count →
//!   interactions → waiting time), and when to rebalance;
//! * [`report`]: `sphdisk decompose`, the imbalance and ghost fraction on a 2D disk and a 3D
//!   clustered box.

pub mod balance;
pub mod comm;
pub mod decomposition;
pub mod exchange;
pub mod ghosts;
#[cfg(feature = "mpi")]
pub mod mpi_comm;
pub mod report;
pub mod team;

pub use balance::{LoadMeasure, LoadStats};
pub use decomposition::{Decomposition, RegionTree, TreeShape, factor_regions};
