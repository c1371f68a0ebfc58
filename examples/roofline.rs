//! This machine's limits on one core, for the roofline estimate in BENCHMARKS.md:
//!
//! - sustained memory bandwidth: a STREAM triad `a[i] = b[i] + s c[i]` over three arrays far
//!   larger than the caches (24 bytes per element, STREAM's count; the write-allocate of
//!   `a` moves 8 more), and the same loop over arrays that fit in L1 and in L2;
//! - peak double-precision flop rate: independent chains of 4-lane fused multiply-adds
//!   (AVX2 + FMA, when the CPU has them), and the same chains written in plain Rust as the
//!   project's baseline x86-64 build compiles them (SSE2, no FMA).
//!
//! Each figure is the best of several repetitions. Run on a quiet core:
//!
//! ```sh
//! cargo run --release --example roofline            # 128 MiB per array
//! cargo run --release --example roofline -- 512     # MiB per array
//! ```

use std::hint::black_box;
use std::time::Instant;

/// Best seconds of `reps` runs of `f`.
fn best(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Bytes per second of the triad over arrays of `n` elements, `inner` passes per timing.
fn triad(n: usize, inner: usize, reps: usize) -> f64 {
    let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
    let c: Vec<f64> = (0..n).map(|i| 1.0 + i as f64).collect();
    let mut a = vec![0.0f64; n];
    let s = black_box(0.5);
    let secs = best(reps, || {
        for _ in 0..inner {
            for ((a, b), c) in a.iter_mut().zip(&b).zip(&c) {
                *a = b + s * c;
            }
            black_box(&mut a);
        }
    });
    (3 * 8 * n * inner) as f64 / secs
}

const CHAINS: usize = 12;

/// Flops per second of `CHAINS` independent chains of 4-lane FMAs.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn fma_avx2(iters: u64) -> f64 {
    use std::arch::x86_64::*;
    let a = _mm256_set1_pd(black_box(0.999_999));
    let b = _mm256_set1_pd(black_box(1e-7));
    let mut acc = [_mm256_set1_pd(black_box(1.0)); CHAINS];
    let t = Instant::now();
    for _ in 0..iters {
        for x in acc.iter_mut() {
            *x = _mm256_fmadd_pd(*x, a, b);
        }
    }
    let secs = t.elapsed().as_secs_f64();
    black_box(acc);
    (iters * CHAINS as u64 * 4 * 2) as f64 / secs
}

/// Flops per second of independent multiply-add chains in plain Rust (whatever the build's
/// target makes of them: SSE2 pairs of mulpd/addpd for baseline x86-64).
fn mul_add_plain(iters: u64) -> f64 {
    const N: usize = 24;
    let a = black_box(0.999_999);
    let b = black_box(1e-7);
    let mut acc = [black_box(1.0f64); N];
    let t = Instant::now();
    for _ in 0..iters {
        for x in acc.iter_mut() {
            *x = *x * a + b;
        }
    }
    let secs = t.elapsed().as_secs_f64();
    black_box(acc);
    (iters * N as u64 * 2) as f64 / secs
}

fn main() {
    let mib: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("MiB per array"))
        .unwrap_or(128);
    let gb = |x: f64| x / 1e9;

    let n = mib * 1024 * 1024 / 8;
    let memory = triad(n, 1, 10);
    println!(
        "triad, 3 × {mib} MiB (memory): {:.2} GB/s (24 B/element; {:.2} GB/s with the write-allocate)",
        gb(memory),
        gb(memory * 32.0 / 24.0)
    );
    println!(
        "triad, 3 × 128 KiB (L2):       {:.2} GB/s",
        gb(triad(16 * 1024, 2000, 10))
    );
    println!(
        "triad, 3 × 8 KiB (L1):         {:.2} GB/s",
        gb(triad(1024, 30000, 10))
    );

    let iters = 100_000_000;
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        let rate = (0..5)
            .map(|_| unsafe { fma_avx2(iters) })
            .fold(0.0, f64::max);
        println!(
            "peak, AVX2 FMA ({CHAINS} chains × 4 lanes): {:.1} GFlop/s = {:.2} GHz × 16 flops/cycle (2 FMA pipes × 4 lanes × 2)",
            gb(rate),
            gb(rate) / 16.0
        );
    }
    let rate = (0..5).map(|_| mul_add_plain(iters)).fold(0.0, f64::max);
    println!(
        "plain Rust multiply-add chains, this build's target: {:.1} GFlop/s",
        gb(rate)
    );
}
