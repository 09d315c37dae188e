//! Checkpoint files of a training run, written so that a killed run resumes exactly.
//!
//! Layout under the run's output directory:
//!
//! ```text
//! checkpoints/latest                      name of the newest complete checkpoint
//! checkpoints/step-00001000/              one checkpoint: model.safetensors + model.json,
//!                                         predictor.json, optimiser.safetensors, state.json
//! checkpoints/entries/0000000042.safetensors   buffer entry 42 (mesh, input columns, labels)
//! ```
//!
//! A checkpoint directory is written under a temporary name and renamed into place, then
//! `latest` is replaced atomically; only then are older checkpoints and entries no longer in the
//! buffer deleted. Buffer entries never change after creation (only their use counts, which live
//! in `state.json`), so each is written once.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};

use amber_graph::FeatureSet;
use amber_mesh::Mesh;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensors};
use serde::{Deserialize, Serialize};

use crate::error::{Result, TrainError, io_error};
use amber_tasks::{Column, MeshState, Problem};

use crate::{BufferEntry, Sample, TargetTransform, TrainingConfig};

/// Sub-directory of the output directory holding the checkpoints.
pub const CHECKPOINTS_DIR: &str = "checkpoints";
const LATEST_FILE: &str = "latest";
const ENTRIES_DIR: &str = "entries";
pub(crate) const STATE_FILE: &str = "state.json";
pub(crate) const OPTIMISER_FILE: &str = "optimiser.safetensors";

/// The exact state of a ChaCha generator.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct RngState {
    seed: [u8; 32],
    stream: u64,
    /// The 128-bit word position, as a decimal string (JSON numbers are not 128-bit).
    word_pos: String,
}

impl RngState {
    pub(crate) fn of(rng: &ChaCha8Rng) -> Self {
        Self { seed: rng.get_seed(), stream: rng.get_stream(), word_pos: rng.get_word_pos().to_string() }
    }

    pub(crate) fn restore(&self, path: &Path) -> Result<ChaCha8Rng> {
        let word_pos: u128 = self.word_pos.parse().map_err(|_| TrainError::Checkpoint {
            path: path.into(),
            message: format!("invalid generator word position `{}`", self.word_pos),
        })?;
        let mut rng = ChaCha8Rng::from_seed(self.seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(word_pos);
        Ok(rng)
    }
}

/// The bookkeeping of one buffer entry (its payload is in `entries/`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct EntryRecord {
    pub id: u64,
    pub problem: usize,
    pub depth: usize,
    pub sampled_count: u64,
}

impl EntryRecord {
    pub(crate) fn of<const D: usize>(e: &BufferEntry<D>) -> Self {
        Self { id: e.id, problem: e.problem, depth: e.depth, sampled_count: e.sampled_count }
    }
}

/// What identifies a training problem well enough to refuse resuming with other problems.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct ProblemFingerprint {
    pub initial_elements: usize,
    pub expert_elements: usize,
    pub expert_volume: f64,
}

/// The fingerprints of a run's training problems, checked on resume.
pub(crate) fn fingerprints<const D: usize, P: Problem<D>>(problems: &[P]) -> Vec<ProblemFingerprint> {
    problems
        .iter()
        .map(|p| ProblemFingerprint {
            initial_elements: p.initial_mesh().num_elements(),
            expert_elements: p.expert_mesh().num_elements(),
            expert_volume: p.expert_mesh().total_volume(),
        })
        .collect()
}

/// A generator of the run's seed on its own stream (1: edge dropout, 2: buffer sampling,
/// 3: the CNN's image subsets).
pub(crate) fn seeded_stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Counts of buffer additions by outcome.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AdditionCounts {
    pub added: u64,
    pub over_budget: u64,
    pub failed: u64,
}

/// The largest next buffer entry id a state may hold: a run adds a few entries per step, so no
/// run reaches 2⁵³ (its ids stay exact in JSON readers that use f64), and ids far below 2⁶⁴
/// cannot wrap around to collide with the protected entries.
const MAX_ENTRY_ID: u64 = 1 << 53;

