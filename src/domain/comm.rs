//! Message passing between ranks, as the distributed run needs it: non-blocking sends of
//! owned buffers, receives matched by source and tag (polled or waited for), and small
//! reductions. Two implementations: [`ThreadComm`] (ranks as threads of one process, for
//! tests and for running the distributed algorithm without MPI) and, with the cargo feature
//! `mpi`, `MpiComm` over rsmpi (`domain/mpi_comm.rs`).
//!
//! Every message is a `Vec<f64>` (integers travel as their exact f64 value, or as bits).
//! Messages between two ranks with the same tag arrive in the order they were sent.

use std::collections::{HashMap, VecDeque};
use std::sync::mpsc::{Receiver, Sender, channel};

/// Message tags (one per kind of message).
pub mod tag {
    pub const ELEMENTS: u16 = 1;
    /// Partial sums of stage k go with `PARTIALS + k`, final values with `FINALS + k`.
    pub const PARTIALS: u16 = 10;
    pub const FINALS: u16 = 20;
    pub const MIGRATE: u16 = 30;
    pub const REDUCE: u16 = 40;
    pub const BROADCAST: u16 = 41;
    pub const GATHER: u16 = 42;
}

/// A communicator of `size()` ranks.
pub trait Comm {
    fn rank(&self) -> usize;
    fn size(&self) -> usize;
    /// Starts sending `data` to `dest`; returns at once (the buffer is kept until sent).
    fn send(&mut self, dest: usize, tag: u16, data: Vec<f64>);
    /// The next message from `src` with `tag`, if it has arrived.
    fn try_recv(&mut self, src: usize, tag: u16) -> Option<Vec<f64>>;
    /// Waits for the next message from `src` with `tag`.
    fn recv(&mut self, src: usize, tag: u16) -> Vec<f64>;
    /// Ends the whole job with `message` (a rank that fails must not leave the others
    /// waiting in a collective).
    fn abort(&self, message: &str) -> !;

    /// Element-wise `op` over every rank's `x`, in rank order (so every rank gets the same
    /// bits), left in `x` on every rank.
    fn all_reduce(&mut self, x: &mut [f64], op: fn(f64, f64) -> f64) {
        let n = self.size();
        if n == 1 {
            return;
        }
        if self.rank() == 0 {
            for src in 1..n {
                let y = self.recv(src, tag::REDUCE);
                for (a, b) in x.iter_mut().zip(y) {
                    *a = op(*a, b);
                }
            }
            for dest in 1..n {
                self.send(dest, tag::BROADCAST, x.to_vec());
            }
        } else {
            self.send(0, tag::REDUCE, x.to_vec());
            let y = self.recv(0, tag::BROADCAST);
            x.copy_from_slice(&y);
        }
    }

    fn sum(&mut self, x: &mut [f64]) {
        self.all_reduce(x, |a, b| a + b);
    }

    fn min(&mut self, x: &mut [f64]) {
        self.all_reduce(x, f64::min);
    }

    fn max(&mut self, x: &mut [f64]) {
        self.all_reduce(x, f64::max);
    }

    /// Every rank's `data`, on rank 0 (in rank order); `None` elsewhere.
    fn gather(&mut self, data: Vec<f64>) -> Option<Vec<Vec<f64>>> {
        if self.rank() == 0 {
            let mut out = vec![data];
            for src in 1..self.size() {
                out.push(self.recv(src, tag::GATHER));
            }
            Some(out)
        } else {
            self.send(0, tag::GATHER, data);
            None
        }
    }

    /// Rank 0's `data` on every rank.
    fn broadcast(&mut self, data: Vec<f64>) -> Vec<f64> {
        if self.rank() == 0 {
            for dest in 1..self.size() {
                self.send(dest, tag::BROADCAST, data.clone());
            }
            data
        } else {
            self.recv(0, tag::BROADCAST)
        }
    }

    /// Every rank's `data` on every rank, in rank order.
    fn all_gather(&mut self, data: Vec<f64>) -> Vec<Vec<f64>> {
        let n = self.size();
        let parts = self.gather(data);
        let flat = match parts {
            Some(parts) => {
                let mut flat: Vec<f64> = parts.iter().map(|p| p.len() as f64).collect();
                for p in parts {
                    flat.extend(p);
                }
                flat
            }
            None => Vec::new(),
        };
        let flat = self.broadcast(flat);
        let mut out = Vec::with_capacity(n);
        let mut at = n;
        for k in 0..n {
            let len = flat[k] as usize;
            out.push(flat[at..at + len].to_vec());
            at += len;
        }
        out
    }
}

