//! `amber convert IN OUT`: any mesh file amber reads to any it writes, the dimension taken from
//! the file, with the per-element and per-vertex fields and the facet tags carried along where
//! the output format stores them.

use std::path::PathBuf;
use std::time::Instant;

use amber_mesh::{AnyMesh, ElementOrder, Encoding, Mesh, MeshData, WriteOptions, read_any_mesh, write_mesh_as};
use anyhow::Context;
use clap::Args;

#[derive(Args)]
pub struct ConvertArgs {
    /// Input mesh: .msh (gmsh 2.2/4.1), .vtu, .vtk, .nas/.bdf, .inp, .mesh or .json.
    input: PathBuf,
    /// Output mesh, format by extension: .msh (4.1), .vtu, .vtk, .nas, .inp, .mesh or .json.
    output: PathBuf,
    /// Write .msh, .vtu or .vtk in binary (default: binary .vtu, ASCII otherwise).
    #[arg(long, conflicts_with = "ascii")]
    binary: bool,
    /// Write .msh, .vtu or .vtk as text.
    #[arg(long)]
    ascii: bool,
    /// Element order of the output: 1, or 2 for 10-node tetrahedra and 6-node triangles with
    /// their edge nodes at the edges' midpoints (.msh, .vtu, .vtk, .nas, .inp).
    #[arg(long, default_value = "1", value_parser = parse_order)]
    order: ElementOrder,
}

/// `--order`: 1 or 2.
pub(crate) fn parse_order(text: &str) -> Result<ElementOrder, String> {
    match text {
        "1" => Ok(ElementOrder::Linear),
        "2" => Ok(ElementOrder::Quadratic),
        _ => Err(format!("the element order is 1 or 2, not `{text}`")),
    }
}

pub fn run(args: ConvertArgs) -> anyhow::Result<()> {
    let encoding = match (args.binary, args.ascii) {
        (true, _) => Some(Encoding::Binary),
        (_, true) => Some(Encoding::Ascii),
        _ => None,
    };
    let start = Instant::now();
    let summary = match read_any_mesh(&args.input).context("cannot read the input mesh")? {
        AnyMesh::Two(mesh, data) => write(&mesh, &data, &args, encoding)?,
        AnyMesh::Three(mesh, data) => write(&mesh, &data, &args, encoding)?,
    };
    eprintln!("{summary} in {:.3} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// Writes the mesh and says what was converted (and what the reader dropped).
fn write<const D: usize>(
    mesh: &Mesh<D>,
    data: &MeshData,
    args: &ConvertArgs,
    encoding: Option<Encoding>,
) -> anyhow::Result<String> {
    let options = WriteOptions { encoding, order: args.order };
    write_mesh_as(mesh, &args.output, data, options).context("cannot write the output mesh")?;
    let mut summary = format!(
        "{} -> {}: {} vertices, {} {}D elements{}{}, {} cell and {} point fields, {} tagged facets",
        args.input.display(),
        args.output.display(),
        mesh.num_vertices(),
        mesh.num_elements(),
        D,
        data.domain_name.as_ref().map_or(String::new(), |name| format!(" in `{name}`")),
        if args.order == ElementOrder::Quadratic { " written as second order" } else { "" },
        data.cell.len(),
        data.point.len(),
        data.facet_tags.len()
    );
    if !data.facet_names.is_empty() {
        let names: Vec<String> = data.facet_names.iter().map(|(tag, name)| format!("{tag} `{name}`")).collect();
        summary += &format!(" (named: {})", names.join(", "));
    }
    if !data.linearised.is_empty() {
        let linearised: Vec<String> = data.linearised.iter().map(|(kind, n)| format!("{n} {kind}")).collect();
        summary += &format!("; read by their corner nodes: {}", linearised.join(", "));
    }
    if !data.dropped.is_empty() {
        let dropped: Vec<String> = data.dropped.iter().map(|(kind, n)| format!("{n} {kind}")).collect();
        summary += &format!("; not meshed elements dropped: {}", dropped.join(", "));
    }
    Ok(summary)
}
