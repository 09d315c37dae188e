//! What the JSON half of a model directory must satisfy when it is read (an AMBER
//! `predictor.json`, a CNN `cnn.json`): a normaliser with a negative variance or a zero count, or
//! limits that are not positive, would turn every prediction into NaN or an empty mesh long after
//! the load, far from the file at fault. The weights are checked by the networks' own loaders.

use std::path::Path;

use amber_graph::RunningMoments;
use amber_stdx::read_json;
use amber_tasks::MeshLimits;
use serde::de::DeserializeOwned;

use crate::error::{Result, TrainError};

/// Reads the JSON file `path` and checks it with `validate`, whose message names the field at
/// fault; the error names the file.
pub(crate) fn read_checked<T: DeserializeOwned>(
    path: &Path,
    validate: impl FnOnce(&T) -> Result<(), String>,
) -> Result<T> {
    let value: T = read_json(path)?;
    validate(&value).map_err(|message| TrainError::InvalidModel { path: path.into(), message })?;
    Ok(value)
}

/// h_min finite and positive, a budget of at least one element.
pub(crate) fn check_limits(limits: &MeshLimits) -> Result<(), String> {
    if !(limits.min_size.is_finite() && limits.min_size > 0.0) {
        return Err(format!("limits.min_size is {}, not a positive size", limits.min_size));
    }
    if limits.max_elements == 0 {
        return Err("limits.max_elements is 0".into());
    }
    if !(limits.final_step_scale.is_finite() && limits.final_step_scale > 0.0) {
        return Err(format!("limits.final_step_scale is {}, not a positive factor", limits.final_step_scale));
    }
    if let Some(count) = limits.final_count
        && !(0.0..=1.0).contains(&count.slope)
    {
        return Err(format!("limits.final_count.slope is {}, not within [0, 1]", count.slope));
    }
    Ok(())
}

