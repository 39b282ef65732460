//! Deterministic parallel map: items are computed in parallel (rayon, when the `parallel` feature is on) in
//! chunks, and handed to the consumer strictly in index order. Results therefore never depend on the number of
//! threads, and memory holds one chunk of results at a time, not all of them.

use crate::error::{Error, Result};

/// Most threads a run may ask for. Ours: 1024 is more cores than any one machine talus runs on has, while a
/// typo such as 100000 would spend minutes starting threads that then fight over the cores.
pub const MAX_THREADS: usize = 1024;

/// Refuses a thread count (named `field`, e.g. `--threads` or `scenario.toml: simulation.threads`) above
/// [`MAX_THREADS`]; 0 (all cores) is for the caller to allow or not.
pub fn check_threads(field: &str, threads: usize) -> Result<()> {
    if threads <= MAX_THREADS {
        return Ok(());
    }
    Err(Error::invalid(
        field,
        format!("{threads} threads is more than the limit of {MAX_THREADS}"),
        "give at most the number of cores, or leave it out to use all cores",
    ))
}

/// Computes `f(i)` for `i` in `0..n` on `threads` threads (0 = all cores) and passes each result to `consume` in
/// increasing `i`. Chunks of `chunk` items are computed at a time.
pub fn map_in_order<T, F, C>(n: usize, threads: usize, chunk: usize, f: F, mut consume: C)
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
    C: FnMut(usize, T),
{
    let chunk = chunk.max(1);
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        if threads == 1 {
            for i in 0..n {
                consume(i, f(i));
            }
            return;
        }
        // The pool we run in (rayon's global pool, started once, unless the caller installed one) when it has the
        // threads asked for (0: all it has); a pool for this call only for another count.
        let own = threads != 0 && threads != rayon::current_num_threads();
        let pool = own.then(|| rayon::ThreadPoolBuilder::new().num_threads(threads).build().ok()).flatten();
        let mut start = 0;
        while start < n {
            let end = (start + chunk).min(n);
            // Split down to single items (ours): rayon otherwise stops splitting at about four pieces per thread
            // unless one is stolen, and a thread left with a piece of costly items (a calibration's items come in run
            // order, and some runs cost ten times others) keeps the other cores idle until it is done.
            let compute = || (start..end).into_par_iter().with_max_len(1).map(&f).collect::<Vec<T>>();
            let results = match &pool {
                Some(p) => p.install(compute),
                None => compute(),
            };
            for (k, r) in results.into_iter().enumerate() {
                consume(start + k, r);
            }
            start = end;
        }
    }
    #[cfg(not(feature = "parallel"))]
    {
        let _ = (threads, chunk);
        for i in 0..n {
            consume(i, f(i));
        }
    }
}

/// The threads `requested` (0 = all cores) come to: what a run records as used.
pub fn threads_used(requested: usize) -> usize {
    #[cfg(feature = "parallel")]
    return if requested == 0 { rayon::current_num_threads() } else { requested };
    #[cfg(not(feature = "parallel"))]
    {
        let _ = requested;
        1
    }
}

/// `f(i)` for `i` in `0..n`, collected in order (see [`map_in_order`]).
pub fn collect_in_order<T, F>(n: usize, threads: usize, f: F) -> Vec<T>
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
{
    let mut out = Vec::with_capacity(n);
    map_in_order(n, threads, 1024, f, |_, r| out.push(r));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_is_kept_for_any_thread_count() {
        for threads in [0, 1, 2, 3] {
            let mut seen = Vec::new();
            map_in_order(100, threads, 7, |i| i * i, |i, r| seen.push((i, r)));
            assert_eq!(seen, (0..100).map(|i| (i, i * i)).collect::<Vec<_>>());
        }
    }
}
