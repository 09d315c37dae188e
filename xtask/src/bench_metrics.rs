//! `cargo xtask bench-metrics`: times the evaluation metric and the label projection at the
//! sizes of issue 4 and writes the numbers, the settings and the targets to one JSON file.
//!
//! - DCD of `--points` vs `--points` uniform random 2D points (target ≤ 1 s on 2 threads);
//! - projection of a structured 42k-triangle expert of the unit square onto a 5k-triangle one
//!   (target ≤ 50 ms), and, for information, the reverse direction, where every element of the
//!   finer current mesh falls back to point location in the expert.
//!
//! Reference in the same run: each case again on one thread (the ratio is the parallel speed-up),
//! and with `--peer-python`, the DCD case computed with pykdtree on the same points
//! (`xtask/peers/bench_metrics.py`, the reference code's way, on `--threads` threads).

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_graph::{Aggregation, project_expert_sizing};
use amber_mesh::Mesh2;
use amber_metrics::point_set_distance;
use amber_stdx::median;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use serde_json::{Value, json};

use crate::peer::{Peer, PeerDir};
use crate::timing::{CpuClock, Load, LoadMeter, cpu_seconds};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/metrics.json")]
    pub out: PathBuf,
    /// Rayon threads for the timed runs.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
    /// Points per set for the DCD case.
    #[arg(long, default_value_t = 1_000_000)]
    points: usize,
    /// Squares per side of the structured expert mesh (2 triangles each; 145 → 42,050).
    #[arg(long, default_value_t = 145)]
    expert_squares: usize,
    /// Squares per side of the structured current mesh (50 → 5,000 triangles).
    #[arg(long, default_value_t = 50)]
    current_squares: usize,
    /// Seed of the random point sets.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Python with pykdtree and numpy: also time the peer on the DCD case.
    #[arg(long)]
    peer_python: Option<PathBuf>,
}

#[derive(Serialize)]
struct Case {
    name: String,
    /// Median wall time on `threads` threads, seconds.
    median_s: f64,
    min_s: f64,
    target_s: Option<f64>,
    within_target: Option<bool>,
    /// Median wall time of the same case on one thread, seconds.
    single_thread_median_s: f64,
    speedup: f64,
    /// Mean CPU seconds per run summed over all threads (Linux), which a busy machine does not
    /// inflate: on an idle machine the wall time approaches `cpu_s / threads`.
    cpu_s: Option<f64>,
    /// The computed value, to catch a benchmark that measures nothing.
    checksum: f64,
    /// The same work in the peer library, in the same run (with `--peer-python`).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer: Option<Value>,
    /// The peer's median wall time over ours on `threads` threads (above 1: ours is faster).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer_time_over_ours: Option<f64>,
    /// The machine around ours and the peer.
    load: Load,
}

#[derive(Serialize)]
struct Report<'a> {
    benchmark: &'static str,
    settings: &'a Args,
    /// CPU, cores and load average: timings on a busy machine are inflated.
    machine: serde_json::Value,
    cases: Vec<Case>,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    anyhow::ensure!(args.repeats > 0 && args.threads > 0, "--repeats and --threads must be positive");
    let mut rng = StdRng::seed_from_u64(args.seed);
    let mut random_points = |n: usize| -> Vec<[f64; 2]> { (0..n).map(|_| [rng.random(), rng.random()]).collect() };
    let (a, b) = (random_points(args.points), random_points(args.points));
    let expert = unit_square(args.expert_squares)?;
    let current = unit_square(args.current_squares)?;

    let mut cases = Vec::new();
    let meter = LoadMeter::start();
    let mut dcd = time_case(&args, format!("dcd_2d_{}_vs_{}", args.points, args.points), Some(1.0), || {
        Ok(point_set_distance(&a, &b)?.dcd)
    })?;
    if let Some(python) = &args.peer_python {
        let peer = run_dcd_peer(python, &a, &b, &args)?;
        dcd.peer_time_over_ours = peer["seconds"].as_f64().map(|p| p / dcd.median_s);
        dcd.peer = Some(peer);
        // The load around ours and the peer.
        dcd.load = meter.finish();
    }
    cases.push(dcd);
    cases.push(time_case(
        &args,
        format!("projection_mean_{}_onto_{}", expert.num_elements(), current.num_elements()),
        Some(0.05),
        || Ok(project_expert_sizing(&current, &expert, Aggregation::Mean)?.iter().sum()),
    )?);
    cases.push(time_case(
        &args,
        format!("projection_mean_{}_onto_{}_mostly_fallback", current.num_elements(), expert.num_elements()),
        None,
        || Ok(project_expert_sizing(&expert, &current, Aggregation::Mean)?.iter().sum()),
    )?);

    for c in &cases {
        let verdict = match c.within_target {
            Some(true) => "within target",
            Some(false) => "OVER TARGET",
            None => "no target",
        };
        let cpu = c.cpu_s.map(|t| format!(", cpu {t:.4} s")).unwrap_or_default();
        println!(
            "{:<48} {:>9.4} s  (1 thread {:>8.4} s, speed-up {:.2}×{cpu})  {verdict}",
            c.name, c.median_s, c.single_thread_median_s, c.speedup
        );
        if let (Some(p), Some(ratio)) = (&c.peer, c.peer_time_over_ours) {
            println!(
                "{:<48} {:>9.4} s  (value {:.12}, ours {:.12}) → peer/ours {ratio:.2}× [other CPUs {:.2}]",
                format!("  {}", p["library"].as_str().unwrap_or("peer")),
                p["seconds"].as_f64().unwrap_or(f64::NAN),
                p["dcd"].as_f64().unwrap_or(f64::NAN),
                c.checksum,
                c.load.other_cpus
            );
        }
    }
    let report = Report { benchmark: "metrics", settings: &args, machine: crate::report::machine(), cases };
    crate::report::write_json(&args.out, &report)
}

