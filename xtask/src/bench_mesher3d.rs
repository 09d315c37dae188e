//! `cargo xtask bench mesher3d`: the 3D generator on every Console train/val part with the
//! expert's own sizing field (the oracle re-mesh): tets against the expert's count, size ratio
//! against the expert field, worst dihedral angle, enclosed volume against the reference
//! surface, and the time of each stage on one thread.
//!
//! With `--peer-python`, gmsh re-meshes every part in the same run as the reference code does
//! (`xtask/peers/bench_mesher3d.py`: the part's CAD, the expert's field as a background view), and
//! its meshes are measured like ours.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mesh::{Mesh3, read_mesh};
use amber_meshgen::mesh3d::{Mesh3dParams, StlFaceIds, Surface, adapt_surface, fill_surface};
use amber_meshgen::{MeshSizing, SizingField};
use amber_stdx::{median, quantile};
use anyhow::Context;
use serde::Serialize;
use serde_json::{Value, json};

use crate::peer::{Peer, PeerDir};
use crate::report::write_json;
use crate::timing::{CpuClock, CpuTimer, LoadMeter};

#[derive(clap::Args, Debug, Serialize)]
pub struct Args {
    /// The Console data directory (`train/`, `val/`, `reference_surface/`).
    #[arg(long, default_value = "../shared/data/console")]
    data: PathBuf,
    /// Where to write the results.
    #[arg(long, default_value = "results/bench/mesher3d.json")]
    pub out: PathBuf,
    /// Threads (the acceptance times are single-threaded).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Only parts whose name (`train/001`) contains this.
    #[arg(long)]
    only: Option<String>,
    /// Python with gmsh and numpy: also re-mesh every part with gmsh (the reference code's way).
    #[arg(long)]
    peer_python: Option<PathBuf>,
}

/// One re-mesh of a part, ours or the peer's.
#[derive(Serialize)]
struct Part {
    name: String,
    expert_tets: usize,
    surface_triangles: usize,
    #[serde(flatten)]
    mesh: Comparison,
    #[serde(flatten)]
    time: StageTimes,
    /// gmsh on the same part and field, in the same run (with `--peer-python`).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer: Option<PeerPart>,
    /// gmsh's total wall time over ours (above 1: ours is faster).
    #[serde(skip_serializing_if = "Option::is_none")]
    peer_time_over_ours: Option<f64>,
}

/// gmsh's re-mesh of a part, measured as ours.
#[derive(Serialize)]
struct PeerPart {
    #[serde(flatten)]
    mesh: Comparison,
    #[serde(flatten)]
    time: StageTimes,
}

/// A tet mesh of a part against the expert's.
#[derive(Serialize)]
struct Comparison {
    tets: usize,
    tets_over_expert: f64,
    /// h(K) / expert field at the midpoint of K, over the mesh's tets.
    size_ratio_p10: f64,
    size_ratio_median: f64,
    size_ratio_p90: f64,
    min_dihedral_deg: f64,
    tets_below_5_deg: usize,
    /// Enclosed volume of the mesh / the reference surface's − 1.
    volume_error: f64,
}

