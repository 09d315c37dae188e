//! `cargo xtask bench mesher3d`: the 3D generator on every Console train/val part with the
//! expert's own sizing field (the oracle re-mesh): tets against the expert's count, size ratio
//! against the expert field, worst dihedral angle, enclosed volume against the reference
//! surface, and the time of each stage on one thread.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mesh::{Mesh3, read_mesh};
use amber_meshgen::mesh3d::{Mesh3dParams, StlFaceIds, Surface, adapt_surface, fill_surface};
use amber_meshgen::{MeshSizing, SizingField};
use amber_stdx::{median, quantile};
use anyhow::Context;
use serde::Serialize;

use crate::report::write_json;
use crate::timing::{CpuClock, CpuTimer};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// The Console data directory (`train/`, `val/`, `reference_surface/`).
    #[arg(long, default_value = "../shared/data/console")]
    data: PathBuf,
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/mesher3d.json")]
    out: PathBuf,
    /// Threads (the acceptance times are single-threaded).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Only parts whose name (`train/001`) contains this.
    #[arg(long)]
    only: Option<String>,
}

#[derive(Serialize)]
struct Part {
    name: String,
    expert_tets: usize,
    tets: usize,
    tets_over_expert: f64,
    surface_triangles: usize,
    /// h(K) / expert field at the midpoint of K, over our tets.
    size_ratio_p10: f64,
    size_ratio_median: f64,
    size_ratio_p90: f64,
    min_dihedral_deg: f64,
    tets_below_5_deg: usize,
    /// Enclosed volume of our mesh / the reference surface's − 1.
    volume_error: f64,
    seconds_surface: f64,
    seconds_volume: f64,
    seconds_total: f64,
    /// CPU time of the meshing thread (both stages): the total without the share lost to
    /// other processes on a busy machine.
    cpu_seconds_total: f64,
}

#[derive(Serialize)]
struct Medians {
    tets_over_expert: f64,
    size_ratio_median: f64,
    min_dihedral_deg: f64,
    abs_volume_error: f64,
    seconds_surface: f64,
    seconds_volume: f64,
    seconds_total: f64,
    seconds_total_max: f64,
    cpu_seconds_total: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build()?;
    let params = Mesh3dParams::default();
    let mut parts = Vec::new();
    for name in part_names(&args.data)? {
        if args.only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let part = pool.install(|| bench_part(&args.data, &name, &params))?;
        println!(
            "{:<10} expert {:>6} tets, ours {:>6} ({:.2}x), {:>6} surface tris, size ratio {:.2} [{:.2}, {:.2}], \
             min dihedral {:>5.1}° ({} < 5°), volume {:+.2e}, {:.2} s + {:.2} s = {:.2} s (CPU {:.2} s)",
            part.name,
            part.expert_tets,
            part.tets,
            part.tets_over_expert,
            part.surface_triangles,
            part.size_ratio_median,
            part.size_ratio_p10,
            part.size_ratio_p90,
            part.min_dihedral_deg,
            part.tets_below_5_deg,
            part.volume_error,
            part.seconds_surface,
            part.seconds_volume,
            part.seconds_total,
            part.cpu_seconds_total
        );
        parts.push(part);
    }
    anyhow::ensure!(!parts.is_empty(), "{}: no parts matched", args.data.display());
    let median_of = |f: &dyn Fn(&Part) -> f64| median(&parts.iter().map(f).collect::<Vec<_>>());
    let medians = Medians {
        tets_over_expert: median_of(&|p| p.tets_over_expert),
        size_ratio_median: median_of(&|p| p.size_ratio_median),
        min_dihedral_deg: median_of(&|p| p.min_dihedral_deg),
        abs_volume_error: median_of(&|p| p.volume_error.abs()),
        seconds_surface: median_of(&|p| p.seconds_surface),
        seconds_volume: median_of(&|p| p.seconds_volume),
        seconds_total: median_of(&|p| p.seconds_total),
        seconds_total_max: parts.iter().map(|p| p.seconds_total).fold(0.0, f64::max),
        cpu_seconds_total: median_of(&|p| p.cpu_seconds_total),
    };
    let acceptance = serde_json::json!({
        "tets_within_0.8_1.3": parts.iter().filter(|p| (0.8..=1.3).contains(&p.tets_over_expert)).count(),
        "size_ratio_median_within_0.85_1.15":
            parts.iter().filter(|p| (0.85..=1.15).contains(&p.size_ratio_median)).count(),
        "no_tet_below_5_deg": parts.iter().filter(|p| p.tets_below_5_deg == 0).count(),
        "volume_within_0.5_percent": parts.iter().filter(|p| p.volume_error.abs() <= 5e-3).count(),
        "parts": parts.len(),
    });
    println!(
        "medians: {:.2}x expert tets, size ratio {:.3}, min dihedral {:.1}°, |volume error| {:.1e}, \
         {:.3} s surface + {:.3} s volume, total {:.3} s (max {:.3} s), CPU {:.3} s",
        medians.tets_over_expert,
        medians.size_ratio_median,
        medians.min_dihedral_deg,
        medians.abs_volume_error,
        medians.seconds_surface,
        medians.seconds_volume,
        medians.seconds_total,
        medians.seconds_total_max,
        medians.cpu_seconds_total
    );
    println!("acceptance counts: {acceptance}");
    write_json(
        &args.out,
        &serde_json::json!({
            "benchmark": "mesher3d",
            "settings": args,
            "params": format!("{params:?}"),
            "machine": crate::report::machine(),
            "parts": parts,
            "medians": medians,
            "acceptance": acceptance,
        }),
    )
}

