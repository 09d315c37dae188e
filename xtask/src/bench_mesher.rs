//! `cargo xtask bench mesher`: the 2D generator on a graded L-shape field at ~10k, ~100k and
//! ~1M triangles (single thread, everything included), with spade's own uniform `refine()` at
//! the same element counts as an in-run reference.
//!
//! With `--peer-python`, gmsh's Frontal-Delaunay meshes each graded case's polygon with the same
//! field in the same run (`xtask/peers/bench_mesher.py`, one thread), and its mesh is measured
//! like ours.

use std::path::{Path, PathBuf};

use amber_mesh::Mesh2;
use amber_meshgen::{ConstantSize, Mesh2dParams, PolygonDomain, QualityReport, SizingField, generate_2d};
use anyhow::Context;
use serde::Serialize;
use serde_json::{Value, json};
use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};

use crate::peer::{Peer, PeerDir};
use crate::report::write_json;
use crate::timing::{CpuClock, Load, LoadMeter, median_time};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/mesher.json")]
    pub out: PathBuf,
    /// Timed repetitions per case (the median is reported).
    #[arg(long, default_value_t = 3)]
    repeats: usize,
    /// Cases to run (all by default): graded-10k, graded-100k, graded-1M,
    /// spade-refine-uniform-10k, spade-refine-uniform-100k, spade-refine-uniform-1M.
    #[arg(long, value_delimiter = ',')]
    cases: Vec<String>,
    /// Python with gmsh and numpy: also mesh each graded case with gmsh.
    #[arg(long)]
    peer_python: Option<PathBuf>,
}

/// The graded cases: name and field scale.
const GRADED: [(&str, f64); 3] = [("graded-10k", 0.21), ("graded-100k", 0.0666), ("graded-1M", 0.021)];
/// The uniform cases of spade's `refine()`: name and triangle count.
const UNIFORM: [(&str, f64); 3] =
    [("spade-refine-uniform-10k", 1e4), ("spade-refine-uniform-100k", 1e5), ("spade-refine-uniform-1M", 1e6)];

/// Field graded towards the re-entrant corner (0.5, 0.5): `scale` · min(0.003 + 0.3 r, 0.1) at
/// distance r from it; `scale` sets the element count (≈ 440 / scale² triangles).
struct GradedField {
    scale: f64,
}

impl GradedField {
    const CORNER: [f64; 2] = [0.5, 0.5];
    const MIN: f64 = 0.003;
    const SLOPE: f64 = 0.3;
    const MAX: f64 = 0.1;

    /// The same formula as a gmsh `MathEval` field expression.
    fn gmsh_expression(&self) -> String {
        let [cx, cy] = Self::CORNER;
        format!(
            "{} * Min({} + {} * Sqrt((x - {cx})^2 + (y - {cy})^2), {})",
            self.scale,
            Self::MIN,
            Self::SLOPE,
            Self::MAX
        )
    }
}

impl SizingField<2> for GradedField {
    fn size_at(&self, x: [f64; 2]) -> f64 {
        let [cx, cy] = Self::CORNER;
        self.scale * (Self::MIN + Self::SLOPE * ((x[0] - cx).powi(2) + (x[1] - cy).powi(2)).sqrt()).min(Self::MAX)
    }
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
    /// gmsh on the same polygon and field, in the same run (with `--peer-python`).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer: Option<PeerCase>,
    /// gmsh's wall time per triangle over ours, i.e. our triangles per second over gmsh's (above
    /// 1: ours is faster).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer_time_per_triangle_over_ours: Option<f64>,
    /// The machine around ours and the peer.
    load: Load,
}

