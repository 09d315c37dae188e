//! Trains AMBER on the Poisson task with a named profile, the stand-in for `amber train` until
//! the CLI is wired: `cargo run --release -p amber-train --example train_poisson -- --help`.
//!
//! Generates (or reuses) the dataset splits the profile asks for under `--data`, trains into
//! `--out` (resuming a killed run there), validates as configured and prints a line every
//! `--print-every` steps.

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_fem::ExpertHeuristic;
use amber_tasks::poisson::{
    DatasetManifest, INITIAL_SIZE, PoissonProblem, Split, SplitRequest, read_split, write_split,
};
use amber_train::{Evaluation, EvaluationSummary, Profile, StepReport, Training, TrainingConfig, TrainingObserver};
use clap::Parser;

#[derive(Parser)]
struct Cli {
    /// Named profile (smoke, quick, paper).
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// A JSON file of config fields overriding the profile's.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Override the number of gradient steps.
    #[arg(long)]
    steps: Option<u64>,
    /// Override the dataset difficulty (easy, medium, hard).
    #[arg(long)]
    difficulty: Option<amber_tasks::poisson::Difficulty>,
    /// Training seed index (selects the training split and seeds the run).
    #[arg(long, default_value_t = 0)]
    seed: usize,
    /// Dataset root: splits go to `<data>/poisson/<difficulty>/<split>`.
    #[arg(long, default_value = "data")]
    data: PathBuf,
    /// Split manifest.
    #[arg(long, default_value = "datasets/poisson.json")]
    manifest: PathBuf,
    /// Output directory.
    #[arg(long)]
    out: PathBuf,
    #[arg(long, default_value_t = 50)]
    print_every: u64,
}

/// `mi_option_purge_decommits` in mimalloc's `mi_option_e` (see amber-mpn's examples/bench.rs).
const MI_OPTION_PURGE_DECOMMITS: libmimalloc_sys::mi_option_t = 5;

fn split(cli: &Cli, config: &TrainingConfig, split: Split, count: usize) -> anyhow::Result<Vec<PoissonProblem>> {
    let manifest = DatasetManifest::read(&cli.manifest)?;
    let (split_seed, size) = manifest.split(split, cli.seed, &cli.manifest)?;
    let name = match split {
        Split::Train if cli.seed > 0 => format!("train-seed{}", cli.seed),
        other => other.name().to_string(),
    };
    let dir = cli.data.join("poisson").join(config.data.difficulty.name()).join(name);
    let request = SplitRequest {
        difficulty: config.data.difficulty,
        split_seed,
        count: count.min(size),
        initial_size: INITIAL_SIZE,
        heuristic: ExpertHeuristic::default(),
    };
    let started = Instant::now();
    let report = write_split(&request, &dir, &|| {})?;
    let mut problems = read_split(&dir)?;
    problems.truncate(request.count);
    let experts: Vec<usize> = problems.iter().map(|p| p.expert_mesh.num_elements()).collect();
    println!(
        "{split}: {} problems in {} ({} generated, {} cached, {:.1} s), expert elements {}..{} (mean {:.0})",
        problems.len(),
        dir.display(),
        report.written,
        report.cached,
        started.elapsed().as_secs_f64(),
        experts.iter().min().unwrap_or(&0),
        experts.iter().max().unwrap_or(&0),
        experts.iter().sum::<usize>() as f64 / experts.len().max(1) as f64,
    );
    Ok(problems)
}

struct Printer {
    every: u64,
    started: Instant,
    since: Instant,
    nodes: usize,
    loss: f64,
    count: u64,
}

impl TrainingObserver for Printer {
    fn step(&mut self, r: &StepReport, total: u64) {
        self.nodes += r.nodes;
        self.loss += r.loss;
        self.count += 1;
        if r.step.is_multiple_of(self.every) || r.step == total {
            let seconds = self.since.elapsed().as_secs_f64();
            println!(
                "step {:>6}/{total} [{:>6.0} s] loss {:.4} lr {:.2e} {:.0} nodes/step {:.2} steps/s {:.0} nodes/s \
                 buffer {:?}",
                r.step,
                self.started.elapsed().as_secs_f64(),
                self.loss / self.count as f64,
                r.learning_rate,
                self.nodes as f64 / self.count as f64,
                self.count as f64 / seconds,
                self.nodes as f64 / seconds,
                r.buffer_depths,
            );
            (self.since, self.nodes, self.loss, self.count) = (Instant::now(), 0, 0.0, 0);
        }
    }

    fn validation(&mut self, step: u64, s: &EvaluationSummary) {
        let per_step: Vec<String> = s
            .steps
            .iter()
            .map(|t| format!("{:.3} ({:.0} el, {} failed)", t.normalised_dcd, t.elements, t.failed))
            .collect();
        println!(
            "validation at step {step} [{:.0} s]: normalised DCD per step {}; d(M0) {:.3} d(M^) {:.3}, expert {:.0} el",
            self.started.elapsed().as_secs_f64(),
            per_step.join(", "),
            s.initial_dcd,
            s.reconstruction_dcd,
            s.expert_elements
        );
    }

    fn checkpoint(&mut self, step: u64, dir: &Path) {
        println!("checkpoint at step {step}: {}", dir.display());
    }
}

fn main() -> anyhow::Result<()> {
    // SAFETY: sets a process-wide allocator option; called before any other thread exists.
    unsafe { libmimalloc_sys::mi_option_set(MI_OPTION_PURGE_DECOMMITS, 0) };
    let cli = Cli::parse();
    let mut config = match &cli.config {
        Some(path) => {
            let mut value = serde_json::to_value(TrainingConfig::profile(cli.profile))?;
            let overrides: serde_json::Value = serde_json::from_slice(&std::fs::read(path)?)?;
            merge(&mut value, overrides);
            serde_json::from_value(value)?
        }
        None => TrainingConfig::profile(cli.profile),
    };
    if let Some(steps) = cli.steps {
        config.steps = steps;
    }
    if let Some(difficulty) = cli.difficulty {
        config.data.difficulty = difficulty;
    }
    config.seed = cli.seed as u64;
    let train = split(&cli, &config, Split::Train, config.data.train_problems)?;
    let val = split(&cli, &config, Split::Val, config.data.val_problems)?;
    let started = Instant::now();
    let mut training = Training::open(config.clone(), train, &cli.out)?;
    println!(
        "{} at step {} ({:.1} s): h_min {:.3e}, budget {} elements",
        if training.step() > 0 { "resumed" } else { "started" },
        training.step(),
        started.elapsed().as_secs_f64(),
        training.limits().min_size,
        training.limits().max_elements
    );
    let validation = Evaluation::new(&val, training.limits())?;
    let now = Instant::now();
    let mut printer = Printer { every: cli.print_every, started: now, since: now, nodes: 0, loss: 0.0, count: 0 };
    training.run(&cli.out, Some(&validation), &mut printer)?;
    println!("done in {:.0} s; additions {:?}", now.elapsed().as_secs_f64(), training.additions());
    Ok(())
}

/// Overwrites fields of `base` with those of `overrides`, recursively for objects.
fn merge(base: &mut serde_json::Value, overrides: serde_json::Value) {
    match (base, overrides) {
        (serde_json::Value::Object(b), serde_json::Value::Object(o)) => {
            for (k, v) in o {
                merge(b.entry(k).or_insert(serde_json::Value::Null), v);
            }
        }
        (b, o) => *b = o,
    }
}