#[derive(Clone, Copy, Serialize, serde::Deserialize)]
struct StageTimes {
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

/// What a part needs besides its re-mesh to measure another one: the expert and the enclosed
/// volume of the reference surface.
struct PartInput {
    expert: Mesh3,
    enclosed_volume: f64,
}

pub fn run(args: Args) -> anyhow::Result<()> {
    let meter = LoadMeter::start();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build()?;
    let params = Mesh3dParams::default();
    let (mut parts, mut inputs) = (Vec::new(), Vec::new());
    for name in part_names(&args.data)? {
        if args.only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let (part, input) = pool.install(|| bench_part(&args.data, &name, &params))?;
        println!(
            "{:<10} expert {:>6} tets, ours {:>6} ({:.2}x), {:>6} surface tris, size ratio {:.2} [{:.2}, {:.2}], \
             min dihedral {:>5.1}° ({} < 5°), volume {:+.2e}, {:.2} s + {:.2} s = {:.2} s (CPU {:.2} s)",
            part.name,
            part.expert_tets,
            part.mesh.tets,
            part.mesh.tets_over_expert,
            part.surface_triangles,
            part.mesh.size_ratio_median,
            part.mesh.size_ratio_p10,
            part.mesh.size_ratio_p90,
            part.mesh.min_dihedral_deg,
            part.mesh.tets_below_5_deg,
            part.mesh.volume_error,
            part.time.seconds_surface,
            part.time.seconds_volume,
            part.time.seconds_total,
            part.time.cpu_seconds_total
        );
        parts.push(part);
        inputs.push(input);
    }
    anyhow::ensure!(!parts.is_empty(), "{}: no parts matched", args.data.display());
    if let Some(python) = &args.peer_python {
        let peer_parts = run_peer(python, &args, &parts, &inputs)?;
        for (part, peer) in parts.iter_mut().zip(peer_parts) {
            let ratio = peer.time.seconds_total / part.time.seconds_total;
            println!(
                "{:<10} gmsh {:>6} tets ({:.2}x), size ratio {:.2} [{:.2}, {:.2}], min dihedral {:>5.1}° ({} < 5°), \
                 volume {:+.2e}, {:.2} s + {:.2} s = {:.2} s → gmsh/ours {ratio:.2}×",
                part.name,
                peer.mesh.tets,
                peer.mesh.tets_over_expert,
                peer.mesh.size_ratio_median,
                peer.mesh.size_ratio_p10,
                peer.mesh.size_ratio_p90,
                peer.mesh.min_dihedral_deg,
                peer.mesh.tets_below_5_deg,
                peer.mesh.volume_error,
                peer.time.seconds_surface,
                peer.time.seconds_volume,
                peer.time.seconds_total,
            );
            part.peer_time_over_ours = Some(ratio);
            part.peer = Some(peer);
        }
    }
    let ours: Vec<_> = parts.iter().map(|p| (&p.mesh, &p.time)).collect();
    let (medians, acceptance) = (medians_of(&ours), acceptance_of(&ours));
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
    let peer: Vec<_> = parts.iter().filter_map(|p| p.peer.as_ref().map(|q| (&q.mesh, &q.time))).collect();
    let peer_summary = (!peer.is_empty()).then(|| {
        let (peer_medians, peer_acceptance) = (medians_of(&peer), acceptance_of(&peer));
        let ratios = json!({
            "median": peer_medians.seconds_total / medians.seconds_total,
            "max": peer_medians.seconds_total_max / medians.seconds_total_max,
        });
        println!(
            "gmsh medians: {:.2}x expert tets, size ratio {:.3}, total {:.3} s (max {:.3} s) → gmsh/ours: median {:.2}×, max {:.2}×",
            peer_medians.tets_over_expert,
            peer_medians.size_ratio_median,
            peer_medians.seconds_total,
            peer_medians.seconds_total_max,
            ratios["median"].as_f64().unwrap_or(f64::NAN),
            ratios["max"].as_f64().unwrap_or(f64::NAN)
        );
        println!("gmsh acceptance counts: {peer_acceptance}");
        json!({ "medians": peer_medians, "acceptance": peer_acceptance, "peer_time_over_ours": ratios })
    });
    write_json(
        &args.out,
        &json!({
            "benchmark": "mesher3d",
            "settings": args,
            "params": format!("{params:?}"),
            "machine": crate::report::machine(),
            "parts": parts,
            "medians": medians,
            "acceptance": acceptance,
            "peer": peer_summary,
            "load": meter.finish(),
        }),
    )
}

fn medians_of(parts: &[(&Comparison, &StageTimes)]) -> Medians {
    let median_of = |f: &dyn Fn(&(&Comparison, &StageTimes)) -> f64| median(&parts.iter().map(f).collect::<Vec<_>>());
    Medians {
        tets_over_expert: median_of(&|p| p.0.tets_over_expert),
        size_ratio_median: median_of(&|p| p.0.size_ratio_median),
        min_dihedral_deg: median_of(&|p| p.0.min_dihedral_deg),
        abs_volume_error: median_of(&|p| p.0.volume_error.abs()),
        seconds_surface: median_of(&|p| p.1.seconds_surface),
        seconds_volume: median_of(&|p| p.1.seconds_volume),
        seconds_total: median_of(&|p| p.1.seconds_total),
        seconds_total_max: parts.iter().map(|p| p.1.seconds_total).fold(0.0, f64::max),
        cpu_seconds_total: median_of(&|p| p.1.cpu_seconds_total),
    }
}

/// How many parts pass each bar.
fn acceptance_of(parts: &[(&Comparison, &StageTimes)]) -> Value {
    let count = |pass: &dyn Fn(&Comparison) -> bool| parts.iter().filter(|p| pass(p.0)).count();
    json!({
        "tets_within_0.8_1.3": count(&|m| (0.8..=1.3).contains(&m.tets_over_expert)),
        "size_ratio_median_within_0.85_1.15": count(&|m| (0.85..=1.15).contains(&m.size_ratio_median)),
        "no_tet_below_5_deg": count(&|m| m.tets_below_5_deg == 0),
        "volume_within_0.5_percent": count(&|m| m.volume_error.abs() <= 5e-3),
        "parts": parts.len(),
    })
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

fn bench_part(data: &Path, name: &str, params: &Mesh3dParams) -> anyhow::Result<(Part, PartInput)> {
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
    let part = Part {
        name: name.into(),
        expert_tets: expert.num_elements(),
        surface_triangles: surface.triangles().len(),
        mesh: compare(&mesh, &field, report.enclosed_volume),
        time: StageTimes {
            seconds_surface,
            seconds_volume: seconds_total - seconds_surface,
            seconds_total,
            cpu_seconds_total,
        },
        peer: None,
        peer_time_over_ours: None,
    };
    Ok((part, PartInput { expert, enclosed_volume: report.enclosed_volume }))
}

/// Measures `mesh` against the expert's field (on the expert mesh) and the reference volume.
fn compare(mesh: &Mesh3, field: &MeshSizing<'_, 3>, enclosed_volume: f64) -> Comparison {
    let expert_tets = field.sizes().len();
    let mut ratios: Vec<f64> =
        (0..mesh.num_elements()).map(|e| mesh.size(e) / field.size_at(mesh.midpoint(e))).collect();
    ratios.sort_by(f64::total_cmp);
    let angles = mesh.min_angles();
    Comparison {
        tets: mesh.num_elements(),
        tets_over_expert: mesh.num_elements() as f64 / expert_tets as f64,
        size_ratio_p10: quantile(&ratios, 0.1),
        size_ratio_median: quantile(&ratios, 0.5),
        size_ratio_p90: quantile(&ratios, 0.9),
        min_dihedral_deg: angles.iter().copied().fold(f64::INFINITY, f64::min),
        tets_below_5_deg: angles.iter().filter(|&&a| a < 5.0).count(),
        volume_error: mesh.total_volume() / enclosed_volume - 1.0,
    }
}

/// Re-meshes every part with gmsh (`xtask/peers/bench_mesher3d.py`) from the part's CAD file and
/// the expert's field, and measures each mesh as ours.
fn run_peer(python: &Path, args: &Args, parts: &[Part], inputs: &[PartInput]) -> anyhow::Result<Vec<PeerPart>> {
    let dir = PeerDir::new("mesher3d")?;
    let mut listed = Vec::new();
    for (part, input) in parts.iter().zip(inputs) {
        let file = part.name.replace('/', "-");
        let expert = &input.expert;
        dir.write_npy(&format!("{file}.vertices"), &[expert.num_vertices(), 3], expert.vertices().as_flattened())?;
        dir.write_npy(&format!("{file}.tets"), &[expert.num_elements(), 4], expert.cells())?;
        dir.write_npy(&format!("{file}.sizes"), &[expert.num_elements()], &expert.sizes())?;
        let step = std::path::absolute(args.data.join(format!("{}.step", part.name)))?;
        listed.push(json!({ "name": part.name, "file": file, "step": step }));
    }
    dir.write_input(&json!({ "parts": listed }))?;
    let result = Peer { python, threads: args.threads }.run_script("bench_mesher3d.py", &dir)?;
    let results = result["parts"].as_array().context("the peer result has no parts")?;
    anyhow::ensure!(results.len() == parts.len(), "the peer meshed {} of {} parts", results.len(), parts.len());
    parts
        .iter()
        .zip(inputs)
        .zip(results)
        .map(|((part, input), peer)| {
            let file = part.name.replace('/', "-");
            let (_, vertices) = dir.read_npy::<f64>(&format!("{file}.gmsh_vertices"))?;
            let (_, tets) = dir.read_npy::<u32>(&format!("{file}.gmsh_tets"))?;
            let vertices = vertices.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            let mesh = Mesh3::new_reoriented(vertices, tets).with_context(|| format!("{}: gmsh's mesh", part.name))?;
            let field = MeshSizing::from_element_sizes(&input.expert);
            let time: StageTimes =
                serde_json::from_value(peer.clone()).with_context(|| format!("{}: the peer's times", part.name))?;
            Ok(PeerPart { mesh: compare(&mesh, &field, input.enclosed_volume), time })
        })
        .collect()
}
