//! `cargo xtask dataset poisson`: generates one split of the Poisson task (spec §1) as
//! `data/poisson/<difficulty>/<split>/NNN.json` (training splits under `train/seed<r>/`, one per
//! training seed), skipping files the cache index already vouches for, prints the expert element
//! counts, and optionally renders a gallery of expert meshes coloured by the solution.

use std::path::{Path, PathBuf};

use amber_fem::{ExpertHeuristic, P1Space, Quadrature, element_stats};
use amber_plot::{RenderOptions, render_png};
use amber_tasks::poisson::{
    DatasetManifest, Difficulty, INITIAL_SIZE, PoissonProblem, Split, SplitRequest, read_split, split_dir, write_split,
};
use anyhow::{Context, bail};
use indicatif::{ProgressBar, ProgressStyle};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    task: Task,
}

#[derive(clap::Subcommand, Debug)]
enum Task {
    /// L-shape, Gaussian-mixture load, initial mesh and expert mesh per problem.
    Poisson(PoissonArgs),
}

#[derive(clap::Args, Debug)]
struct PoissonArgs {
    /// easy (25 expert steps), medium (50) or hard (75).
    #[arg(long)]
    difficulty: Difficulty,
    /// train, val or test.
    #[arg(long)]
    split: Split,
    /// Training seed (train split only): picks the split seed listed in the manifest.
    #[arg(long)]
    seed: Option<usize>,
    /// Number of problems (default: the split size in the manifest).
    #[arg(long)]
    count: Option<usize>,
    /// Root directory of the Poisson data.
    #[arg(long, default_value = "data/poisson")]
    out: PathBuf,
    /// Split seeds and sizes.
    #[arg(long, default_value = "datasets/poisson.json")]
    manifest: PathBuf,
    /// Render the first N expert meshes, coloured by the element mean of the solution, to
    /// `<split dir>/gallery/NNN.png`.
    #[arg(long, default_value_t = 0)]
    gallery: usize,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    match args.task {
        Task::Poisson(args) => poisson(args),
    }
}

fn poisson(args: PoissonArgs) -> anyhow::Result<()> {
    let manifest = DatasetManifest::read(&args.manifest)?;
    if args.split != Split::Train && args.seed.is_some() {
        bail!(
            "--seed selects training problems; the {} split has a fixed seed in {}",
            args.split,
            args.manifest.display()
        );
    }
    let dir = split_dir(&args.out, args.difficulty, args.split, args.seed.unwrap_or(0));
    let (split_seed, size) = manifest.split(args.split, args.seed.unwrap_or(0), &args.manifest)?;
    let request = SplitRequest {
        difficulty: args.difficulty,
        split_seed,
        count: args.count.unwrap_or(size),
        initial_size: INITIAL_SIZE,
        heuristic: ExpertHeuristic::default(),
    };
    let bar = ProgressBar::new(request.count as u64).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} {elapsed_precise} (eta {eta})")?
            .progress_chars("=> "),
    );
    bar.set_message(format!("{} {} (split seed {split_seed})", args.difficulty, args.split));
    let report = write_split(&request, &dir, &|| bar.inc(1))?;
    bar.finish();
    println!("{}: {} written, {} cached", dir.display(), report.written, report.cached);

    let problems = read_split(&dir)?;
    let counts: Vec<usize> = problems.iter().take(request.count).map(|p| p.expert_mesh.num_elements()).collect();
    let initial: Vec<usize> = problems.iter().take(request.count).map(|p| p.initial_mesh.num_elements()).collect();
    if let (Some(min), Some(max), Some(min0), Some(max0)) =
        (counts.iter().min(), counts.iter().max(), initial.iter().min(), initial.iter().max())
    {
        let mean = counts.iter().sum::<usize>() as f64 / counts.len() as f64;
        println!("expert triangles: mean {mean:.0}, min {min}, max {max}; initial triangles {min0}–{max0}");
    }
    for (k, problem) in problems.iter().take(args.gallery).enumerate() {
        let path = dir.join("gallery").join(format!("{k:03}.png"));
        render_solution(problem, &format!("{} {} {k:03}", args.difficulty, args.split), &path)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Solves the problem on its expert mesh and draws the mesh coloured by the element mean of u.
fn render_solution(problem: &PoissonProblem, name: &str, path: &Path) -> anyhow::Result<()> {
    let mesh = &problem.expert_mesh;
    let space = P1Space::new(mesh)?;
    let quadrature = Quadrature::simplex::<2>(2)?;
    let solution = space.solve_poisson(&space.sample_load(&problem.load, &quadrature)?)?;
    let means: Vec<f64> = element_stats(mesh, &solution.u)?.iter().map(|s| s.mean).collect();
    std::fs::create_dir_all(path.parent().unwrap_or(Path::new(".")))
        .with_context(|| format!("{}: cannot create", path.display()))?;
    let title = format!("{name}: {} triangles, element mean of u", mesh.num_elements());
    render_png(
        mesh,
        &means,
        &RenderOptions { title: Some(title), width: 900, height: 800, ..Default::default() },
        path,
    )?;
    Ok(())
}
