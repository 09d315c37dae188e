//! The paper's experiments as library functions, shared by `cargo xtask` and the `amber`
//! command: methods and their variants as configurations of one code path ([`MethodSpec`]), a
//! run directory per (method, variant, difficulty, seed) keyed by a hash of its whole
//! configuration (trained models are reused, killed runs resume), evaluation on the test
//! problems with the paper's metrics, and the outputs every experiment writes: `results.json`
//! in one schema ([`ExperimentResults`]), `table.md` with the paper's numbers beside ours, and
//! PNG charts and mesh galleries. An experiment's runs can also be listed ([`PlannedRun`]), run
//! one at a time by a scheduler, and collected from their caches ([`CachePolicy::Require`]).
//! Progress goes to the terminal as bars and lines.

mod card;
mod console;
mod folder;
mod grid;
mod method;
mod outputs;
mod poisson;
mod profiles;
mod progress;
mod report;
mod results;
mod run;
mod table;

pub use card::{CARD_FILE, CardCalibration, CardEvaluation, ModelCard, resolve_model};
pub use console::ConsoleExperiment;
pub use folder::{FolderTraining, train_folder};
pub use grid::{CachePolicy, PlannedRun};
pub use method::{Method, MethodSpec, Variant};
pub use poisson::{PoissonExperiment, train_poisson};
pub use profiles::{Task, amber_config, cnn_config};
pub use progress::{TrainingProgress, item_bar};
pub use report::{built_from_a_clean_commit, commit, config_hash, machine, merge_json, write_atomic, write_json};
pub use results::{ExperimentResults, ProblemEvaluation, RunKey, RunResult, RunThreads, StepEvaluation};
pub use run::{train_run, training_commits};
pub use table::{markdown as markdown_table, row_label};
