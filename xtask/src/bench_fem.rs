//! `cargo xtask bench fem`: the P1 Poisson pipeline at the sizes of issue 3.
//!
//! - one hard (75-step) expert mesh from M⁰ on one thread, everything included (target ≤ 1 s);
//! - assembly (load sampling, load vector, stiffness) and sparse Cholesky solve on ~200k and ~1M
//!   triangles built by uniform red refinement, assembly on `--threads` threads and, as the
//!   in-run reference, on one thread (the ratio is the parallel speed-up).
//!
//! For comparison: `shared/spec/dependencies.md` §2.3 measured the faer solve of a 183k-triangle
//! L-shape at 0.19 s and triplet assembly at 0.17 s on this kind of machine.

use std::path::PathBuf;

use amber_fem::{ExpertHeuristic, P1Space, Quadrature};
use amber_mesh::Mesh2;
use amber_meshgen::rgb::refine_rgb;
use amber_tasks::poisson::{Difficulty, INITIAL_SIZE, ProblemSample, initial_mesh, problem_seeds};
use serde::Serialize;

use crate::report::write_json;
use crate::timing::{CpuClock, median_time};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/fem.json")]
    out: PathBuf,
    /// Rayon threads for the parallel assembly.
    #[arg(long, default_value_t = 2)]
    threads: usize,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// The problem: this many-th problem of the validation split (split seed 0).
    #[arg(long, default_value_t = 0)]
    problem: usize,
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
}

#[derive(Serialize)]
struct SolveCase {
    triangles: usize,
    dofs: usize,
    nnz_lower: usize,
    /// Median wall times on `threads` threads.
    assemble_seconds: f64,
    solve_seconds: f64,
    /// Median assembly wall time on one thread.
    single_thread_assemble_seconds: f64,
    assembly_speedup: f64,
    relative_residual: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let seed = *problem_seeds(0, args.problem + 1).last().expect("at least one seed");
    let sample = ProblemSample::draw(seed)?;
    let m0 = initial_mesh(sample.corner, INITIAL_SIZE)?;
    let steps = Difficulty::Hard.steps();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let parallel = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build()?;

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
        let case = SolveCase {
            triangles: mesh.num_elements(),
            dofs: stiffness.dofs(),
            nnz_lower: stiffness.nnz_lower(),
            assemble_seconds,
            solve_seconds,
            single_thread_assemble_seconds,
            assembly_speedup: single_thread_assemble_seconds / assemble_seconds,
            relative_residual: stiffness.relative_residual(&x, &rhs),
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
        solve_cases.push(case);
    }
    write_json(
        &args.out,
        &serde_json::json!({
            "benchmark": "fem",
            "settings": args,
            "machine": crate::report::machine(),
            "expert": expert_case,
            "assemble_and_solve": solve_cases,
        }),
    )
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