#[derive(Serialize)]
struct PeerCase {
    /// What the script reported: versions, triangles, median wall seconds, triangles per second.
    result: Value,
    /// gmsh's mesh measured against the field as ours is.
    quality: QualityReport,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let domain = PolygonDomain::lshape(GradedField::CORNER)?;
    let known = GRADED.iter().map(|c| c.0).chain(UNIFORM.iter().map(|c| c.0)).collect::<Vec<_>>();
    if let Some(unknown) = args.cases.iter().find(|c| !known.contains(&c.as_str())) {
        anyhow::bail!("unknown case `{unknown}` ({})", known.join(", "));
    }
    let selected = |name: &str| args.cases.is_empty() || args.cases.iter().any(|c| c == name);
    let mut cases = Vec::new();
    for (name, scale) in GRADED.into_iter().filter(|c| selected(c.0)) {
        let meter = LoadMeter::start();
        let field = GradedField { scale };
        let (mesh, seconds, cpu) =
            median_time(args.repeats, CpuClock::Thread, || generate_2d(&domain, &field, &Mesh2dParams::default()))?;
        let quality = QualityReport::measure(&mesh, &field);
        let peer = match &args.peer_python {
            Some(python) => Some(run_peer(python, &domain, &field, args.repeats)?),
            None => None,
        };
        cases.push(case(name, &mesh, seconds, cpu, quality, peer, &meter));
    }
    for (name, triangles) in UNIFORM.into_iter().filter(|c| selected(c.0)) {
        let meter = LoadMeter::start();
        let max_area = 1.5 * domain.area() / triangles;
        let (mesh, seconds, cpu) = median_time(args.repeats, CpuClock::Thread, || spade_uniform(&domain, max_area))?;
        // Sizes measured against the regular triangle of half the area cap (refine's typical area).
        let target = amber_mesh::size_from_volume::<2>(0.5 * max_area);
        cases.push(case(name, &mesh, seconds, cpu, QualityReport::measure(&mesh, &ConstantSize(target)), None, &meter));
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
        if let (Some(p), Some(ratio)) = (&c.peer, c.peer_time_per_triangle_over_ours) {
            println!(
                "{:<28} {:>9} tris {:>8.3} s {:>10.0} tris/s                      size ratio {:.3} [{:.3}, {:.3}]  min angle {:.1}°  mean min angle {:.1}°  → gmsh/ours per triangle {ratio:.2}× [other CPUs {:.2}]",
                "  gmsh Frontal-Delaunay",
                p.quality.elements,
                p.result["seconds"].as_f64().unwrap_or(f64::NAN),
                p.result["triangles_per_second"].as_f64().unwrap_or(f64::NAN),
                p.quality.size_ratio_median,
                p.quality.size_ratio_p10,
                p.quality.size_ratio_p90,
                p.quality.min_angle,
                p.quality.mean_min_angle,
                c.load.other_cpus
            );
        }
    }
    write_json(
        &args.out,
        &json!({ "benchmark": "mesher", "settings": args, "machine": crate::report::machine(), "cases": cases }),
    )
}

fn case(
    name: &str,
    mesh: &Mesh2,
    seconds: f64,
    cpu_seconds: f64,
    quality: QualityReport,
    peer: Option<PeerCase>,
    meter: &LoadMeter,
) -> Case {
    let triangles = mesh.num_elements();
    let peer_time_per_triangle_over_ours = peer
        .as_ref()
        .and_then(|p| p.result["triangles_per_second"].as_f64())
        .map(|peer_rate| triangles as f64 / seconds / peer_rate);
    Case {
        name: name.into(),
        triangles,
        seconds,
        triangles_per_second: triangles as f64 / seconds,
        cpu_seconds,
        triangles_per_cpu_second: triangles as f64 / cpu_seconds,
        quality,
        peer,
        peer_time_per_triangle_over_ours,
        load: meter.finish(),
    }
}

/// Meshes `domain` with gmsh (`xtask/peers/bench_mesher.py`) and measures its mesh against `field`.
fn run_peer(python: &Path, domain: &PolygonDomain, field: &GradedField, repeats: usize) -> anyhow::Result<PeerCase> {
    let dir = PeerDir::new("mesher")?;
    dir.write_npy("outer", &[domain.outer().len(), 2], domain.outer().as_flattened())?;
    dir.write_input(&json!({ "field": field.gmsh_expression(), "repeats": repeats }))?;
    let result = Peer { python, threads: 1 }.run_script("bench_mesher.py", &dir)?;
    let (_, vertices) = dir.read_npy::<f64>("vertices")?;
    let (_, triangles) = dir.read_npy::<u32>("triangles")?;
    let vertices = vertices.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
    let mesh = Mesh2::new_reoriented(vertices, triangles).context("gmsh's mesh")?;
    Ok(PeerCase { result, quality: QualityReport::measure(&mesh, field) })
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
