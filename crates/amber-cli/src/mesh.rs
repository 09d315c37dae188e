//! `amber mesh`: a geometry plus a sizing field in, a mesh file or picture out.

use std::path::{Path, PathBuf};
use std::time::Instant;

use amber_mesh::{Mesh2, MeshData, read_mesh_with_data, write_mesh};
use amber_meshgen::{ConstantSize, Mesh2dParams, MeshSizing, PolygonDomain, QualityReport, SizingField, generate_2d};
use amber_plot::{RenderOptions, render_png};
use anyhow::{Context, bail};
use clap::Args;

#[derive(Args)]
pub struct MeshArgs {
    /// `lshape`, `square`, or a JSON file `{"outer": [[x, y], ...], "holes": [[[x, y], ...], ...]}`.
    #[arg(long, default_value = "lshape")]
    domain: String,
    /// Re-entrant corner of the L-shape.
    #[arg(long, value_parser = parse_point, default_value = "0.5,0.5")]
    corner: [f64; 2],
    /// A constant size (edge length), or a mesh file (.vtu, .msh, .json) whose element sizes
    /// define a piecewise-constant field (a `size` cell array in a .vtu overrides them).
    #[arg(long, allow_hyphen_values = true)]
    size: String,
    /// Refuse to build more elements than this.
    #[arg(long, default_value_t = 5_000_000)]
    max_elements: usize,
    /// Output: .vtu (ParaView), .msh (gmsh 4.1), .json, or .png (coloured by element size).
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(args: MeshArgs) -> anyhow::Result<()> {
    let domain = parse_domain(&args.domain, &args.corner)?;
    let params = Mesh2dParams::default().with_max_elements(args.max_elements);
    let start = Instant::now();
    let (mesh, report) = match args.size.parse::<f64>() {
        Ok(h) => mesh_with(&domain, &ConstantSize(h), &params)?,
        Err(_) => {
            let (field_mesh, sizes) = read_sizing_mesh(Path::new(&args.size))?;
            mesh_with(&domain, &MeshSizing::new(&field_mesh, sizes), &params)?
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    write_output(&mesh, &args.output)?;
    eprintln!(
        "{} triangles in {seconds:.3} s; size ratio median {:.3} (p10 {:.3}, p90 {:.3}); min angle {:.1}°, mean min angle {:.1}°; wrote {}",
        mesh.num_elements(),
        report.size_ratio_median,
        report.size_ratio_p10,
        report.size_ratio_p90,
        report.min_angle,
        report.mean_min_angle,
        args.output.display()
    );
    Ok(())
}

fn mesh_with<F: SizingField<2>>(
    domain: &PolygonDomain,
    field: &F,
    params: &Mesh2dParams,
) -> anyhow::Result<(Mesh2, QualityReport)> {
    let mesh = generate_2d(domain, field, params).context("mesh generation failed")?;
    let report = QualityReport::measure(&mesh, field);
    Ok((mesh, report))
}

fn parse_point(text: &str) -> Result<[f64; 2], String> {
    match text.split(',').map(str::trim).map(str::parse::<f64>).collect::<Result<Vec<_>, _>>() {
        Ok(v) if v.len() == 2 => Ok([v[0], v[1]]),
        _ => Err(format!("expected two comma-separated numbers like 0.5,0.5, got `{text}`")),
    }
}

fn parse_domain(domain: &str, corner: &[f64; 2]) -> anyhow::Result<PolygonDomain> {
    Ok(match domain {
        "lshape" => PolygonDomain::lshape(*corner)?,
        "square" => PolygonDomain::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![])?,
        path => {
            let text = std::fs::read_to_string(path).with_context(|| format!("{path}: cannot read the domain file"))?;
            serde_json::from_str(&text).with_context(|| format!("{path}: not a valid domain"))?
        }
    })
}

fn read_sizing_mesh(path: &Path) -> anyhow::Result<(Mesh2, Vec<f64>)> {
    let (mesh, data) = read_mesh_with_data::<2>(path)
        .with_context(|| format!("--size {}: not a number and not a readable mesh", path.display()))?;
    let sizes = data.cell.get("size").cloned().unwrap_or_else(|| mesh.sizes());
    if sizes.len() != mesh.num_elements() {
        bail!(
            "{}: the `size` cell array has {} values for {} elements",
            path.display(),
            sizes.len(),
            mesh.num_elements()
        );
    }
    Ok((mesh, sizes))
}

fn write_output(mesh: &Mesh2, output: &Path) -> anyhow::Result<()> {
    let sizes = mesh.sizes();
    match output.extension().and_then(|e| e.to_str()) {
        Some("png") => {
            let options = RenderOptions { title: Some("element size h".into()), log_scale: true, ..Default::default() };
            render_png(mesh, &sizes, &options, output)?
        }
        _ => write_mesh(mesh, output, &MeshData::new().with_cell("size", sizes))?,
    }
    Ok(())
}
