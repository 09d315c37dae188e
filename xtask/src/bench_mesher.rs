//! `cargo xtask bench mesher`: the 2D generator on a graded L-shape field at ~10k, ~100k and
//! ~1M triangles (single thread, everything included), with spade's own uniform `refine()` at
//! the same element counts as an in-run reference.

use std::path::PathBuf;

use amber_mesh::Mesh2;
use amber_meshgen::{ConstantSize, FnSize, Mesh2dParams, PolygonDomain, QualityReport, generate_2d};
use serde::Serialize;
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};

use crate::report::write_json;
use crate::timing::{CpuClock, median_time};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/mesher.json")]
    out: PathBuf,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
}

/// Field graded towards the re-entrant corner (0.5, 0.5); `scale` sets the element count
/// (≈ 440 / scale² triangles).
fn graded_field(scale: f64) -> impl Fn([f64; 2]) -> f64 + Sync {
    move |x: [f64; 2]| scale * (0.003 + 0.3 * ((x[0] - 0.5).powi(2) + (x[1] - 0.5).powi(2)).sqrt()).min(0.1)
}

#[derive(Serialize)]
struct Case {
    name: String,
    triangles: usize,
    /// Median wall time.
    seconds: f64,
    triangles_per_second: f64,
    /// Median CPU time of the meshing thread: the wall time without the share lost to other
    /// processes on a busy machine.
    cpu_seconds: f64,
    triangles_per_cpu_second: f64,
    quality: QualityReport,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let domain = PolygonDomain::lshape([0.5, 0.5])?;
    let mut cases = Vec::new();
    for (name, scale) in [("graded-10k", 0.21), ("graded-100k", 0.0666), ("graded-1M", 0.021)] {
        let field = FnSize(graded_field(scale));
        let (mesh, seconds, cpu) =
            median_time(args.repeats, CpuClock::Thread, || generate_2d(&domain, &field, &Mesh2dParams::default()))?;
        cases.push(case(name, &mesh, seconds, cpu, QualityReport::measure(&mesh, &field)));
    }
    for (name, triangles) in
        [("spade-refine-uniform-10k", 1e4), ("spade-refine-uniform-100k", 1e5), ("spade-refine-uniform-1M", 1e6)]
    {
        let max_area = 1.5 * domain.area() / triangles;
        let (mesh, seconds, cpu) = median_time(args.repeats, CpuClock::Thread, || spade_uniform(&domain, max_area))?;
        // Sizes measured against the regular triangle of half the area cap (refine's typical area).
        let target = amber_mesh::size_from_volume::<2>(0.5 * max_area);
        cases.push(case(name, &mesh, seconds, cpu, QualityReport::measure(&mesh, &ConstantSize(target))));
    }
    for c in &cases {
        println!(
            "{:<28} {:>9} tris {:>8.3} s {:>10.0} tris/s ({:>8.0} per CPU s)  size ratio {:.3} [{:.3}, {:.3}]  min angle {:.1}°  mean min angle {:.1}°",
            c.name,
            c.triangles,
            c.seconds,
            c.triangles_per_second,
            c.triangles_per_cpu_second,
            c.quality.size_ratio_median,
            c.quality.size_ratio_p10,
            c.quality.size_ratio_p90,
            c.quality.min_angle,
            c.quality.mean_min_angle
        );
    }
    write_json(
        &args.out,
        &serde_json::json!({ "benchmark": "mesher", "settings": args, "machine": crate::report::machine(), "cases": cases }),
    )
}

fn case(name: &str, mesh: &Mesh2, seconds: f64, cpu_seconds: f64, quality: QualityReport) -> Case {
    let triangles = mesh.num_elements();
    Case {
        name: name.into(),
        triangles,
        seconds,
        triangles_per_second: triangles as f64 / seconds,
        cpu_seconds,
        triangles_per_cpu_second: triangles as f64 / cpu_seconds,
        quality,
    }
}

/// spade's built-in refinement: a uniform area bound, 20° angle limit, notch excluded.
fn spade_uniform(domain: &PolygonDomain, max_area: f64) -> anyhow::Result<Mesh2> {
    let outer = domain.outer();
    let points = outer.iter().map(|p| Point2::new(p[0], p[1])).collect();
    let edges = (0..outer.len()).map(|i| [i, (i + 1) % outer.len()]).collect();
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::bulk_load_cdt(points, edges)
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let result = cdt.refine(
        RefinementParameters::new()
            .with_max_allowed_area(max_area)
            .with_angle_limit(AngleLimit::from_deg(20.0))
            .exclude_outer_faces(true)
            .with_max_additional_vertices(10_000_000),
    );
    let vertices = cdt.vertices().map(|v| [v.position().x, v.position().y]).collect();
    let cells = cdt
        .inner_faces()
        .filter(|f| !result.excluded_faces.contains(&f.fix()))
        .flat_map(|f| f.vertices().map(|v| v.fix().index() as u32))
        .collect();
    Ok(Mesh2::new(vertices, cells)?)
}
