//! `bench-mpn`: training-step and inference throughput of the message passing network on one
//! large random mesh-like graph, for the stock-candle composition and the fused ops, optionally
//! next to the PyTorch peer (`shared/peers/bench_mpn.py`) run on a graph of the same size.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mpn::MpnConfig;
use amber_mpn::bench::{BenchCase, BenchStep, candle_threads};
use amber_stdx::median;
use amber_train::TrainingConfig;
use anyhow::bail;
use serde_json::{Value, json};

use crate::peer::{self, Peer, PeerDir};
use crate::timing::{CpuClock, CpuTimer, LoadMeter};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Where to write the results (JSON).
    #[arg(long, default_value = "results/bench/mpn.json")]
    pub out: PathBuf,
    /// Latent width D of the network (64: Poisson's; 128: Console's). The peer runs at the same
    /// width (other than 64 through `xtask/peers/mpn_latent.py`).
    #[arg(long, default_value_t = 64)]
    pub latent: usize,
    /// Nodes of the benchmark graph.
    #[arg(long, default_value_t = 50_000)]
    pub nodes: usize,
    /// Directed edges besides the self-loops (about 3 neighbours per node by default).
    #[arg(long, default_value_t = 150_000)]
    pub edges: usize,
    /// Nodes for the naive training step, which keeps about 12 kB per node and unit of D (at
    /// D = 64: 10,000 nodes need 7.6 GB, the 50,000 of the other cases were killed for memory on
    /// a 24 GB machine). Default: 640,000 / D.
    #[arg(long)]
    pub naive_nodes: Option<usize>,
    /// Variants to time: naive (stock candle ops), fast (fused ops), fast-dropout (training step of
    /// the fused ops with the training-mode edge dropout of 0.1).
    #[arg(long, value_delimiter = ',', default_value = "fast,fast-dropout,naive")]
    pub variants: Vec<String>,
    /// Modes to time: infer (forward of a plain-tensor model), train (forward, backward, clip, Adam).
    #[arg(long, value_delimiter = ',', default_value = "infer,train")]
    pub modes: Vec<String>,
    /// Timed iterations per case (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub iters: usize,
    /// Untimed iterations before timing (first touches of memory are slow).
    #[arg(long, default_value_t = 2)]
    pub warmup: usize,
    /// Python interpreter with torch and torch_geometric, to also run the PyTorch peer.
    #[arg(long)]
    pub peer_python: Option<PathBuf>,
    /// The peer script.
    #[arg(long, default_value = "../shared/peers/bench_mpn.py")]
    pub peer_script: PathBuf,
    /// Threads for the peer (PEERS_THREADS); ours follow RAYON_NUM_THREADS (default: all cores).
    #[arg(long, default_value_t = 2)]
    pub peer_threads: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let config = MpnConfig::small(args.latent, MpnConfig::poisson().network.message_passing_steps);
    let paper = TrainingConfig::paper();
    let naive_nodes = args.naive_nodes.unwrap_or(640_000 / args.latent.max(1));
    // The peer first: after the naive training step this process keeps its peak memory, and at
    // D = 128 the two together were killed for memory on a 24 GB machine.
    let peer = match &args.peer_python {
        Some(python) => Some(run_peer(python, &args)?),
        None => None,
    };
    let mut cases = Vec::new();
    for variant in &args.variants {
        // Dropout only exists in training.
        for mode in args.modes.iter().filter(|m| !(variant == "fast-dropout" && *m == "infer")) {
            let nodes = if variant == "naive" && mode == "train" { naive_nodes.min(args.nodes) } else { args.nodes };
            let edges = args.edges * nodes / args.nodes;
            let case = bench_case(&config, &paper, variant, mode, nodes, edges, &args)?;
            println!(
                "{variant:>13} {mode:5} N={nodes:>7} E={:>7}: median {:8.1} ms  {:>8.0} nodes/s  (CPU {:6.1} s)  peak RSS {:.2} GiB  [other processes {:.2} CPUs]",
                case["n_edges"],
                case["s_median"].as_f64().unwrap_or(0.0) * 1e3,
                case["nodes_per_s"].as_f64().unwrap_or(0.0),
                case["cpu_s_median"].as_f64().unwrap_or(0.0),
                case["peak_rss_gib"].as_f64().unwrap_or(f64::NAN),
                case["other_cpus_median"].as_f64().unwrap_or(0.0)
            );
            cases.push(case);
        }
    }
    let result = json!({
        "benchmark": "mpn",
        "config": config,
        "train": { "learning_rate": paper.learning_rate, "max_grad_norm": paper.max_grad_norm },
        "graph": { "nodes": args.nodes, "directed_edges": args.edges, "self_loops": args.nodes, "generator": "amber_mpn::synthetic::random_graph (uniform random pairs, both directions, dst-sorted)" },
        "rayon_threads": rayon::current_num_threads(),
        "candle_threads": candle_threads(),
        "iters": args.iters,
        "warmup": args.warmup,
        "machine": crate::report::machine(),
        "cases": cases,
        "ratios": ratios(&cases, peer.as_ref()),
        "peer": peer,
    });
    crate::report::write_json(&args.out, &result)?;
    Ok(())
}

