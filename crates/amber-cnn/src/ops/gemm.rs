//! Strided matrix products on raw buffers (the `gemm` crate candle itself uses), and the work
//! split the convolutions share: many small single-threaded products in parallel when there are
//! enough tiles, else one multi-threaded product per tile.

use amber_nn::reduce::{chunks, ordered_fold};
use rayon::prelude::*;

use super::Float;

/// A strided matrix view: element (i, j) lives at `ptr + i·rows + j·cols`.
#[derive(Clone, Copy)]
pub(super) struct Strided<T> {
    pub ptr: *const T,
    pub rows: isize,
    pub cols: isize,
}

impl<T> Strided<T> {
    /// A row-major matrix with `cols` columns.
    pub fn row_major(data: &[T], cols: usize) -> Self {
        Self { ptr: data.as_ptr(), rows: cols as isize, cols: 1 }
    }

    /// The transpose of a row-major matrix with `cols` columns.
    pub fn transposed(data: &[T], cols: usize) -> Self {
        Self { ptr: data.as_ptr(), rows: 1, cols: cols as isize }
    }
}

/// `dst (m×n) = [dst +] a (m×k) · b (k×n)`; `dst` row-major with row stride `dst_rows`.
///
/// # Safety
/// Every element the strides address must lie inside live buffers, and no other thread may
/// touch the addressed part of `dst` meanwhile.
#[allow(clippy::too_many_arguments)]
pub(super) unsafe fn matmul<T: Float>(
    m: usize,
    n: usize,
    k: usize,
    dst: *mut T,
    dst_rows: usize,
    accumulate: bool,
    a: Strided<T>,
    b: Strided<T>,
    threads: usize,
) {
    if m == 0 || n == 0 {
        return;
    }
    let parallelism = if threads > 1 { gemm::Parallelism::Rayon(threads) } else { gemm::Parallelism::None };
    // SAFETY: forwarded to the caller.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            dst,
            1,
            dst_rows as isize,
            accumulate,
            a.ptr,
            a.cols,
            a.rows,
            b.ptr,
            b.cols,
            b.rows,
            T::from_f64(1.0),
            T::from_f64(1.0),
            false,
            false,
            false,
            parallelism,
        )
    }
}

/// Scratch memory of one worker, reused from item to item (zero-filled only when it grows, and
/// every user overwrites what it reads).
pub(super) struct Scratch<T>(Vec<T>);

impl<T: Float> Scratch<T> {
    fn new() -> Self {
        Self(Vec::new())
    }

    /// The first `len` elements, grown if needed.
    pub fn take(&mut self, len: usize) -> &mut [T] {
        if self.0.len() < len {
            self.0.resize(len, T::zero());
        }
        &mut self.0[..len]
    }
}

/// Runs `work(item, threads_for_its_matmuls, scratch)` for every item: items in parallel with
/// single-threaded products when there are enough of them to keep every thread busy, else one
/// after the other with multi-threaded products (the deep, small levels of a U-Net).
pub(super) fn for_each_item<T: Float>(items: usize, work: impl Fn(usize, usize, &mut Scratch<T>) + Sync) {
    let threads = rayon::current_num_threads();
    if items >= 2 * threads {
        (0..items).into_par_iter().for_each_init(Scratch::new, |scratch, i| work(i, 1, scratch));
    } else {
        let mut scratch = Scratch::new();
        (0..items).for_each(|i| work(i, threads, &mut scratch));
    }
}

/// The longest inner dimension `gemm` sums in one block (its `kc` is at least this or the whole
/// inner dimension): a product of inner dimension up to this, added into a non-zero destination,
/// rounds each entry once, exactly as adding its separately computed result would.
const ONE_BLOCK_INNER: usize = 512;

/// The most accumulator entries the chunks of [`sum_over_items`] may hold at once when they run
/// in parallel (64 MB of f32); beyond it they run one after the other in a reused buffer.
const PARALLEL_ACCUMULATORS: usize = 1 << 24;

/// How [`sum_over_items`] adds its items; every way gives the same sum.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Summation {
    /// Items one after the other, each adding its multi-threaded products into one running sum.
    InPlace,
    /// Chunks in parallel, each with its own accumulator and single-threaded products.
    ParallelChunks,
    /// Chunks one after the other in one reused accumulator, with multi-threaded products.
    SequentialChunks,
}