/// Times `work` `repeats` times on `threads` threads and on one thread (after one warm-up run).
fn time_case(
    args: &Args,
    name: String,
    target_s: Option<f64>,
    work: impl Fn() -> anyhow::Result<f64> + Sync,
) -> anyhow::Result<Case> {
    let meter = LoadMeter::start();
    let median_on = |threads: usize| -> anyhow::Result<Timing> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
        let checksum = pool.install(&work)?;
        let cpu_start = pool_cpu_seconds(&pool);
        let mut times = Vec::with_capacity(args.repeats);
        for _ in 0..args.repeats {
            let start = Instant::now();
            std::hint::black_box(pool.install(&work)?);
            times.push(start.elapsed().as_secs_f64());
        }
        let cpu_s = cpu_start.zip(pool_cpu_seconds(&pool)).map(|(a, b)| (b - a) / args.repeats as f64);
        let min_s = times.iter().copied().fold(f64::INFINITY, f64::min);
        Ok(Timing { median_s: median(&times), min_s, cpu_s, checksum })
    };
    let Timing { median_s, min_s, cpu_s, checksum } = median_on(args.threads)?;
    let single_thread_median_s = median_on(1)?.median_s;
    Ok(Case {
        name,
        median_s,
        min_s,
        target_s,
        within_target: target_s.map(|t| median_s <= t),
        single_thread_median_s,
        speedup: single_thread_median_s / median_s,
        cpu_s,
        checksum,
        peer: None,
        peer_time_over_ours: None,
        load: meter.finish(),
    })
}

/// Runs pykdtree's DCD on the same point sets (`xtask/peers/bench_metrics.py`).
fn run_dcd_peer(python: &Path, first: &[[f64; 2]], second: &[[f64; 2]], args: &Args) -> anyhow::Result<Value> {
    let dir = PeerDir::new("metrics")?;
    dir.write_npy("first", &[first.len(), 2], first.as_flattened())?;
    dir.write_npy("second", &[second.len(), 2], second.as_flattened())?;
    dir.write_input(&json!({ "repeats": args.repeats }))?;
    Peer { python, threads: args.threads }.run_script("bench_metrics.py", &dir)
}

struct Timing {
    median_s: f64,
    min_s: f64,
    cpu_s: Option<f64>,
    checksum: f64,
}

/// CPU time consumed so far by the threads of `pool`, from Linux's per-thread `schedstat` (ns).
fn pool_cpu_seconds(pool: &rayon::ThreadPool) -> Option<f64> {
    pool.broadcast(|_| cpu_seconds(CpuClock::Thread)).into_iter().sum()
}

/// The unit square as `n × n` squares, each split into two triangles along its rising diagonal.
fn unit_square(n: usize) -> anyhow::Result<Mesh2> {
    anyhow::ensure!(n > 0, "a structured mesh needs at least one square per side");
    let h = 1.0 / n as f64;
    let vertices = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64 * h, j as f64 * h])).collect();
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let cells = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .flat_map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)])
        .collect();
    Ok(Mesh2::new(vertices, cells)?)
}
