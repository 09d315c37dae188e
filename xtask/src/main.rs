//! `cargo xtask`: benchmarks, datasets and reproductions of the paper's experiments.
//!
//! Every command writes its results atomically under `results/` (or `--out`), with the settings,
//! the machine and the commit beside the numbers; only a build of a clean commit writes under
//! `results/`.

mod bench_cnn;
mod bench_fem;
mod bench_mesher;
mod bench_mesher3d;
mod bench_metrics;
mod bench_mpn;
mod dataset;
mod fit_budget;
mod label_rollouts;
mod peer;
mod plan;
mod reference_distances;
mod report;
mod reproduce;
mod ship_model;
mod timing;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "cargo xtask", about = "amber project automation")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Speed and quality benchmarks; each writes a JSON file under results/bench/.
    #[command(subcommand)]
    Bench(Bench),
    /// Generate a dataset split under data/ (cached: existing identical files are kept).
    Dataset(dataset::Args),
    /// d(M⁰, M*) and d(M̂, M*) on a dataset split: the anchors of the normalised DCD.
    ReferenceDistances(reference_distances::Args),
    /// Rollouts that mesh the projected expert labels instead of predictions: the ceiling of
    /// imitation, per generation step.
    LabelRollouts(label_rollouts::Args),
    /// Reproduce an experiment of the paper: results.json, table.md and plots under results/.
    Reproduce(reproduce::Args),
    /// The paper's ablations on Poisson hard (results/ablate/).
    Ablate(reproduce::AblateArgs),
    /// Copy a reproduction's trained model into models/NAME with its card.
    ShipModel(ship_model::Args),
    /// The AMBER steps that keep an experiment's quick budget on this machine, from the
    /// network's measured speed against the reference machine's: a `--config` file.
    FitBudget(fit_budget::Args),
}

#[derive(Subcommand)]
enum Bench {
    /// The 2D generator on a graded L-shape at ~10k/100k/1M triangles, next to spade's refine().
    Mesher(bench_mesher::Args),
    /// The 3D generator on the Console train/val parts with the expert's own sizing field.
    Mesher3d(bench_mesher3d::Args),
    /// DCD of 1M vs 1M points and the 42k → 5k label projection.
    Metrics(bench_metrics::Args),
    /// P1 Poisson: one hard 75-step expert run, assemble + solve at ~200k and ~1M triangles.
    Fem(bench_fem::Args),
    /// MPN train step and inference on a 50k-node graph: fused ops vs stock candle (vs PyTorch).
    Mpn(bench_mpn::Args),
    /// U-Net train step and inference on 1×4×256² and 1×1×64³ (vs PyTorch).
    Cnn(bench_cnn::Args),
}

impl Bench {
    /// Runs the bench, refusing at once (not after minutes of timing) a results file under
    /// `results/` that a dirty build would write.
    fn run(self) -> anyhow::Result<()> {
        let out = match &self {
            Bench::Mesher(args) => &args.out,
            Bench::Mesher3d(args) => &args.out,
            Bench::Metrics(args) => &args.out,
            Bench::Fem(args) => &args.out,
            Bench::Mpn(args) => &args.out,
            Bench::Cnn(args) => &args.out,
        };
        report::check_provenance(out, None)?;
        match self {
            Bench::Mesher(args) => bench_mesher::run(args),
            Bench::Mesher3d(args) => bench_mesher3d::run(args),
            Bench::Metrics(args) => bench_metrics::run(args),
            Bench::Fem(args) => bench_fem::run(args),
            Bench::Mpn(args) => bench_mpn::run(args),
            Bench::Cnn(args) => bench_cnn::run(args),
        }
    }
}

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> anyhow::Result<()> {
    // Never hand freed memory back to the OS (15 = mi_option_purge_delay, -1 = never purge): the
    // networks free and reallocate tens of MB of activations every step, and re-faulting (and
    // zeroing) those pages cost a third of an MPN training step (measured with perf).
    // SAFETY: sets a process-wide allocator option before any thread starts.
    unsafe { libmimalloc_sys::mi_option_set(15, -1) };
    // Commands run from any directory; relative paths are taken from the workspace root.
    std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))?;
    match Cli::parse().command {
        Command::Bench(bench) => bench.run(),
        Command::Dataset(args) => dataset::run(args),
        Command::ShipModel(args) => ship_model::run(args),
        Command::ReferenceDistances(args) => reference_distances::run(args),
        Command::LabelRollouts(args) => label_rollouts::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Ablate(args) => reproduce::ablate(args),
        Command::FitBudget(args) => fit_budget::run(args),
    }
}
