//! End to end on tiny Poisson problems generated in the test (a few expert steps): training
//! lowers the loss, a killed and resumed run matches an uninterrupted one, the buffer keeps its
//! invariants, rollouts return every intermediate mesh with finite metrics.

use std::path::Path;

use amber_fem::ExpertHeuristic;
use amber_graph::EdgeFeature;
use amber_tasks::LOG_SIZE_COLUMN;
use amber_tasks::poisson::{INITIAL_SIZE, LOG_ERROR_INDICATOR_COLUMN, LOG_LOAD_COLUMN, PoissonProblem};
use amber_train::{
    AmberModel, AmberSizing, DataConfig, Evaluation, EvaluationSummary, MODEL_DIR, NetworkConfig, Predictor,
    ReplayBuffer, StepReport, StepStatus, Training, TrainingConfig, TrainingObserver, WEIGHTS_FILE, rollouts,
};

/// Problems with small experts (8 refinement steps: a few hundred triangles).
fn problems(seeds: &[u64]) -> Vec<PoissonProblem> {
    seeds.iter().map(|&s| PoissonProblem::generate(s, 8, INITIAL_SIZE, &ExpertHeuristic::default()).unwrap()).collect()
}

fn tiny_config(steps: u64) -> TrainingConfig {
    TrainingConfig {
        data: DataConfig { train_problems: 2, val_problems: 1 },
        network: NetworkConfig { latent_dim: 16, message_passing_steps: 3, ..NetworkConfig::default() },
        steps,
        batch_nodes: 1_500,
        buffer_capacity: 6,
        add_interval: 3,
        checkpoint_interval: 1_000,
        validation_interval: 0,
        inference_steps: 3,
        ..TrainingConfig::quick()
    }
}

/// Evaluation-mode mean squared log error of the sizes `network` predicts on every buffer entry.
fn log_size_error(network: &amber_mpn::Mpn, predictor: &Predictor, buffer: &ReplayBuffer<2>) -> f64 {
    let entries: Vec<_> = buffer.entries().collect();
    let states: Vec<_> = entries.iter().map(|e| &e.sample.state).collect();
    let sizes = predictor.predict(network, &states).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for (entry, sizes) in entries.iter().zip(sizes) {
        for (h, y) in sizes.iter().zip(&entry.sample.labels) {
            sum += (h / y).ln().powi(2);
            n += 1;
        }
    }
    sum / n as f64
}

fn single_thread<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(f)
}

#[test]
fn training_lowers_the_loss_and_keeps_the_buffer_invariants() {
    let config = tiny_config(150);
    let mut training = Training::new(config.clone(), problems(&[11, 12])).unwrap();
    let dir = tempfile::tempdir().unwrap();
    training.save_model(dir.path()).unwrap();
    let mut reports = Vec::new();
    for _ in 0..config.steps {
        reports.push(training.train_step().unwrap());
    }
    // On the data the run ended with, the trained network beats the initial one by far.
    let initial = AmberModel::load(dir.path()).unwrap();
    let before = log_size_error(&initial.network, &initial.predictor, training.buffer());
    let after = log_size_error(training.network(), training.predictor(), training.buffer());
    assert!(after < before / 3.0, "log-size error {before} -> {after}");
    assert!(
        reports.iter().all(|r| r.loss.is_finite() && r.nodes > 0 && (r.nodes <= config.batch_nodes || r.graphs == 1))
    );

    // One addition attempt every `add_interval` steps; protected entries stay, the FIFO is full.
    let additions = training.additions();
    assert_eq!(additions.added + additions.over_budget + additions.failed, config.steps.div_ceil(config.add_interval));
    assert!(additions.added > config.buffer_capacity as u64, "{additions:?}");
    let buffer = training.buffer();
    assert_eq!(
        buffer.protected().iter().map(|e| (e.id, e.problem, e.depth)).collect::<Vec<_>>(),
        [(0, 0, 0), (1, 1, 0)]
    );
    assert_eq!(buffer.generated().count(), config.buffer_capacity);
    assert!(buffer.generated().all(|e| (1..=config.max_source_depth + 1).contains(&e.depth)));
    let ids: Vec<u64> = buffer.generated().map(|e| e.id).collect();
    assert!(ids.windows(2).all(|w| w[0] < w[1]), "FIFO order {ids:?}");
    // Every step reports the buffer it trained from, and its loss split by depth: the batch loss
    // is a node-weighted mean of the per-depth losses, so it lies between them.
    let last = reports.last().unwrap();
    assert_eq!(last.buffer_depths.iter().sum::<usize>(), last.buffer_size);
    for r in &reports {
        let by_depth: Vec<f64> = r.loss_by_depth.iter().flatten().copied().collect();
        let (lo, hi) = by_depth.iter().fold((f64::INFINITY, 0f64), |(lo, hi), &l| (lo.min(l), hi.max(l)));
        assert!(
            lo <= r.loss * (1.0 + 1e-5) && r.loss <= hi * (1.0 + 1e-5),
            "step {}: {} vs {by_depth:?}",
            r.step,
            r.loss
        );
    }
    assert!(reports.iter().any(|r| r.loss_by_depth.iter().flatten().count() > 1), "batches mix depths");
}

