//! Where a network trains: the CPU (the fused kernels) or a CUDA GPU (stock candle ops, with
//! the `cuda` cargo feature).

use candle_core::{Device, Result};
use serde::{Deserialize, Serialize};

/// The device of a network, as a configuration names it: `"cpu"` or `{"cuda": ordinal}`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    #[default]
    Cpu,
    Cuda(usize),
}

impl Backend {
    pub fn is_cpu(&self) -> bool {
        *self == Backend::Cpu
    }

    /// The candle device; a CUDA backend in a build without the `cuda` feature, or without the
    /// GPU, is candle's error saying so.
    pub fn device(self) -> Result<Device> {
        match self {
            Backend::Cpu => Ok(Device::Cpu),
            Backend::Cuda(ordinal) => Device::new_cuda(ordinal),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_and_the_cpu_is_the_default() {
        assert_eq!(serde_json::from_str::<Backend>("\"cpu\"").unwrap(), Backend::Cpu);
        assert_eq!(serde_json::from_str::<Backend>(r#"{"cuda": 1}"#).unwrap(), Backend::Cuda(1));
        assert!(serde_json::from_str::<Backend>("\"gpu\"").is_err());
        assert!(Backend::default().device().unwrap().is_cpu());
    }

    #[cfg(not(feature = "cuda"))]
    #[test]
    fn cuda_without_the_feature_is_an_error_not_a_panic() {
        let message = Backend::Cuda(0).device().unwrap_err().to_string();
        assert!(message.to_lowercase().contains("cuda"), "{message}");
    }
}
