//! gmsh `.msh` 4.1 ASCII. The reader accepts what gmsh writes: entity blocks, non-contiguous
//! node tags, elements of every dimension (only the simplices of the mesh dimension are kept),
//! sections it does not know (skipped), and scalar `$NodeData` / `$ElementData`. The writer puts
//! the whole mesh into one entity without `$Entities`, which gmsh accepts.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use super::{Lines, MeshData, assemble, write_error};
use crate::{Mesh, MeshError};

/// gmsh element type numbers of the linear simplices.
const TRIANGLE: u32 = 2;
const TETRAHEDRON: u32 = 4;

fn simplex_type(dim: usize) -> u32 {
    if dim == 2 { TRIANGLE } else { TETRAHEDRON }
}

/// One `$NodeData` / `$ElementData` section, resolved to mesh indices once the whole file is read.
struct DataSection {
    on_elements: bool,
    name: String,
    values: Vec<(u64, f64)>,
    /// Line of the section's end, for errors found while resolving it.
    line: usize,
}

pub(super) fn read<const D: usize>(path: &Path, bytes: &[u8]) -> Result<(Mesh<D>, MeshData), MeshError> {
    let mut lines = Lines::new(path, bytes);
    let mut seen_format = false;
    let mut nodes = Nodes { index: HashMap::new(), tags: Vec::new(), vertices: Vec::new(), off_plane: None };
    // Kept elements as node tags, resolved once all nodes are known.
    let mut element_nodes: Vec<u64> = Vec::new();
    let mut element_tags: Vec<u64> = Vec::new();
    let mut max_dim = 0;
    let mut sections = Vec::new();
    while let Some(line) = lines.next()? {
        let header = line.trim();
        if header.is_empty() {
            continue;
        }
        let Some(name) = header.strip_prefix('$') else {
            return Err(lines.error(format!("expected a section header, found `{header}`")));
        };
        if !seen_format && name != "MeshFormat" {
            return Err(lines.error("not a gmsh file: it must start with $MeshFormat"));
        }
        match name {
            "MeshFormat" => {
                read_format(&mut lines)?;
                seen_format = true;
            }
            "Nodes" => read_nodes(&mut lines, &mut nodes)?,
            "Elements" => max_dim = max_dim.max(read_elements::<D>(&mut lines, &mut element_nodes, &mut element_tags)?),
            "NodeData" | "ElementData" => sections.extend(read_data(&mut lines, name == "ElementData")?),
            _ => loop {
                if lines.expect(&format!("$End{name}"))?.trim() == format!("$End{name}") {
                    break;
                }
            },
        }
    }
    if !seen_format {
        return Err(lines.error("empty file"));
    }
    if max_dim != D {
        return Err(MeshError::DimensionMismatch { path: path.to_owned(), expected: D, found: max_dim });
    }
    if let Some((line, z)) = nodes.off_plane {
        let message = format!("z = {z} in a 2D mesh, which must lie in the plane z = 0");
        return Err(MeshError::Parse { path: path.to_owned(), line, message });
    }
    let cells = element_nodes
        .iter()
        .map(|tag| {
            nodes.index.get(tag).copied().ok_or_else(|| MeshError::Format {
                path: path.to_owned(),
                message: format!("an element references node {tag}, which $Nodes does not define"),
            })
        })
        .collect::<Result<Vec<u32>, _>>()?;
    let data = resolve_data(path, sections, &nodes, &element_tags)?;
    assemble(path, nodes.vertices, cells, data)
}

/// The nodes read so far: coordinates, gmsh tags, and tag → index.
struct Nodes<const D: usize> {
    index: HashMap<u64, u32>,
    tags: Vec<u64>,
    vertices: Vec<[f64; D]>,
    /// The first node off the plane z = 0 in 2D (line, z), reported only once the file is known
    /// to hold a 2D mesh, so that a 3D file is reported as such.
    off_plane: Option<(usize, f64)>,
}

/// Consumes the line `$End{name}` that must follow a section body.
fn expect_end(lines: &mut Lines, name: &str) -> Result<(), MeshError> {
    let end = format!("$End{name}");
    let line = lines.expect(&end)?.trim();
    if line != end {
        return Err(lines.error(format!("expected {end}, found `{line}`")));
    }
    Ok(())
}