/// Loss column of the log written by `Training::run`.
fn logged_losses(out: &Path) -> Vec<(u64, f64)> {
    std::fs::read_to_string(out.join(amber_train::LOG_FILE))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v["kind"] == "step")
        .map(|v| (v["step"].as_u64().unwrap(), v["loss"].as_f64().unwrap()))
        .collect()
}

/// Panics after the given step, like a process killed mid-run.
struct KillAfter(u64);

impl TrainingObserver for KillAfter {
    fn step(&mut self, report: &StepReport, _total: u64) {
        assert!(report.step() < self.0, "killed after step {}", report.step());
    }
}

#[test]
fn a_resumed_run_continues_exactly_where_the_killed_one_stopped() {
    resumes_exactly(TrainingConfig { checkpoint_interval: 7, ..tiny_config(20) });
}

/// Random orientations come from their own seeded stream, which the checkpoint keeps.
#[test]
fn a_resumed_run_in_random_orientations_continues_exactly() {
    resumes_exactly(TrainingConfig {
        checkpoint_interval: 7,
        edge_features: Some(vec![EdgeFeature::MidpointDistance, EdgeFeature::MidpointDifference]),
        random_orientation: true,
        ..tiny_config(20)
    });
}

/// The checkpoint holds the weight average (the model) and the trained weights beside it.
#[test]
fn a_resumed_run_with_a_weight_average_continues_exactly() {
    resumes_exactly(TrainingConfig { checkpoint_interval: 7, weight_average_decay: Some(0.9), ..tiny_config(20) });
}

fn resumes_exactly(config: TrainingConfig) {
    let dir = tempfile::tempdir().unwrap();
    let (whole, killed) = (dir.path().join("whole"), dir.path().join("killed"));
    single_thread(|| {
        let mut run = Training::new(config.clone(), problems(&[21, 22])).unwrap();
        run.run(&whole, None, &mut ()).unwrap();

        // The killed run: checkpoint at step 7, killed (a panic) after step 10, so that steps 8-10
        // are in the log but lost.
        let crash = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut run = Training::new(config.clone(), problems(&[21, 22])).unwrap();
            run.run(&killed, None, &mut KillAfter(10)).unwrap();
        }));
        assert!(crash.is_err());
        assert_eq!(logged_losses(&killed).len(), 10);
        let mut run = Training::open(config.clone(), problems(&[21, 22]), &killed).unwrap();
        assert_eq!(run.step(), 7);
        run.run(&killed, None, &mut ()).unwrap();
        assert_eq!(run.step(), 20);
    });
    let (a, b) = (logged_losses(&whole), logged_losses(&killed));
    assert_eq!(a.iter().map(|x| x.0).collect::<Vec<_>>(), (1..=20).collect::<Vec<_>>());
    // The lost steps 8-10 were dropped from the log and redone.
    assert_eq!(b.iter().map(|x| x.0).collect::<Vec<_>>(), (1..=20).collect::<Vec<_>>());
    for ((step, la), (_, lb)) in a.iter().zip(&b) {
        assert!((la - lb).abs() <= 1e-6 * la.abs().max(1.0), "step {step}: {la} vs {lb}");
    }
    // The same model, byte for byte.
    let weights = |run: &Path| std::fs::read(run.join(MODEL_DIR).join(WEIGHTS_FILE)).unwrap();
    assert!(weights(&whole) == weights(&killed), "the resumed run's model differs");
    // Only the newest checkpoint is kept, and it names the final step.
    let latest = amber_train::latest_checkpoint(&killed).unwrap().unwrap();
    assert!(latest.ends_with("step-00000020"), "{latest:?}");
    let kept = std::fs::read_dir(killed.join(amber_train::CHECKPOINTS_DIR)).unwrap().count();
    assert_eq!(kept, 3, "latest, entries/ and one step directory");

    // A mismatching configuration is refused.
    let other = TrainingConfig { seed: 1, ..config };
    assert!(Training::open(other, problems(&[21, 22]), &killed).is_err());
}

