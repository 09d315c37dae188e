//! `cargo xtask reference-distances`: the two anchors of the normalised DCD on a dataset split:
//! d(M⁰, M*) (the initial mesh) and d(M̂, M*) (the generator run with the expert's own sizing
//! field), per problem and summarised. A large deviation from the reference code's values
//! (Poisson: ≈ 0.50 and ≈ 0.22) means the generator or the data differ.

use std::path::PathBuf;

use amber_meshgen::{Mesh2dParams, MeshSizing, PolygonDomain, generate_2d};
use amber_metrics::midpoint_distance;
use amber_tasks::poisson::read_split;
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;

use crate::report::{machine, write_json};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// A split directory of Poisson problem files.
    #[arg(long, default_value = "data/poisson/hard/val")]
    data: PathBuf,
    /// Where to write the per-problem distances.
    #[arg(long, default_value = "results/poisson/reference_distances.json")]
    out: PathBuf,
}

#[derive(Serialize)]
struct Row {
    problem: usize,
    expert_elements: usize,
    reconstruction_elements: usize,
    dcd_initial: f64,
    dcd_reconstruction: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let problems = read_split(&args.data)
        .with_context(|| format!("{}: run `cargo xtask dataset poisson` first", args.data.display()))?;
    let rows = problems
        .par_iter()
        .enumerate()
        .map(|(problem, p)| {
            let domain = PolygonDomain::lshape(p.corner)?;
            let field = MeshSizing::from_element_sizes(&p.expert_mesh);
            let reconstruction = generate_2d(&domain, &field, &Mesh2dParams::default())?;
            Ok(Row {
                problem,
                expert_elements: p.expert_mesh.num_elements(),
                reconstruction_elements: reconstruction.num_elements(),
                dcd_initial: midpoint_distance(&p.initial_mesh, &p.expert_mesh)?.dcd,
                dcd_reconstruction: midpoint_distance(&reconstruction, &p.expert_mesh)?.dcd,
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mean = |f: fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / rows.len().max(1) as f64;
    let summary = serde_json::json!({
        "problems": rows.len(),
        "dcd_initial_mean": mean(|r| r.dcd_initial),
        "dcd_reconstruction_mean": mean(|r| r.dcd_reconstruction),
        "reconstruction_over_expert_elements_mean": mean(|r| r.reconstruction_elements as f64 / r.expert_elements as f64),
    });
    println!("{}", serde_json::to_string_pretty(&summary)?);
    write_json(
        &args.out,
        &serde_json::json!({ "data": args.data, "summary": summary, "machine": machine(), "problems": rows }),
    )
}
