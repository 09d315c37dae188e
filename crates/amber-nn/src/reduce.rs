//! Parallel reductions whose result does not depend on the thread pool.
//!
//! Floating-point addition is not associative, so a rayon `fold`/`reduce` (which splits its work
//! where the scheduler happens to steal it) sums in an order that changes with the number of
//! threads and from run to run, and two trainings with the same seed drift apart. Here the items
//! are cut into at most [`MAX_CHUNKS`] contiguous chunks fixed by the number of items alone; each
//! chunk is folded sequentially, the chunks run in parallel, and the chunk results are combined
//! one after the other in chunk order. The result is the same at any thread count.

use std::ops::Range;

use rayon::prelude::*;

/// The most chunks a reduction is cut into: enough to keep the threads of a large machine busy,
/// few enough that one accumulator per chunk (a whole weight gradient) stays cheap.
pub const MAX_CHUNKS: usize = 32;

/// Items per chunk for `len` items: ⌈len / [`MAX_CHUNKS`]⌉, at least one.
fn chunk_len(len: usize) -> usize {
    len.div_ceil(MAX_CHUNKS).max(1)
}

/// The chunks `0..len` is cut into, in order: contiguous, all of ⌈len / [`MAX_CHUNKS`]⌉ items
/// but the last. [`ordered_fold`] folds exactly these ranges, so a caller that must fold some
/// chunks on one thread (with multi-threaded work inside each item) gets the same result.
pub fn chunks(len: usize) -> Vec<Range<usize>> {
    let step = chunk_len(len);
    (0..len).step_by(step).map(|start| start..(start + step).min(len)).collect()
}

/// Folds `items` chunk by chunk ([`chunks`] of their number), each chunk sequentially from
/// `identity()` and the chunks in parallel, then combines the chunk results in chunk order:
/// `combine(combine(c₀, c₁), c₂)…`. No items: `identity()`.
pub fn ordered_fold<I, A>(
    items: I,
    identity: impl Fn() -> A + Send + Sync,
    fold: impl Fn(A, I::Item) -> A + Send + Sync,
    combine: impl FnMut(A, A) -> A,
) -> A
where
    I: IndexedParallelIterator,
    A: Send,
{
    let len = items.len();
    let parts: Vec<A> = items.fold_chunks(chunk_len(len), &identity, fold).collect();
    parts.into_iter().reduce(combine).unwrap_or_else(identity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_cover_the_items_in_order_and_depend_on_the_length_only() {
        for len in [0, 1, 5, 31, 32, 33, 64, 65, 1000] {
            let c = chunks(len);
            assert!(c.len() <= MAX_CHUNKS);
            assert_eq!(c.iter().flat_map(|r| r.clone()).collect::<Vec<_>>(), (0..len).collect::<Vec<_>>());
            // The fold visits the same ranges, each in order.
            let visited = ordered_fold(
                (0..len).into_par_iter(),
                Vec::new,
                |mut v: Vec<usize>, i| {
                    v.push(i);
                    v
                },
                |mut a, b| {
                    a.push(usize::MAX);
                    a.extend(b);
                    a
                },
            );
            let expected: Vec<usize> = c
                .iter()
                .enumerate()
                .flat_map(|(k, r)| (k > 0).then_some(usize::MAX).into_iter().chain(r.clone()))
                .collect();
            assert_eq!(visited, expected, "len {len}");
        }
    }

    #[test]
    fn sums_are_the_same_at_any_thread_count() {
        // Magnitudes spread over many orders, so that any change of order changes the rounding.
        let values: Vec<f64> =
            (0..10_000).map(|i| ((i * 7919 % 1000) as f64 - 500.0) * 10f64.powi(i % 17 - 8)).collect();
        let sum = |values: &[f64]| ordered_fold(values.par_iter(), || 0.0, |s, &v| s + v, |a, b| a + b);
        let sums: Vec<u64> = (1..=4)
            .map(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| sum(&values)).to_bits())
            .collect();
        assert!(sums.iter().all(|&s| s == sums[0]), "{sums:?}");
        assert_eq!(sum(&[]), 0.0);
    }
}
