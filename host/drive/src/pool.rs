//! Parallel correspondence search for the core: its `Executor` over a rayon pool.
//!
//! The core fixes the chunking and the reduction order, so any thread count gives the same
//! bits; the pool only decides who computes which chunk.

use kiss_odom_core::{Executor, Sequential};
use rayon::prelude::*;

/// A pool of worker threads, or the calling thread alone.
pub enum Pool {
    /// One thread: no pool at all.
    Single(Sequential),
    /// A dedicated rayon pool.
    Rayon(rayon::ThreadPool),
}

impl Pool {
    /// A pool of `threads` workers (1 runs on the caller).
    pub fn new(threads: usize) -> anyhow::Result<Self> {
        if threads <= 1 {
            return Ok(Self::Single(Sequential));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        Ok(Self::Rayon(pool))
    }
}

impl Executor for Pool {
    fn for_each<C: Send>(&self, chunks: &mut [C], work: &(dyn Fn(&mut C) + Sync)) {
        match self {
            Self::Single(s) => s.for_each(chunks, work),
            Self::Rayon(pool) => pool.install(|| chunks.par_iter_mut().for_each(work)),
        }
    }
}
