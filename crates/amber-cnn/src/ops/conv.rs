//! Convolution with an odd cubic kernel, stride 1 and "same" zero padding, over any number of
//! spatial axes (the U-Net's 3×3 / 3×3×3 convolutions and its 1×1 output layer).
//!
//! Forward: per tile of rows, im2col into a scratch matrix `(C·K) × T` and one gemm
//! `W (O × C·K) · cols` written straight into the output. Backward: the input gradient is the
//! same convolution of the output gradient with the flipped, transposed kernel; the weight
//! gradient is `Σ dY_tile · colsᵀ`, summed over the tiles in the fixed chunks of
//! `amber_nn::reduce` (the same at any thread count).

use amber_nn::op::{Fused, SliceOp};
use candle_core::{Layout, Result, Shape, Tensor, bail};

use super::gemm::{Strided, for_each_item, matmul, sum_over_items};
use super::{Float, SharedMut, image_dims};

/// Scratch elements of one im2col tile (512 KB in f32): big enough for efficient products, small
/// enough to stay in cache between the unfold and the product.
const TILE_ELEMENTS: usize = 1 << 17;

/// `x (N, C, spatial...)` convolved with `w (O, C, k, ..., k)` (odd k, one k per spatial axis),
/// stride 1, zero padding k/2 (the output has the input's spatial shape), no bias.
pub fn conv(x: &Tensor, w: &Tensor) -> Result<Tensor> {
    let spatial_axes = x.rank().saturating_sub(2);
    let (_, c, kernel) = kernel_dims(w.dims(), spatial_axes)?;
    if x.dim(1)? != c {
        bail!("conv: input has {} channels, the kernel {c} (kernel shape {:?})", x.dim(1)?, w.dims());
    }
    x.contiguous()?.apply_op2(&w.contiguous()?, Fused(Conv { kernel }))
}

/// `(O, C, k)` of a kernel tensor `(O, C, k, ..., k)` with `spatial_axes` equal odd sizes k.
fn kernel_dims(dims: &[usize], spatial_axes: usize) -> Result<(usize, usize, usize)> {
    match dims {
        [o, c, ks @ ..]
            if *o > 0
                && *c > 0
                && spatial_axes > 0
                && ks.len() == spatial_axes
                && ks[0] % 2 == 1
                && ks.iter().all(|&k| k == ks[0]) =>
        {
            Ok((*o, *c, ks[0]))
        }
        _ => bail!("conv: the kernel must be (O, C) (both positive) plus {spatial_axes} equal odd sizes, got {dims:?}"),
    }
}

struct Conv {
    kernel: usize,
}

/// How a tile of rows unfolds: the spatial shape, split into rows along the last axis.
struct Unfold {
    spatial: Vec<usize>,
    kernel: usize,
    row_len: usize,
    rows: usize,
}

impl Unfold {
    fn new(spatial: &[usize], kernel: usize) -> Self {
        let row_len = *spatial.last().expect("at least one spatial axis");
        let rows = spatial[..spatial.len() - 1].iter().product();
        Self { spatial: spatial.to_vec(), kernel, row_len, rows }
    }

    fn positions(&self) -> usize {
        self.rows * self.row_len
    }

    /// Kernel offsets K = kᴰ.
    fn taps(&self) -> usize {
        self.kernel.pow(self.spatial.len() as u32)
    }

    /// Rows per tile for `channels` input channels.
    fn tile_rows(&self, channels: usize) -> usize {
        (TILE_ELEMENTS / (channels * self.taps() * self.row_len).max(1)).clamp(1, self.rows)
    }

    /// For every row of `rows` and every kernel offset over the leading (non-row) axes, the
    /// source row, or `None` where it falls into the padding. Indexed `[prefix][row - start]`.
    fn source_rows(&self, rows: std::ops::Range<usize>) -> Vec<Vec<Option<usize>>> {
        let leading = &self.spatial[..self.spatial.len() - 1];
        let half = (self.kernel / 2) as isize;
        let prefixes = self.kernel.pow(leading.len() as u32);
        (0..prefixes)
            .map(|prefix| {
                rows.clone()
                    .map(|row| {
                        // Decode row and prefix (row-major, last leading axis fastest), shift, encode.
                        let (mut r, mut p, mut stride, mut source) = (row, prefix, 1, 0usize);
                        for &size in leading.iter().rev() {
                            let at = (r % size) as isize + (p % self.kernel) as isize - half;
                            if at < 0 || at >= size as isize {
                                return None;
                            }
                            source += at as usize * stride;
                            stride *= size;
                            r /= size;
                            p /= self.kernel;
                        }
                        Some(source)
                    })
                    .collect()
            })
            .collect()
    }