/// `train/001`, …, `val/002`: every `.nas` under `train/` and `val/`, sorted.
fn part_names(data: &Path) -> anyhow::Result<Vec<String>> {
    let mut names = Vec::new();
    for split in ["train", "val"] {
        let dir = data.join(split);
        let entries = std::fs::read_dir(&dir).with_context(|| {
            format!("{}: not found (the Console data bundle, see datasets/console/README.md)", dir.display())
        })?;
        for entry in entries {
            let path = entry?.path();
            if path.extension().is_some_and(|e| e == "nas")
                && let Some(stem) = path.file_stem().and_then(|s| s.to_str())
            {
                names.push(format!("{split}/{stem}"));
            }
        }
    }
    names.sort();
    Ok(names)
}

fn bench_part(data: &Path, name: &str, params: &Mesh3dParams) -> anyhow::Result<Part> {
    let expert: Mesh3 = read_mesh(data.join(format!("{name}.nas")))?;
    let surface_path = data.join("reference_surface").join(format!("{name}.stl"));
    let (reference, report) = Surface::load(&surface_path, StlFaceIds::FromFile)?;
    let field = MeshSizing::from_element_sizes(&expert);
    let (start, cpu) = (Instant::now(), CpuTimer::start(CpuClock::Thread));
    let surface = adapt_surface(&reference, &field, params).with_context(|| format!("{name}: surface"))?;
    let seconds_surface = start.elapsed().as_secs_f64();
    let mesh = fill_surface(&surface, &field, params).with_context(|| format!("{name}: volume"))?;
    let seconds_total = start.elapsed().as_secs_f64();
    let cpu_seconds_total = cpu.seconds();
    let mut ratios: Vec<f64> =
        (0..mesh.num_elements()).map(|e| mesh.size(e) / field.size_at(mesh.midpoint(e))).collect();
    ratios.sort_by(f64::total_cmp);
    let angles = mesh.min_angles();
    Ok(Part {
        name: name.into(),
        expert_tets: expert.num_elements(),
        tets: mesh.num_elements(),
        tets_over_expert: mesh.num_elements() as f64 / expert.num_elements() as f64,
        surface_triangles: surface.triangles().len(),
        size_ratio_p10: quantile(&ratios, 0.1),
        size_ratio_median: quantile(&ratios, 0.5),
        size_ratio_p90: quantile(&ratios, 0.9),
        min_dihedral_deg: angles.iter().copied().fold(f64::INFINITY, f64::min),
        tets_below_5_deg: angles.iter().filter(|&&a| a < 5.0).count(),
        volume_error: mesh.total_volume() / report.enclosed_volume - 1.0,
        seconds_surface,
        seconds_volume: seconds_total - seconds_surface,
        seconds_total,
        cpu_seconds_total,
    })
}
