//! Seeded parameter initialisation: candle's own `Init` draws from an unseeded generator.

use std::sync::Mutex;

use candle_core::{DType, Device, Shape, Tensor, Var, bail};
use candle_nn::var_builder::SimpleBackend;
use candle_nn::{Init, VarMap};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// A `VarBuilder` backend that creates each missing variable in a `VarMap` from a seeded
/// generator (creation order is the model's construction order, hence deterministic).
pub(super) struct SeededInit {
    varmap: VarMap,
    rng: Mutex<StdRng>,
}

impl SeededInit {
    pub fn new(varmap: VarMap, seed: u64) -> Self {
        Self { varmap, rng: Mutex::new(StdRng::seed_from_u64(seed)) }
    }
}

impl SimpleBackend for SeededInit {
    fn get(&self, s: Shape, name: &str, h: Init, dtype: DType, dev: &Device) -> candle_core::Result<Tensor> {
        let (Ok(mut vars), Ok(mut rng)) = (self.varmap.data().lock(), self.rng.lock()) else {
            bail!("poisoned variable map");
        };
        if let Some(var) = vars.get(name) {
            if var.shape() != &s {
                bail!("variable {name} has shape {:?}, expected {s:?}", var.shape());
            }
            return Ok(var.as_tensor().clone());
        }
        let n = s.elem_count();
        let values: Vec<f64> = match h {
            Init::Const(c) => vec![c; n],
            Init::Uniform { lo, up } => (0..n).map(|_| lo + (up - lo) * rng.random::<f64>()).collect(),
            other => bail!("unsupported initialisation {other:?} for {name}"),
        };
        let var = Var::from_tensor(&Tensor::from_vec(values, s, dev)?.to_dtype(dtype)?)?;
        vars.insert(name.to_owned(), var.clone());
        Ok(var.as_tensor().clone())
    }

    fn get_unchecked(&self, name: &str, _dtype: DType, _dev: &Device) -> candle_core::Result<Tensor> {
        bail!("{name}: the seeded initialiser needs a shape")
    }

    fn contains_tensor(&self, name: &str) -> bool {
        self.varmap.data().lock().map(|v| v.contains_key(name)).unwrap_or(false)
    }
}