    /// Unfolds rows `rows` of one image `x (C × positions)` into `cols ((C·K) × T)`, T = rows ×
    /// row length: `cols[c·K + tap][t]` is the input under kernel tap `tap` at output position t.
    fn im2col<T: Float>(&self, x: &[T], channels: usize, rows: std::ops::Range<usize>, cols: &mut [T]) {
        let (len, k, half) = (self.row_len, self.kernel, self.kernel / 2);
        let tile = rows.len() * len;
        let taps = self.taps();
        let sources = self.source_rows(rows);
        for c in 0..channels {
            let image = &x[c * self.positions()..(c + 1) * self.positions()];
            for (prefix, sources) in sources.iter().enumerate() {
                for dx in 0..k {
                    let out = &mut cols[(c * taps + prefix * k + dx) * tile..][..tile];
                    for (out, source) in out.chunks_exact_mut(len).zip(sources) {
                        let Some(source) = source else {
                            out.fill(T::zero());
                            continue;
                        };
                        let src = &image[source * len..(source + 1) * len];
                        // out[i] = src[i + dx - half], zero outside the row.
                        if dx < half {
                            let shift = half - dx;
                            let shift = shift.min(len);
                            out[..shift].fill(T::zero());
                            out[shift..].copy_from_slice(&src[..len - shift]);
                        } else {
                            let shift = (dx - half).min(len);
                            out[..len - shift].copy_from_slice(&src[shift..]);
                            out[len - shift..].fill(T::zero());
                        }
                    }
                }
            }
        }
    }
}

/// The forward kernel: `x (N × C × P)`, `w (O × C·K)` → `(N × O × P)`.
fn forward<T: Float>(x: &[T], w: &[T], n: usize, c: usize, o: usize, unfold: &Unfold) -> Vec<T> {
    let (p, taps) = (unfold.positions(), unfold.taps());
    // Every entry is written by exactly one product below: no zero fill needed.
    let mut out: Vec<T> = Vec::with_capacity(n * o * p);
    let tile_rows = unfold.tile_rows(c);
    let tiles = unfold.rows.div_ceil(tile_rows);
    let dst = SharedMut(out.spare_capacity_mut().as_mut_ptr().cast::<T>());
    for_each_item(n * tiles, |item, threads, scratch| {
        let (image, tile) = (item / tiles, item % tiles);
        let rows = tile * tile_rows..((tile + 1) * tile_rows).min(unfold.rows);
        let (start, width) = (rows.start * unfold.row_len, rows.len() * unfold.row_len);
        let cols = scratch.take(c * taps * width);
        unfold.im2col(&x[image * c * p..(image + 1) * c * p], c, rows, cols);
        // SAFETY: this item writes only columns [start, start + width) of image `image`'s
        // (O × P) output block, disjoint from every other item; operands are in bounds.
        unsafe {
            matmul(
                o,
                width,
                c * taps,
                dst.ptr().add(image * o * p + start),
                p,
                false,
                Strided::row_major(w, c * taps),
                Strided::row_major(cols, width),
                threads,
            );
        }
    });
    // SAFETY: the tiles cover every row of every image, and each product writes all its O rows.
    unsafe { out.set_len(n * o * p) };
    out
}

