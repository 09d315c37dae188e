//! Plain slice kernels behind the fused ops: row-block matmuls, LeakyReLU, LayerNorm and the
//! "second layer + residual + LayerNorm" tail shared by the edge and node updates.
//!
//! Everything is generic over f32 (training, inference) and f64 (gradient checks). Callers
//! parallelise over blocks of rows, so every matmul here runs on one thread.

use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicUsize, Ordering};

use candle_core::WithDType;
use rayon::prelude::*;

/// Rows per parallel work item: large enough for efficient matmuls, small enough that a block's
/// temporaries stay in L2.
pub(crate) const BLOCK_ROWS: usize = 256;
pub(crate) const NEGATIVE_SLOPE: f64 = 0.01;
pub(crate) const LAYER_NORM_EPS: f64 = 1e-5;

pub(crate) trait Real: WithDType {
    fn sqrt(self) -> Self;
    /// Branch-free so that loops over it vectorise.
    fn tanh(self) -> Self;
}
impl Real for f32 {
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }

    /// Rational approximation on [-7.9, 7.9], clamped outside (Eigen's `generic_fast_tanh_float`);
    /// absolute error below 5e-7.
    #[inline(always)]
    fn tanh(self) -> Self {
        let x = self.clamp(-7.905_311, 7.905_311);
        let x2 = x * x;
        let mut p = x2 * -2.760_768_4e-16 + 2.000_188e-13;
        p = x2 * p + -8.604_672e-11;
        p = x2 * p + 5.122_297e-8;
        p = x2 * p + 1.485_722_4e-5;
        p = x2 * p + 6.372_619_3e-4;
        p = x2 * p + 4.893_524_6e-3;
        let mut q = x2 * 1.198_258_4e-6 + 1.185_347_1e-4;
        q = x2 * q + 2.268_434_6e-3;
        q = x2 * q + 4.893_525e-3;
        x * p / q
    }
}
impl Real for f64 {
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }

    fn tanh(self) -> Self {
        f64::tanh(self)
    }
}

/// A zero-filled buffer for a parallel loop over its chunks. Each chunk is zeroed by the thread
/// that takes it, in cache, right before the loop's kernel writes it: `vec![0; n]` zeroes the
/// whole buffer first, on one thread, in a separate pass over memory (`memset` is a tenth of a
/// Console training step, docs/PROFILES.md).
pub(crate) struct ZeroedByChunk<T> {
    values: Vec<T>,
    len: usize,
    handed_out: bool,
    zeroed: AtomicUsize,
}

impl<T: Real> ZeroedByChunk<T> {
    pub(crate) fn new(len: usize) -> Self {
        Self { values: Vec::with_capacity(len), len, handed_out: false, zeroed: AtomicUsize::new(0) }
    }

    /// The buffer as zero-filled chunks of `chunk` values (the last may be shorter), in order.
    /// Hands them out once.
    pub(crate) fn par_chunks_mut(&mut self, chunk: usize) -> impl IndexedParallelIterator<Item = &mut [T]> {
        assert!(!self.handed_out, "the chunks of a buffer are handed out once");
        self.handed_out = true;
        let (zeroed, zero) = (&self.zeroed, T::from_f64(0.0));
        self.values.spare_capacity_mut()[..self.len].par_chunks_mut(chunk).map(move |values| {
            values.iter_mut().for_each(|v| {
                v.write(zero);
            });
            zeroed.fetch_add(values.len(), Ordering::Relaxed);
            // SAFETY: every element of `values` was just written.
            unsafe { &mut *(values as *mut [MaybeUninit<T>] as *mut [T]) }
        })
    }

    /// The buffer as the loop left it. Panics unless the loop took every chunk.
    pub(crate) fn into_vec(mut self) -> Vec<T> {
        assert_eq!(*self.zeroed.get_mut(), self.len, "a parallel loop left chunks of its buffer unwritten");
        // SAFETY: the chunks, handed out once, do not overlap, and each was zeroed before use;
        // together they hold `len` values, so all of them are initialised.
        unsafe { self.values.set_len(self.len) };
        self.values
    }
}

