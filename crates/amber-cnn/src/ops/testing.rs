//! Test helpers: channel-major images in f64 for naive reference loops, random data, autograd
//! of a probe loss, a relative comparison and (re-exported) `amber_nn`'s finite-difference and
//! thread-count checks.

pub use amber_nn::gradcheck::{
    assert_same_at_any_thread_count, autograd, check_finite_differences, probe_loss, values,
};
use candle_core::{DType, Device, Tensor, Var};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn random_vec(len: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..len).map(|_| rng.random_range(-1.0..1.0)).collect()
}

pub fn tensor(data: &[f64], dims: &[usize], dtype: DType) -> Tensor {
    Tensor::from_slice(data, dims, &Device::Cpu).unwrap().to_dtype(dtype).unwrap()
}

/// A `(N, C, spatial...)` image in f64 with index helpers for naive loops.
#[derive(Clone, Debug)]
pub struct Image {
    pub n: usize,
    pub c: usize,
    pub spatial: Vec<usize>,
    pub data: Vec<f64>,
}

impl Image {
    pub fn zeros(n: usize, c: usize, spatial: &[usize]) -> Self {
        let len = n * c * spatial.iter().product::<usize>();
        Self { n, c, spatial: spatial.to_vec(), data: vec![0.0; len] }
    }

    pub fn random(n: usize, c: usize, spatial: &[usize], seed: u64) -> Self {
        let mut image = Self::zeros(n, c, spatial);
        image.data = random_vec(image.data.len(), seed);
        image
    }

    pub fn positions(&self) -> usize {
        self.spatial.iter().product()
    }

    pub fn dims(&self) -> Vec<usize> {
        [vec![self.n, self.c], self.spatial.clone()].concat()
    }

    pub fn tensor(&self, dtype: DType) -> Tensor {
        tensor(&self.data, &self.dims(), dtype)
    }

    pub fn get(&self, n: usize, c: usize, p: usize) -> f64 {
        self.data[(n * self.c + c) * self.positions() + p]
    }

    pub fn get_mut(&mut self, n: usize, c: usize, p: usize) -> &mut f64 {
        let positions = self.positions();
        &mut self.data[(n * self.c + c) * positions + p]
    }

    /// The multi-index of flat position `p`.
    pub fn index(&self, mut p: usize) -> Vec<usize> {
        let mut index = vec![0; self.spatial.len()];
        for (axis, &size) in self.spatial.iter().enumerate().rev() {
            index[axis] = p % size;
            p /= size;
        }
        index
    }

    /// The flat position of a multi-index, if inside.
    pub fn flat(&self, index: &[isize]) -> Option<usize> {
        let mut p = 0;
        for (&i, &size) in index.iter().zip(&self.spatial) {
            if i < 0 || i >= size as isize {
                return None;
            }
            p = p * size + i as usize;
        }
        Some(p)
    }

    /// Position `p` moved by `offset`, if inside.
    pub fn shifted(&self, p: usize, offset: &[isize]) -> Option<usize> {
        let index: Vec<isize> = self.index(p).iter().zip(offset).map(|(&i, &d)| i as isize + d).collect();
        self.flat(&index)
    }
}

/// The offsets of a centred kernel of odd size `k` in `axes` dimensions, in row-major tap order.
pub fn taps(axes: usize, k: usize) -> Vec<Vec<isize>> {
    let half = (k / 2) as isize;
    (0..k.pow(axes as u32))
        .map(|mut tap| {
            let mut offset = vec![0; axes];
            for axis in (0..axes).rev() {
                offset[axis] = (tap % k) as isize - half;
                tap /= k;
            }
            offset
        })
        .collect()
}

/// The output of `f(inputs)` and the gradients of Σ output·probe with respect to every input.
pub fn forward_and_grads(
    inputs: &[Tensor],
    probe: &Image,
    f: impl Fn(&[Tensor]) -> candle_core::Result<Tensor>,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let vars: Vec<Var> = inputs.iter().map(|t| Var::from_tensor(t).unwrap()).collect();
    let tensors: Vec<Tensor> = vars.iter().map(|v| v.as_tensor().clone()).collect();
    let y = f(&tensors).unwrap();
    let loss = (&y * probe.tensor(y.dtype())).unwrap().sum_all().unwrap();
    let grads = loss.backward().unwrap();
    let grads = vars.iter().map(|v| values(grads.get(v).expect("every input gets a gradient"))).collect();
    (values(&y), grads)
}

/// Asserts |a − b| ≤ tol · max(1, max |b|) entry by entry.
pub fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    let scale = b.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((x - y).abs() <= tol * scale, "{what}: entry {i}: {x} vs {y}");
    }
}
