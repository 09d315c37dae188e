//! `cargo xtask bench fem`: the P1 Poisson pipeline at the sizes of issue 3.
//!
//! - one hard (75-step) expert mesh from M⁰ on one thread, everything included (target ≤ 1 s);
//! - assembly (load sampling, load vector, stiffness) and sparse Cholesky solve on ~200k and ~1M
//!   triangles built by uniform red refinement, assembly on `--threads` threads and, as the
//!   in-run reference, on one thread (the ratio is the parallel speed-up).
//!
//! With `--peer-python`, scikit-fem assembles and solves each assemble + solve case's mesh and
//! load in the same run (`xtask/peers/bench_fem.py`: spsolve and pyamg's AMG-CG), and the case
//! records both times and their ratios.
//!
//! For comparison: `shared/spec/dependencies.md` §2.3 measured the faer solve of a 183k-triangle
//! L-shape at 0.19 s and triplet assembly at 0.17 s on this kind of machine.

use std::path::{Path, PathBuf};

use amber_fem::{ExpertHeuristic, GaussianMixture, P1Space, Quadrature};
use amber_mesh::Mesh2;
use amber_meshgen::rgb::refine_rgb;
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE, ProblemSample, initial_mesh, problem_seeds};
use anyhow::Context;
use serde::Serialize;
use serde_json::{Value, json};

use crate::peer::{Peer, PeerDir};
use crate::report::write_json;
use crate::timing::{CpuClock, Load, LoadMeter, median_time};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/fem.json")]
    pub out: PathBuf,
    /// Rayon threads for the parallel assembly.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// The problem: this many-th problem of the validation split (split seed 0).
    #[arg(long, default_value_t = 0)]
    problem: usize,
    /// Python with scikit-fem, scipy and pyamg: also time the peer on each assemble + solve case.
    #[arg(long)]
    peer_python: Option<PathBuf>,
}

#[derive(Serialize)]
struct ExpertCase {
    seed: u64,
    steps: usize,
    initial_triangles: usize,
    expert_triangles: usize,
    /// Median wall time on one thread.
    seconds: f64,
    /// Median process CPU time (the wall time without the share lost to other processes).
    cpu_seconds: f64,
    target_seconds: f64,
    load: Load,
}

#[derive(Serialize)]
struct SolveCase {
    triangles: usize,
    dofs: usize,
    nnz_upper: usize,
    /// Median wall times on `threads` threads.
    assemble_seconds: f64,
    solve_seconds: f64,
    /// Median assembly wall time on one thread.
    single_thread_assemble_seconds: f64,
    assembly_speedup: f64,
    relative_residual: f64,
    /// scikit-fem on the same mesh and load, in the same run (with `--peer-python`).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer: Option<Value>,
    /// The peer's wall time over ours (above 1: ours is faster).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer_time_over_ours: Option<Ratios>,
    /// The machine around ours and the peer.
    load: Load,
}

/// Peer time / our time, per path; the solves are against our sparse Cholesky solve.
#[derive(Serialize)]
struct Ratios {
    assemble: f64,
    solve_spsolve: f64,
    solve_amg_cg: f64,
    assemble_and_solve_spsolve: f64,
    assemble_and_solve_amg_cg: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let seed = *problem_seeds(0, args.problem + 1).last().expect("at least one seed");
    let sample = ProblemSample::draw(seed)?;
    let m0 = initial_mesh(sample.corner, INITIAL_SIZE)?;
    let steps = Difficulty::Hard.steps();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let parallel = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build()?;

    let meter = LoadMeter::start();
    let (expert, seconds, cpu_seconds) = median_time(args.repeats, CpuClock::Process, || {
        one.install(|| ExpertHeuristic::default().run(&m0, &sample.load, steps))
    })?;
    let expert_case = ExpertCase {
        seed,
        steps,
        initial_triangles: m0.num_elements(),
        expert_triangles: expert.num_elements(),
        seconds,
        cpu_seconds,
        target_seconds: 1.0,
        load: meter.finish(),
    };
    println!(
        "expert {steps} steps: {} → {} triangles in {seconds:.3} s ({cpu_seconds:.3} CPU s, target 1 s)",
        m0.num_elements(),
        expert.num_elements()
    );