/// `out (m×n) [+]= op(a) · op(b)` with row-major operands, where `op(a)` is `a` (m×k) or, if
/// `a_t`, the transpose of a stored k×m matrix (likewise `b`: k×n or stored n×k).
#[allow(clippy::too_many_arguments)]
pub(crate) fn matmul<T: Real>(
    m: usize,
    k: usize,
    n: usize,
    a: &[T],
    a_t: bool,
    b: &[T],
    b_t: bool,
    out: &mut [T],
    accumulate: bool,
) {
    assert!(a.len() >= m * k && b.len() >= k * n && out.len() >= m * n, "matmul operand too short");
    if m == 0 || n == 0 {
        return;
    }
    let (a_rs, a_cs) = if a_t { (1, m) } else { (k, 1) };
    let (b_rs, b_cs) = if b_t { (1, k) } else { (n, 1) };
    // SAFETY: the assert above keeps every index the strides produce inside the slices.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            out.as_mut_ptr(),
            1,
            n as isize,
            accumulate,
            a.as_ptr(),
            a_cs as isize,
            a_rs as isize,
            b.as_ptr(),
            b_cs as isize,
            b_rs as isize,
            T::from_f64(1.0),
            T::from_f64(1.0),
            false,
            false,
            false,
            gemm::Parallelism::None,
        )
    }
}

#[inline]
pub(crate) fn leaky_relu<T: Real>(v: T) -> T {
    if v >= T::from_f64(0.0) { v } else { v * T::from_f64(NEGATIVE_SLOPE) }
}

/// Derivative of LeakyReLU read off its output (the slope keeps the sign).
#[inline]
pub(crate) fn leaky_relu_slope<T: Real>(activation: T) -> T {
    if activation >= T::from_f64(0.0) { T::from_f64(1.0) } else { T::from_f64(NEGATIVE_SLOPE) }
}

pub(crate) fn add_assign<T: Real>(acc: &mut [T], v: &[T]) {
    for (a, &b) in acc.iter_mut().zip(v) {
        *a += b;
    }
}

/// Weights of one residual MLP block `y = LayerNorm(r + act(act(u·W1 + b1)·W2 + b2))`, unpacked
/// from the flat parameter vector the ops receive. Matrices are stored input-major
/// (`w1[i * d + j]` multiplies input `i` into output `j`), i.e. transposed from candle's
/// `(out, in)` weights.
pub(crate) struct MlpWeights<T> {
    pub d: usize,
    pub w1: Vec<T>,
    pub b1: Vec<T>,
    pub w2: Vec<T>,
    pub b2: Vec<T>,
    pub gamma: Vec<T>,
    pub beta: Vec<T>,
}

/// Length of the flat vector `[W1 (d×in), b1, W2 (d×d), b2, γ, β]` (candle layouts, row-major).
pub(crate) fn packed_len(in_dim: usize, d: usize) -> usize {
    d * in_dim + d * d + 4 * d
}

fn transpose<T: Real>(m: &[T], rows: usize, cols: usize) -> Vec<T> {
    let mut t = Vec::with_capacity(m.len());
    for c in 0..cols {
        t.extend((0..rows).map(|r| m[r * cols + c]));
    }
    t
}

impl<T: Real> MlpWeights<T> {
    pub fn unpack(theta: &[T], in_dim: usize, d: usize) -> Self {
        assert_eq!(theta.len(), packed_len(in_dim, d), "packed MLP parameters");
        let (w1, rest) = theta.split_at(d * in_dim);
        let (b1, rest) = rest.split_at(d);
        let (w2, rest) = rest.split_at(d * d);
        let (b2, rest) = rest.split_at(d);
        let (gamma, beta) = rest.split_at(d);
        Self {
            d,
            w1: transpose(w1, d, in_dim),
            b1: b1.to_vec(),
            w2: transpose(w2, d, d),
            b2: b2.to_vec(),
            gamma: gamma.to_vec(),
            beta: beta.to_vec(),
        }
    }

    /// Rows `rows` of `W1` (input-major), i.e. the weights of one part of a concatenated input.
    pub fn w1_rows(&self, rows: std::ops::Range<usize>) -> &[T] {
        &self.w1[rows.start * self.d..rows.end * self.d]
    }
}

