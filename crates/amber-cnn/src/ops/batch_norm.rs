//! BatchNorm followed by ReLU, fused: `y = max(0, γ·(x − μ)/√(σ² + ε) + β)` per channel.
//!
//! In training the statistics are the batch's own (over images and positions) and the backward
//! includes their dependence on x; in evaluation they are the running statistics, constants.
//! Channel sums are accumulated in f64.

use amber_nn::op::{Fused, SliceOp, with_slice};
use candle_core::{DType, Layout, Result, Shape, Tensor, bail};
use rayon::prelude::*;

use super::{Float, build_by_planes};

/// Added to the variance (PyTorch's default).
pub const EPSILON: f64 = 1e-5;

/// Per-channel mean and variance.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchNormStats {
    pub mean: Vec<f64>,
    pub variance: Vec<f64>,
}

/// BatchNorm + ReLU of `x (N, C, spatial...)` with per-channel `gamma` and `beta` (C).
///
/// With `running = None` (training) x is normalised by its own batch statistics, which are
/// returned with the variance unbiased (what running averages take, as in PyTorch); with
/// running statistics (evaluation) those are used and returned unchanged.
pub fn batch_norm_relu(
    x: &Tensor,
    gamma: &Tensor,
    beta: &Tensor,
    running: Option<&BatchNormStats>,
) -> Result<(Tensor, BatchNormStats)> {
    let x = x.contiguous()?;
    let dims = x.dims();
    if dims.len() < 3 || gamma.dims() != [dims[1]] || beta.dims() != [dims[1]] {
        bail!(
            "batch_norm_relu: input {dims:?} needs gamma and beta of shape [C], got {:?} and {:?}",
            gamma.dims(),
            beta.dims()
        );
    }
    let (channels, plane) = (dims[1], dims[2..].iter().product::<usize>());
    let count = dims[0] * plane;
    let (normalising, reported) = match running {
        Some(stats) => {
            if stats.mean.len() != channels || stats.variance.len() != channels {
                bail!("batch_norm_relu: running statistics for {} channels, input has {channels}", stats.mean.len());
            }
            (stats.clone(), stats.clone())
        }
        None => {
            let batch = match x.dtype() {
                DType::F32 => with_slice::<f32, _>(&x, |v| Ok(channel_stats(v, channels, plane)))?,
                DType::F64 => with_slice::<f64, _>(&x, |v| Ok(channel_stats(v, channels, plane)))?,
                other => bail!("batch_norm_relu: unsupported dtype {other:?}"),
            };
            let unbiased = count as f64 / (count.max(2) - 1) as f64;
            let reported = BatchNormStats {
                mean: batch.mean.clone(),
                variance: batch.variance.iter().map(|v| v * unbiased).collect(),
            };
            (batch, reported)
        }
    };
    let op = BatchNormRelu {
        rstd: normalising.variance.iter().map(|v| 1.0 / (v + EPSILON).sqrt()).collect(),
        mean: normalising.mean,
        batch_statistics: running.is_none(),
    };
    Ok((x.apply_op3(&gamma.contiguous()?, &beta.contiguous()?, Fused(op))?, reported))
}

/// Mean and biased variance of every channel of `(N, C, plane)` data.
fn channel_stats<T: Float>(x: &[T], channels: usize, plane: usize) -> BatchNormStats {
    let images = x.len() / (channels * plane).max(1);
    let planes = |c: usize| (0..images).map(move |n| &x[(n * channels + c) * plane..][..plane]);
    let count = (images * plane).max(1) as f64;
    let (mean, variance) = (0..channels)
        .into_par_iter()
        .map(|c| {
            let mean = planes(c).flatten().map(|v| v.to_f64()).sum::<f64>() / count;
            let variance = planes(c).flatten().map(|v| (v.to_f64() - mean).powi(2)).sum::<f64>() / count;
            (mean, variance)
        })
        .unzip();
    BatchNormStats { mean, variance }
}

struct BatchNormRelu {
    mean: Vec<f64>,
    rstd: Vec<f64>,
    /// Whether `mean` and `rstd` are the batch's own (their gradient then flows into x).
    batch_statistics: bool,
}

