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
//! Elsewhere than Linux with glibc the allocator is left as it is.

/// Sets glibc's mmap threshold to its largest value (32 MiB: blocks up to that come from
/// the heaps and are reused) and its trim threshold to 1 GiB (free heap space up to that
/// is kept). Call once at start-up, before the threads start.
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets allocator parameters; called before other threads
        // allocate.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
            libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        }
    }
}
