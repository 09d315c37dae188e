//! `fit-budget`: the AMBER training steps that keep a quick experiment within its time budget
//! on this machine. It times the network's training step as `bench mpn` does and compares it
//! with the machine the profiles' times were measured on; where this one is slower it writes a
//! `--config` file with the steps scaled down by the ratio, and says so. The steps are then
//! part of each run's config (and cache key), so a run stays reproducible from its config.

use std::path::PathBuf;
use std::time::Instant;

use amber_experiments::{Task, amber_config};
use amber_mpn::MpnConfig;
use amber_mpn::bench::{BenchCase, BenchStep};
use amber_stdx::median;
use amber_train::Profile;
use anyhow::{Context, bail};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The experiment whose AMBER runs are fitted.
    experiment: Experiment,
    /// The profile whose steps are scaled.
    #[arg(long, default_value = "quick")]
    profile: Profile,
    /// The config file to write (pass it to `reproduce --config`; add other overrides to it).
    #[arg(long, default_value = "fit-budget.json")]
    out: PathBuf,
    /// Nodes of the timed graph (the references were measured at 50,000).
    #[arg(long, default_value_t = 50_000)]
    nodes: usize,
    /// Timed training steps after one untimed one (the median counts).
    #[arg(long, default_value_t = 3)]
    iters: usize,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum Experiment {
    Poisson,
    Console,
}

/// Training-step speed (nodes/s) of the network, by latent width, on the machine the quick
/// profiles' times were measured on (2-core AMD EPYC): `bench mpn`'s fused training step on
/// 50,000 nodes, results/bench/mpn.json (D = 64) and results/bench/mpn-d128.json (D = 128).
const REFERENCE_SPEEDS: [(usize, f64); 2] = [(64, 25_657.0), (128, 7_966.0)];

/// Below this fraction of the reference speed the steps are scaled: within it, timing noise
/// would change a run's steps, and so its key, from one call to the next.
const SLOWER_THAN: f64 = 0.9;

pub fn run(args: Args) -> anyhow::Result<()> {
    let task = match args.experiment {
        Experiment::Poisson => Task::Poisson,
        Experiment::Console => Task::Console,
    };
    let config = amber_config(task, args.profile);
    let (profile_steps, latent) = (config.steps, config.network.latent_dim);
    let Some(&(_, reference)) = REFERENCE_SPEEDS.iter().find(|(d, _)| *d == latent) else {
        bail!("no reference speed for latent width {latent}: fit-budget knows {REFERENCE_SPEEDS:?}");
    };
    let speed = training_speed(latent, args.nodes, args.iters)?;
    let steps = fitted_steps(profile_steps, speed, reference);
    amber_stdx::write_json_atomic(&args.out, &serde_json::json!({ "steps": steps }))
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "the network trains at {speed:.0} nodes/s here (D = {latent}), the reference machine at {reference:.0}: \
         {}; wrote {{\"steps\": {steps}}} to {} (pass it as --config; the CNN runs keep their steps)",
        if steps == profile_steps {
            format!("the {profile_steps} steps of the profile stay")
        } else {
            format!("the profile's {profile_steps} steps become {steps}")
        },
        args.out.display(),
    );
    Ok(())
}

/// The median speed (nodes/s) of `iters` fused training steps of a network of width `latent`
/// (Poisson's feature widths, which the step's time hardly depends on) on a random graph of
/// `nodes` nodes and three neighbours each, after one untimed step.
fn training_speed(latent: usize, nodes: usize, iters: usize) -> anyhow::Result<f64> {
    if nodes == 0 || iters == 0 {
        bail!("--nodes and --iters must be positive");
    }
    let config = MpnConfig::small(latent, MpnConfig::poisson().network.message_passing_steps);
    let paper = amber_train::TrainingConfig::paper();
    let mut case =
        BenchCase::new(&config, paper.objective, nodes, 3 * nodes / 2, paper.learning_rate, paper.max_grad_norm)?;
    case.run(BenchStep::FastTrain)?;
    let mut times = Vec::with_capacity(iters);
    for _ in 0..iters {
        let start = Instant::now();
        case.run(BenchStep::FastTrain)?;
        times.push(start.elapsed().as_secs_f64());
    }
    Ok(nodes as f64 / median(&times))
}

/// `steps` scaled by `speed / reference` down to a multiple of 100 (at least 100); unchanged
/// unless this machine is slower than [`SLOWER_THAN`] × the reference (never scaled up).
fn fitted_steps(steps: u64, speed: f64, reference: f64) -> u64 {
    let ratio = speed / reference;
    if ratio >= SLOWER_THAN || ratio.is_nan() {
        return steps;
    }
    let scaled = (steps as f64 * ratio / 100.0).floor() as u64 * 100;
    scaled.clamp(100.min(steps), steps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_shrink_with_the_speed_and_never_grow() {
        // The Xeon that took 42 minutes for one quick Poisson variant (EPYC: ~27) runs at ~0.64×.
        assert_eq!(fitted_steps(2_500, 16_400.0, 25_657.0), 1_500);
        assert_eq!(fitted_steps(2_500, 0.75 * 25_657.0, 25_657.0), 1_800);
        assert_eq!(fitted_steps(2_500, 0.95 * 25_657.0, 25_657.0), 2_500, "within the noise");
        assert_eq!(fitted_steps(2_500, 3.0 * 25_657.0, 25_657.0), 2_500, "never more steps");
        assert_eq!(fitted_steps(1_200, 10.0, 7_966.0), 100, "at least 100");
        assert_eq!(fitted_steps(60, 10.0, 7_966.0), 60, "a run shorter than 100 steps stays");
    }

    #[test]
    fn every_quick_experiment_has_a_reference_speed() {
        for task in [Task::Poisson, Task::Console] {
            let latent = amber_config(task, Profile::Quick).network.latent_dim;
            assert!(REFERENCE_SPEEDS.iter().any(|(d, _)| *d == latent), "{task:?}: D = {latent}");
        }
    }

    #[test]
    fn a_small_graph_is_timed() {
        let speed = training_speed(8, 200, 1).unwrap();
        assert!(speed.is_finite() && speed > 0.0, "{speed}");
        assert!(training_speed(8, 0, 1).is_err());
    }
}
