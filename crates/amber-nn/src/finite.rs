//! The check both networks run on the tensors of a weights file when they load it: a NaN or an
//! infinity in a weight poisons every prediction silently, so a model file holding one is
//! rejected, naming the tensor.

use std::collections::HashMap;

use candle_core::{DType, Result, Tensor};

/// The name of a tensor with a NaN or infinite entry (the first in name order, so the message
/// is the same from run to run), or `None` if every entry of every tensor is finite.
pub fn first_non_finite(tensors: &HashMap<String, Tensor>) -> Result<Option<&str>> {
    let mut names: Vec<&String> = tensors.keys().collect();
    names.sort();
    for name in names {
        let values = tensors[name].to_dtype(DType::F64)?.flatten_all()?.to_vec1::<f64>()?;
        if values.iter().any(|v| !v.is_finite()) {
            return Ok(Some(name));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use candle_core::Device;

    use super::*;

    #[test]
    fn names_the_first_tensor_with_a_nan_or_an_infinity() {
        let t = |v: &[f32]| Tensor::new(v, &Device::Cpu).unwrap();
        let mut tensors = HashMap::from([("a".to_string(), t(&[1.0, 2.0])), ("b".to_string(), t(&[f32::MAX]))]);
        assert_eq!(first_non_finite(&tensors).unwrap(), None);
        tensors.insert("d".into(), t(&[0.0, f32::NAN]));
        tensors.insert("c".into(), t(&[f32::NEG_INFINITY]));
        assert_eq!(first_non_finite(&tensors).unwrap(), Some("c"));
    }
}