/// Times one (variant, mode): `infer` is a forward of a plain-tensor model, `train` is forward,
/// MSE, backward, global-norm clipping and a step of the Adam that trains, with the paper's
/// objective and settings (softplus, 0.5, 3e-4).
fn bench_case(
    config: &MpnConfig,
    paper: &TrainingConfig,
    variant: &str,
    mode: &str,
    nodes: usize,
    edges: usize,
    args: &Args,
) -> anyhow::Result<Value> {
    let kind = match (variant, mode) {
        ("naive", "infer") => BenchStep::NaiveInfer,
        ("fast", "infer") => BenchStep::FastInfer,
        ("naive", "train") => BenchStep::NaiveTrain,
        ("fast", "train") => BenchStep::FastTrain,
        ("fast-dropout", "train") => BenchStep::FastDropoutTrain,
        _ => bail!("unknown variant/mode {variant}/{mode}"),
    };
    let mut bench =
        BenchCase::new(config, paper.objective, nodes, edges / 2, paper.learning_rate, paper.max_grad_norm)?;
    let mut step = || bench.run(kind);
    let peak_reset = reset_peak_rss();
    for _ in 0..args.warmup {
        step()?;
    }
    let (mut times, mut cpu, mut others) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..args.iters.max(1) {
        let (load, own) = (LoadMeter::start(), CpuTimer::start(CpuClock::Process));
        let t = Instant::now();
        step()?;
        times.push(t.elapsed().as_secs_f64());
        cpu.push(own.seconds());
        others.push(load.other_cpus());
    }
    let s_median = median(&times);
    Ok(json!({
        "variant": variant,
        "mode": mode,
        "n_nodes": nodes,
        "n_edges": bench.num_edges(),
        "s_median": s_median,
        "s_min": times.iter().copied().fold(f64::INFINITY, f64::min),
        "s_all": times,
        "cpu_s_median": median(&cpu),
        "nodes_per_s": nodes as f64 / s_median,
        "peak_rss_gib": peak_rss_gib(),
        "peak_rss_is_process_wide": !peak_reset,
        "other_cpus_median": median(&others),
    }))
}

/// Resets the kernel's peak-RSS counter of this process (Linux `clear_refs` 5).
fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn peak_rss_gib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let kib: f64 = status.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / (1024.0 * 1024.0))
}

/// Runs the PyTorch peer (plain and PyG aggregation) on a graph of the same size, with self-loops,
/// at the same latent width, and returns its JSON.
fn run_peer(python: &Path, args: &Args) -> anyhow::Result<Value> {
    let sizes = args.nodes.to_string();
    let steps = args.iters.to_string();
    let mut peer_args: Vec<&OsStr> = Vec::new();
    let (script, latent) = (args.peer_script.as_os_str(), args.latent.to_string());
    // The peer's width is a module constant (64); `mpn_latent.py` runs it at another.
    let wrapper = Path::new(peer::SCRIPTS).join("mpn_latent.py");
    let entry = if args.latent == MpnConfig::poisson().network.latent_dim {
        script
    } else {
        peer_args.extend([script, OsStr::new(&latent)]);
        wrapper.as_os_str()
    };
    let rest = ["--sizes", &sizes, "--variants", "plain,pyg", "--ckpt-sizes", "", "--self-loops", "--steps", &steps];
    peer_args.extend(rest.iter().map(OsStr::new));
    let peer = Peer { python, threads: args.peer_threads };
    peer.run(Path::new(entry), &peer_args, &[], &PeerDir::new("mpn")?, "mpn.json")
}

/// Speed-ups of the fused variant over the naive one and over each peer case.
fn ratios(cases: &[Value], peer: Option<&Value>) -> Value {
    let rate = |cs: &[Value], variant: &str, mode: &str| {
        cs.iter()
            .find(|c| c["variant"] == variant && c["mode"] == mode && c["status"] != "skipped")
            .and_then(|c| c["nodes_per_s"].as_f64())
    };
    let mut out = serde_json::Map::new();
    for mode in ["train", "infer"] {
        let Some(fast) = rate(cases, "fast", mode) else {
            continue;
        };
        if let Some(naive) = rate(cases, "naive", mode) {
            out.insert(format!("fast_over_naive_{mode}"), json!(fast / naive));
        }
        if let Some(peer_cases) = peer.and_then(|p| p["cases"].as_array()) {
            for v in ["plain", "pyg"] {
                if let Some(p) = rate(peer_cases, v, mode) {
                    out.insert(format!("fast_over_torch_{v}_{mode}"), json!(fast / p));
                }
            }
        }
    }
    Value::Object(out)
}
