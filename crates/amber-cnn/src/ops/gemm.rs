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

/// Like [`for_each_item`], but every item adds into an accumulator of `len` zeros; returns the
/// sum of all accumulators. The items are summed in the chunks of `amber_nn::reduce` (one
/// accumulator per chunk, the chunks added in order), whether the chunks run in parallel or one
/// after the other: the sum is the same at any thread count (a product's own result does not
/// depend on its threads, since `gemm` splits only the output between them).
pub(super) fn sum_over_items<T: Float>(
    items: usize,
    len: usize,
    work: impl Fn(usize, usize, &mut [T], &mut Scratch<T>) + Sync,
) -> Vec<T> {
    let threads = rayon::current_num_threads();
    let zeros = || vec![T::zero(); len];
    let add = |mut a: Vec<T>, b: Vec<T>| {
        a.iter_mut().zip(&b).for_each(|(a, &b)| *a += b);
        a
    };
    if items >= 2 * threads {
        let fold = |(mut acc, mut scratch): (Vec<T>, Scratch<T>), i| {
            work(i, 1, &mut acc, &mut scratch);
            (acc, scratch)
        };
        ordered_fold((0..items).into_par_iter(), || (zeros(), Scratch::new()), fold, |(a, s), (b, _)| (add(a, b), s)).0
    } else {
        let mut scratch = Scratch::new();
        let sums = chunks(items).into_iter().map(|range| {
            let mut acc = zeros();
            range.for_each(|i| work(i, threads, &mut acc, &mut scratch));
            acc
        });
        sums.reduce(add).unwrap_or_else(zeros)
    }
}