/// The weight gradient `(O × C·K)`: Σ over images and tiles of `dY_tile · colsᵀ`.
fn weight_grad<T: Float>(x: &[T], dy: &[T], n: usize, c: usize, o: usize, unfold: &Unfold) -> Vec<T> {
    let (p, taps) = (unfold.positions(), unfold.taps());
    let tile_rows = unfold.tile_rows(c);
    let tiles = unfold.rows.div_ceil(tile_rows);
    sum_over_items(n * tiles, o * c * taps, tile_rows * unfold.row_len, |item, threads, acc: &mut [T], scratch| {
        let (image, tile) = (item / tiles, item % tiles);
        let rows = tile * tile_rows..((tile + 1) * tile_rows).min(unfold.rows);
        let (start, width) = (rows.start * unfold.row_len, rows.len() * unfold.row_len);
        let cols = scratch.take(c * taps * width);
        unfold.im2col(&x[image * c * p..(image + 1) * c * p], c, rows, cols);
        let dy = Strided { ptr: dy[image * o * p + start..].as_ptr(), rows: p as isize, cols: 1 };
        // SAFETY: `acc` is lent to this item alone while it runs; operands are in bounds.
        unsafe {
            matmul(o, c * taps, width, acc.as_mut_ptr(), c * taps, true, dy, Strided::transposed(cols, width), threads);
        }
    })
}

/// `w (O × C·K)` → `(C × O·K)` with every kernel flipped: the kernel of the input gradient.
fn flip_transpose<T: Float>(w: &[T], o: usize, c: usize, taps: usize) -> Vec<T> {
    let mut out = vec![T::zero(); w.len()];
    for oi in 0..o {
        for ci in 0..c {
            for tap in 0..taps {
                out[(ci * o + oi) * taps + taps - 1 - tap] = w[(oi * c + ci) * taps + tap];
            }
        }
    }
    out
}

impl Conv {
    fn shapes(&self, x: &Layout, w: &Layout) -> Result<(usize, usize, usize, Unfold)> {
        let (n, c, spatial) = image_dims("conv", x.dims(), x.dims().len().saturating_sub(2))?;
        let (o, wc, k) = kernel_dims(w.dims(), spatial.len())?;
        if wc != c || k != self.kernel {
            bail!("conv: input {:?} does not fit kernel {:?}", x.dims(), w.dims());
        }
        Ok((n, c, o, Unfold::new(&spatial, k)))
    }
}

impl<T: Float> SliceOp<T, 2> for Conv {
    const NAME: &'static str = "amber-conv";

    fn forward(&self, [x, w]: [&[T]; 2], [xl, wl]: [&Layout; 2]) -> Result<(Vec<T>, Shape)> {
        let (n, c, o, unfold) = self.shapes(xl, wl)?;
        let mut dims = xl.dims().to_vec();
        dims[1] = o;
        Ok((forward(x, w, n, c, o, &unfold), Shape::from(dims)))
    }

    fn backward(
        &self,
        [x, w]: [&[T]; 2],
        [xl, wl]: [&Layout; 2],
        _: &[T],
        dy: &[T],
        [x_tracked, _]: [bool; 2],
    ) -> Result<[Option<Vec<T>>; 2]> {
        let (n, c, o, unfold) = self.shapes(xl, wl)?;
        // The network's input image needs no gradient: skip the most expensive product.
        let dx = x_tracked.then(|| forward(dy, &flip_transpose(w, o, c, unfold.taps()), n, o, c, &unfold));
        Ok([dx, Some(weight_grad(x, dy, n, c, o, &unfold))])
    }
}

#[cfg(test)]
mod tests {
    use candle_core::DType;

    use super::*;
    use crate::ops::testing::*;

    /// Direct loops: y[n,o,p] = Σ_c Σ_tap w[o,c,tap] · x[n,c,p + offset(tap)].
    fn naive_forward(x: &Image, w: &[f64], o: usize, k: usize) -> Image {
        let mut y = Image::zeros(x.n, o, &x.spatial);
        for n in 0..x.n {
            for oi in 0..o {
                for p in 0..x.positions() {
                    let mut sum = 0.0;
                    for c in 0..x.c {
                        for (tap, offset) in taps(x.spatial.len(), k).iter().enumerate() {
                            if let Some(q) = x.shifted(p, offset) {
                                sum += w[(oi * x.c + c) * k.pow(x.spatial.len() as u32) + tap] * x.get(n, c, q);
                            }
                        }
                    }
                    *y.get_mut(n, oi, p) = sum;
                }
            }
        }
        y
    }

