//! Max pooling with window 2 and stride 2 over every spatial axis (odd trailing entries are
//! dropped, as in PyTorch). The backward routes each output gradient to the first maximum of its
//! window, found again by comparing the input with the stored result.

use amber_nn::op::{Fused, SliceOp};
use candle_core::{Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use super::{Float, build_by_planes, image_dims};

/// `x (N, C, spatial...)` → `(N, C, spatial/2...)`, the maximum of every 2×…×2 window.
pub fn max_pool2(x: &Tensor) -> Result<Tensor> {
    x.contiguous()?.apply_op1(Fused(MaxPool2))
}

struct MaxPool2;

/// Input and output shapes of one (image, channel) plane.
struct Windows {
    input: Vec<usize>,
    output: Vec<usize>,
    /// Offsets of the 2ᴰ window entries from the window's first entry, row-major.
    offsets: Vec<usize>,
}

impl Windows {
    fn new(input: &[usize]) -> Result<Self> {
        let output: Vec<usize> = input.iter().map(|s| s / 2).collect();
        if output.contains(&0) {
            bail!("max_pool2: every spatial axis needs at least 2 entries, got {input:?}");
        }
        let strides = strides(input);
        let offsets = (0..1usize << input.len())
            .map(|bits| (0..input.len()).map(|axis| ((bits >> (input.len() - 1 - axis)) & 1) * strides[axis]).sum())
            .collect();
        Ok(Self { input: input.to_vec(), output, offsets })
    }

    fn input_len(&self) -> usize {
        self.input.iter().product()
    }

    fn output_len(&self) -> usize {
        self.output.iter().product()
    }

    /// Calls `f(output_index, window_start)` for every output entry of a plane.
    fn for_each(&self, mut f: impl FnMut(usize, usize)) {
        let strides = strides(&self.input);
        let row = *self.output.last().expect("a spatial axis");
        let last_stride = *strides.last().expect("a spatial axis");
        for r in 0..self.output_len() / row {
            let (mut rest, mut start) = (r, 0);
            for axis in (0..self.output.len() - 1).rev() {
                start += 2 * (rest % self.output[axis]) * strides[axis];
                rest /= self.output[axis];
            }
            for i in 0..row {
                f(r * row + i, start + 2 * i * last_stride);
            }
        }
    }
}

fn strides(shape: &[usize]) -> Vec<usize> {
    let mut strides = vec![1; shape.len()];
    for axis in (0..shape.len().saturating_sub(1)).rev() {
        strides[axis] = strides[axis + 1] * shape[axis + 1];
    }
    strides
}

fn forward<T: Float>(x: &[T], windows: &Windows) -> Vec<T> {
    let planes = x.len() / windows.input_len();
    build_by_planes(planes * windows.output_len(), windows.output_len(), |i, out| {
        let x = &x[i * windows.input_len()..(i + 1) * windows.input_len()];
        windows.for_each(|o, start| {
            let mut best = x[start];
            for &d in &windows.offsets[1..] {
                if x[start + d] > best {
                    best = x[start + d];
                }
            }
            out[o].write(best);
        });
    })
}

fn backward<T: Float>(x: &[T], y: &[T], dy: &[T], windows: &Windows) -> Vec<T> {
    let mut dx = vec![T::zero(); x.len()];
    let (input, output) = (windows.input_len(), windows.output_len());
    dx.par_chunks_mut(input).zip(x.par_chunks(input)).zip(y.par_chunks(output).zip(dy.par_chunks(output))).for_each(
        |((dx, x), (y, dy))| {
            windows.for_each(|o, start| {
                if let Some(&d) = windows.offsets.iter().find(|&&d| x[start + d] == y[o]) {
                    dx[start + d] = dy[o];
                }
            });
        },
    );
    dx
}

/// The windows of a `(N, C, spatial...)` input.
fn windows(dims: &[usize]) -> Result<Windows> {
    let (_, _, spatial) = image_dims("amber-max-pool2", dims, dims.len().saturating_sub(2))?;
    Windows::new(&spatial)
}

impl<T: Float> SliceOp<T, 1> for MaxPool2 {
    const NAME: &'static str = "amber-max-pool2";

    fn forward(&self, [x]: [&[T]; 1], [l]: [&Layout; 1]) -> Result<(Vec<T>, Shape)> {
        let windows = windows(l.dims())?;
        let dims: Vec<usize> = l.dims()[..2].iter().chain(&windows.output).copied().collect();
        Ok((forward(x, &windows), Shape::from(dims)))
    }

    fn backward(
        &self,
        [x]: [&[T]; 1],
        [l]: [&Layout; 1],
        y: &[T],
        dy: &[T],
        _: [bool; 1],
    ) -> Result<[Option<Vec<T>>; 1]> {
        Ok([Some(backward(x, y, dy, &windows(l.dims())?))])
    }
}

#[cfg(test)]
mod tests {
    use candle_core::DType;

    use super::*;
    use crate::ops::testing::*;

    /// Direct loops over windows: the maximum, and its gradient to the first maximal entry.
    fn naive(x: &Image, g: &Image) -> (Image, Image) {
        let out_spatial: Vec<usize> = x.spatial.iter().map(|s| s / 2).collect();
        let mut y = Image::zeros(x.n, x.c, &out_spatial);
        let mut dx = Image::zeros(x.n, x.c, &x.spatial);
        let axes = x.spatial.len();
        for n in 0..x.n {
            for c in 0..x.c {
                for o in 0..y.positions() {
                    let corner: Vec<isize> = y.index(o).iter().map(|&i| 2 * i as isize).collect();
                    let mut best: Option<(f64, usize)> = None;
                    for bits in 0..1usize << axes {
                        let at: Vec<isize> =
                            (0..axes).map(|a| corner[a] + ((bits >> (axes - 1 - a)) & 1) as isize).collect();
                        let q = x.flat(&at).unwrap();
                        if best.is_none_or(|(b, _)| x.get(n, c, q) > b) {
                            best = Some((x.get(n, c, q), q));
                        }
                    }
                    let (value, q) = best.unwrap();
                    *y.get_mut(n, c, o) = value;
                    *dx.get_mut(n, c, q) += g.get(n, c, o);
                }
            }
        }
        (y, dx)
    }

    fn check(n: usize, c: usize, spatial: &[usize], seed: u64) {
        let x = Image::random(n, c, spatial, seed);
        let out_spatial: Vec<usize> = spatial.iter().map(|s| s / 2).collect();
        let g = Image::random(n, c, &out_spatial, seed + 1);
        let (expected, expected_dx) = naive(&x, &g);
        for dtype in [DType::F64, DType::F32] {
            let (y, grads) = forward_and_grads(&[x.tensor(dtype)], &g, |t| max_pool2(&t[0]));
            assert_close(&y, &expected.data, 1e-6, "forward");
            assert_close(&grads[0], &expected_dx.data, 1e-6, "gradient");
        }
    }

    #[test]
    fn pool2d_matches_naive_loops_and_drops_odd_edges() {
        check(2, 3, &[6, 8], 1);
        check(1, 2, &[5, 7], 2);
    }

    #[test]
    fn pool3d_matches_naive_loops() {
        check(2, 2, &[4, 6, 2], 3);
        check(1, 1, &[3, 5, 4], 4);
    }

    #[test]
    fn gradient_goes_to_the_maximum_unscaled() {
        // candle's own max_pool2d returns 0.25 here.
        let x = tensor(&[1.0, 2.0, 3.0, 4.0], &[1, 1, 2, 2], DType::F32);
        let probe = Image { n: 1, c: 1, spatial: vec![1, 1], data: vec![1.0] };
        let (_, grads) = forward_and_grads(&[x], &probe, |t| max_pool2(&t[0]));
        assert_eq!(grads[0], vec![0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn gradient_is_the_same_at_any_thread_count() {
        let x = Image::random(4, 8, &[16, 16], 5).tensor(DType::F32);
        assert_same_at_any_thread_count(|| autograd(std::slice::from_ref(&x), &|t| probe_loss(&max_pool2(&t[0])?, 6)));
    }

    #[test]
    fn too_small_inputs_are_errors() {
        assert!(max_pool2(&tensor(&[1.0, 2.0], &[1, 1, 1, 2], DType::F32)).is_err());
    }
}