fn read_format(lines: &mut Lines) -> Result<(), MeshError> {
    let line = lines.expect("the format line `4.1 0 8`")?;
    let mut t = line.split_ascii_whitespace();
    let version = t.next().ok_or_else(|| lines.error("missing format version"))?;
    let file_type: u32 = lines.parse(t.next(), "file type")?;
    if version != "4.1" {
        return Err(lines.error(format!("gmsh format version {version} is not supported, only 4.1")));
    }
    if file_type != 0 {
        return Err(lines.error("binary .msh files are not supported, only ASCII"));
    }
    expect_end(lines, "MeshFormat")
}

/// Reads a `$Nodes` body: `numEntityBlocks numNodes minTag maxTag`, then per block
/// `entityDim entityTag parametric numNodesInBlock`, the block's tags, then its coordinates.
fn read_nodes<const D: usize>(lines: &mut Lines, nodes: &mut Nodes<D>) -> Result<(), MeshError> {
    let line = lines.expect("the $Nodes header")?;
    let mut t = line.split_ascii_whitespace();
    let blocks: usize = lines.parse(t.next(), "number of node blocks")?;
    let total: usize = lines.parse(t.next(), "number of nodes")?;
    let mut read = 0;
    for _ in 0..blocks {
        let line = lines.expect("a node block header")?;
        let mut t = line.split_ascii_whitespace();
        let _dim: usize = lines.parse(t.next(), "entity dimension")?;
        let _entity: i64 = lines.parse(t.next(), "entity tag")?;
        let _parametric: u8 = lines.parse(t.next(), "parametric flag")?;
        let count: usize = lines.parse(t.next(), "number of nodes in block")?;
        let first = nodes.vertices.len();
        for _ in 0..count {
            let line = lines.expect("a node tag")?;
            let tag: u64 = lines.parse(line.split_ascii_whitespace().next(), "node tag")?;
            if nodes.index.insert(tag, nodes.vertices.len() as u32).is_some() {
                return Err(lines.error(format!("node {tag} is defined twice")));
            }
            nodes.tags.push(tag);
            nodes.vertices.push([0.0; D]);
        }
        for vertex in &mut nodes.vertices[first..] {
            let line = lines.expect("node coordinates")?;
            let mut t = line.split_ascii_whitespace();
            let xyz: [f64; 3] = [
                finite(lines, t.next(), "x coordinate")?,
                finite(lines, t.next(), "y coordinate")?,
                finite(lines, t.next(), "z coordinate")?,
            ];
            if D == 2 && xyz[2] != 0.0 && nodes.off_plane.is_none() {
                nodes.off_plane = Some((lines.line, xyz[2]));
            }
            *vertex = std::array::from_fn(|k| xyz[k]);
        }
        read += count;
    }
    if read != total {
        return Err(lines.error(format!("the $Nodes header announces {total} nodes, the blocks hold {read}")));
    }
    expect_end(lines, "Nodes")
}

