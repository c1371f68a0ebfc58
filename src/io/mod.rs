//! Everything written to or read from disk: per-particle CSV (final state, snapshots, initial
//! conditions), `summary.json`, and the atomic write that keeps what was written valid.

pub mod atomic;
pub mod checkpoint;
pub mod csv;
pub mod hdf5;
pub mod log;
pub mod run_folder;
pub mod snapshot;
pub mod snapshot_index;
pub mod summary;
pub mod timeseries;
