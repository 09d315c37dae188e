//! Dataset splits of the Poisson task: the manifest (`datasets/poisson.json`), per-problem
//! seeds derived from a split seed, and writing a split as `NNN.json` files with a cache.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use amber_fem::ExpertHeuristic;
use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::{Difficulty, PoissonProblem};
use crate::TaskError;

/// Version of the generated content; bump it whenever a change (sampling, M⁰ generator, FEM,
/// refinement) alters the files, so that cached files are regenerated.
pub const GENERATOR_VERSION: u32 = 1;

/// Name of the cache index inside a split directory.
pub(super) const INDEX_FILE: &str = "index.json";

/// A dataset split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Training problems: different for every training seed.
    Train,
    /// Validation problems: fixed.
    Val,
    /// Test problems: fixed.
    Test,
}

impl Split {
    /// Lower-case name, as in paths and the manifest.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Val => "val",
            Split::Test => "test",
        }
    }
}

impl fmt::Display for Split {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Split {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [Split::Train, Split::Val, Split::Test]
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| format!("unknown split `{s}` (train, val, test)"))
    }
}

/// `datasets/poisson.json`: split sizes and seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DatasetManifest {
    /// Training split: its seed depends on the training seed (run repetition).
    pub train: TrainSplit,
    /// Validation split.
    pub val: FixedSplit,
    /// Test split.
    pub test: FixedSplit,
}

/// A split whose problems change with the training seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainSplit {
    /// Problems per training seed.
    pub size: usize,
    /// Split seed for training seed 0, 1, ...
    pub split_seeds: Vec<u64>,
}

/// A split that is the same for every run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedSplit {
    /// Number of problems.
    pub size: usize,
    /// Split seed.
    pub seed: u64,
}

impl DatasetManifest {
    /// Reads a manifest.
    pub fn read(path: &Path) -> Result<Self, TaskError> {
        let bytes = std::fs::read(path).map_err(|source| TaskError::Io { path: path.into(), source })?;
        serde_json::from_slice(&bytes).map_err(|source| TaskError::Json { path: path.into(), source })
    }

    /// `(split seed, size)` of `split`; `training_seed` selects the training problems and is
    /// ignored for the fixed splits. `path` names the manifest in errors.
    pub fn split(&self, split: Split, training_seed: usize, path: &Path) -> Result<(u64, usize), TaskError> {
        match split {
            Split::Train => match self.train.split_seeds.get(training_seed) {
                Some(&seed) => Ok((seed, self.train.size)),
                None => Err(TaskError::Manifest {
                    path: path.into(),
                    message: format!(
                        "training seed {training_seed} has no split seed ({} listed in train.split_seeds)",
                        self.train.split_seeds.len()
                    ),
                }),
            },
            Split::Val => Ok((self.val.seed, self.val.size)),
            Split::Test => Ok((self.test.seed, self.test.size)),
        }
    }
}

/// The seeds of the first `count` problems of the split with seed `split_seed` (a prefix of
/// a longer split's seeds).
pub fn problem_seeds(split_seed: u64, count: usize) -> Vec<u64> {
    let mut rng = ChaCha8Rng::seed_from_u64(split_seed);
    (0..count).map(|_| rng.next_u64()).collect()
}

/// What to generate.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SplitRequest {
    /// Expert refinement steps come from it.
    pub difficulty: Difficulty,
    /// Seed the problem seeds are derived from.
    pub split_seed: u64,
    /// Number of problems.
    pub count: usize,
    /// Target size of M⁰.
    pub initial_size: f64,
    /// Expert heuristic settings.
    pub heuristic: ExpertHeuristic,
}

/// What [`write_split`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SplitReport {
    /// Files (re)generated.
    pub written: usize,
    /// Files kept because their inputs and content hash matched the cache index.
    pub cached: usize,
}

/// One file's entry in the cache index.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
struct CacheEntry {
    /// SHA-256 of the generator inputs (version, seed, steps, M⁰ size, heuristic).
    inputs: String,
    /// SHA-256 of the file content.
    content: String,
}