    /// Direct loops for the gradients of Σ y·g: dx[n,c,p+off] += w·g[n,o,p], dw += x·g.
    fn naive_backward(x: &Image, w: &[f64], g: &Image, k: usize) -> (Image, Vec<f64>) {
        let mut dx = Image::zeros(x.n, x.c, &x.spatial);
        let mut dw = vec![0.0; w.len()];
        let kk = k.pow(x.spatial.len() as u32);
        for n in 0..x.n {
            for oi in 0..g.c {
                for p in 0..x.positions() {
                    for c in 0..x.c {
                        for (tap, offset) in taps(x.spatial.len(), k).iter().enumerate() {
                            if let Some(q) = x.shifted(p, offset) {
                                let wi = (oi * x.c + c) * kk + tap;
                                *dx.get_mut(n, c, q) += w[wi] * g.get(n, oi, p);
                                dw[wi] += x.get(n, c, q) * g.get(n, oi, p);
                            }
                        }
                    }
                }
            }
        }
        (dx, dw)
    }

    fn check(n: usize, c: usize, o: usize, spatial: &[usize], k: usize, seed: u64) {
        let x = Image::random(n, c, spatial, seed);
        let mut wdims = vec![o, c];
        wdims.extend(std::iter::repeat_n(k, spatial.len()));
        let w = random_vec(wdims.iter().product(), seed + 1);
        let g = Image::random(n, o, spatial, seed + 2);
        let expected = naive_forward(&x, &w, o, k);
        let (expected_dx, expected_dw) = naive_backward(&x, &w, &g, k);
        for dtype in [DType::F64, DType::F32] {
            let (xt, wt) = (x.tensor(dtype), tensor(&w, &wdims, dtype));
            let (y, grads) = forward_and_grads(&[xt, wt], &g, |t| conv(&t[0], &t[1]));
            assert_close(&y, &expected.data, 1e-4, "forward");
            assert_close(&grads[0], &expected_dx.data, 1e-4, "input gradient");
            assert_close(&grads[1], &expected_dw, 1e-4, "weight gradient");
        }
    }

    #[test]
    fn conv2d_matches_naive_loops() {
        check(2, 3, 4, &[5, 7], 3, 1);
        check(1, 2, 3, &[4, 4], 1, 2);
        check(1, 1, 2, &[1, 3], 3, 3);
    }

    #[test]
    fn conv3d_matches_naive_loops() {
        check(2, 2, 3, &[4, 3, 5], 3, 4);
        check(1, 3, 1, &[2, 2, 2], 1, 5);
    }

    #[test]
    fn many_tiles_and_images_match_naive_loops() {
        // Enough images and rows for several parallel tiles per image.
        check(3, 5, 4, &[40, 32], 3, 6);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let x = Image::random(1, 2, &[3, 4, 2], 7).tensor(DType::F64);
        let w = tensor(&random_vec(3 * 2 * 27, 8), &[3, 2, 3, 3, 3], DType::F64);
        check_finite_differences(&[x, w], &|t| probe_loss(&conv(&t[0], &t[1])?, 99));
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        // Five items (one tile per image): in parallel at 1 and 2 threads, one after the other
        // with multi-threaded products at 3. Forty items (five tiles per image): several per chunk.
        for (n, c, spatial) in [(5, 4, [24, 32]), (8, 16, [64, 64])] {
            let x = Image::random(n, c, &spatial, 1).tensor(DType::F32);
            let w = tensor(&random_vec(8 * c * 9, 2), &[8, c, 3, 3], DType::F32);
            assert_same_at_any_thread_count(|| {
                autograd(&[x.clone(), w.clone()], &|t| probe_loss(&conv(&t[0], &t[1])?, 3))
            });
        }
    }

    #[test]
    fn bad_shapes_are_errors() {
        let x = Image::random(1, 2, &[4, 4], 9).tensor(DType::F32);
        assert!(conv(&x, &tensor(&random_vec(3 * 3 * 9, 1), &[3, 3, 3, 3], DType::F32)).is_err());
        assert!(conv(&x, &tensor(&random_vec(3 * 2 * 4, 1), &[3, 2, 2, 2], DType::F32)).is_err());
    }
}
