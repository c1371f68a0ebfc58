//! Keeping the working set between right-hand-side evaluations. Every evaluation builds
//! its local view of the particles, the ghosts, the grid, the window of pair blocks and
//! the per-slab accumulators afresh; they are of much the same sizes from step to step.
//! glibc's malloc serves blocks above its mmap threshold (128 KiB, adjusted upwards on the
//! fly) with fresh mappings and returns them to the kernel when freed, and trims its heaps
//! above 128 KiB of free space at the top: each evaluation then page-faults its whole
//! working set back in (zeroed pages from the kernel) — 258 000 minor faults and 10% of
//! the CPU time in system time for 10 steps of `problems/disk3d.toml` on one thread.
//! [`keep_freed_memory`] raises both thresholds so that freed buffers stay in the process
//! and the next evaluation reuses them: 16 500 faults, system time 0.73 s → 0.14 s
//! (BENCHMARKS.md). The peak resident memory is what the evaluations need anyway.
//!
//! The thresholds govern the main heap only: each worker thread otherwise gets its own
//! arena, made of 64 MiB heaps that glibc unmaps as soon as one is wholly free, whatever
//! the trim threshold — a working set allocated partly by rayon's workers came back as
//! fresh pages at every evaluation (131 000 faults for 8 steps of the 10⁵-particle bench,
//! against 31 000 with one arena). All threads therefore share the main arena: the sweep
//! allocates in large blocks (a slab's arrays, a group's pairs), so its lock is rarely
//! contended.
//! The sums' per-task buffers come from a pool of scratch vectors ([`scratch_vec`]),
//! handed out as their last user left them: a task clears only the entries it uses.
//! Elsewhere than Linux with glibc the allocator is left as it is.

/// Sets glibc's mmap threshold to its largest value (32 MiB: blocks up to that come from
/// the heaps and are reused), its trim threshold to 1 GiB (free heap space up to that
/// is kept) and its number of arenas to one (the main heap, which those thresholds
/// govern). Call once at start-up, before the threads start.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; called before other threads
        // allocate.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
            libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
            libc::mallopt(libc::M_ARENA_MAX, 1);
        }
    }
}

/// Vectors of any element type kept for reuse, at most `max` of them.
struct Pool {
    kept: std::sync::Mutex<Vec<Box<dyn std::any::Any + Send>>>,
    max: usize,
}

impl Pool {
    const fn new(max: usize) -> Self {
        Self {
            kept: std::sync::Mutex::new(Vec::new()),
            max,
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Box<dyn std::any::Any + Send>>> {
        self.kept.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A kept vector of element type `T`, the most recently kept (its memory is the
    /// likeliest to be in cache), if there is one.
    fn take<T: Send + 'static>(&self) -> Option<Vec<T>> {
        let mut k = self.lock();
        let i = k.iter().rposition(|b| b.is::<Vec<T>>())?;
        k.remove(i).downcast::<Vec<T>>().ok().map(|v| *v)
    }

    /// Keeps `v` unless `max` vectors are kept already.
    fn put<T: Send + 'static>(&self, v: Vec<T>) {
        let mut k = self.lock();
        if k.len() < self.max {
            k.push(Box::new(v));
        }
    }
}

/// Vectors above the mmap threshold, kept from one evaluation for the next: glibc maps
/// such blocks afresh at every allocation and unmaps them when freed, whatever the
/// thresholds (at 10⁶ particles the accumulators, 144 MB, and the velocity gradients and
/// stresses, 72 MB each, page-faulted in at every evaluation). At most 16 are kept (one
/// evaluation holds a handful).
static KEPT: Pool = Pool::new(16);

/// Below this a vector comes from the heaps, which reuse its memory anyway.
const KEEP_BYTES: usize = 32 << 20;

/// `len` copies of `value`, in a kept vector of the same type if there is one, else freshly
/// allocated; filled in parallel either way.
pub fn filled_vec<T: Copy + Send + Sync + 'static>(len: usize, value: T) -> Vec<T> {
    use rayon::prelude::*;
    match KEPT.take::<T>() {
        Some(mut v) => {
            v.truncate(len);
            v.par_iter_mut()
                .with_min_len(1 << 14)
                .for_each(|x| *x = value);
            v.resize(len, value);
            v
        }
        None => (0..len)
            .into_par_iter()
            .with_min_len(1 << 14)
            .map(|_| value)
            .collect(),
    }
}

/// Keeps `v` for the next [`filled_vec`] of its type when it is large enough to be mapped
/// afresh otherwise; drops it else.
pub fn keep_vec<T: Send + 'static>(v: Vec<T>) {
    if v.capacity() * std::mem::size_of::<T>() >= KEEP_BYTES {
        KEPT.put(v);
    }
}

/// Scratch vectors kept between uses by [`scratch_vec`] and [`keep_scratch`]: the sums'
/// per-task buffers, reused from sum to sum instead of allocated and filled afresh. At
/// most 64 are kept (a batch of small slabs holds one per task of each of its blocks).
static SCRATCH: Pool = Pool::new(64);

/// Scratch vectors larger than this are dropped rather than kept.
const SCRATCH_BYTES: usize = 64 << 20;

/// A vector of `len` elements for scratch use: a kept vector of the same type, whose
/// elements hold whatever its last user left in them (the caller writes every element
/// before it reads it), grown with `fill` if it was shorter; else a new one filled with
/// `fill`.
pub fn scratch_vec<T: Copy + Send + 'static>(len: usize, fill: T) -> Vec<T> {
    match SCRATCH.take::<T>() {
        Some(mut v) => {
            v.truncate(len);
            v.resize(len, fill);
            v
        }
        None => vec![fill; len],
    }
}

/// Drops every kept scratch vector.
pub fn clear_scratch() {
    SCRATCH.lock().clear();
}

/// Keeps `v` for a later [`scratch_vec`] of its type (unless too many or too large are
/// kept already).
pub fn keep_scratch<T: Send + 'static>(v: Vec<T>) {
    if v.capacity() * std::mem::size_of::<T>() <= SCRATCH_BYTES {
        SCRATCH.put(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kept vector comes back refilled with the new value at the new length, and one of
    /// another type is never handed out.
    #[test]
    fn kept_vectors_come_back_refilled() {
        let n = (KEEP_BYTES / 8) + 10;
        let mut v = filled_vec(n, 1.5f64);
        assert!(v.iter().all(|&x| x == 1.5));
        v[3] = 7.0;
        let ptr = v.as_ptr();
        keep_vec(v);
        let w: Vec<f64> = filled_vec(n - 5, 0.25);
        assert_eq!(w.len(), n - 5);
        assert!(w.iter().all(|&x| x == 0.25));
        // Other tests may share the pool; when this one got its own vector back, it is
        // the same memory.
        if w.as_ptr() == ptr {
            assert!(w.capacity() >= n);
        }
        let u: Vec<u32> = filled_vec(4, 9u32);
        assert_eq!(u, vec![9; 4]);
        keep_vec(w);
        let longer: Vec<f64> = filled_vec(n + 100, -1.0);
        assert!(longer.len() == n + 100 && longer.iter().all(|&x| x == -1.0));
        // Small vectors are not kept.
        keep_vec(vec![0u8; 16]);
        let k = KEPT.lock();
        assert!(k.iter().all(|b| !b.is::<Vec<u8>>()));
    }
}
