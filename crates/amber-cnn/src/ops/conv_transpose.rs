//! Transposed convolution with kernel 2 and stride 2 over every spatial axis (the U-Net's
//! up-sampling), with bias. Each input position owns its own 2ᴰ output block, so the op is a
//! product `Z (O·2ᴰ × P) = Wᵀ · X` plus a scatter of Z's rows into the blocks.

use amber_nn::op::{Fused, SliceOp};
use candle_core::{Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use super::gemm::{Strided, matmul, sum_over_items};
use super::{Float, SharedMut, image_dims};

/// Scratch elements of one tile of Z.
const TILE_ELEMENTS: usize = 1 << 18;

/// `x (N, C, spatial...)` with `w (C, O, 2, ..., 2)` and `b (O)` → `(N, O, 2·spatial...)`:
/// `y[n, o, 2i + a] = b[o] + Σ_c x[n, c, i] · w[c, o, a]`.
pub fn conv_transpose2(x: &Tensor, w: &Tensor, b: &Tensor) -> Result<Tensor> {
    x.contiguous()?.apply_op3(&w.contiguous()?, &b.contiguous()?, Fused(ConvTranspose2))
}

struct ConvTranspose2;

/// Where every input position's output block starts, and the offsets inside a block.
struct Blocks {
    n: usize,
    c: usize,
    o: usize,
    positions: usize,
    /// Output flat index of the block of each input position.
    starts: Vec<usize>,
    /// Offsets of the 2ᴰ block entries from the block start, row-major over the kernel.
    offsets: Vec<usize>,
}

impl Blocks {
    fn new(x: &[usize], w: &[usize], b: &[usize]) -> Result<Self> {
        let (n, c, spatial) = image_dims("conv_transpose2", x, x.len().saturating_sub(2))?;
        let axes = spatial.len();
        if w.len() != axes + 2 || w[0] != c || c == 0 || w[1] == 0 || w[2..].iter().any(|&k| k != 2) || b != [w[1]] {
            bail!(
                "conv_transpose2: input {x:?}, kernel {w:?} and bias {b:?} do not fit (kernel (C, O, 2, ...), bias (O))"
            );
        }
        let out: Vec<usize> = spatial.iter().map(|s| 2 * s).collect();
        let mut out_strides = vec![1; axes];
        for a in (0..axes - 1).rev() {
            out_strides[a] = out_strides[a + 1] * out[a + 1];
        }
        let positions: usize = spatial.iter().product();
        let starts = (0..positions)
            .map(|mut p| {
                let mut start = 0;
                for a in (0..axes).rev() {
                    start += 2 * (p % spatial[a]) * out_strides[a];
                    p /= spatial[a];
                }
                start
            })
            .collect();
        let offsets = (0..1usize << axes)
            .map(|bits| (0..axes).map(|a| ((bits >> (axes - 1 - a)) & 1) * out_strides[a]).sum())
            .collect();
        Ok(Self { n, c, o: w[1], positions, starts, offsets })
    }

    fn block(&self) -> usize {
        self.offsets.len()
    }

    fn output_positions(&self) -> usize {
        self.positions * self.block()
    }

    /// Positions per tile, and tiles per image.
    fn tiling(&self) -> (usize, usize) {
        let width = (TILE_ELEMENTS / (self.o * self.block())).clamp(1, self.positions);
        (width, self.positions.div_ceil(width))
    }
}

fn forward<T: Float>(x: &[T], w: &[T], bias: &[T], blocks: &Blocks) -> Vec<T> {
    let (c, o, p, k) = (blocks.c, blocks.o, blocks.positions, blocks.block());
    let out_p = blocks.output_positions();
    // Every entry is written exactly once by the scatter below: no zero fill needed.
    let mut out: Vec<T> = Vec::with_capacity(blocks.n * o * out_p);
    let (width, tiles) = blocks.tiling();
    let dst = SharedMut(out.spare_capacity_mut().as_mut_ptr().cast::<T>());
    super::gemm::for_each_item(blocks.n * tiles, |item, threads, scratch| {
        let (image, tile) = (item / tiles, item % tiles);
        let range = tile * width..((tile + 1) * width).min(p);
        let t = range.len();
        let z = scratch.take(o * k * t);
        let xs = Strided { ptr: x[image * c * p + range.start..].as_ptr(), rows: p as isize, cols: 1 };
        // SAFETY: `z` is this item's own; operands are in bounds.
        unsafe { matmul(o * k, t, c, z.as_mut_ptr(), t, false, Strided::transposed(w, o * k), xs, threads) };
        for oi in 0..o {
            let plane = image * o * out_p + oi * out_p;
            for (s, &offset) in blocks.offsets.iter().enumerate() {
                let row = &z[(oi * k + s) * t..][..t];
                for (&v, &start) in row.iter().zip(&blocks.starts[range.clone()]) {
                    // SAFETY: the blocks of this tile's positions belong to this item alone.
                    unsafe { *dst.ptr().add(plane + start + offset) = v + bias[oi] };
                }
            }
        }
    });
    // SAFETY: the tiles cover every input position, and each position's block is written for
    // every output channel and kernel entry.
    unsafe { out.set_len(blocks.n * o * out_p) };
    out
}

/// Input gradient (if `want_dx`), kernel gradient and bias gradient.
fn backward<T: Float>(x: &[T], w: &[T], dy: &[T], blocks: &Blocks, want_dx: bool) -> (Option<Vec<T>>, Vec<T>, Vec<T>) {
    let (c, o, p, k) = (blocks.c, blocks.o, blocks.positions, blocks.block());
    let out_p = blocks.output_positions();
    let mut dx = want_dx.then(|| vec![T::zero(); blocks.n * c * p]);
    let dx_ptr = SharedMut(dx.as_mut().map_or(std::ptr::null_mut(), |d| d.as_mut_ptr()));
    let (width, tiles) = blocks.tiling();
    let dw = sum_over_items(blocks.n * tiles, c * o * k, width, |item, threads, acc: &mut [T], scratch| {
        let (image, tile) = (item / tiles, item % tiles);
        let range = tile * width..((tile + 1) * width).min(p);
        let t = range.len();
        let dz = scratch.take(o * k * t);
        for oi in 0..o {
            let plane = &dy[image * o * out_p + oi * out_p..][..out_p];
            for (s, &offset) in blocks.offsets.iter().enumerate() {
                let row = &mut dz[(oi * k + s) * t..][..t];
                for (v, &start) in row.iter_mut().zip(&blocks.starts[range.clone()]) {
                    *v = plane[start + offset];
                }
            }
        }
        let xs = Strided { ptr: x[image * c * p + range.start..].as_ptr(), rows: p as isize, cols: 1 };
        // SAFETY: `acc` is lent to this item alone while it runs, and the dx columns of this tile are written by
        // this item alone; operands are in bounds.
        unsafe {
            matmul(c, o * k, t, acc.as_mut_ptr(), o * k, true, xs, Strided::transposed(dz, t), threads);
            if want_dx {
                let dst = dx_ptr.ptr().add(image * c * p + range.start);
                matmul(c, t, o * k, dst, p, false, Strided::row_major(w, o * k), Strided::row_major(dz, t), threads);
            }
        }
    });
    let db = (0..o)
        .into_par_iter()
        .map(|oi| {
            (0..blocks.n)
                .fold(T::zero(), |sum, image| dy[(image * o + oi) * out_p..][..out_p].iter().fold(sum, |s, &v| s + v))
        })
        .collect();
    (dx, dw, db)
}

impl<T: Float> SliceOp<T, 3> for ConvTranspose2 {
    const NAME: &'static str = "amber-conv-transpose2";

    fn forward(&self, [x, w, b]: [&[T]; 3], [xl, wl, bl]: [&Layout; 3]) -> Result<(Vec<T>, Shape)> {
        let blocks = Blocks::new(xl.dims(), wl.dims(), bl.dims())?;
        let dims: Vec<usize> = [blocks.n, blocks.o].into_iter().chain(xl.dims()[2..].iter().map(|s| 2 * s)).collect();
        Ok((forward(x, w, b, &blocks), Shape::from(dims)))
    }

    fn backward(
        &self,
        [x, w, _]: [&[T]; 3],
        [xl, wl, bl]: [&Layout; 3],
        _: &[T],
        dy: &[T],
        [x_tracked, ..]: [bool; 3],
    ) -> Result<[Option<Vec<T>>; 3]> {
        let blocks = Blocks::new(xl.dims(), wl.dims(), bl.dims())?;
        let (dx, dw, db) = backward(x, w, dy, &blocks, x_tracked);
        Ok([dx, Some(dw), Some(db)])
    }
}

#[cfg(test)]
mod tests {
    use candle_core::DType;

    use super::*;
    use crate::ops::testing::*;

    /// Direct loops: y[n,o,2i+a] = b[o] + Σ_c x[n,c,i]·w[c,o,a], and the gradients of Σ y·g.
    fn naive(x: &Image, w: &[f64], b: &[f64], g: &Image) -> (Image, Image, Vec<f64>, Vec<f64>) {
        let (o, axes) = (b.len(), x.spatial.len());
        let k = 1usize << axes;
        let out_spatial: Vec<usize> = x.spatial.iter().map(|s| 2 * s).collect();
        let mut y = Image::zeros(x.n, o, &out_spatial);
        let (mut dx, mut dw, mut db) = (Image::zeros(x.n, x.c, &x.spatial), vec![0.0; w.len()], vec![0.0; o]);
        for n in 0..x.n {
            for oi in 0..o {
                for q in 0..y.positions() {
                    let index = y.index(q);
                    let i: Vec<isize> = index.iter().map(|&j| (j / 2) as isize).collect();
                    let a = index.iter().fold(0, |s, &j| 2 * s + j % 2);
                    let p = x.flat(&i).unwrap();
                    let mut v = b[oi];
                    for c in 0..x.c {
                        let wi = (c * o + oi) * k + a;
                        v += x.get(n, c, p) * w[wi];
                        *dx.get_mut(n, c, p) += w[wi] * g.get(n, oi, q);
                        dw[wi] += x.get(n, c, p) * g.get(n, oi, q);
                    }
                    *y.get_mut(n, oi, q) = v;
                    db[oi] += g.get(n, oi, q);
                }
            }
        }
        (y, dx, dw, db)
    }

    fn check(n: usize, c: usize, o: usize, spatial: &[usize], seed: u64) {
        let x = Image::random(n, c, spatial, seed);
        let wdims: Vec<usize> = [c, o].into_iter().chain(std::iter::repeat_n(2, spatial.len())).collect();
        let w = random_vec(wdims.iter().product(), seed + 1);
        let b = random_vec(o, seed + 2);
        let out_spatial: Vec<usize> = spatial.iter().map(|s| 2 * s).collect();
        let g = Image::random(n, o, &out_spatial, seed + 3);
        let (expected, edx, edw, edb) = naive(&x, &w, &b, &g);
        for dtype in [DType::F64, DType::F32] {
            let inputs = [x.tensor(dtype), tensor(&w, &wdims, dtype), tensor(&b, &[o], dtype)];
            let (y, grads) = forward_and_grads(&inputs, &g, |t| conv_transpose2(&t[0], &t[1], &t[2]));
            assert_close(&y, &expected.data, 1e-4, "forward");
            assert_close(&grads[0], &edx.data, 1e-4, "input gradient");
            assert_close(&grads[1], &edw, 1e-4, "kernel gradient");
            assert_close(&grads[2], &edb, 1e-4, "bias gradient");
        }
    }

    #[test]
    fn transposed_conv2d_matches_naive_loops() {
        check(2, 3, 4, &[3, 5], 1);
        check(3, 2, 2, &[40, 40], 2);
    }

    #[test]
    fn transposed_conv3d_matches_naive_loops() {
        check(2, 3, 2, &[2, 3, 4], 3);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let x = Image::random(1, 2, &[2, 3, 2], 4).tensor(DType::F64);
        let w = tensor(&random_vec(2 * 3 * 8, 5), &[2, 3, 2, 2, 2], DType::F64);
        let b = tensor(&random_vec(3, 6), &[3], DType::F64);
        check_finite_differences(&[x, w, b], &|t| probe_loss(&conv_transpose2(&t[0], &t[1], &t[2])?, 99));
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        // Five items, then 34 (two tiles per image), as in the convolution's test.
        for (n, c, o, spatial) in [(5, 8, 4, [16, 16]), (17, 4, 64, [32, 32])] {
            let x = Image::random(n, c, &spatial, 1).tensor(DType::F32);
            let w = tensor(&random_vec(c * o * 4, 2), &[c, o, 2, 2], DType::F32);
            let b = tensor(&random_vec(o, 3), &[o], DType::F32);
            let loss = |t: &[Tensor]| probe_loss(&conv_transpose2(&t[0], &t[1], &t[2])?, 4);
            assert_same_at_any_thread_count(|| autograd(&[x.clone(), w.clone(), b.clone()], &loss));
        }
    }

    #[test]
    fn mismatched_kernels_are_errors() {
        let x = Image::random(1, 2, &[2, 2], 7).tensor(DType::F32);
        let w = tensor(&random_vec(3 * 3 * 4, 1), &[3, 3, 2, 2], DType::F32);
        assert!(conv_transpose2(&x, &w, &tensor(&[0.0; 3], &[3], DType::F32)).is_err());
    }
}