impl BatchNormRelu {
    fn normalise<T: Float>(&self, x: &[T], gamma: &[T], beta: &[T], plane: usize) -> Vec<T> {
        let channels = self.mean.len();
        build_by_planes(x.len(), plane, |i, y| {
            let c = i % channels;
            let scale = gamma[c].to_f64() * self.rstd[c];
            let (scale, shift) = (T::from_f64(scale), T::from_f64(beta[c].to_f64() - self.mean[c] * scale));
            for (y, &x) in y.iter_mut().zip(&x[i * plane..(i + 1) * plane]) {
                let v = x * scale + shift;
                y.write(if v > T::zero() { v } else { T::zero() });
            }
        })
    }

    /// Gradients of x, γ and β from the output `y` (its sign is the ReLU mask) and `dy`.
    fn gradients<T: Float>(&self, x: &[T], gamma: &[T], y: &[T], dy: &[T], plane: usize) -> (Vec<T>, Vec<T>, Vec<T>) {
        let channels = self.mean.len();
        let images = x.len() / (channels * plane).max(1);
        // Σ g and Σ g·x̂ per channel, g = dy where the ReLU passed.
        let (sum_g, sum_gx): (Vec<f64>, Vec<f64>) = (0..channels)
            .into_par_iter()
            .map(|c| {
                let (mut sg, mut sgx) = (0.0, 0.0);
                for n in 0..images {
                    let at = (n * channels + c) * plane..(n * channels + c + 1) * plane;
                    for ((&x, &y), &dy) in x[at.clone()].iter().zip(&y[at.clone()]).zip(&dy[at]) {
                        if y > T::zero() {
                            let g = dy.to_f64();
                            sg += g;
                            sgx += g * (x.to_f64() - self.mean[c]) * self.rstd[c];
                        }
                    }
                }
                (sg, sgx)
            })
            .unzip();
        let count = (images * plane).max(1) as f64;
        let dx = build_by_planes(x.len(), plane, |i, dx| {
            let c = i % channels;
            let at = i * plane..(i + 1) * plane;
            // dx = γ·rstd·(g − Σg/M − x̂·Σg·x̂/M) with batch statistics, γ·rstd·g with fixed ones;
            // per element in T: (g − a − x·b + mean·b)·scale with x̂ = (x − mean)·rstd expanded.
            let scale = gamma[c].to_f64() * self.rstd[c];
            let (mean_g, mean_gx) =
                if self.batch_statistics { (sum_g[c] / count, sum_gx[c] / count) } else { (0.0, 0.0) };
            let slope = mean_gx * self.rstd[c];
            let (scale_t, slope_t, offset_t) =
                (T::from_f64(scale), T::from_f64(slope), T::from_f64(self.mean[c] * slope - mean_g));
            for ((dx, &x), (&y, &dy)) in dx.iter_mut().zip(&x[at.clone()]).zip(y[at.clone()].iter().zip(&dy[at])) {
                let g = if y > T::zero() { dy } else { T::zero() };
                dx.write((g - x * slope_t + offset_t) * scale_t);
            }
        });
        let to_t = |v: Vec<f64>| v.into_iter().map(T::from_f64).collect();
        (dx, to_t(sum_gx), to_t(sum_g))
    }
}

impl<T: Float> SliceOp<T, 3> for BatchNormRelu {
    const NAME: &'static str = "amber-batch-norm-relu";

    fn forward(&self, [x, gamma, beta]: [&[T]; 3], [xl, ..]: [&Layout; 3]) -> Result<(Vec<T>, Shape)> {
        let plane = xl.dims()[2..].iter().product();
        Ok((self.normalise(x, gamma, beta, plane), xl.shape().clone()))
    }