    let mut solve_cases = Vec::new();
    // 5² and 11² squares, two triangles each, six red refinements: 204,800 and 991,232 triangles.
    for squares in [5, 11] {
        let mut mesh = grid(squares)?;
        for _ in 0..6 {
            let all: Vec<usize> = (0..mesh.num_elements()).collect();
            mesh = refine_rgb(&mesh, &all)?;
        }
        let meter = LoadMeter::start();
        let quadrature = Quadrature::simplex::<2>(2)?;
        let assemble = |mesh: &Mesh2| -> anyhow::Result<_> {
            let space = P1Space::new(mesh)?;
            let rhs = space.load_vector(&space.sample_load(&sample.load, &quadrature)?);
            Ok((space.stiffness(), rhs))
        };
        let ((stiffness, rhs), assemble_seconds, _) =
            median_time(args.repeats, CpuClock::Process, || parallel.install(|| assemble(&mesh)))?;
        let (_, single_thread_assemble_seconds, _) =
            median_time(args.repeats, CpuClock::Process, || one.install(|| assemble(&mesh)))?;
        let (x, solve_seconds, _) = median_time(args.repeats, CpuClock::Process, || stiffness.solve(&rhs))?;
        let peer = match &args.peer_python {
            Some(python) => Some(run_peer(python, &mesh, &sample.load, &args)?),
            None => None,
        };
        let peer_time_over_ours = match &peer {
            Some(p) => Some(ratios(p, assemble_seconds, solve_seconds)?),
            None => None,
        };
        let case = SolveCase {
            triangles: mesh.num_elements(),
            dofs: stiffness.dofs(),
            nnz_upper: stiffness.nnz_upper(),
            assemble_seconds,
            solve_seconds,
            single_thread_assemble_seconds,
            assembly_speedup: single_thread_assemble_seconds / assemble_seconds,
            relative_residual: stiffness.relative_residual(&x, &rhs),
            peer,
            peer_time_over_ours,
            load: meter.finish(),
        };
        println!(
            "{:>9} triangles, {:>7} dofs: assemble {:.3} s ({} threads; 1 thread {:.3} s), solve {:.3} s, residual {:.1e}",
            case.triangles,
            case.dofs,
            assemble_seconds,
            args.threads,
            single_thread_assemble_seconds,
            solve_seconds,
            case.relative_residual
        );
        if let (Some(p), Some(r)) = (&case.peer, &case.peer_time_over_ours) {
            let time = |key: &str| p[key].as_f64().unwrap_or(f64::NAN);
            println!(
                "{:>9} scikit-fem: assemble {:.3} s, spsolve {:.3} s, AMG setup {:.3} s + CG {:.3} s ({} iterations) \
                 → peer/ours: assemble {:.2}×, + spsolve {:.2}×, + AMG-CG {:.2}× [other CPUs {:.2}]",
                "",
                time("assemble_seconds"),
                time("spsolve_seconds"),
                time("amg_setup_seconds"),
                time("amg_cg_seconds"),
                p["amg_cg_iterations"],
                r.assemble,
                r.assemble_and_solve_spsolve,
                r.assemble_and_solve_amg_cg,
                case.load.other_cpus
            );
        }
        solve_cases.push(case);
    }
    write_json(
        &args.out,
        &json!({
            "benchmark": "fem",
            "settings": args,
            "machine": crate::report::machine(),
            "expert": expert_case,
            "assemble_and_solve": solve_cases,
        }),
    )
}

/// Runs scikit-fem on `mesh` and `load` (`xtask/peers/bench_fem.py`).
fn run_peer(python: &Path, mesh: &Mesh2, load: &GaussianMixture, args: &Args) -> anyhow::Result<Value> {
    let dir = PeerDir::new("fem")?;
    dir.write_npy("vertices", &[mesh.num_vertices(), 2], mesh.vertices().as_flattened())?;
    dir.write_npy("triangles", &[mesh.num_elements(), 3], mesh.cells())?;
    dir.write_input(&json!({ "load": load.params(), "repeats": args.repeats }))?;
    Peer { python, threads: args.threads }.run_script("bench_fem.py", &dir)
}

fn ratios(peer: &Value, assemble: f64, solve: f64) -> anyhow::Result<Ratios> {
    let time = |key: &str| peer[key].as_f64().with_context(|| format!("the peer result has no {key}"));
    let (peer_assemble, spsolve) = (time("assemble_seconds")?, time("spsolve_seconds")?);
    let amg = time("amg_setup_seconds")? + time("amg_cg_seconds")?;
    Ok(Ratios {
        assemble: peer_assemble / assemble,
        solve_spsolve: spsolve / solve,
        solve_amg_cg: amg / solve,
        assemble_and_solve_spsolve: (peer_assemble + spsolve) / (assemble + solve),
        assemble_and_solve_amg_cg: (peer_assemble + amg) / (assemble + solve),
    })
}

/// The unit square as `n × n` squares, each cut along its diagonal.
fn grid(n: usize) -> anyhow::Result<Mesh2> {
    let vertices = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64 / n as f64, j as f64 / n as f64])).collect();
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let cells = (0..n)
        .flat_map(|j| (0..n).map(move |i| (i, j)))
        .flat_map(|(i, j)| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)])
        .collect();
    Ok(Mesh2::new(vertices, cells)?)
}