/// Reads an `$Elements` body, appending the node tags and element tags of the `D`-simplices.
/// Returns the highest dimension of any element block.
fn read_elements<const D: usize>(
    lines: &mut Lines,
    element_nodes: &mut Vec<u64>,
    element_tags: &mut Vec<u64>,
) -> Result<usize, MeshError> {
    let line = lines.expect("the $Elements header")?;
    let mut t = line.split_ascii_whitespace();
    let blocks: usize = lines.parse(t.next(), "number of element blocks")?;
    let total: usize = lines.parse(t.next(), "number of elements")?;
    let mut read = 0;
    let mut max_dim = 0;
    for _ in 0..blocks {
        let line = lines.expect("an element block header")?;
        let mut t = line.split_ascii_whitespace();
        let dim: usize = lines.parse(t.next(), "entity dimension")?;
        let _entity: i64 = lines.parse(t.next(), "entity tag")?;
        let element_type: u32 = lines.parse(t.next(), "element type")?;
        let count: usize = lines.parse(t.next(), "number of elements in block")?;
        max_dim = max_dim.max(dim);
        let keep = dim == D;
        if keep && element_type != simplex_type(D) {
            return Err(lines.error(format!(
                "element type {element_type} in a {D}D block: only linear {} are supported",
                if D == 2 { "triangles (type 2)" } else { "tetrahedra (type 4)" }
            )));
        }
        for _ in 0..count {
            let line = lines.expect("an element")?;
            if !keep {
                continue;
            }
            let mut t = line.split_ascii_whitespace();
            element_tags.push(lines.parse(t.next(), "element tag")?);
            for _ in 0..=D {
                element_nodes.push(lines.parse(t.next(), "node tag")?);
            }
            if t.next().is_some() {
                return Err(lines.error(format!("too many nodes for a {D}D simplex")));
            }
        }
        read += count;
    }
    if read != total {
        return Err(lines.error(format!("the $Elements header announces {total} elements, the blocks hold {read}")));
    }
    expect_end(lines, "Elements")?;
    Ok(max_dim)
}

fn finite(lines: &Lines, token: Option<&str>, what: &str) -> Result<f64, MeshError> {
    let x: f64 = lines.parse(token, what)?;
    if x.is_finite() { Ok(x) } else { Err(lines.error(format!("{what} is not finite"))) }
}

/// Reads a `$NodeData` / `$ElementData` section through its end line. Returns `None` for
/// non-scalar fields, which are skipped.
fn read_data(lines: &mut Lines, on_elements: bool) -> Result<Option<DataSection>, MeshError> {
    let section = if on_elements { "ElementData" } else { "NodeData" };
    let mut tags = |what: &str| -> Result<Vec<String>, MeshError> {
        let count = lines.expect(&format!("number of {what} tags"))?;
        let n: usize = lines.parse(Some(count.trim()), "tag count")?;
        (0..n).map(|_| lines.expect(&format!("a {what} tag")).map(|s| s.trim().to_owned())).collect()
    };
    let strings = tags("string")?;
    let _reals = tags("real")?;
    let integers = tags("integer")?;
    let integer =
        |i: usize, what: &str| -> Result<usize, MeshError> { lines.parse(integers.get(i).map(String::as_str), what) };
    let components = integer(1, "number of components")?;
    let count = integer(2, "number of entities")?;
    let name = strings.first().map(|s| s.trim_matches('"').to_owned()).unwrap_or_default();
    let mut values = Vec::new();
    for _ in 0..count {
        let line = lines.expect("a data line")?;
        let mut t = line.split_ascii_whitespace();
        let tag: u64 = lines.parse(t.next(), "tag")?;
        let value: f64 = lines.parse(t.next(), "value")?;
        values.push((tag, value));
    }
    expect_end(lines, section)?;
    Ok((components == 1).then_some(DataSection { on_elements, name, values, line: lines.line }))
}

/// Turns tag-indexed data sections into fields over the parsed vertices and kept elements.
/// Values on dropped elements are ignored; every kept element and vertex needs a value.
fn resolve_data<const D: usize>(
    path: &Path,
    sections: Vec<DataSection>,
    nodes: &Nodes<D>,
    element_tags: &[u64],
) -> Result<MeshData, MeshError> {
    let element_index: HashMap<u64, usize> = element_tags.iter().enumerate().map(|(i, &t)| (t, i)).collect();
    let mut data = MeshData::new();
    for s in sections {
        let (tags, kind) = if s.on_elements { (element_tags, "element") } else { (&nodes.tags[..], "node") };
        let len = tags.len();
        let mut field = vec![f64::NAN; len];
        let mut filled = vec![false; len];
        for (tag, value) in s.values {
            let index = if s.on_elements {
                element_index.get(&tag).copied()
            } else {
                nodes.index.get(&tag).map(|&i| i as usize)
            };
            if let Some(i) = index {
                field[i] = value;
                filled[i] = true;
            }
        }
        if let Some(missing) = filled.iter().position(|&f| !f) {
            return Err(MeshError::Parse {
                path: path.to_owned(),
                line: s.line,
                message: format!("field `{}` has no value for {kind} {}", s.name, tags[missing]),
            });
        }
        if s.on_elements {
            data.cell.insert(s.name, field)
        } else {
            data.point.insert(s.name, field)
        };
    }
    Ok(data)
}

