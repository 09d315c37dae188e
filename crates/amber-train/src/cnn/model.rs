//! A trained U-Net and everything that turns a problem into its input and its output into a
//! sizing field: the auxiliary mesh, the raster, the normalisers, the clip and budget.

use std::path::Path;

use amber_cnn::{PixelGrid, Raster, UNet, UNetConfig};
use amber_graph::{GraphError, NodeFeature, RunningMoments, VARIANCE_EPSILON};
use amber_mesh::Mesh;
use amber_meshgen::SizingField;
use amber_nn::Objective;
use amber_stdx::write_json_atomic;
use amber_tasks::{Domain, MeshLimits};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError, in_problem, io_error};
use crate::model_file::{check_limits, check_moments, read_checked};
use crate::{CnnConfig, PredictedField, SizingModel};

/// File of the U-Net weights (and BatchNorm statistics) inside a CNN model directory.
pub const CNN_WEIGHTS_FILE: &str = "cnn.safetensors";
/// File of everything else of a CNN model ([`CnnPredictor`]).
pub const CNN_PREDICTOR_FILE: &str = "cnn.json";

/// Everything of a trained CNN except its weights.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CnnPredictor {
    pub network: UNetConfig,
    /// Pixels per axis.
    pub resolution: usize,
    /// `loss` in the JSON, as in [`crate::CnnConfig`].
    #[serde(rename = "loss")]
    pub objective: Objective,
    /// Moments of the input channels over the training pixels; `None`: inputs are fed raw.
    pub normaliser: Option<RunningMoments>,
    /// Moments of the targets over the inside training pixels; `None`: the network regresses
    /// the raw targets.
    pub label_moments: Option<RunningMoments>,
    /// h_min and the element budget (from the training experts).
    pub limits: MeshLimits,
}

/// One problem's auxiliary mesh, rasterised, with the network input of its pixels.
pub(super) struct Rasterised<const D: usize> {
    pub auxiliary: Mesh<D>,
    pub raster: Raster<D>,
    /// Channel-major `(columns + mask) × pixels`, not normalised.
    pub channels: Vec<f32>,
}

/// Target size of the auxiliary mesh's elements: the reference's element volume
/// vol(bounding box)/(2·rᴰ), about two elements per pixel.
fn auxiliary_size<const D: usize>(grid: &PixelGrid<D>) -> f64 {
    amber_mesh::size_from_volume::<D>(grid.cell_volume() / 2.0)
}

/// Meshes the auxiliary mesh of `problem` for a grid of `resolution` pixels per axis over its
/// geometry's bounding box, computes its columns and rasterises them.
pub(super) fn rasterise<const D: usize, P: Domain<D> + ?Sized>(
    problem: &P,
    index: usize,
    resolution: usize,
) -> Result<Rasterised<D>> {
    let initial = problem.initial_mesh();
    let grid = PixelGrid::over_mesh(initial, resolution)?;
    let size = auxiliary_size(&grid);
    let expected = initial.total_volume() / amber_mesh::volume_from_size::<D>(size);
    let cap = (4.0 * expected) as usize + 1_000;
    let auxiliary = problem.remesh(initial, vec![size; initial.num_elements()], cap).map_err(in_problem(index))?;
    let raster = Raster::new(grid, &auxiliary)?;
    // The task's own input columns, in its feature set's order: a problem may compute more
    // (optional AMBER inputs) than the baseline reads.
    let columns = problem.columns(&auxiliary).map_err(in_problem(index))?;
    let values: Vec<&[f64]> = problem
        .feature_set()
        .node
        .iter()
        .filter_map(|feature| match feature {
            NodeFeature::Column(name) => Some(name),
            _ => None,
        })
        .map(|name| {
            let column = columns.iter().find(|c| &c.name == name);
            column
                .map(|c| c.values.as_slice())
                .ok_or_else(|| in_problem(index)(GraphError::MissingColumn { name: name.clone() }))
        })
        .collect::<Result<_>>()?;
    let channels = raster.channels(&values)?;
    Ok(Rasterised { auxiliary, raster, channels })
}

/// Channel-major `channels × pixels` ↔ pixel-major rows (the normaliser's layout).
pub(super) fn transpose(data: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    let mut out = vec![0.0; data.len()];
    for r in 0..rows {
        for c in 0..cols {
            out[c * rows + r] = data[r * cols + c];
        }
    }
    out
}

impl CnnPredictor {
    /// Reads a `cnn.json`, checking it ([`Self::validate`]); the error names the file and the
    /// field.
    pub(crate) fn read(path: &Path) -> Result<Self> {
        read_checked(path, Self::validate)
    }