/// `state.json`: everything of a run that is neither the network, the optimiser moments, the
/// predictor nor an entry payload.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct TrainingState {
    pub config: TrainingConfig,
    /// Gradient steps completed.
    pub step: u64,
    pub optimiser_steps: u64,
    pub dropout_rng: RngState,
    pub buffer_rng: RngState,
    /// The orientation stream, in a run that turns its batches (`random_orientation`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_rng: Option<RngState>,
    pub problems: Vec<ProblemFingerprint>,
    pub next_entry_id: u64,
    pub protected: Vec<EntryRecord>,
    pub generated: Vec<EntryRecord>,
    pub additions: AdditionCounts,
}

impl TrainingState {
    /// Checks what the file says against itself and the run's `problems` training problems:
    /// entry ids unique and below the next id, the next id far from wrapping, problem indices in
    /// range.
    pub(crate) fn check(&self, problems: usize) -> std::result::Result<(), String> {
        if self.next_entry_id > MAX_ENTRY_ID {
            return Err(format!(
                "next_entry_id {} is above {MAX_ENTRY_ID}, more entries than a run adds",
                self.next_entry_id
            ));
        }
        let entries = || self.protected.iter().chain(&self.generated);
        let mut ids = HashSet::new();
        for e in entries() {
            if e.id >= self.next_entry_id || !ids.insert(e.id) {
                return Err(format!("buffer entry id {} is repeated or not below next_entry_id", e.id));
            }
            if e.problem >= problems {
                return Err(format!("buffer entry {} belongs to problem {}, of {problems}", e.id, e.problem));
            }
        }
        Ok(())
    }
}

/// The directory of the newest complete checkpoint under `out_dir`, if any. `latest` must name
/// a checkpoint of this run (`step-NNNNNNNN`), never a path elsewhere. Every run is opened
/// through here, so this is where the temporary files of writes killed mid-way are removed.
pub fn latest_checkpoint(out_dir: &Path) -> Result<Option<PathBuf>> {
    amber_stdx::remove_stale_temporaries(out_dir)?;
    let root = out_dir.join(CHECKPOINTS_DIR);
    let latest = root.join(LATEST_FILE);
    match std::fs::read_to_string(&latest) {
        Ok(name) => {
            let name = name.trim();
            let digits = name.strip_prefix("step-").filter(|d| d.len() == 8 && d.bytes().all(|b| b.is_ascii_digit()));
            if digits.is_none() {
                let message = format!("`{name}` is not the name of a checkpoint (step-NNNNNNNN)");
                return Err(TrainError::Checkpoint { path: latest, message });
            }
            Ok(Some(root.join(name)))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(io_error(latest)(e)),
    }
}

/// Writes a checkpoint named after `step`: first every entry payload not yet on disk, then the
/// files `write` puts into a fresh directory, which is renamed into place and made `latest`;
/// finally older checkpoints and payloads of entries that left the buffer are removed.
pub(crate) fn commit<'e, const D: usize>(
    out_dir: &Path,
    step: u64,
    entries: impl Iterator<Item = &'e BufferEntry<D>>,
    write: impl FnOnce(&Path) -> Result<()>,
) -> Result<PathBuf> {
    let root = out_dir.join(CHECKPOINTS_DIR);
    let entries_dir = root.join(ENTRIES_DIR);
    std::fs::create_dir_all(&entries_dir).map_err(io_error(&entries_dir))?;
    let mut live = HashSet::new();
    for entry in entries {
        let path = entry_path(&entries_dir, entry.id);
        if !path.exists() {
            save_entry(&path, &entry.sample)?;
        }
        live.insert(path);
    }
    let name = format!("step-{step:08}");
    let tmp = root.join(format!(".tmp-{name}"));
    remove_dir_if_present(&tmp)?;
    std::fs::create_dir_all(&tmp).map_err(io_error(&tmp))?;
    write(&tmp)?;
    let dir = root.join(&name);
    remove_dir_if_present(&dir)?;
    std::fs::rename(&tmp, &dir).map_err(io_error(&dir))?;
    amber_stdx::write_atomic(&root.join(LATEST_FILE), name.as_bytes())?;

    for item in std::fs::read_dir(&root).map_err(io_error(&root))? {
        let path = item.map_err(io_error(&root))?.path();
        let file = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        // Older checkpoints, and leftovers of a checkpoint write that was killed.
        if (file.starts_with("step-") || file.starts_with(".tmp-step-")) && file != name {
            remove_dir_if_present(&path)?;
        }
    }
    for item in std::fs::read_dir(&entries_dir).map_err(io_error(&entries_dir))? {
        let path = item.map_err(io_error(&entries_dir))?.path();
        if !live.contains(&path) {
            std::fs::remove_file(&path).map_err(io_error(&path))?;
        }
    }
    Ok(dir)
}