type Envelope = (usize, u16, Vec<f64>);

/// Ranks as threads of one process, connected by channels.
pub struct ThreadComm {
    rank: usize,
    peers: Vec<Sender<Envelope>>,
    inbox: Receiver<Envelope>,
    mailbox: HashMap<(usize, u16), VecDeque<Vec<f64>>>,
}

impl ThreadComm {
    /// `n` connected communicators, one per rank.
    pub fn create(n: usize) -> Vec<ThreadComm> {
        let (senders, receivers): (Vec<_>, Vec<_>) = (0..n).map(|_| channel()).unzip();
        receivers
            .into_iter()
            .enumerate()
            .map(|(rank, inbox)| ThreadComm {
                rank,
                peers: senders.clone(),
                inbox,
                mailbox: HashMap::new(),
            })
            .collect()
    }

    /// Runs `f` on `n` ranks (one thread each) and returns their results in rank order.
    /// A panic on any rank is re-raised here.
    pub fn run<T: Send>(n: usize, f: impl Fn(&mut ThreadComm) -> T + Sync) -> Vec<T> {
        let comms = Self::create(n);
        std::thread::scope(|s| {
            let handles: Vec<_> = comms
                .into_iter()
                .map(|mut c| {
                    let f = &f;
                    s.spawn(move || f(&mut c))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        })
    }

    fn file(&mut self, e: Envelope) {
        self.mailbox.entry((e.0, e.1)).or_default().push_back(e.2);
    }

    fn take(&mut self, src: usize, tag: u16) -> Option<Vec<f64>> {
        self.mailbox
            .get_mut(&(src, tag))
            .and_then(VecDeque::pop_front)
    }
}

impl Comm for ThreadComm {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.peers.len()
    }

    fn send(&mut self, dest: usize, tag: u16, data: Vec<f64>) {
        // A peer that has ended (e.g. panicked) no longer listens; its failure is reported
        // by `run`.
        let _ = self.peers[dest].send((self.rank, tag, data));
    }

    fn try_recv(&mut self, src: usize, tag: u16) -> Option<Vec<f64>> {
        while let Ok(e) = self.inbox.try_recv() {
            self.file(e);
        }
        self.take(src, tag)
    }

    fn recv(&mut self, src: usize, tag: u16) -> Vec<f64> {
        loop {
            if let Some(m) = self.take(src, tag) {
                return m;
            }
            match self.inbox.recv() {
                Ok(e) => self.file(e),
                Err(_) => panic!("rank {}: every peer has ended", self.rank),
            }
        }
    }

    fn abort(&self, message: &str) -> ! {
        panic!("rank {}: {message}", self.rank)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reductions_gather_and_broadcast_agree_on_every_rank() {
        let out = ThreadComm::run(3, |c| {
            let r = c.rank() as f64;
            let mut s = [r, 1.0];
            c.sum(&mut s);
            let mut m = [r];
            c.min(&mut m);
            let mut x = [r];
            c.max(&mut x);
            let all = c.all_gather(vec![r; c.rank() + 1]);
            (s, m[0], x[0], all)
        });
        for (s, m, x, all) in out {
            assert_eq!(s, [3.0, 3.0]);
            assert_eq!((m, x), (0.0, 2.0));
            assert_eq!(all, vec![vec![0.0], vec![1.0, 1.0], vec![2.0, 2.0, 2.0]]);
        }
    }

    #[test]
    fn messages_with_one_tag_arrive_in_order_and_tags_do_not_mix() {
        let out = ThreadComm::run(2, |c| {
            if c.rank() == 0 {
                c.send(1, 7, vec![1.0]);
                c.send(1, 8, vec![9.0]);
                c.send(1, 7, vec![2.0]);
                vec![]
            } else {
                let b = c.recv(0, 8);
                let a1 = c.recv(0, 7);
                let a2 = c.recv(0, 7);
                vec![b[0], a1[0], a2[0]]
            }
        });
        assert_eq!(out[1], vec![9.0, 1.0, 2.0]);
    }
}