    /// Checks what a file could get wrong: the network's configuration, a resolution the
    /// network can pool (a positive multiple of 2^depth) and a run could have trained at (at most
    /// [`CnnConfig::MAX_RESOLUTION`]), an objective that needs no current mesh, the input and
    /// label moments (finite, non-negative variances, positive counts, one column per input
    /// channel or one label) and the limits (positive).
    fn validate(&self) -> Result<(), String> {
        self.network.validate().map_err(|e| format!("network: {e}"))?;
        let multiple = self.network.size_multiple();
        if self.resolution == 0 || !self.resolution.is_multiple_of(multiple) {
            return Err(format!(
                "resolution is {}, not a positive multiple of {multiple} (a depth of {})",
                self.resolution, self.network.depth
            ));
        }
        if self.resolution > CnnConfig::MAX_RESOLUTION {
            return Err(format!(
                "resolution is {}, at most {} is supported",
                self.resolution,
                CnnConfig::MAX_RESOLUTION
            ));
        }
        if self.objective.needs_current_size() {
            return Err("loss softplus_residual needs a current mesh".into());
        }
        if let Some(moments) = &self.normaliser {
            check_moments("normaliser", moments, self.network.in_channels)?;
        }
        if let Some(moments) = &self.label_moments {
            check_moments("label_moments", moments, 1)?;
        }
        check_limits(&self.limits)
    }

    /// The normalised network input of one rasterised problem, channel-major `C × pixels`.
    pub(super) fn input<const D: usize>(&self, sample: &Rasterised<D>) -> Result<Vec<f32>> {
        let (channels, pixels) = (self.network.in_channels, sample.raster.grid.len());
        if sample.channels.len() != channels * pixels {
            return Err(TrainError::InvalidConfig(format!(
                "the problem gives {} input channels, the network takes {channels}",
                sample.channels.len() / pixels
            )));
        }
        Ok(match &self.normaliser {
            Some(moments) => {
                let mut rows = transpose(&sample.channels, channels, pixels);
                moments.normalise(&mut rows)?;
                transpose(&rows, pixels, channels)
            }
            None => sample.channels.clone(),
        })
    }

    /// The predicted size of every auxiliary element: the network's pixel field, outside pixels
    /// filled from inside ones, read at the element midpoints.
    fn predict<const D: usize>(&self, network: &UNet, sample: &Rasterised<D>) -> Result<Vec<f64>> {
        let shape: Vec<usize> = [1, self.network.in_channels].into_iter().chain(sample.raster.grid.shape).collect();
        let z = network.predict(&self.input(sample)?, &shape)?;
        let (scale, shift) = match &self.label_moments {
            Some(m) => ((m.variance()[0] + VARIANCE_EPSILON).sqrt(), m.mean()[0]),
            None => (1.0, 0.0),
        };
        let mut sizes: Vec<f64> =
            z.into_iter().map(|z| self.objective.size(f64::from(z) * scale + shift, None)).collect();
        sample.raster.fill_outside(&mut sizes)?;
        let field = sample.raster.grid.sizing(sizes);
        Ok(sample.auxiliary.midpoints().into_iter().map(|x| field.size_at(x)).collect())
    }
}

/// A trained CNN ready for inference.
pub struct CnnModel {
    pub network: UNet,
    pub predictor: CnnPredictor,
}

impl CnnModel {
    /// Writes `cnn.safetensors` and `cnn.json` into `dir` (created if missing).
    pub fn save(network: &UNet, predictor: &CnnPredictor, dir: &Path) -> Result<()> {
        std::fs::create_dir_all(dir).map_err(io_error(dir))?;
        network.save(&dir.join(CNN_WEIGHTS_FILE))?;
        Ok(write_json_atomic(&dir.join(CNN_PREDICTOR_FILE), predictor)?)
    }

    /// Loads a model directory written by [`Self::save`] (a checkpoint directory is one too).
    /// A predictor with invalid moments or limits and weights that are not
    /// finite, not of the configuration's shapes or with a negative running variance are errors
    /// naming the file and the field or tensor.
    pub fn load(dir: &Path) -> Result<Self> {
        let predictor = CnnPredictor::read(&dir.join(CNN_PREDICTOR_FILE))?;
        let network = UNet::load(predictor.network.clone(), &dir.join(CNN_WEIGHTS_FILE))?;
        Ok(Self { network, predictor })
    }

    /// The model as a [`SizingModel`] for rollouts.
    pub fn sizing(&self) -> CnnSizing<'_> {
        CnnSizing { network: &self.network, predictor: &self.predictor }
    }
}

/// A U-Net with its predictor, as a [`SizingModel`]: whatever the current mesh, the field is
/// the prediction on the problem's auxiliary mesh (the CNN predicts once, from the geometry), so
/// one generation step is the method's whole rollout.
pub struct CnnSizing<'m> {
    pub network: &'m UNet,
    pub predictor: &'m CnnPredictor,
}

impl SizingModel for CnnSizing<'_> {
    fn limits(&self) -> &MeshLimits {
        &self.predictor.limits
    }

    fn predict<const D: usize, P: Domain<D>>(
        &self,
        problems: &[&P],
        _meshes: &[&Mesh<D>],
    ) -> Result<Vec<PredictedField<D>>> {
        problems
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let sample = rasterise(*p, i, self.predictor.resolution)?;
                let sizes = self.predictor.predict(self.network, &sample)?;
                Ok(PredictedField { mesh: Some(sample.auxiliary), sizes })
            })
            .collect()
    }
}