fn remove_dir_if_present(dir: &Path) -> Result<()> {
    match std::fs::remove_dir_all(dir) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_error(dir)(e)),
        _ => Ok(()),
    }
}

fn entry_path(entries_dir: &Path, id: u64) -> PathBuf {
    entries_dir.join(format!("{id:010}.safetensors"))
}

/// Writes one entry's mesh, input columns and labels (safetensors: `vertices` f64 `(V, D)`,
/// `cells` u32 `(K, D + 1)`, `labels` f64, `column.<name>` f64).
fn save_entry<const D: usize>(path: &Path, sample: &Sample<D>) -> Result<()> {
    let mesh = &sample.state.mesh;
    let vertices: Vec<f64> = mesh.vertices().iter().flatten().copied().collect();
    let mut tensors = vec![
        ("vertices".to_string(), Dtype::F64, vec![mesh.num_vertices(), D], le_bytes(&vertices, f64::to_le_bytes)),
        ("cells".to_string(), Dtype::U32, vec![mesh.num_elements(), D + 1], le_bytes(mesh.cells(), u32::to_le_bytes)),
        ("labels".to_string(), Dtype::F64, vec![sample.labels.len()], le_bytes(&sample.labels, f64::to_le_bytes)),
    ];
    for c in &sample.state.columns {
        tensors.push((
            format!("column.{}", c.name),
            Dtype::F64,
            vec![c.values.len()],
            le_bytes(&c.values, f64::to_le_bytes),
        ));
    }
    amber_stdx::write_atomic_via(path, |tmp| {
        let fail =
            |e: safetensors::SafeTensorError| TrainError::Checkpoint { path: tmp.into(), message: e.to_string() };
        let views = tensors
            .iter()
            .map(|(name, dtype, shape, data)| Ok((name.as_str(), TensorView::new(*dtype, shape.clone(), data)?)))
            .collect::<Result<Vec<_>, safetensors::SafeTensorError>>()
            .map_err(fail)?;
        safetensors::serialize_to_file(views, None, tmp).map_err(fail)
    })
}

/// The little-endian bytes of `values`, as safetensors stores them.
fn le_bytes<T: Copy, const N: usize>(values: &[T], to_bytes: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| to_bytes(v)).collect()
}

/// The values of a stored tensor of `dtype` (any shape, row-major).
fn le_values<T, const N: usize>(
    name: &str,
    view: &TensorView<'_>,
    dtype: Dtype,
    from_bytes: impl Fn([u8; N]) -> T,
) -> Result<Vec<T>, String> {
    if view.dtype() != dtype {
        return Err(format!("tensor `{name}` is {:?}, expected {dtype:?}", view.dtype()));
    }
    Ok(view.data().chunks_exact(N).map(|b| from_bytes(b.try_into().expect("chunks of N bytes"))).collect())
}

