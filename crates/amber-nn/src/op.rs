//! Custom ops whose forward and backward are slice loops: an op implements [`SliceOp`] for f32
//! and f64 (usually once, generic over its own float trait), and [`Fused`] makes it a candle
//! `CustomOp1`, `CustomOp2` or `CustomOp3`, doing the dtype dispatch and the storage access in
//! one place; [`with_slice`] lends any tensor's data to a slice loop. CPU only; op inputs must
//! be contiguous.

use candle_core::backend::BackendStorage;
use candle_core::{CpuStorage, CustomOp1, CustomOp2, CustomOp3, DType, Layout, Result, Shape, Storage, Tensor, bail};

/// An op of `N` inputs on the contiguous data of its tensors, in the float type `T`.
pub trait SliceOp<T, const N: usize>: Send + Sync {
    const NAME: &'static str;

    /// The output's data and shape from the inputs' data and layouts.
    fn forward(&self, inputs: [&[T]; N], layouts: [&Layout; N]) -> Result<(Vec<T>, Shape)>;

    /// The gradient of every input (laid out as that input; `None`: not computed) from the
    /// inputs' data and layouts, the forward's output and the output's gradient; `tracked[i]`
    /// says whether input `i` is part of an autograd graph.
    fn backward(
        &self,
        inputs: [&[T]; N],
        layouts: [&Layout; N],
        output: &[T],
        grad: &[T],
        tracked: [bool; N],
    ) -> Result<[Option<Vec<T>>; N]>;
}

/// The candle custom op of a [`SliceOp`] implemented for f32 and f64.
pub struct Fused<Op>(pub Op);

/// The contiguous data of a CPU storage.
fn cpu_slice<'a, T: candle_core::WithDType>(s: &'a CpuStorage, l: &Layout) -> Result<&'a [T]> {
    match l.contiguous_offsets() {
        Some((start, end)) => Ok(&s.as_slice::<T>()?[start..end]),
        None => bail!("custom ops need contiguous inputs"),
    }
}

/// Runs `f` on the contiguous data of the CPU tensor `t` (made contiguous first if need be).
pub fn with_slice<T: candle_core::WithDType, R>(t: &Tensor, f: impl FnOnce(&[T]) -> Result<R>) -> Result<R> {
    let t = t.contiguous()?;
    let (storage, layout) = t.storage_and_layout();
    match &*storage {
        Storage::Cpu(s) => f(cpu_slice(s, layout)?),
        _ => bail!("custom ops run on the CPU only"),
    }
}

/// The common float dtype of an op's tensors.
fn float_dtype(op: &str, dtypes: &[DType]) -> Result<DType> {
    match dtypes {
        [first, rest @ ..] if matches!(first, DType::F32 | DType::F64) && rest.iter().all(|d| d == first) => Ok(*first),
        _ => bail!("{op}: inputs must be all f32 or all f64, got {dtypes:?}"),
    }
}

impl<Op> Fused<Op> {
    fn forward_n<const N: usize>(&self, inputs: [(&CpuStorage, &Layout); N]) -> Result<(CpuStorage, Shape)>
    where
        Op: SliceOp<f32, N> + SliceOp<f64, N>,
    {
        let name = <Op as SliceOp<f32, N>>::NAME;
        let layouts = inputs.map(|(_, l)| l);
        fn run<T: candle_core::WithDType, Op: SliceOp<T, N>, const N: usize>(
            op: &Op,
            inputs: [(&CpuStorage, &Layout); N],
            layouts: [&Layout; N],
        ) -> Result<(CpuStorage, Shape)> {
            let mut slices: [&[T]; N] = [&[]; N];
            for (slot, (s, l)) in slices.iter_mut().zip(inputs) {
                *slot = cpu_slice(s, l)?;
            }
            let (data, shape) = op.forward(slices, layouts)?;
            Ok((T::to_cpu_storage_owned(data), shape))
        }
        match float_dtype(name, &inputs.map(|(s, _)| s.dtype()))? {
            DType::F32 => run::<f32, Op, N>(&self.0, inputs, layouts),
            _ => run::<f64, Op, N>(&self.0, inputs, layouts),
        }
    }

    fn backward_n<const N: usize>(
        &self,
        inputs: [&Tensor; N],
        output: &Tensor,
        grad: &Tensor,
    ) -> Result<[Option<Tensor>; N]>
    where
        Op: SliceOp<f32, N> + SliceOp<f64, N>,
    {
        let name = <Op as SliceOp<f32, N>>::NAME;
        let mut dtypes: Vec<DType> = inputs.iter().map(|t| t.dtype()).collect();
        dtypes.extend([output.dtype(), grad.dtype()]);
        match float_dtype(name, &dtypes)? {
            DType::F32 => backward_as::<f32, Op, N>(&self.0, inputs, output, grad),
            _ => backward_as::<f64, Op, N>(&self.0, inputs, output, grad),
        }
    }
}

