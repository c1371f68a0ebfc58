//! Thread scaling of pair finding alone, two ways, on the benchmark's periodic box: one
//! parallel region per slab, as the sweep runs it (both threads on one slab, joined at its
//! end), and one region over all slabs (each thread takes whole slabs, no join until the
//! last). The difference is what the sweep's per-slab joins cost (BENCHMARKS.md, "Where
//! the second thread's time goes").
//!
//! `cargo run --release --example find_regions -- [PARTICLES] [REPEATS]`

use std::time::Instant;

use rayon::prelude::*;
use sphdisk::kernel::Kernel;
use sphdisk::sweep::local::Local;
use sphdisk::sweep::pairs::PairBlock;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map_or(Ok(100_000), |s| s.parse())?;
    let repeats: usize = args.next().map_or(Ok(10), |s| s.parse())?;
    let (p, bx, h) = sphdisk::bench::uniform_box(n, 50.0, 7)?;
    let kernel = Kernel::<3>::new(h);
    let local = Local::build(&p, &bx, kernel.support());
    let ns = local.num_slabs();
    println!("{} particles, {ns} slabs, {repeats} repeats", p.len());
    println!("threads  per-slab regions s  one region s");
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let (per_slab, one) = pool.install(|| {
            let mut pairs = 0;
            let c = Instant::now();
            for _ in 0..repeats {
                for s in 0..ns {
                    pairs += PairBlock::find(&local, &kernel, s).len();
                }
            }
            let per_slab = c.elapsed().as_secs_f64() / repeats as f64;
            let c = Instant::now();
            for _ in 0..repeats {
                pairs += (0..ns)
                    .into_par_iter()
                    .with_min_len(1)
                    .map(|s| PairBlock::find(&local, &kernel, s).len())
                    .sum::<usize>();
            }
            let one = c.elapsed().as_secs_f64() / repeats as f64;
            std::hint::black_box(pairs);
            (per_slab, one)
        });
        println!("{threads:>7}  {per_slab:>18.4}  {one:>12.4}");
    }
    Ok(())
}