#[test]
fn rollouts_return_every_mesh_with_finite_metrics() {
    let train = problems(&[31, 32]);
    // A generous budget: these experts are tiny, and a briefly trained model overshoots them.
    let config = TrainingConfig { learning_rate: 3e-3, budget_factor: 2.0, ..tiny_config(400) };
    let dir = tempfile::tempdir().unwrap();
    let training = single_thread(|| {
        let mut training = Training::new(config, train.clone()).unwrap();
        training.run(dir.path(), None, &mut ()).unwrap();
        training
    });

    // The saved model predicts what the training run predicts.
    let model = AmberModel::load(&dir.path().join(MODEL_DIR)).unwrap();
    let evaluation = Evaluation::new(&train, training.limits()).unwrap();
    let steps = 3;
    let out = rollouts(&model.sizing(), &train, &evaluation.references, steps).unwrap();
    let live = AmberSizing { network: training.network(), predictor: training.predictor() };
    let (_, summary) = evaluation.run(&live, steps).unwrap();
    assert_eq!(summary.steps.len(), steps);
    for rollout in &out {
        assert_eq!(rollout.steps.len(), steps);
        assert!(rollout.initial_dcd > rollout.reconstruction_dcd && rollout.reconstruction_dcd > 0.0);
        assert!((rollout.initial.normalised_dcd - 1.0).abs() < 1e-12);
        let mut previous = (rollout.initial, None);
        for (t, step) in rollout.steps.iter().enumerate() {
            assert!(step.metrics.dcd.is_finite() && step.metrics.normalised_dcd.is_finite());
            assert_eq!(step.metrics.elements, step.mesh.num_elements());
            if step.status == StepStatus::Meshed {
                assert!(previous.1.is_none(), "no step after a failure meshes");
            } else {
                // A failed step keeps the last mesh and its metrics; the rollout stops there.
                assert_eq!(step.metrics, previous.0);
                let first_failure = *previous.1.get_or_insert(t);
                assert!(t == first_failure || step.status == StepStatus::Stopped);
            }
            previous.0 = step.metrics;
        }
    }
    let last = summary.steps.last().unwrap();
    assert_eq!(last.failed, out.iter().filter(|r| r.steps.iter().any(|s| s.status != StepStatus::Meshed)).count());
    // After training on these very problems the rollouts come closer to the expert than M⁰. How
    // close at each step, and which of the two rollouts stays within the budget, depends on the
    // last bits of the machine's matmul kernel (measured: 1.19, 0.69, 0.31 with both meshed;
    // 1.08, 0.57, 0.33 over the one meshed when the other went over the budget at step 2; 1.03,
    // 0.40, 0.50 on an AVX-512 Xeon, overshooting the expert's count at step 3), so the
    // successful ones are judged, each later step against the first.
    let successful: Vec<f64> = summary
        .steps
        .iter()
        .map(|s| s.normalised_dcd_successful.unwrap_or_else(|| panic!("every rollout failed: {summary:?}")))
        .collect();
    assert!(successful[1..].iter().all(|&d| d < successful[0]), "{summary:?}");
    assert!(successful[steps - 1] < 0.7, "{summary:?}");
    let from_file: Vec<f64> = out.iter().map(|r| r.steps[steps - 1].metrics.normalised_dcd).collect();
    assert!((from_file.iter().sum::<f64>() / 2.0 - last.normalised_dcd).abs() < 1e-9);
}

#[test]
fn fields_over_the_budget_are_skipped_or_scaled_to_it() {
    let problem = problems(&[3]).remove(0);
    let m0 = amber_tasks::Domain::initial_mesh(&problem).clone();
    let mut limits = amber_tasks::MeshLimits {
        min_size: 1e-6,
        max_elements: 2_000,
        scale_to_budget: false,
        final_step_scale: 1.0,
        final_count: None,
    };
    // 0.005 everywhere asks for ~70k triangles on the L-shape.
    let fine = vec![0.005; m0.num_elements()];
    let outcome =
        amber_tasks::generation_step(&problem, &m0, fine.clone(), &limits, &amber_tasks::SizeBounds::default());
    assert!(
        matches!(outcome, amber_tasks::StepOutcome::OverBudget { estimated_elements } if estimated_elements > 50_000.0)
    );
    limits.scale_to_budget = true;
    let amber_tasks::StepOutcome::Meshed(mesh) =
        amber_tasks::generation_step(&problem, &m0, fine, &limits, &amber_tasks::SizeBounds::default())
    else {
        panic!("a field scaled to the budget is meshed")
    };
    let n = mesh.num_elements();
    assert!((1_400..=2_200).contains(&n), "{n} elements for a budget of 2,000 (aiming at 95 %)");
}