/// Reads the entry `record` from the checkpoint `dir` and rebuilds its graph and targets.
pub(crate) fn load_entry<const D: usize>(
    dir: &Path,
    record: &EntryRecord,
    features: &FeatureSet,
    target: &TargetTransform,
) -> Result<BufferEntry<D>> {
    let path = entry_path(&dir.parent().unwrap_or(dir).join(ENTRIES_DIR), record.id);
    let fail = |message: String| TrainError::Checkpoint { path: path.clone(), message };
    let bytes = std::fs::read(&path).map_err(io_error(&path))?;
    let file = SafeTensors::deserialize(&bytes).map_err(|e| fail(e.to_string()))?;
    let mut tensors: HashMap<String, TensorView<'_>> = file.tensors().into_iter().collect();
    let mut take = |name: &str| tensors.remove(name).ok_or_else(|| fail(format!("missing tensor `{name}`")));
    let vertices = le_values("vertices", &take("vertices")?, Dtype::F64, f64::from_le_bytes).map_err(fail)?;
    let cells = le_values("cells", &take("cells")?, Dtype::U32, u32::from_le_bytes).map_err(fail)?;
    let labels = le_values("labels", &take("labels")?, Dtype::F64, f64::from_le_bytes).map_err(fail)?;
    let vertices = vertices.chunks_exact(D).map(|v| std::array::from_fn(|k| v[k])).collect();
    let mesh = Mesh::new(vertices, cells).map_err(|e| fail(e.to_string()))?;
    let mut columns = Vec::new();
    for (name, t) in tensors {
        let name = name.strip_prefix("column.").ok_or_else(|| fail(format!("unexpected tensor `{name}`")))?;
        let values = le_values(name, &t, Dtype::F64, f64::from_le_bytes).map_err(fail)?;
        columns.push(Column { name: name.to_string(), values });
    }
    columns.sort_by(|a, b| a.name.cmp(&b.name));
    let state = MeshState::from_columns(features, mesh, columns).map_err(|e| fail(e.to_string()))?;
    if labels.len() != state.mesh.num_elements() {
        return Err(fail(format!("{} labels for {} elements", labels.len(), state.mesh.num_elements())));
    }
    let targets = target.raw_targets(&labels, &state.mesh.sizes());
    Ok(BufferEntry {
        id: record.id,
        problem: record.problem,
        depth: record.depth,
        sampled_count: record.sampled_count,
        sample: Sample { state, labels, targets },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latest_names_a_checkpoint_of_the_run_and_nothing_else() {
        let out = std::env::temp_dir().join(format!("amber-latest-{}", std::process::id()));
        let root = out.join(CHECKPOINTS_DIR);
        std::fs::create_dir_all(&root).unwrap();
        assert_eq!(latest_checkpoint(&out).unwrap(), None);
        for bad in ["../../elsewhere", "/etc", "step-1", "step-0000000x", ""] {
            std::fs::write(root.join(LATEST_FILE), bad).unwrap();
            let err = latest_checkpoint(&out).unwrap_err().to_string();
            assert!(err.contains("not the name of a checkpoint"), "{bad}: {err}");
        }
        std::fs::write(root.join(LATEST_FILE), "step-00000250\n").unwrap();
        assert_eq!(latest_checkpoint(&out).unwrap(), Some(root.join("step-00000250")));
        std::fs::remove_dir_all(&out).unwrap();
    }

    #[test]
    fn a_state_with_colliding_or_foreign_entries_is_refused() {
        let entry = |id, problem| EntryRecord { id, problem, depth: 0, sampled_count: 0 };
        let rng = RngState::of(&seeded_stream(0, 1));
        let state = |next_entry_id, protected: Vec<EntryRecord>| TrainingState {
            config: TrainingConfig::smoke(),
            step: 0,
            optimiser_steps: 0,
            dropout_rng: rng.clone(),
            buffer_rng: rng.clone(),
            orientation_rng: None,
            problems: Vec::new(),
            next_entry_id,
            protected,
            generated: vec![entry(1, 0)],
            additions: AdditionCounts::default(),
        };
        assert!(state(2, vec![entry(0, 1)]).check(2).is_ok());
        assert!(state(0, vec![entry(0, 1)]).check(2).unwrap_err().contains("next_entry_id"), "wrapped id");
        assert!(state(u64::MAX, vec![entry(0, 1)]).check(2).unwrap_err().contains("above"), "id about to wrap");
        assert!(state(2, vec![entry(1, 1)]).check(2).is_err(), "repeated id");
        assert!(state(2, vec![entry(0, 5)]).check(2).unwrap_err().contains("problem 5"));
    }
}