/// Valid moments ([`RunningMoments::validate`]) of `columns` columns, `field` naming them.
pub(crate) fn check_moments(field: &str, moments: &RunningMoments, columns: usize) -> Result<(), String> {
    moments.validate().map_err(|reason| format!("{field}: {reason}"))?;
    if moments.dim() != columns {
        return Err(format!("{field}: {} columns, the network takes {columns}", moments.dim()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use amber_cnn::{UNet, UNetConfig};
    use amber_graph::{FeatureNormaliser, FeatureSet};
    use amber_mpn::{MpnConfig, MpnTrainer};
    use safetensors::SafeTensors;
    use safetensors::tensor::TensorView;
    use serde_json::{Value, json};

    use super::*;
    use crate::amber::PREDICTOR_FILE;
    use amber_nn::Backend;

    use crate::{
        AmberModel, CNN_PREDICTOR_FILE, CNN_WEIGHTS_FILE, CnnModel, CnnPredictor, Objective, Predictor,
        TargetTransform, WEIGHTS_FILE,
    };

    const LIMITS: MeshLimits = MeshLimits {
        min_size: 0.01,
        max_elements: 1_000,
        scale_to_budget: false,
        final_step_scale: 1.0,
        final_count: None,
    };

    /// An untrained AMBER model (the console features: one node and two edge columns).
    fn amber_model(dir: &Path) {
        let network = MpnConfig { node_features: 1, edge_features: 2, ..MpnConfig::small(4, 1) };
        let predictor = Predictor {
            features: FeatureSet::console(),
            normaliser: Some(FeatureNormaliser::new(1, 2)),
            target: TargetTransform::new(Objective::SoftplusResidual, true),
            limits: LIMITS,
        };
        AmberModel::save(
            &MpnTrainer::new(network, Objective::SoftplusResidual, 0, None, Backend::Cpu).unwrap(),
            &predictor,
            dir,
        )
        .unwrap();
    }

    /// An untrained CNN of two input channels.
    fn cnn_model(dir: &Path) {
        let network = UNetConfig { spatial_axes: 2, in_channels: 2, initial_channels: 2, depth: 1 };
        let predictor = CnnPredictor {
            network: network.clone(),
            resolution: 16,
            objective: Objective::LogMse,
            normaliser: Some(RunningMoments::new(2)),
            label_moments: Some(RunningMoments::new(1)),
            limits: LIMITS,
        };
        CnnModel::save(&UNet::init(network, 0).unwrap(), &predictor, dir).unwrap();
    }

    /// Sets the JSON field at `pointer` of the file to `value`.
    fn set_json(file: &Path, pointer: &str, value: Value) {
        let mut json: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        *json.pointer_mut(pointer).unwrap_or_else(|| panic!("no field {pointer}")) = value;
        std::fs::write(file, json.to_string()).unwrap();
    }

    /// Rewrites the f32 tensor `name` of a safetensors file with `edit(shape, values)`.
    fn edit_tensor(file: &Path, name: &str, edit: impl Fn(&mut Vec<usize>, &mut Vec<f32>)) {
        let bytes = std::fs::read(file).unwrap();
        let tensors = SafeTensors::deserialize(&bytes).unwrap();
        let mut owned: Vec<(String, safetensors::Dtype, Vec<usize>, Vec<u8>)> = tensors
            .tensors()
            .into_iter()
            .map(|(n, view)| (n, view.dtype(), view.shape().to_vec(), view.data().to_vec()))
            .collect();
        let (_, _, shape, data) = owned.iter_mut().find(|(n, ..)| n == name).unwrap();
        let mut values: Vec<f32> = data.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        edit(shape, &mut values);
        *data = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let views: Vec<(&str, TensorView)> = owned
            .iter()
            .map(|(n, dtype, shape, data)| (n.as_str(), TensorView::new(*dtype, shape.clone(), data).unwrap()))
            .collect();
        safetensors::serialize_to_file(views, None, file).unwrap();
    }

    /// Makes a fresh model with `make`, corrupts it with `corrupt`, and asserts that `load` fails
    /// with a message naming `file` and containing `needle`.
    fn assert_rejected(
        make: fn(&Path),
        load: fn(&Path) -> Result<()>,
        file: &str,
        needle: &str,
        corrupt: impl FnOnce(&Path),
    ) {
        let dir = tempfile::tempdir().unwrap();
        make(dir.path());
        load(dir.path()).unwrap();
        corrupt(&dir.path().join(file));
        let message = load(dir.path()).err().unwrap_or_else(|| panic!("{file}: {needle} was accepted")).to_string();
        assert!(message.contains(file) && message.contains(needle), "{message}");
    }

    #[test]
    fn amber_models_with_bad_moments_limits_or_weights_are_rejected_naming_the_file() {
        let load = |dir: &Path| AmberModel::load(dir).map(|_| ());
        let json = |pointer: &'static str, value: Value, needle: &str| {
            assert_rejected(amber_model, load, PREDICTOR_FILE, needle, |f| set_json(f, pointer, value));
        };
        json("/features/node", json!([]), "features.node: 0 node features, but the network (model.json) reads 1");
        json("/features/edge", json!([]), "features.edge: 0 or 0 columns");
        json("/normaliser/node/var/0", json!(-1.0), "normaliser.node: variance of column 0 is -1");
        json("/normaliser/edge/count", json!(0.0), "normaliser.edge: count 0");
        json("/normaliser/node/mean", json!([0.0, 0.0]), "normaliser.node: 2 means but 1 variances");
        json("/target/moments/var", json!([-2.0]), "target.moments: variance of column 0 is -2");
        json("/limits/min_size", json!(0.0), "limits.min_size is 0");
        json("/limits/min_size", json!(-0.5), "limits.min_size is -0.5");
        json("/limits/max_elements", json!(0), "limits.max_elements is 0");
        json("/limits/final_step_scale", json!(-2.0), "limits.final_step_scale is -2");
        let count = json!({"slope": 1.5, "model_log_mean": 7.0, "expert_log_mean": 7.0});
        let limits = json!({"min_size": 0.01, "max_elements": 1_000, "final_count": count});
        json("/limits", limits, "limits.final_count.slope is 1.5");
        // The fuzz input fuzz/corpus/model_dir/crash-predictor-fewer-features-than-network: without
        // a normaliser, a feature list cut short loaded and failed only in the first prediction,
        // with a message naming no file.
        let cut = |pointer: &'static str, needle: &str| {
            assert_rejected(amber_model, load, PREDICTOR_FILE, needle, |f| {
                set_json(f, "/normaliser", Value::Null);
                set_json(f, pointer, json!([]));
            });
        };
        cut("/features/node", "features.node: 0 node features, but the network (model.json) reads 1");
        cut("/features/edge", "features.edge: 0 or 0 columns in 2D or 3D, but the network (model.json) reads 2");
        let weights = |name: &'static str, needle: &str, edit: fn(&mut Vec<usize>, &mut Vec<f32>)| {
            assert_rejected(amber_model, load, WEIGHTS_FILE, needle, |f| edit_tensor(f, name, edit));
        };
        weights("steps.0.edge.norm.weight", "steps.0.edge.norm.weight", |_, v| v[1] = f32::NAN);
        weights("decoder.2.bias", "decoder.2.bias", |_, v| v[0] = f32::INFINITY);
        weights("node_encoder.weight", "node_encoder.weight", |shape, v| {
            shape[0] -= 1;
            v.truncate(shape.iter().product());
        });
    }

    #[test]
    fn cnn_models_with_bad_moments_limits_or_weights_are_rejected_naming_the_file() {
        let load = |dir: &Path| CnnModel::load(dir).map(|_| ());
        let json = |pointer: &'static str, value: Value, needle: &str| {
            assert_rejected(cnn_model, load, CNN_PREDICTOR_FILE, needle, |f| set_json(f, pointer, value));
        };
        json("/normaliser/var/1", json!(-1.0), "normaliser: variance of column 1 is -1");
        json("/normaliser/count", json!(0.0), "normaliser: count 0");
        json("/label_moments/var", json!([1.0, 1.0]), "label_moments: 1 means but 2 variances");
        json("/resolution", json!(0), "resolution is 0");
        // The fuzz inputs fuzz/corpus/model_dir/crash-cnn-resolution-*: a grid the U-Net cannot
        // pool failed only in the first prediction, naming no file; a million pixels per axis
        // meshed an auxiliary mesh for minutes.
        json("/resolution", json!(17), "resolution is 17, not a positive multiple of 2");
        json("/resolution", json!(1_000_000), "resolution is 1000000, at most 2048");
        json("/limits/min_size", json!(-1.0), "limits.min_size is -1");
        json("/limits/max_elements", json!(0), "limits.max_elements is 0");
        let weights = |name: &'static str, needle: &str, edit: fn(&mut Vec<usize>, &mut Vec<f32>)| {
            assert_rejected(cnn_model, load, CNN_WEIGHTS_FILE, needle, |f| edit_tensor(f, name, edit));
        };
        weights("down.0.0.weight", "down.0.0.weight", |_, v| v[3] = f32::NAN);
        weights("down.0.1.running_var", "negative variance", |_, v| v[0] = -1.0);
        weights("out.weight", "out.weight", |shape, v| {
            shape[1] += 1;
            v.push(0.0);
        });
    }
}