/// Gradient accumulators matching [`MlpWeights`], summed over row blocks (in the fixed order of
/// `amber_nn::reduce`, so that the sum is the same at any thread count).
pub(crate) struct MlpGrads<T> {
    pub w1: Vec<T>,
    pub b1: Vec<T>,
    pub w2: Vec<T>,
    pub b2: Vec<T>,
    pub gamma: Vec<T>,
    pub beta: Vec<T>,
}

impl<T: Real> MlpGrads<T> {
    pub fn zeros(in_dim: usize, d: usize) -> Self {
        let z = |n| vec![T::from_f64(0.0); n];
        Self { w1: z(in_dim * d), b1: z(d), w2: z(d * d), b2: z(d), gamma: z(d), beta: z(d) }
    }

    pub fn merge(mut self, other: Self) -> Self {
        for (a, b) in [
            (&mut self.w1, &other.w1),
            (&mut self.b1, &other.b1),
            (&mut self.w2, &other.w2),
            (&mut self.b2, &other.b2),
            (&mut self.gamma, &other.gamma),
            (&mut self.beta, &other.beta),
        ] {
            add_assign(a, b);
        }
        self
    }

    /// Packs into the layout of the flat parameter vector (weights back to `(out, in)`).
    pub fn pack(self, in_dim: usize, d: usize) -> Vec<T> {
        let mut theta = transpose(&self.w1, in_dim, d);
        theta.extend_from_slice(&self.b1);
        theta.extend(transpose(&self.w2, d, d));
        theta.extend_from_slice(&self.b2);
        theta.extend_from_slice(&self.gamma);
        theta.extend_from_slice(&self.beta);
        theta
    }
}

/// Per-block tensors of the tail kept for the backward pass (or scratch in inference).
pub(crate) struct TailState<'a, T> {
    /// In: first-layer pre-activation without bias. Out: first-layer activation.
    pub h1: &'a mut [T],
    /// Second-layer activation.
    pub h2: &'a mut [T],
    pub mean: &'a mut [T],
    pub rstd: &'a mut [T],
}