/// Like [`for_each_item`], but every item adds into an accumulator of `len` zeros; returns the
/// sum of all accumulators. The items are summed in the chunks of `amber_nn::reduce` (one
/// accumulator per chunk, the chunks added in order), whether the chunks run in parallel or one
/// after the other: the sum is the same at any thread count (a product's own result does not
/// depend on its threads, since `gemm` splits only the output between them).
///
/// `inner` is the longest inner dimension of the products an item adds. When every chunk is a
/// single item and `inner` is at most [`ONE_BLOCK_INNER`], the items add straight into one
/// running sum: the same sum without an accumulator per chunk (the deep levels of a U-Net, whose
/// few items each carry a whole weight gradient).
pub(super) fn sum_over_items<T: Float>(
    items: usize,
    len: usize,
    inner: usize,
    work: impl Fn(usize, usize, &mut [T], &mut Scratch<T>) + Sync,
) -> Vec<T> {
    let chunk_count = chunks(items).len();
    let summation = if chunk_count == items && inner <= ONE_BLOCK_INNER {
        Summation::InPlace
    } else if items >= 2 * rayon::current_num_threads() && chunk_count * len <= PARALLEL_ACCUMULATORS {
        Summation::ParallelChunks
    } else {
        Summation::SequentialChunks
    };
    sum_over_items_as(summation, items, len, work)
}

fn sum_over_items_as<T: Float>(
    summation: Summation,
    items: usize,
    len: usize,
    work: impl Fn(usize, usize, &mut [T], &mut Scratch<T>) + Sync,
) -> Vec<T> {
    let threads = rayon::current_num_threads();
    let zeros = || vec![T::zero(); len];
    let add = |sum: &mut [T], part: &[T]| sum.iter_mut().zip(part).for_each(|(s, &p)| *s += p);
    let mut scratch = Scratch::new();
    match summation {
        Summation::InPlace => {
            let mut sum = zeros();
            (0..items).for_each(|i| work(i, threads, &mut sum, &mut scratch));
            sum
        }
        Summation::ParallelChunks => {
            let fold = |(mut acc, mut scratch): (Vec<T>, Scratch<T>), i| {
                work(i, 1, &mut acc, &mut scratch);
                (acc, scratch)
            };
            let combine = |(mut a, s): (Vec<T>, _), (b, _): (Vec<T>, _)| {
                add(&mut a, &b);
                (a, s)
            };
            ordered_fold((0..items).into_par_iter(), || (zeros(), Scratch::new()), fold, combine).0
        }
        Summation::SequentialChunks => {
            let (mut sum, mut acc) = (None, zeros());
            for range in chunks(items) {
                acc.fill(T::zero());
                range.for_each(|i| work(i, threads, &mut acc, &mut scratch));
                match &mut sum {
                    None => sum = Some(acc.clone()),
                    Some(sum) => add(sum, &acc),
                }
            }
            sum.unwrap_or(acc)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::testing::random_vec;

    /// `items` items, each adding a product `a_i (m × inner) · b_i (inner × n)` (the U-Net's
    /// weight-gradient tiles), summed every way that applies, on two threads.
    fn sums(items: usize, inner: usize) -> Vec<Vec<f32>> {
        let (m, n) = (96, 300);
        let f32s = |len, seed| random_vec(len, seed).into_iter().map(|v| v as f32).collect::<Vec<f32>>();
        let a: Vec<Vec<f32>> = (0..items).map(|i| f32s(m * inner, 2 * i as u64)).collect();
        let b: Vec<Vec<f32>> = (0..items).map(|i| f32s(inner * n, 2 * i as u64 + 1)).collect();
        let work = |i: usize, threads, acc: &mut [f32], _: &mut Scratch<f32>| {
            // SAFETY: `acc` is m × n and the operands m × inner and inner × n.
            unsafe {
                matmul(
                    m,
                    n,
                    inner,
                    acc.as_mut_ptr(),
                    n,
                    true,
                    Strided::row_major(&a[i], inner),
                    Strided::row_major(&b[i], n),
                    threads,
                )
            }
        };
        let mut ways = vec![Summation::ParallelChunks, Summation::SequentialChunks];
        if chunks(items).len() == items && inner <= ONE_BLOCK_INNER {
            ways.push(Summation::InPlace);
        }
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        pool.install(|| ways.into_iter().map(|way| sum_over_items_as(way, items, m * n, work)).collect())
    }

    #[test]
    fn every_way_of_summing_gives_the_same_bits() {
        // Single-item chunks (in place too, up to one gemm block), then two items per chunk.
        for (items, inner) in [(16, 16), (16, 256), (16, ONE_BLOCK_INNER), (16, 700), (64, 16), (64, 700)] {
            let sums = sums(items, inner);
            for other in &sums[1..] {
                assert!(
                    other.iter().zip(&sums[0]).all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{items} items, inner {inner}"
                );
            }
        }
    }
}