    fn backward(
        &self,
        [x, gamma, _]: [&[T]; 3],
        [xl, ..]: [&Layout; 3],
        y: &[T],
        dy: &[T],
        _: [bool; 3],
    ) -> Result<[Option<Vec<T>>; 3]> {
        let plane = xl.dims()[2..].iter().product();
        let (dx, dgamma, dbeta) = self.gradients(x, gamma, y, dy, plane);
        Ok([Some(dx), Some(dgamma), Some(dbeta)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::testing::*;

    /// The composition from stock candle ops (differentiable), with batch statistics.
    fn composed(x: &Tensor, gamma: &Tensor, beta: &Tensor) -> Result<Tensor> {
        let c = x.dim(1)?;
        let shape: Vec<usize> =
            std::iter::once(1).chain(std::iter::once(c)).chain(std::iter::repeat_n(1, x.rank() - 2)).collect();
        let axes: Vec<usize> = std::iter::once(0).chain(2..x.rank()).collect();
        let mean = x.mean_keepdim(axes.as_slice())?;
        let centred = x.broadcast_sub(&mean)?;
        let var = centred.sqr()?.mean_keepdim(axes.as_slice())?;
        let normalised = centred.broadcast_div(&(var + EPSILON)?.sqrt()?)?;
        normalised
            .broadcast_mul(&gamma.reshape(shape.as_slice())?)?
            .broadcast_add(&beta.reshape(shape.as_slice())?)?
            .relu()
    }

    fn inputs(dtype: DType) -> [Tensor; 3] {
        let x = Image::random(3, 4, &[5, 3], 1);
        let gamma = random_vec(4, 2).iter().map(|g| 1.0 + 0.5 * g).collect::<Vec<_>>();
        [x.tensor(dtype), tensor(&gamma, &[4], dtype), tensor(&random_vec(4, 3), &[4], dtype)]
    }

    #[test]
    fn training_mode_matches_the_composition_forward_and_backward() {
        let probe = Image::random(3, 4, &[5, 3], 4);
        let (expected, expected_grads) =
            forward_and_grads(&inputs(DType::F64), &probe, |t| composed(&t[0], &t[1], &t[2]));
        for dtype in [DType::F64, DType::F32] {
            let (y, grads) =
                forward_and_grads(&inputs(dtype), &probe, |t| Ok(batch_norm_relu(&t[0], &t[1], &t[2], None)?.0));
            assert_close(&y, &expected, 1e-5, "forward");
            for (g, e) in grads.iter().zip(&expected_grads) {
                assert_close(g, e, 1e-4, "gradient");
            }
        }
    }

    #[test]
    fn gradient_matches_finite_differences_in_both_modes() {
        check_finite_differences(&inputs(DType::F64), &|t| {
            probe_loss(&batch_norm_relu(&t[0], &t[1], &t[2], None)?.0, 99)
        });
        let running = BatchNormStats { mean: vec![0.1, -0.2, 0.0, 0.3], variance: vec![0.5, 1.0, 2.0, 0.25] };
        check_finite_differences(&inputs(DType::F64), &|t| {
            probe_loss(&batch_norm_relu(&t[0], &t[1], &t[2], Some(&running))?.0, 99)
        });
    }

    #[test]
    fn gradients_are_the_same_at_any_thread_count() {
        let x = Image::random(4, 8, &[16, 16], 5).tensor(DType::F32);
        let (gamma, beta) = (tensor(&random_vec(8, 6), &[8], DType::F32), tensor(&random_vec(8, 7), &[8], DType::F32));
        let loss = |t: &[Tensor]| probe_loss(&batch_norm_relu(&t[0], &t[1], &t[2], None)?.0, 8);
        assert_same_at_any_thread_count(|| autograd(&[x.clone(), gamma.clone(), beta.clone()], &loss));
    }

    #[test]
    fn batch_statistics_are_reported_unbiased() {
        let x = tensor(&[1.0, 3.0, 10.0, 10.0], &[2, 2, 1, 1], DType::F32);
        let ones = tensor(&[1.0, 1.0], &[2], DType::F32);
        let (_, stats) = batch_norm_relu(&x, &ones, &ones, None).unwrap();
        // Channel 0 holds 1 and 10, channel 1 holds 3 and 10.
        assert_eq!(stats.mean, vec![5.5, 6.5]);
        assert_eq!(stats.variance, vec![40.5, 24.5]);
    }
}