/// Defines `fn $name<T: Real>(args)` that runs its body compiled for AVX2 when the CPU has it
/// (the crate is built for baseline x86-64, where these loops get only 4-wide SSE), else for the
/// baseline.
macro_rules! multiversion {
    ($(#[$m:meta])* fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $body:block) => {
        $(#[$m])*
        #[allow(clippy::too_many_arguments)]
        pub(crate) fn $name<T: Real>($($arg: $ty),*) {
            #[inline(always)]
            #[allow(clippy::too_many_arguments)]
            fn generic<T: Real>($($arg: $ty),*) $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx2")]
                #[allow(clippy::too_many_arguments)]
                unsafe fn avx2<T: Real>($($arg: $ty),*) {
                    generic($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: AVX2 was just detected on this CPU.
                    return unsafe { avx2($($arg),*) };
                }
            }
            generic($($arg),*)
        }
    };
}

/// Lane-wise partial sums: a plain `for` reduction is sequential under IEEE rules and does not
/// vectorise.
const LANES: usize = 16;

#[inline(always)]
fn dot<T: Real>(a: &[T], b: &[T]) -> T {
    let zero = T::from_f64(0.0);
    let mut acc = [zero; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = acc.iter().fold(zero, |s, &v| s + v);
    for (&x, &y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

#[inline(always)]
fn sum<T: Real>(a: &[T]) -> T {
    let zero = T::from_f64(0.0);
    let mut acc = [zero; LANES];
    let chunks = a.chunks_exact(LANES);
    let rest = chunks.remainder();
    for x in chunks {
        for l in 0..LANES {
            acc[l] += x[l];
        }
    }
    rest.iter().fold(acc.iter().fold(zero, |s, &v| s + v), |s, &v| s + v)
}

/// Finishes a residual MLP block on `rows` rows: `h1 = act(h1 + b1)`, `h2 = act(h1·W2 + b2)`,
/// `out = LayerNorm(residual + h2)`.
pub(crate) fn tail_forward<T: Real>(w: &MlpWeights<T>, residual: &[T], st: TailState<'_, T>, out: &mut [T]) {
    let d = w.d;
    let rows = residual.len() / d;
    bias_leaky_relu(st.h1, &w.b1);
    matmul(rows, d, d, st.h1, false, &w.w2, false, st.h2, false);
    residual_norm_forward(w, residual, st.h2, st.mean, st.rstd, out)
}

multiversion! {
    fn bias_leaky_relu(h: &mut [T], bias: &[T]) {
        for row in h.chunks_exact_mut(bias.len()) {
            for (v, &b) in row.iter_mut().zip(bias) {
                *v = leaky_relu(*v + b);
            }
        }
    }
}

multiversion! {
fn residual_norm_forward(w: &MlpWeights<T>, residual: &[T], h2: &mut [T], mean: &mut [T], rstd: &mut [T], out: &mut [T]) {
    let d = w.d;
    let inv_d = T::from_f64(1.0 / d as f64);
    let eps = T::from_f64(LAYER_NORM_EPS);
    let rows = h2.chunks_exact_mut(d).zip(residual.chunks_exact(d)).zip(out.chunks_exact_mut(d));
    for (((h2, res), o), (mean, rstd)) in rows.zip(mean.iter_mut().zip(rstd.iter_mut())) {
        for (((h, &r), o), &b) in h2.iter_mut().zip(res).zip(o.iter_mut()).zip(&w.b2) {
            *h = leaky_relu(*h + b);
            *o = r + *h;
        }
        let mu = sum(o) * inv_d;
        o.iter_mut().for_each(|v| *v -= mu);
        let rs = T::from_f64(1.0) / (dot(o, o) * inv_d + eps).sqrt();
        for ((o, &g), &b) in o.iter_mut().zip(&w.gamma).zip(&w.beta) {
            *o = *o * rs * g + b;
        }
        *mean = mu;
        *rstd = rs;
    }
}
}

/// Backward of [`tail_forward`] for one block, given `grad` of its output, in place: `h2` is
/// replaced by the gradient of the residual input and `h1` by the gradient of the first-layer
/// pre-activation. Accumulates `b1, W2, b2, γ, β` gradients into `g` (the caller handles `W1`,
/// whose input it knows). `scratch` holds `2 × rows × d` values.
#[allow(clippy::too_many_arguments)]
pub(crate) fn tail_backward<T: Real>(
    w: &MlpWeights<T>,
    grad: &[T],
    residual: &[T],
    h1: &mut [T],
    h2: &mut [T],
    mean: &[T],
    rstd: &[T],
    scratch: &mut [T],
    g: &mut MlpGrads<T>,
) {
    let d = w.d;
    let rows = grad.len() / d;
    let (dz, dh1) = scratch.split_at_mut(rows * d);
    residual_norm_backward(w, grad, residual, h2, mean, rstd, dz, g);
    matmul(d, rows, d, h1, true, dz, false, &mut g.w2, true);
    matmul(rows, d, d, dz, false, &w.w2, true, dh1, false);
    leaky_relu_backward(h1, dh1, &mut g.b1)
}

multiversion! {
/// LayerNorm, residual and second activation backward: `h2` becomes d(residual), `dz` receives
/// d(second-layer pre-activation).
fn residual_norm_backward(
    w: &MlpWeights<T>,
    grad: &[T],
    residual: &[T],
    h2: &mut [T],
    mean: &[T],
    rstd: &[T],
    dz: &mut [T],
    g: &mut MlpGrads<T>,
) {
    let d = w.d;
    let inv_d = T::from_f64(1.0 / d as f64);
    let mut n_hat = vec![T::from_f64(0.0); d];
    let rows = grad.chunks_exact(d).zip(residual.chunks_exact(d)).zip(h2.chunks_exact_mut(d)).zip(dz.chunks_exact_mut(d));
    for ((((gr, res), a2), dz), (&mu, &rs)) in rows.zip(mean.iter().zip(rstd)) {
        for ((n, &r), &a) in n_hat.iter_mut().zip(res).zip(a2.iter()) {
            *n = (r + a - mu) * rs;
        }
        for (((dn, &gv), &gm), ((gg, gb), &n)) in
            dz.iter_mut().zip(gr).zip(&w.gamma).zip(g.gamma.iter_mut().zip(g.beta.iter_mut()).zip(&n_hat))
        {
            *dn = gv * gm;
            *gg += gv * n;
            *gb += gv;
        }
        let mean_dn = sum(dz) * inv_d;
        let mean_dn_n = dot(dz, &n_hat) * inv_d;
        for (((a, dn), &n), gb2) in a2.iter_mut().zip(dz.iter_mut()).zip(&n_hat).zip(g.b2.iter_mut()) {
            let ds = rs * (*dn - mean_dn - n * mean_dn_n);
            *dn = ds * leaky_relu_slope(*a);
            *a = ds;
            *gb2 += *dn;
        }
    }
}
}

multiversion! {
/// `h1` (activations) becomes `dh1 ⊙ act'(h1)`, summed into `db1`.
fn leaky_relu_backward(h1: &mut [T], dh1: &[T], db1: &mut [T]) {
    for (h, dh) in h1.chunks_exact_mut(db1.len()).zip(dh1.chunks_exact(db1.len())) {
        for ((h, &dh), db) in h.iter_mut().zip(dh).zip(db1.iter_mut()) {
            *h = dh * leaky_relu_slope(*h);
            *db += *h;
        }
    }
}
}

multiversion! {
/// `h[i] += p[src[i]] + q[dst[i]]` row-wise: the gathered node terms of the split first layer.
fn add_gathered(h: &mut [T], p: &[T], q: &[T], src: &[u32], dst: &[u32], d: usize) {
    for ((h, &s), &t) in h.chunks_exact_mut(d).zip(src).zip(dst) {
        let (s, t) = (s as usize * d, t as usize * d);
        for ((h, &a), &b) in h.iter_mut().zip(&p[s..s + d]).zip(&q[t..t + d]) {
            *h += a + b;
        }
    }
}
}

multiversion! {
/// `x ← tanh(x)` elementwise.
fn tanh_rows(x: &mut [T]) {
    x.iter_mut().for_each(|v| *v = v.tanh());
}
}

multiversion! {
/// `out[v] += Σ rows[k]` over `k` in `ids[offsets[v]..offsets[v + 1]]` (or the contiguous range
/// `offsets[v]..offsets[v + 1]` when `ids` is `None`), for the nodes `first..` covered by `out`.
fn segment_sum(out: &mut [T], rows: &[T], offsets: &[u32], ids: Option<&[u32]>, first: usize, d: usize) {
    for (i, o) in out.chunks_exact_mut(d).enumerate() {
        for idx in offsets[first + i] as usize..offsets[first + i + 1] as usize {
            let k = ids.map_or(idx, |ids| ids[idx] as usize);
            for (o, &r) in o.iter_mut().zip(&rows[k * d..(k + 1) * d]) {
                *o += r;
            }
        }
    }
}
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_zeroed_by_chunk_holds_what_its_loop_wrote() {
        let mut buffer = ZeroedByChunk::<f32>::new(10);
        buffer.par_chunks_mut(4).enumerate().for_each(|(c, chunk)| {
            assert!(chunk.iter().all(|&v| v == 0.0), "handed out zeroed");
            chunk[0] = c as f32 + 1.0;
        });
        assert_eq!(buffer.into_vec(), [1.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 3.0, 0.0]);
        assert!(ZeroedByChunk::<f32>::new(0).into_vec().is_empty());
    }

    #[test]
    fn a_buffer_whose_loop_skipped_chunks_is_refused() {
        let mut buffer = ZeroedByChunk::<f32>::new(10);
        buffer.par_chunks_mut(4).take(2).for_each(|chunk| chunk[0] = 1.0);
        let refused = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| buffer.into_vec())).unwrap_err();
        let message = refused.downcast_ref::<String>().expect("a formatted message");
        assert!(message.contains("left chunks of its buffer unwritten"), "{message}");
    }
}