/// Borrows the tensors' data (made contiguous), runs the op's backward and shapes each gradient
/// as its input.
fn backward_as<T: candle_core::WithDType, Op: SliceOp<T, N>, const N: usize>(
    op: &Op,
    inputs: [&Tensor; N],
    output: &Tensor,
    grad: &Tensor,
) -> Result<[Option<Tensor>; N]> {
    let contiguous = |t: &Tensor| t.contiguous();
    let tensors: Vec<Tensor> = inputs.iter().copied().chain([output, grad]).map(contiguous).collect::<Result<_>>()?;
    let guards: Vec<_> = tensors.iter().map(|t| t.storage_and_layout()).collect();
    let mut slices: Vec<&[T]> = Vec::with_capacity(N + 2);
    for (storage, layout) in &guards {
        match &**storage {
            Storage::Cpu(s) => slices.push(cpu_slice(s, layout)?),
            _ => bail!("{}: custom ops run on the CPU only", Op::NAME),
        }
    }
    let input_slices: [&[T]; N] = std::array::from_fn(|i| slices[i]);
    let layouts: [&Layout; N] = std::array::from_fn(|i| guards[i].1);
    let grads = op.backward(input_slices, layouts, slices[N], slices[N + 1], inputs.map(|t| t.track_op()))?;
    let mut out: [Option<Tensor>; N] = std::array::from_fn(|_| None);
    for ((slot, g), input) in out.iter_mut().zip(grads).zip(inputs) {
        *slot = g.map(|g| Tensor::from_vec(g, input.shape(), input.device())).transpose()?;
    }
    Ok(out)
}

impl<Op: SliceOp<f32, 1> + SliceOp<f64, 1>> CustomOp1 for Fused<Op> {
    fn name(&self) -> &'static str {
        <Op as SliceOp<f32, 1>>::NAME
    }

    fn cpu_fwd(&self, s: &CpuStorage, l: &Layout) -> Result<(CpuStorage, Shape)> {
        self.forward_n([(s, l)])
    }

    fn bwd(&self, a: &Tensor, res: &Tensor, grad: &Tensor) -> Result<Option<Tensor>> {
        let [da] = self.backward_n([a], res, grad)?;
        Ok(da)
    }
}

impl<Op: SliceOp<f32, 2> + SliceOp<f64, 2>> CustomOp2 for Fused<Op> {
    fn name(&self) -> &'static str {
        <Op as SliceOp<f32, 2>>::NAME
    }

    fn cpu_fwd(&self, s1: &CpuStorage, l1: &Layout, s2: &CpuStorage, l2: &Layout) -> Result<(CpuStorage, Shape)> {
        self.forward_n([(s1, l1), (s2, l2)])
    }

    fn bwd(&self, a: &Tensor, b: &Tensor, res: &Tensor, grad: &Tensor) -> Result<(Option<Tensor>, Option<Tensor>)> {
        let [da, db] = self.backward_n([a, b], res, grad)?;
        Ok((da, db))
    }
}

impl<Op: SliceOp<f32, 3> + SliceOp<f64, 3>> CustomOp3 for Fused<Op> {
    fn name(&self) -> &'static str {
        <Op as SliceOp<f32, 3>>::NAME
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
        s3: &CpuStorage,
        l3: &Layout,
    ) -> Result<(CpuStorage, Shape)> {
        self.forward_n([(s1, l1), (s2, l2), (s3, l3)])
    }

    fn bwd(
        &self,
        a: &Tensor,
        b: &Tensor,
        c: &Tensor,
        res: &Tensor,
        grad: &Tensor,
    ) -> Result<(Option<Tensor>, Option<Tensor>, Option<Tensor>)> {
        let [da, db, dc] = self.backward_n([a, b, c], res, grad)?;
        Ok((da, db, dc))
    }
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Var};

    use super::*;
    use crate::gradcheck::{check_finite_differences, probe_loss, random};

    /// `y = a·b` elementwise, with `b`'s gradient only when it is tracked.
    struct Product;

    impl<T: candle_core::WithDType> SliceOp<T, 2> for Product {
        const NAME: &'static str = "test-product";

        fn forward(&self, [a, b]: [&[T]; 2], [la, _]: [&Layout; 2]) -> Result<(Vec<T>, Shape)> {
            Ok((a.iter().zip(b).map(|(&x, &y)| x * y).collect(), la.shape().clone()))
        }

        fn backward(
            &self,
            [a, b]: [&[T]; 2],
            _: [&Layout; 2],
            _: &[T],
            g: &[T],
            tracked: [bool; 2],
        ) -> Result<[Option<Vec<T>>; 2]> {
            let times = |x: &[T]| -> Vec<T> { x.iter().zip(g).map(|(&x, &g)| x * g).collect() };
            Ok([Some(times(b)), tracked[1].then(|| times(a))])
        }
    }

    #[test]
    fn the_adapter_dispatches_dtypes_and_shapes_gradients() {
        let inputs = [random((3, 4), 1), random((3, 4), 2)];
        check_finite_differences(&inputs, &|t| probe_loss(&t[0].apply_op2(&t[1], Fused(Product))?, 3));
        let (a, b) = (inputs[0].to_dtype(DType::F32).unwrap(), inputs[1].to_dtype(DType::F32).unwrap());
        let y = a.apply_op2(&b, Fused(Product)).unwrap();
        assert_eq!(y.to_vec2::<f32>().unwrap(), (&a * &b).unwrap().to_vec2::<f32>().unwrap());
        let var = Var::from_tensor(&a).unwrap();
        let grads = var.as_tensor().apply_op2(&b, Fused(Product)).unwrap().sum_all().unwrap().backward().unwrap();
        assert_eq!(grads.get(&var).unwrap().to_vec2::<f32>().unwrap(), b.to_vec2::<f32>().unwrap());
        let mixed = Tensor::ones((3, 4), DType::F64, &Device::Cpu).unwrap();
        assert!(a.apply_op2(&mixed, Fused(Product)).is_err());
    }
}