pub(super) fn write<const D: usize>(
    mesh: &Mesh<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    for name in data.cell.keys().chain(data.point.keys()) {
        if name.contains(['"', '\n', '\r']) {
            return Err(MeshError::Format {
                path: path.to_owned(),
                message: format!("field name {name:?} cannot be stored in a .msh string tag"),
            });
        }
    }
    write_body(mesh, data, w).map_err(write_error(path))
}

/// Node and element tags are 1-based indices; coordinates use Rust's shortest round-trip form.
fn write_body<const D: usize>(mesh: &Mesh<D>, data: &MeshData, w: &mut impl Write) -> std::io::Result<()> {
    let (nv, ne) = (mesh.num_vertices(), mesh.num_elements());
    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat")?;
    writeln!(w, "$Nodes\n1 {nv} 1 {nv}\n{D} 1 0 {nv}")?;
    for tag in 1..=nv {
        writeln!(w, "{tag}")?;
    }
    for p in mesh.vertices() {
        let z = if D == 3 { p[2] } else { 0.0 };
        writeln!(w, "{:?} {:?} {:?}", p[0], p[1], z)?;
    }
    writeln!(w, "$EndNodes\n$Elements\n1 {ne} 1 {ne}\n{D} 1 {} {ne}", simplex_type(D))?;
    for (e, cell) in mesh.elements().enumerate() {
        write!(w, "{}", e + 1)?;
        for &v in cell {
            write!(w, " {}", v + 1)?;
        }
        writeln!(w)?;
    }
    writeln!(w, "$EndElements")?;
    let sections = data.point.iter().map(|f| ("NodeData", f)).chain(data.cell.iter().map(|f| ("ElementData", f)));
    for (section, (name, values)) in sections {
        writeln!(w, "${section}\n1\n\"{name}\"\n1\n0\n3\n0\n1\n{}", values.len())?;
        for (i, v) in values.iter().enumerate() {
            writeln!(w, "{} {v:?}", i + 1)?;
        }
        writeln!(w, "$End{section}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        read(Path::new("inline.msh"), text.as_bytes())
    }

    /// A unit square as gmsh 4.15 writes it (two triangles, clockwise as gmsh may list them),
    /// with entities, boundary lines, corner points and non-contiguous node tags.
    const GMSH_2D: &str = "$MeshFormat\r\n4.1 0 8\r\n$EndMeshFormat\r\n\
$PhysicalNames\r\n1\r\n2 1 \"domain\"\r\n$EndPhysicalNames\r\n\
$Entities\r\n4 4 1 0\r\n1 0 0 0 0\r\n2 1 0 0 0\r\n3 1 1 0 0\r\n4 0 1 0 0\r\n\
1 0 0 0 1 0 0 0 2 1 -2\r\n2 1 0 0 1 1 0 0 2 2 -3\r\n3 0 1 0 1 1 0 0 2 3 -4\r\n4 0 0 0 0 1 0 0 2 4 -1\r\n\
1 0 0 0 1 1 0 1 1 4 1 2 3 4\r\n$EndEntities\r\n\
$Nodes\r\n2 4 10 40\r\n0 1 0 1\r\n10\r\n0 0 0\r\n2 1 0 3\r\n20\r\n30\r\n40\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n$EndNodes\r\n\
$Elements\r\n3 5 1 9\r\n0 1 15 1\r\n1 10\r\n1 1 1 2\r\n2 10 20\r\n3 20 30\r\n2 1 2 2\r\n8 10 30 20\r\n9 10 40 30\r\n$EndElements\r\n";

    #[test]
    fn reads_what_gmsh_writes() {
        let (mesh, data) = parse::<2>(GMSH_2D).unwrap();
        assert_eq!(mesh.num_vertices(), 4);
        assert_eq!(mesh.num_elements(), 2);
        assert!(mesh.volumes().iter().all(|&v| (v - 0.5).abs() < 1e-15));
        assert!(data.is_empty());
        assert!(matches!(parse::<3>(GMSH_2D), Err(MeshError::DimensionMismatch { expected: 3, found: 2, .. })));
    }

    #[test]
    fn drops_surface_triangles_of_a_3d_mesh_and_reads_data() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n\
0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n2 2 1 7\n2 1 2 1\n3 1 2 3\n3 1 4 1\n7 1 3 2 4\n$EndElements\n\
$ElementData\n1\n\"h\"\n1\n0.0\n3\n0\n1\n2\n3 9.5\n7 0.25\n$EndElementData\n\
$NodeData\n1\n\"vec\"\n1\n0.0\n3\n0\n3\n1\n1 1 2 3\n$EndNodeData\n";
        let (mesh, data) = parse::<3>(text).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert!(mesh.volume(0) > 0.0, "the negative tetrahedron is flipped");
        assert_eq!(data.cell["h"], vec![0.25]);
        assert!(data.point.is_empty(), "vector fields are skipped");
        assert!(matches!(parse::<2>(text), Err(MeshError::DimensionMismatch { expected: 2, found: 3, .. })));
    }

    #[test]
    fn writer_round_trips_bit_exactly() {
        let vertices = vec![[-0.0, 0.1, 0.2], [1.0 / 3.0, 0.1, 0.2], [0.0, 2f64.sqrt(), 0.2], [1e-7, 0.1, 0.3 + 0.6]];
        let mesh = Mesh3::new_reoriented(vertices, vec![0, 1, 2, 3]).unwrap();
        let data = MeshData::new().with_cell("h", vec![f64::NAN]).with_point("u", vec![5e-324, 1e300, -2.5, -0.0]);
        let mut bytes = Vec::new();
        write(&mesh, &data, &mut bytes, Path::new("x.msh")).unwrap();
        let (back, back_data) = parse::<3>(std::str::from_utf8(&bytes).unwrap()).unwrap();
        assert_eq!(back, mesh);
        assert!(back_data.cell["h"][0].is_nan());
        assert_eq!(back_data.point, data.point);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases: [(&str, usize, &str); 9] = [
            ("", 0, "empty"),
            ("$Nodes\n", 1, "$MeshFormat"),
            ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n", 2, "version 2.2"),
            ("$MeshFormat\n4.1 1 8\n$EndMeshFormat\n", 2, "binary"),
            (
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n",
                10,
                "announces 3 nodes",
            ),
            (
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 x 0\n$EndNodes\n",
                8,
                "bad y coordinate `x`",
            ),
            (
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0.5\n1 0 0\n0 1 0\n$EndNodes\n\
$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n",
                10,
                "plane z = 0",
            ),
            ("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n2 1 0 2\n1\n", 8, "unexpected end of file"),
            (
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n1 1 1 1\n2 1 3 1\n1 1 2 3 4\n$EndElements\n",
                6,
                "element type 3",
            ),
        ];
        for (text, line, needle) in cases {
            let err = parse::<2>(text).unwrap_err();
            let message = err.to_string();
            assert!(message.contains(needle), "{message}");
            if line > 0 {
                assert!(message.starts_with(&format!("inline.msh:{line}:")), "{message}");
            }
        }
        let missing = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0 0\n$EndNodes\n\
$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
        assert!(parse::<2>(missing).unwrap_err().to_string().contains("node 2"));
        let binary = b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n\xff\xfe\n";
        assert!(read::<2>(Path::new("b.msh"), binary).unwrap_err().to_string().contains("b.msh:5"));
    }

    #[test]
    fn writes_two_dimensional_meshes_in_the_plane() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let mut bytes = Vec::new();
        write(&mesh, &MeshData::new(), &mut bytes, Path::new("x.msh")).unwrap();
        let text = String::from_utf8(bytes).unwrap();
        assert!(text.contains("\n2 1 0 3\n") && text.contains("\n2 1 2 1\n1 1 2 3\n"), "{text}");
        assert_eq!(parse::<2>(&text).unwrap().0, mesh);
    }
}