#[test]
fn validation_scales_a_field_over_the_budget_to_it_as_evaluation_does() {
    // A budget of a tenth of the largest expert: an untrained model's fields are over it.
    let config = TrainingConfig { budget_factor: 0.1, ..tiny_config(1) };
    let training = Training::new(config, problems(&[11, 12])).unwrap();
    let val = problems(&[13]);
    let evaluation = Evaluation::new(&val, training.limits()).unwrap();
    let sizing = AmberSizing { network: training.network(), predictor: training.predictor() };
    let (skipped, _) = evaluation.run(&sizing, 2).unwrap();
    assert!(
        matches!(skipped[0].steps[0].status, StepStatus::OverBudget { .. }),
        "the model's own limits skip the field: {:?}",
        skipped[0].steps[0].status
    );
    let summary = training.validate(&evaluation).unwrap();
    let budget = training.limits().max_elements as f64;
    for step in &summary.steps {
        assert_eq!(step.failed, 0, "{summary:?}");
        assert!(step.elements <= 1.1 * budget, "{} elements for a budget of {budget}", step.elements);
    }
}

/// Records the validations a training run reports.
#[derive(Default)]
struct Validations {
    periodic: Vec<(u64, EvaluationSummary)>,
    fitted: Vec<(u64, EvaluationSummary)>,
}

impl TrainingObserver for Validations {
    fn validation(&mut self, step: u64, summary: &EvaluationSummary) {
        self.periodic.push((step, summary.clone()));
    }

    fn final_validation(&mut self, step: u64, summary: &EvaluationSummary) {
        self.fitted.push((step, summary.clone()));
    }
}

/// The last validation of a calibrated run scores the saved model, its last step fitted, as
/// `amber evaluate` would; a run resumed at its end redoes it rather than logging it twice.
#[test]
fn a_calibrated_run_validates_the_saved_model_once_more() {
    let config = TrainingConfig { calibrate_element_count: true, validation_interval: 4, ..tiny_config(4) };
    let (train, val) = (problems(&[41, 42]), problems(&[43]));
    let dir = tempfile::tempdir().unwrap();
    let mut seen = Validations::default();
    let limits = single_thread(|| {
        let mut training = Training::new(config.clone(), train.clone()).unwrap();
        let evaluation = Evaluation::new(&val, training.limits()).unwrap();
        training.run(dir.path(), Some(&evaluation), &mut seen).unwrap();
        *training.limits()
    });
    assert_eq!(seen.periodic.iter().map(|v| v.0).collect::<Vec<_>>(), [4]);
    assert_eq!(seen.fitted.iter().map(|v| v.0).collect::<Vec<_>>(), [4]);

    let mut model = AmberModel::load(&dir.path().join(MODEL_DIR)).unwrap();
    assert_ne!(model.predictor.limits.final_step_scale, 1.0, "the saved model's last step is fitted");
    // Validation scales a field over the budget to it, as `amber evaluate` does.
    model.predictor.limits.scale_to_budget = true;
    let evaluation = Evaluation::new(&val, &limits).unwrap();
    let (_, saved) = single_thread(|| evaluation.run(&model.sizing(), config.inference_steps)).unwrap();
    assert_eq!(seen.fitted[0].1, saved, "the final validation scores the saved model");

    let validations = |kind: &str| {
        let log = std::fs::read_to_string(dir.path().join(amber_train::LOG_FILE)).unwrap();
        log.lines().filter(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["kind"] == kind).count()
    };
    single_thread(|| {
        let mut resumed = Training::open(config.clone(), train.clone(), dir.path()).unwrap();
        let evaluation = Evaluation::new(&val, resumed.limits()).unwrap();
        resumed.run(dir.path(), Some(&evaluation), &mut ()).unwrap();
    });
    assert_eq!((validations("validation"), validations("final_validation")), (1, 1));
}