/// A file's cache entry and whether it was already cached, or why generating it failed.
type Outcome = Result<(CacheEntry, bool), TaskError>;

/// Generates the split into `dir` as `000.json`, `001.json`, ... (problems in parallel), skipping
/// every file whose inputs and content hash match `dir/index.json`. `on_problem` is called once
/// per problem, when it is done or found cached (for progress bars).
///
/// Safe to run concurrently on one split (the runs of a plan may): every file appears
/// atomically, a problem generates the same bytes in any process, the index keeps the entries
/// of problems beyond `request.count`, and a split found whole in the cache is not written at
/// all. Two processes that both miss a file generate it twice, and an index entry lost to a
/// concurrent rewrite only costs a regeneration later.
///
/// The first failing problem's error is returned after the others finished and the index was
/// written, so a rerun only redoes what failed.
pub fn write_split(
    request: &SplitRequest,
    dir: &Path,
    on_problem: &(dyn Fn() + Sync),
) -> Result<SplitReport, TaskError> {
    std::fs::create_dir_all(dir).map_err(|source| TaskError::Io { path: dir.into(), source })?;
    let index_path = dir.join(INDEX_FILE);
    let old_index: BTreeMap<String, CacheEntry> = match std::fs::read(&index_path) {
        Ok(bytes) => {
            serde_json::from_slice(&bytes).map_err(|source| TaskError::Json { path: index_path.clone(), source })?
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => BTreeMap::new(),
        Err(source) => return Err(TaskError::Io { path: index_path, source }),
    };
    let steps = request.difficulty.steps();
    let outcomes: Vec<(String, Outcome)> = problem_seeds(request.split_seed, request.count)
        .into_par_iter()
        .enumerate()
        .map(|(k, seed)| {
            let name = format!("{k:03}.json");
            let path = dir.join(&name);
            let inputs = inputs_hash(request, seed);
            let outcome = match old_index.get(&name) {
                Some(entry)
                    if entry.inputs == inputs && file_hash(&path).as_deref() == Some(entry.content.as_str()) =>
                {
                    Ok((entry.clone(), true))
                }
                _ => PoissonProblem::generate(seed, steps, request.initial_size, &request.heuristic).and_then(
                    |problem| {
                        let json = problem.to_json();
                        amber_stdx::write_atomic(&path, &json)?;
                        Ok((CacheEntry { inputs, content: hex(&Sha256::digest(&json)) }, false))
                    },
                ),
            };
            on_problem();
            (name, outcome)
        })
        .collect();

    let mut index = old_index.clone();
    let mut report = SplitReport::default();
    let mut first_error = None;
    for (name, outcome) in outcomes {
        match outcome {
            Ok((entry, cached)) => {
                if cached {
                    report.cached += 1
                } else {
                    report.written += 1
                }
                index.insert(name, entry);
            }
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    if index != old_index {
        amber_stdx::write_json_atomic(&index_path, &index)?;
    }
    match first_error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}

/// Where a split lives under the Poisson data root: `<root>/<difficulty>/<split>`, training
/// splits under `<root>/<difficulty>/train/seed<r>` (one per training seed).
pub fn split_dir(root: &Path, difficulty: Difficulty, split: Split, training_seed: usize) -> PathBuf {
    let dir = root.join(difficulty.name()).join(split.name());
    match split {
        Split::Train => dir.join(format!("seed{training_seed}")),
        Split::Val | Split::Test => dir,
    }
}

/// The first `count` problems (default: the manifest's split size) of a split, generated into
/// [`split_dir`] first where the cache does not already hold them. `on_problem` ticks once per
/// problem generated or found cached.
pub fn load_split(
    root: &Path,
    manifest_path: &Path,
    difficulty: Difficulty,
    split: Split,
    training_seed: usize,
    count: Option<usize>,
    on_problem: &(dyn Fn() + Sync),
) -> Result<(Vec<PoissonProblem>, SplitReport), TaskError> {
    let manifest = DatasetManifest::read(manifest_path)?;
    let (split_seed, size) = manifest.split(split, training_seed, manifest_path)?;
    let request = SplitRequest {
        difficulty,
        split_seed,
        count: count.unwrap_or(size),
        initial_size: super::INITIAL_SIZE,
        heuristic: ExpertHeuristic::default(),
    };
    let dir = split_dir(root, difficulty, split, training_seed);
    let report = write_split(&request, &dir, on_problem)?;
    let mut problems = super::read_split(&dir)?;
    problems.truncate(request.count);
    Ok((problems, report))
}

fn inputs_hash(request: &SplitRequest, seed: u64) -> String {
    let inputs = serde_json::json!({
        "version": GENERATOR_VERSION,
        "seed": seed,
        "steps": request.difficulty.steps(),
        "initial_size": request.initial_size,
        "heuristic": request.heuristic,
    });
    hex(&Sha256::digest(inputs.to_string().as_bytes()))
}

fn file_hash(path: &PathBuf) -> Option<String> {
    std::fs::read(path).ok().map(|bytes| hex(&Sha256::digest(bytes)))
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_are_deterministic_prefixes() {
        let long = problem_seeds(0, 20);
        assert_eq!(problem_seeds(0, 5), long[..5]);
        assert_ne!(problem_seeds(1, 5), long[..5]);
    }

    #[test]
    fn the_repository_manifest_parses() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/poisson.json");
        let manifest = DatasetManifest::read(&path).unwrap();
        assert_eq!(manifest.split(Split::Val, 0, &path).unwrap(), (0, 20));
        assert_eq!(manifest.split(Split::Test, 3, &path).unwrap(), (1, 100));
        assert_eq!(manifest.split(Split::Train, 0, &path).unwrap().1, 20);
        let err = manifest.split(Split::Train, 99, &path).unwrap_err().to_string();
        assert!(err.contains("poisson.json") && err.contains("training seed 99"), "{err}");
    }

    #[test]
    fn splits_are_cached_and_byte_identical() {
        let dir = std::env::temp_dir().join(format!("amber-tasks-cache-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let request = SplitRequest {
            difficulty: Difficulty::Easy,
            split_seed: 5,
            count: 2,
            initial_size: super::super::INITIAL_SIZE,
            heuristic: ExpertHeuristic::default(),
        };
        let done = std::sync::atomic::AtomicUsize::new(0);
        let tick = || {
            done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        assert_eq!(write_split(&request, &dir, &tick).unwrap(), SplitReport { written: 2, cached: 0 });
        let first = std::fs::read(dir.join("001.json")).unwrap();
        // A split found whole in the cache is not written (its index keeps its inode), nor is a
        // shorter prefix of it: the concurrent runs of a plan only read their data.
        use std::os::unix::fs::MetadataExt;
        let inode = || std::fs::metadata(dir.join(INDEX_FILE)).unwrap().ino();
        let before = inode();
        assert_eq!(write_split(&request, &dir, &tick).unwrap(), SplitReport { written: 0, cached: 2 });
        let prefix = SplitRequest { count: 1, ..request.clone() };
        assert_eq!(write_split(&prefix, &dir, &tick).unwrap(), SplitReport { written: 0, cached: 1 });
        assert_eq!(inode(), before);
        // A tampered file is regenerated, byte-identical to the first run.
        std::fs::write(dir.join("001.json"), b"{}").unwrap();
        assert_eq!(write_split(&request, &dir, &tick).unwrap(), SplitReport { written: 1, cached: 1 });
        assert_eq!(std::fs::read(dir.join("001.json")).unwrap(), first);
        assert_eq!(done.load(std::sync::atomic::Ordering::Relaxed), 7);
        let problems = super::super::read_split(&dir).unwrap();
        assert_eq!(problems.len(), 2);
        assert_eq!(problems[1].metadata.steps, Some(25));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
