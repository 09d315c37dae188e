//! The finite-difference gradient check of custom ops (for tests): random inputs in f64, a
//! probe loss that gives every output entry its own gradient, autograd of a loss, central
//! differences compared with autograd, and the check that a computation gives the same bits at
//! any thread count.

use candle_core::{DType, Device, Result, Shape, Tensor, Var};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// An f64 tensor of `shape` with entries uniform in [-1, 1), drawn row-major from `seed`.
pub fn random(shape: impl Into<Shape>, seed: u64) -> Tensor {
    let shape = shape.into();
    let mut rng = StdRng::seed_from_u64(seed);
    let v: Vec<f64> = (0..shape.elem_count()).map(|_| rng.random_range(-1.0..1.0)).collect();
    Tensor::from_vec(v, shape, &Device::Cpu).expect("the data fits its shape")
}

/// The entries of `t` as f64, row-major.
pub fn values(t: &Tensor) -> Vec<f64> {
    t.to_dtype(DType::F64).and_then(|t| t.flatten_all()).and_then(|t| t.to_vec1()).expect("a float tensor")
}

/// `Σ out·w` with fixed random weights `w` ([`random`] of `seed`), so that every output entry
/// gets a distinct gradient.
pub fn probe_loss(out: &Tensor, seed: u64) -> Result<Tensor> {
    let w = random(out.shape(), seed).to_dtype(out.dtype())?;
    (out * w)?.sum_all()
}

/// Gradients of `loss(inputs)` with respect to every input, via autograd.
pub fn autograd(inputs: &[Tensor], loss: &dyn Fn(&[Tensor]) -> Result<Tensor>) -> Vec<Vec<f64>> {
    let vars: Vec<Var> = inputs.iter().map(|t| Var::from_tensor(t).expect("a tensor")).collect();
    let tensors: Vec<Tensor> = vars.iter().map(|v| v.as_tensor().clone()).collect();
    let grads = loss(&tensors).and_then(|l| l.backward()).expect("the loss backpropagates");
    vars.iter().map(|v| values(grads.get(v).expect("every input gets a gradient"))).collect()
}

/// Asserts that autograd of the scalar f64 `loss` agrees with central differences (step 1e-6,
/// relative error below 1e-6) on up to 40 entries of every input.
pub fn check_finite_differences(inputs: &[Tensor], loss: &dyn Fn(&[Tensor]) -> Result<Tensor>) {
    let analytic = autograd(inputs, loss);
    let eval = |i: usize, idx: usize, delta: f64| {
        let mut v = values(&inputs[i]);
        v[idx] += delta;
        let mut perturbed = inputs.to_vec();
        perturbed[i] = Tensor::from_vec(v, inputs[i].shape(), &Device::Cpu).expect("same shape");
        loss(&perturbed).and_then(|l| l.to_scalar::<f64>()).expect("an f64 scalar loss")
    };
    let eps = 1e-6;
    for (i, grad) in analytic.iter().enumerate() {
        let step = grad.len().div_ceil(40);
        for idx in (0..grad.len()).step_by(step) {
            let fd = (eval(i, idx, eps) - eval(i, idx, -eps)) / (2.0 * eps);
            let err = (fd - grad[idx]).abs() / fd.abs().max(grad[idx].abs()).max(1.0);
            assert!(err < 1e-6, "input {i} entry {idx}: finite difference {fd}, autograd {}", grad[idx]);
        }
    }
}

/// Asserts that `f` returns the same values, bit for bit, in rayon pools of 1, 2 and 3 threads:
/// what every op with a parallel reduction must do for training to be reproducible.
pub fn assert_same_at_any_thread_count(f: impl Fn() -> Vec<Vec<f64>> + Send + Sync) {
    let bits = |threads: usize| -> Vec<Vec<u64>> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
        pool.install(|| f().iter().map(|v| v.iter().map(|x| x.to_bits()).collect()).collect())
    };
    let one = bits(1);
    for threads in [2, 3] {
        for (i, (a, b)) in one.iter().zip(bits(threads)).enumerate() {
            let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
            assert!(a.len() == b.len() && differ == 0, "result {i}: {differ} values differ at {threads} threads");
        }
    }
}
