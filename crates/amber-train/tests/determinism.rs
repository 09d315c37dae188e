//! A training run is a function of its configuration and problems whatever the number of
//! threads: two AMBER runs and two CNN runs at two threads and one of each at one thread write
//! the same model bytes (the fused ops reduce their gradients in an order fixed by the data
//! alone, `amber_nn::reduce`).

use std::path::Path;

use amber_fem::ExpertHeuristic;
use amber_tasks::poisson::{INITIAL_SIZE, PoissonProblem};
use amber_train::{
    CNN_WEIGHTS_FILE, CnnConfig, CnnTraining, DataConfig, MODEL_DIR, NetworkConfig, Training, TrainingConfig,
    WEIGHTS_FILE,
};
use sha2::{Digest, Sha256};

/// Problems with small experts (8 refinement steps: a few hundred triangles).
fn problems() -> Vec<PoissonProblem> {
    [11, 12]
        .iter()
        .map(|&s| PoissonProblem::generate(s, 8, INITIAL_SIZE, &ExpertHeuristic::default()).unwrap())
        .collect()
}

/// `f` in a rayon pool of `threads` threads.
fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

/// The bytes of `file` and their sha256 in hex.
fn read_hashed(file: &Path) -> (Vec<u8>, String) {
    let bytes = std::fs::read(file).unwrap();
    let hash = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
    (bytes, hash)
}

/// Trains at 2, 2 and 1 threads with `train` (which writes its model under the directory it is
/// given and returns the weights file) and asserts the three weights files are identical.
fn assert_reproducible(method: &str, train: impl Fn(&Path) -> std::path::PathBuf + Sync) {
    let runs: Vec<(Vec<u8>, String)> = [2, 2, 1]
        .into_iter()
        .map(|threads| {
            let dir = tempfile::tempdir().unwrap();
            in_pool(threads, || read_hashed(&train(dir.path())))
        })
        .collect();
    println!("{method} weights sha256 at 2, 2 and 1 threads: {}, {}, {}", runs[0].1, runs[1].1, runs[2].1);
    assert!(runs[0].0 == runs[1].0, "{method}: two runs at 2 threads differ");
    assert!(runs[0].0 == runs[2].0, "{method}: the runs at 1 and 2 threads differ");
}

#[test]
fn amber_training_writes_the_same_model_at_any_thread_count() {
    // Two buffer additions (rollouts and meshing) within the six steps; batches of several row
    // blocks, so that the fused ops' reductions have several chunks.
    let config = TrainingConfig {
        data: DataConfig { train_problems: 2, val_problems: 1 },
        network: NetworkConfig { latent_dim: 16, message_passing_steps: 3, ..NetworkConfig::default() },
        steps: 6,
        batch_nodes: 1_500,
        buffer_capacity: 6,
        add_interval: 3,
        checkpoint_interval: 1_000,
        validation_interval: 0,
        inference_steps: 3,
        ..TrainingConfig::quick()
    };
    assert_reproducible("AMBER", |dir| {
        Training::new(config.clone(), problems()).unwrap().run(dir, None, &mut ()).unwrap();
        dir.join(MODEL_DIR).join(WEIGHTS_FILE)
    });
}

#[test]
fn cnn_training_writes_the_same_model_at_any_thread_count() {
    let config = CnnConfig {
        resolution: 16,
        initial_channels: 4,
        steps: 4,
        checkpoint_interval: 1_000,
        learning_rate: 3e-3,
        ..CnnConfig::smoke()
    };
    assert_reproducible("CNN", |dir| {
        let model = CnnTraining::new(config.clone(), problems()).unwrap().run(dir, &mut ()).unwrap();
        model.join(CNN_WEIGHTS_FILE)
    });
}
