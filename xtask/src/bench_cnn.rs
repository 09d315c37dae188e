//! `bench cnn`: a training step (forward, masked MSE, backward, clip 0.5, Adam 3e-4) and an
//! evaluation forward of the U-Net baseline (32 initial channels, depth 4) on a 1×4×256² image
//! and a 1×1×64³ voxel grid, next to the PyTorch peer (`shared/peers/bench_unet.py`) on the same
//! shapes in the same session.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_cnn::UNetConfig;
use amber_cnn::bench::BenchCase;
use amber_stdx::median;
use amber_train::CnnConfig;
use anyhow::Context;
use serde_json::{Value, json};

use crate::peer::{Peer, PeerDir};
use crate::report;
use crate::timing::load_average;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Where to write the results (JSON).
    #[arg(long, default_value = "results/bench/cnn.json")]
    pub out: PathBuf,
    /// Cases to time: 2d (1×4×256²), 3d (1×1×64³).
    #[arg(long, value_delimiter = ',', default_value = "2d,3d")]
    pub cases: Vec<String>,
    /// Timed iterations per case (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub iters: usize,
    /// Untimed iterations before timing (first touches of memory are slow).
    #[arg(long, default_value_t = 1)]
    pub warmup: usize,
    /// Initial channels of the U-Net.
    #[arg(long, default_value_t = 32)]
    pub channels: usize,
    /// Python interpreter with torch, to also run the PyTorch peer.
    #[arg(long)]
    pub peer_python: Option<PathBuf>,
    /// The peer script.
    #[arg(long, default_value = "../shared/peers/bench_unet.py")]
    pub peer_script: PathBuf,
    /// Threads for ours (the rayon pool) and for the peer (PEERS_THREADS).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
}

/// One benchmark shape.
struct Case {
    name: &'static str,
    spatial_axes: usize,
    in_channels: usize,
    resolution: usize,
}

const CASES: [Case; 2] = [
    Case { name: "2d", spatial_axes: 2, in_channels: 4, resolution: 256 },
    Case { name: "3d", spatial_axes: 3, in_channels: 1, resolution: 64 },
];

pub fn run(args: Args) -> anyhow::Result<()> {
    rayon::ThreadPoolBuilder::new().num_threads(args.threads).build_global().context("starting the thread pool")?;
    let mut results = Vec::new();
    for name in &args.cases {
        let case = CASES.iter().find(|c| c.name == name).with_context(|| format!("unknown case `{name}` (2d, 3d)"))?;
        let ours = bench_ours(case, &args)?;
        println!(
            "amber-cnn {:>2} {}: train {:7.3} s/step (forward {:.3} s, backward {:.3} s)  infer {:7.3} s  ({} parameters) [load average {}]",
            case.name,
            ours["input_shape"],
            ours["train_s_median"].as_f64().unwrap_or(f64::NAN),
            ours["train_forward_s_median"].as_f64().unwrap_or(f64::NAN),
            ours["train_backward_s_median"].as_f64().unwrap_or(f64::NAN),
            ours["infer_s_median"].as_f64().unwrap_or(f64::NAN),
            ours["parameters"],
            ours["load_average_after"].as_str().unwrap_or("?"),
        );
        let peer = match &args.peer_python {
            Some(python) => Some(run_peer(python, case, &args)?),
            None => None,
        };
        let ratio = |key: &str, peer_key: &str| {
            let p = peer.as_ref()?[peer_key].as_f64()?;
            Some(ours[key].as_f64()? / p)
        };
        let (train_ratio, infer_ratio) =
            (ratio("train_s_median", "train_step_s_median"), ratio("infer_s_median", "infer_s_median"));
        if let (Some(p), Some(t), Some(i)) = (&peer, train_ratio, infer_ratio) {
            println!(
                "  torch {:>2}: train {:7.3} s/step  infer {:7.3} s  → ours/torch: train {t:.2}×, infer {i:.2}×",
                case.name,
                p["train_step_s_median"].as_f64().unwrap_or(f64::NAN),
                p["infer_s_median"].as_f64().unwrap_or(f64::NAN)
            );
        }
        results.push(json!({
            "case": case.name,
            "amber_cnn": ours,
            "torch": peer,
            "time_ratio_ours_over_torch": { "train": train_ratio, "infer": infer_ratio },
        }));
    }
    let result = json!({
        "benchmark": "cnn",
        "network": { "initial_channels": args.channels, "depth": 4, "bias_in_convs_before_batchnorm": false },
        "step": "forward (batch statistics) + MSE over all pixels + backward + global-norm clip 0.5 + Adam 3e-4",
        "rayon_threads": rayon::current_num_threads(),
        "iters": args.iters,
        "warmup": args.warmup,
        "machine": report::machine(),
        "cases": results,
    });
    report::write_json(&args.out, &result)
}