#[test]
fn the_optional_features_reach_a_saved_model_that_predicts_on_new_meshes() {
    let inputs = [LOG_SIZE_COLUMN, LOG_LOAD_COLUMN, LOG_ERROR_INDICATOR_COLUMN].map(String::from).to_vec();
    let config = TrainingConfig { inputs, ..tiny_config(3) };
    let problems = problems(&[11, 12]);
    let mut training = Training::new(config, problems.clone()).unwrap();
    for _ in 0..3 {
        training.train_step().unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    training.save_model(dir.path()).unwrap();
    let model = AmberModel::load(dir.path()).unwrap();
    let names: Vec<String> = model.predictor.features.node.iter().map(|f| format!("{f:?}")).collect();
    assert!(names.iter().any(|n| n.contains(LOG_SIZE_COLUMN)), "{names:?}");
    assert!(names.iter().any(|n| n.contains(LOG_LOAD_COLUMN)), "{names:?}");
    assert!(names.iter().any(|n| n.contains(LOG_ERROR_INDICATOR_COLUMN)), "{names:?}");
    assert_eq!(model.network.config().node_features, 7, "the paper's 4 node features + 3");

    let problem = &problems[0];
    let state = amber_tasks::MeshState::new(problem, &model.predictor.features, problem.expert_mesh.clone()).unwrap();
    let sizes = model.predict(&[&state]).unwrap();
    assert_eq!(sizes[0].len(), problem.expert_mesh.num_elements());
    assert!(sizes[0].iter().all(|h| h.is_finite() && *h > 0.0));
}

/// A config's edge features replace the task's: the saved model reads them, and predicts with
/// them on a mesh it has not seen.
#[test]
fn a_configured_edge_feature_set_replaces_the_tasks() {
    let edge_features = vec![EdgeFeature::MidpointDifference, EdgeFeature::MidpointDistance];
    let config = TrainingConfig { edge_features: Some(edge_features.clone()), ..tiny_config(2) };
    let problems = problems(&[11, 12]);
    let mut training = Training::new(config, problems.clone()).unwrap();
    training.train_step().unwrap();
    let dir = tempfile::tempdir().unwrap();
    training.save_model(dir.path()).unwrap();
    let model = AmberModel::load(dir.path()).unwrap();
    assert_eq!(model.predictor.features.edge, edge_features);
    assert_eq!(model.network.config().edge_features, 3, "a 2D difference vector and a distance");
    let problem = &problems[0];
    let state = amber_tasks::MeshState::new(problem, &model.predictor.features, problem.expert_mesh.clone()).unwrap();
    assert!(model.predict(&[&state]).unwrap()[0].iter().all(|h| h.is_finite() && *h > 0.0));

    let none = TrainingConfig { edge_features: Some(Vec::new()), ..tiny_config(2) };
    let Err(error) = Training::new(none, problems.clone()) else { panic!("trained without edge features") };
    assert!(error.to_string().contains("edge_features"), "{error}");
}

/// A run in random orientations normalises every axis alike, trains on turned batches (other
/// losses than the same run's without), and refuses edge features with no vector to turn.
#[test]
fn random_orientation_turns_the_batches_and_pools_the_axes() {
    let edge_features = vec![EdgeFeature::MidpointDistance, EdgeFeature::MidpointDifference];
    let config = TrainingConfig { edge_features: Some(edge_features), ..tiny_config(4) };
    let turned = TrainingConfig { random_orientation: true, ..config.clone() };
    let losses = |config: TrainingConfig| {
        let mut training = Training::new(config, problems(&[11, 12])).unwrap();
        let losses: Vec<f64> = (0..4).map(|_| training.train_step().unwrap().loss).collect();
        (losses, training.predictor().normaliser.clone().unwrap())
    };
    let ((plain, plain_moments), (turned_losses, turned_moments)) = (losses(config), losses(turned.clone()));
    assert_ne!(plain, turned_losses);
    let [_, x, y] = plain_moments.edge.variance().try_into().unwrap();
    assert_ne!(x, y);
    let [_, x, y] = turned_moments.edge.variance().try_into().unwrap();
    assert!((x - y).abs() < 1e-12 * x, "{x} {y}");
    assert_eq!(losses(turned).0, turned_losses, "the same seed turns the same way");

    let poisson = TrainingConfig { random_orientation: true, ..tiny_config(2) };
    let Err(error) = Training::new(poisson, problems(&[11, 12])) else { panic!("turned a distance") };
    assert!(error.to_string().contains("midpoint_difference"), "{error}");
}

#[cfg(not(feature = "cuda"))]
#[test]
fn a_gpu_device_in_a_cpu_build_is_an_error_that_says_so() {
    let config = TrainingConfig { device: amber_train::Backend::Cuda(0), ..tiny_config(1) };
    let Err(error) = Training::new(config, problems(&[11, 12])) else { panic!("trained on a GPU it has no code for") };
    assert!(error.to_string().to_lowercase().contains("cuda"), "{error}");
}
