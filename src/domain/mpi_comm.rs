//! [`Comm`] over MPI (rsmpi, OpenMPI), with the cargo feature `mpi`.
//!
//! Sends are non-blocking (`MPI_Isend`) on buffers the communicator owns until they
//! complete; receives are matched by source and tag with `MPI_Improbe`/`MPI_Mrecv`, so a
//! message of any length can be polled for without posting a buffer first. A failing rank
//! ends the job with `MPI_Abort` (see [`install_abort_on_panic`]), so that no rank is left
//! waiting.

use mpi::point_to_point::{Destination, MatchedReceiveVec, Source};
use mpi::request::{Request, StaticScope};
use mpi::topology::{Communicator, SimpleCommunicator};

use super::comm::Comm;

/// A send in flight and the buffer it reads (leaked until the send completes).
type InFlight = (Request<'static, [f64], StaticScope>, *mut [f64]);

/// The world communicator.
pub struct MpiComm {
    world: SimpleCommunicator,
    rank: usize,
    size: usize,
    /// Sends in flight with the buffers they read (freed once complete).
    pending: Vec<InFlight>,
}

impl MpiComm {
    pub fn new(world: SimpleCommunicator) -> Self {
        let (rank, size) = (world.rank() as usize, world.size() as usize);
        Self {
            world,
            rank,
            size,
            pending: Vec::new(),
        }
    }

    /// Frees the buffers of completed sends.
    fn reap(&mut self) {
        let mut still = Vec::with_capacity(self.pending.len());
        for (req, buf) in self.pending.drain(..) {
            match req.test() {
                // SAFETY: `buf` came from `Box::leak` in `send` and its request is complete,
                // so MPI no longer reads it and nothing else refers to it.
                Ok(_) => drop(unsafe { Box::from_raw(buf) }),
                Err(req) => still.push((req, buf)),
            }
        }
        self.pending = still;
    }

    /// Waits for every send in flight.
    pub fn flush(&mut self) {
        for (req, buf) in self.pending.drain(..) {
            req.wait();
            // SAFETY: as in `reap`.
            drop(unsafe { Box::from_raw(buf) });
        }
    }
}

impl Drop for MpiComm {
    fn drop(&mut self) {
        self.flush();
    }
}

impl Comm for MpiComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn send(&mut self, dest: usize, tag: u16, data: Vec<f64>) {
        self.reap();
        let buf: &'static mut [f64] = Box::leak(data.into_boxed_slice());
        let ptr: *mut [f64] = buf;
        // SAFETY: the buffer stays alive (leaked) until the request completes; it is only
        // read, by MPI, until then.
        let shared: &'static [f64] = unsafe { &*ptr };
        let req = self
            .world
            .process_at_rank(dest as i32)
            .immediate_send_with_tag(StaticScope, shared, tag as i32);
        self.pending.push((req, ptr));
    }

    fn try_recv(&mut self, src: usize, tag: u16) -> Option<Vec<f64>> {
        self.world
            .process_at_rank(src as i32)
            .immediate_matched_probe_with_tag(tag as i32)
            .map(|m| m.matched_receive_vec::<f64>().0)
    }

    fn recv(&mut self, src: usize, tag: u16) -> Vec<f64> {
        self.world
            .process_at_rank(src as i32)
            .matched_probe_with_tag(tag as i32)
            .matched_receive_vec::<f64>()
            .0
    }

    fn abort(&self, message: &str) -> ! {
        eprintln!("sphdisk: rank {}: {message}", self.rank);
        self.world.abort(1)
    }
}

/// Makes a panic on any rank end the whole job at once (`MPI_Abort`), after printing the
/// panic's message with the rank: otherwise the other ranks would wait for it forever.
pub fn install_abort_on_panic(rank: usize) {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        eprintln!("sphdisk: rank {rank} failed");
        default(info);
        // SAFETY: MPI_Abort on the world communicator, which exists for the whole program.
        unsafe {
            mpi::ffi::MPI_Abort(mpi::ffi::RSMPI_COMM_WORLD, 1);
        }
    }));
}