fn bench_ours(case: &Case, args: &Args) -> anyhow::Result<Value> {
    let config = UNetConfig {
        spatial_axes: case.spatial_axes,
        in_channels: case.in_channels,
        initial_channels: args.channels,
        depth: 4,
    };
    // The Adam that trains, with the paper's settings; its log-MSE is a plain MSE of the output.
    let paper = CnnConfig::paper();
    let mut bench = BenchCase::new(config, case.resolution, paper.objective, paper.learning_rate, paper.max_grad_norm)?;
    let mut forward_s = Vec::new();
    let load_average_before = load_average();
    let train = time(args, &mut || -> anyhow::Result<()> {
        forward_s.push(bench.train_step()?);
        Ok(())
    })?;
    // The timed steps' forward passes (after the warm-up).
    let forward_s = forward_s.split_off(args.warmup.min(forward_s.len()));
    // Forward and backward without the optimiser: the rest of a step is clipping and Adam.
    let mut backward_s = Vec::new();
    time(args, &mut || -> anyhow::Result<()> {
        backward_s.push(bench.backward()?);
        Ok(())
    })?;
    let backward_s = backward_s.split_off(args.warmup.min(backward_s.len()));
    let infer = time(args, &mut || Ok(bench.infer()?))?;
    Ok(json!({
        "input_shape": bench.input_shape(),
        "parameters": bench.parameter_count(),
        "train_s_median": median(&train),
        "train_s_all": train,
        "train_forward_s_median": median(&forward_s),
        "train_backward_s_median": median(&backward_s),
        "infer_s_median": median(&infer),
        "infer_s_all": infer,
        "load_average_before": load_average_before,
        "load_average_after": load_average(),
    }))
}

/// Wall seconds of each timed iteration.
fn time(args: &Args, step: &mut dyn FnMut() -> anyhow::Result<()>) -> anyhow::Result<Vec<f64>> {
    for _ in 0..args.warmup {
        step()?;
    }
    (0..args.iters.max(1))
        .map(|_| {
            let t = Instant::now();
            step()?;
            Ok(t.elapsed().as_secs_f64())
        })
        .collect()
}

/// Runs the PyTorch peer with the case's input channels and returns its case of the same
/// dimension (the script times both dimensions with one channel count).
fn run_peer(python: &Path, case: &Case, args: &Args) -> anyhow::Result<Value> {
    let peer = Peer { python, threads: args.threads };
    let env = [
        ("PEERS_REPEATS", args.iters.max(1).to_string()),
        // The peer waits (bounded) for a quiet machine before timing; a shared machine may never be.
        ("PEERS_MAX_WAIT", "10".to_string()),
    ];
    let dir = PeerDir::new(&format!("unet-{}", case.name))?;
    let channels = case.in_channels.to_string();
    let mut all = peer.run(&args.peer_script, &["--channels", &channels], &env, &dir, "unet.json")?;
    let cases = all["cases"].as_array_mut().context("peer result without cases")?;
    let index = cases
        .iter()
        .position(|c| c["dim"] == case.spatial_axes)
        .with_context(|| format!("the peer has no {}D case", case.spatial_axes))?;
    let mut chosen = cases.swap_remove(index);
    chosen["versions"] = all["versions"].take();
    chosen["torch_num_threads"] = all["torch_num_threads"].take();
    Ok(chosen)
}
