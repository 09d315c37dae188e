//! The smoke profile of `reproduce poisson` end to end (what CI runs): datasets, training of
//! AMBER-Mean and AMBER-Max, test rollouts, and every output; then a rerun that must reuse the
//! cached runs and reproduce the same results.

use std::path::Path;

use amber_experiments::{ExperimentResults, PoissonExperiment};
use amber_train::Profile;

fn png_size(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().unwrap();
    (reader.info().width, reader.info().height)
}

#[test]
fn smoke_profile_writes_every_output_and_reuses_its_runs() {
    let dir = tempfile::tempdir().unwrap();
    let mut experiment = PoissonExperiment::new(Profile::Smoke);
    experiment.manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/poisson.json");
    experiment.data_root = dir.path().join("data/poisson");
    experiment.runs_root = dir.path().join("data/runs");
    experiment.out = dir.path().join("results/poisson");
    experiment.methods.push(amber_experiments::MethodSpec::plain(amber_experiments::Method::Cnn { resolution: 32 }));
    let results = experiment.run().unwrap();

    // results.json is the schema the issue names, and what run() returned.
    let text = std::fs::read_to_string(experiment.out.join("results.json")).unwrap();
    let value: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in ["experiment", "profile", "commit", "machine", "config", "runs"] {
        assert!(value.get(key).is_some(), "results.json lacks `{key}`");
    }
    assert_eq!(serde_json::from_value::<ExperimentResults>(value.clone()).unwrap(), results);
    let runs = value["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3, "AMBER-Mean, AMBER-Max and the 32² CNN on easy, one seed");
    let fields = [
        "method",
        "variant",
        "difficulty",
        "seed",
        "ndcd",
        "ndcd_quantiles",
        "ndcd_per_step",
        "dcd",
        "dcd_initial",
        "dcd_reconstruction",
        "volume_difference",
        "elements",
        "expert_elements",
        "failed_steps",
        "train_seconds",
        "eval_seconds",
    ];
    let steps = amber_train::TrainingConfig::smoke().inference_steps;
    for run in runs {
        for key in fields {
            assert!(run.get(key).is_some(), "a run lacks `{key}`: {run}");
        }
        let cnn = run["method"].as_str().unwrap().starts_with("cnn");
        assert_eq!(run["ndcd_per_step"].as_array().unwrap().len(), if cnn { 1 } else { steps });
        assert_eq!(run["test_problems"], 3);
        let ndcd = run["ndcd"].as_f64().unwrap();
        assert!(ndcd.is_finite(), "{run}");
        let q = run["ndcd_quantiles"].as_array().unwrap();
        assert!(q[0].as_f64().unwrap() <= q[1].as_f64().unwrap());
        // d(M̂) < d(M⁰): the normalisation is well defined.
        assert!(run["dcd_reconstruction"].as_f64().unwrap() < run["dcd_initial"].as_f64().unwrap(), "{run}");
        assert!(run["train_seconds"].as_f64().unwrap() > 0.0);
        let threads = rayon::current_num_threads();
        assert_eq!(run["threads"], serde_json::json!({ "train": threads, "eval": threads }), "{run}");
    }
    let methods: Vec<&str> = runs.iter().map(|r| r["method"].as_str().unwrap()).collect();
    assert_eq!(methods, ["amber-mean", "amber-max", "cnn-32"]);

    // The table names every method with its numbers; the pictures are real PNGs.
    let table = std::fs::read_to_string(experiment.out.join("table.md")).unwrap();
    for run in &results.runs {
        assert!(table.contains(&format!("| {} | {:.3}", run.method, run.ndcd)), "{table}");
    }
    assert_eq!(png_size(&experiment.out.join("ndcd_bars.png")), (1000, 620));
    assert_eq!(png_size(&experiment.out.join("ndcd_per_step_easy.png")), (1000, 620));
    // Three methods × two problems; steps 1, 2, T and the expert (the CNN: its one step).
    assert_eq!(png_size(&experiment.out.join("gallery_easy.png")), (4 * 420, 6 * 380));

    // Every run's model has a card with the command and commit that trained it and its scores,
    // so `amber mesh --model <run>` takes it as it takes a shipped model.
    for (config, run) in value["config"]["runs"].as_array().unwrap().iter().zip(&results.runs) {
        let model = Path::new(config["run_dir"].as_str().unwrap()).join("model");
        let card = amber_experiments::ModelCard::read(&model).unwrap();
        assert_eq!(card.task, amber_experiments::Task::Poisson);
        assert_eq!(card.method, run.method);
        assert_eq!(card.commit, amber_experiments::commit());
        assert!(card.command.contains("smoke"), "the test binary's command line: {}", card.command);
        let evaluation = card.evaluation.unwrap();
        assert_eq!(evaluation.normalised_dcd, run.ndcd);
        assert_eq!(evaluation.normalised_dcd_per_step, run.ndcd_per_step);
        assert_eq!(card.training_seconds, run.train_seconds);
    }

    // A rerun trains and evaluates nothing: the same numbers come back from the caches.
    let again = experiment.run().unwrap();
    assert_eq!(again.runs, results.runs);
}

#[test]
fn ablations_are_variants_of_one_training_path_with_the_papers_numbers_beside() {
    let dir = tempfile::tempdir().unwrap();
    let mut experiment = PoissonExperiment::ablation(Profile::Smoke);
    experiment.manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../datasets/poisson.json");
    experiment.data_root = dir.path().join("data/poisson");
    experiment.runs_root = dir.path().join("data/runs");
    experiment.out = dir.path().join("results/ablate");
    // Few steps: this checks the plumbing of every variant, not their quality.
    amber_experiments::merge_json(
        &mut experiment.overrides,
        &serde_json::json!({ "steps": 24, "checkpoint_interval": 12, "validation_interval": 0 }),
    );
    experiment.cnn_overrides = serde_json::json!({ "steps": 4, "checkpoint_interval": 2 });
    let results = experiment.run().unwrap();
    assert_eq!(results.experiment, "ablate");
    let rows: Vec<String> = results.runs.iter().map(amber_experiments::row_label).collect();
    assert_eq!(
        rows,
        [
            "amber-mean",
            "amber-max",
            "amber-mean (log-loss)",
            "amber-max (log-loss)",
            "amber-max (no-softplus)",
            "amber-max (random-buffer)",
            "amber-max (no-input-normalisation)",
            "amber-mean (graph-context)",
            "amber-mean (error-indicator)",
            "cnn-32",
            "cnn-32 (softplus-mse)",
            "cnn-32 (plain-mse)",
            "cnn-32 (max-labels)",
            "amber-max (1-problems)",
            "amber-max (3-problems)",
        ]
    );
    // Each variant really changed its run's config.
    let configs = results.config["runs"].as_array().unwrap();
    let training = |k: usize| &configs[k]["training"];
    assert_eq!(training(2)["amber"]["objective"], "log_mse");
    assert_eq!(training(4)["amber"]["objective"], "mse");
    assert_eq!(training(5)["amber"]["source_selection"], "uniform");
    assert_eq!(training(6)["amber"]["normalise_inputs"], false);
    // The ablations run on the paper's network and inputs, the graph context being a variant.
    assert_eq!(training(0)["amber"]["network"].get("graph_context"), None);
    assert_eq!(training(0)["amber"]["inputs"], serde_json::json!(["log_size"]));
    assert_eq!(training(7)["amber"]["network"]["graph_context"], true);
    assert_eq!(training(8)["amber"]["inputs"], serde_json::json!(["log_size", "log_error_indicator"]));
    assert_eq!(training(10)["cnn"]["loss"], "softplus_mse");
    assert_eq!(training(11)["cnn"]["loss"], "mse");
    assert_eq!(training(12)["cnn"]["aggregation"], "max");
    assert_eq!(training(14)["amber"]["data"]["train_problems"], 3);
    for run in &results.runs {
        let steps = if run.method.starts_with("cnn") { 1 } else { 3 };
        assert!(run.ndcd.is_finite() && run.ndcd_per_step.len() == steps, "{run:?}");
    }
    let table = std::fs::read_to_string(experiment.out.join("table.md")).unwrap();
    assert!(table.contains("| amber-max (no-softplus) |"), "{table}");
    assert!(experiment.out.join("ndcd_bars.png").exists());
}

/// The smoke Console experiment on ../shared/data/console (`None` where it is absent), its runs
/// and outputs under `dir`, training `steps` steps: these tests check the 3D plumbing end to
/// end, not the quality.
fn console_experiment(dir: &Path, steps: u64) -> Option<amber_experiments::ConsoleExperiment> {
    let data = amber_testdata::shared("data/console")?;
    let mut experiment = amber_experiments::ConsoleExperiment::new(Profile::Smoke, &data);
    experiment.runs_root = dir.join("data/runs");
    experiment.out = dir.join("results/console");
    experiment.overrides =
        serde_json::json!({ "steps": steps, "checkpoint_interval": steps.div_ceil(2), "validation_interval": 0 });
    Some(experiment)
}

#[test]
fn console_smoke_trains_evaluates_on_val_and_draws_surfaces() {
    let dir = tempfile::tempdir().unwrap();
    let Some(experiment) = console_experiment(dir.path(), 16) else { return };
    let results = experiment.run().unwrap();
    assert_eq!(results.experiment, "console");
    assert_eq!(results.config["test_split"], "val");
    let methods: Vec<&str> = results.runs.iter().map(|r| r.method.as_str()).collect();
    assert_eq!(methods, ["amber-mean", "amber-max"]);
    for run in &results.runs {
        assert_eq!(run.test_problems, 2, "val/001 and val/002");
        assert_eq!(run.ndcd_per_step.len(), amber_train::TrainingConfig::smoke().inference_steps);
        // The raw anchors of the normalisation are the spec's (d(M⁰) ≈ 0.75–0.85, d(M̂) ≈ 0.46–0.52).
        assert!((0.6..0.95).contains(&run.dcd_initial) && (0.35..0.6).contains(&run.dcd_reconstruction), "{run:?}");
        assert!(run.ndcd.is_finite());
    }
    for file in [
        "results.json",
        "table.md",
        "ndcd_bars.png",
        "ndcd_per_step_console.png",
        "gallery_console_view1.png",
        "gallery_console_view2.png",
    ] {
        assert!(experiment.out.join(file).exists(), "{file} missing");
    }
    // Two methods × two parts; steps 1, 2, T and the expert.
    assert_eq!(png_size(&experiment.out.join("gallery_console_view1.png")), (4 * 460, 4 * 380));
}

#[test]
fn console_cross_validation_scores_every_training_part_once() {
    let dir = tempfile::tempdir().unwrap();
    let Some(mut experiment) = console_experiment(dir.path(), 4) else { return };
    experiment.methods = vec![amber_experiments::MethodSpec::plain(amber_experiments::Method::AmberMax)];
    experiment.folds = Some(1);
    assert!(experiment.plan().unwrap_err().to_string().contains("takes 2 to 15 folds"));
    // The paper's 15 training parts in 5 folds of 3: part i is held out by fold i mod 5.
    experiment.folds = Some(5);
    let plan = experiment.plan().unwrap();
    assert_eq!(plan.len(), 5, "one run per fold");
    assert!(plan.iter().enumerate().all(|(f, run)| run.key.contains(&format!("console-cv5-fold{f}/"))), "{plan:?}");
    let results = experiment.run().unwrap();
    assert_eq!(results.config["test_split"], "cross-validation");
    assert_eq!(results.runs.len(), 1, "the folds pool into one row");
    let run = &results.runs[0];
    assert_eq!((run.difficulty.as_str(), run.test_problems), ("console-cv", 15));
    let names: Vec<&str> = run.problems.iter().map(|p| p.name.as_deref().unwrap()).collect();
    let expected: Vec<String> = (0..5).flat_map(|f| (0..3).map(move |k| format!("{:03}", 1 + f + 5 * k))).collect();
    assert_eq!(names, expected, "fold order, each part once");
    let card = std::fs::read_to_string(plan[0].dir.join("model/card.json")).unwrap();
    assert!(
        card.contains("but the 3 fold 0 of 5 holds out (001, 006, 011)"),
        "the card names the parts not trained on: {card}"
    );
    let table = std::fs::read_to_string(experiment.out.join("table.md")).unwrap();
    assert!(table.contains("5-fold cross-validation"), "{table}");
    assert!(table.contains("| amber-max | ") && !table.contains("0.238"), "no paper number beside a CV score: {table}");
}
