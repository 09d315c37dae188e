//! Legacy VTK (`.vtk`) unstructured grids, ASCII or binary (big-endian), in both cell layouts:
//! `CELLS n size` with a count before every cell (versions up to 4.2, as gmsh writes) and
//! `OFFSETS` / `CONNECTIVITY` (5.1, as VTK 9 and meshio write). Scalar `SCALARS` and one-component
//! `FIELD` arrays are read as fields; vectors, normals, tensors, colours and `METADATA` are
//! skipped. The writer writes version 2.0 (which gmsh, meshio and VTK all read) with the fields as
//! `SCALARS`.

use std::io::Write;
use std::path::Path;

use super::cursor::{Cursor, Number, Scalar, as_index};
use super::nodes::Nodes;
use super::raw::{Kind, RawMesh};
use super::{MeshData, write_error};
use crate::MeshError;

/// The kind of a VTK cell type code (shared with `.vtu`).
pub(super) fn vtk_kind(code: u8) -> Option<Kind> {
    let other = |dim, name| Some(Kind { dim, name });
    match code {
        1 => Some(Kind::VERTEX),
        2 => other(0, "polyvertex"),
        3 => Some(Kind::LINE),
        4 => other(1, "polyline"),
        5 => Some(Kind::TRIANGLE),
        6 => other(2, "triangle_strip"),
        7 => other(2, "polygon"),
        8 => other(2, "pixel"),
        9 => other(2, "quad"),
        10 => Some(Kind::TETRA),
        11 => other(3, "voxel"),
        12 => other(3, "hexahedron"),
        13 => other(3, "wedge"),
        14 => other(3, "pyramid"),
        15 => other(3, "pentagonal_prism"),
        16 => other(3, "hexagonal_prism"),
        21 => Some(Kind::LINE3),
        22 => Some(Kind::TRIANGLE6),
        23 => other(2, "quad8"),
        24 => Some(Kind::TETRA10),
        25 => other(3, "hexahedron20"),
        26 => other(3, "wedge15"),
        27 => other(3, "pyramid13"),
        28 => other(2, "quad9"),
        29 => other(3, "hexahedron27"),
        34 => other(2, "triangle7"),
        35 => other(1, "line4"),
        42 => other(3, "polyhedron"),
        68 => other(1, "lagrange_curve"),
        69 => other(2, "lagrange_triangle"),
        70 => other(2, "lagrange_quadrilateral"),
        71 => other(3, "lagrange_tetrahedron"),
        72 => other(3, "lagrange_hexahedron"),
        73 => other(3, "lagrange_wedge"),
        74 => other(3, "lagrange_pyramid"),
        _ => None,
    }
}

/// Reads `count` numbers of legacy type `ty`: words in ASCII, big-endian values in binary.
fn numbers(c: &mut Cursor, binary: bool, ty: Scalar, count: u64, what: &str) -> Result<Vec<f64>, MeshError> {
    let n = c.bound(count, if binary { ty.size() } else { 2 }, what)?;
    if binary { c.values(ty, n, what) } else { (0..n).map(|_| c.parse::<f64>(what)).collect() }
}

/// The next word as a legacy data type name.
fn type_word(c: &mut Cursor, what: &str) -> Result<Scalar, MeshError> {
    let name = c.expect_word(what)?;
    Scalar::from_vtk_legacy(name).ok_or_else(|| c.error(format!("data type `{name}` is not supported")))
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut c = Cursor::new(path, bytes);
    c.big_endian = true;
    let first = c.expect_line("the `# vtk DataFile` line")?;
    if !first.starts_with("# vtk DataFile") {
        return Err(c.error("not a legacy VTK file: it must start with `# vtk DataFile`"));
    }
    c.expect_line("the title")?;
    let binary = match c.expect_line("ASCII or BINARY")?.trim().to_ascii_uppercase().as_str() {
        "ASCII" => false,
        "BINARY" => true,
        other => return Err(c.error(format!("expected ASCII or BINARY, found `{other}`"))),
    };
    let mut raw = RawMesh::default();
    let mut types: Option<Vec<f64>> = None;
    // Which data section the arrays belong to: (cell data?, count).
    let mut section: Option<(bool, usize)> = None;
    while let Some(keyword) = c.word()? {
        match keyword.to_ascii_uppercase().as_str() {
            "DATASET" => {
                let kind = c.expect_word("the dataset type")?;
                if !kind.eq_ignore_ascii_case("UNSTRUCTURED_GRID") {
                    return Err(c.error(format!("a {kind} dataset, not an UNSTRUCTURED_GRID")));
                }
            }
            "POINTS" => {
                let n: u64 = c.parse("number of points")?;
                let ty = type_word(&mut c, "the point type")?;
                c.skip_line();
                let xyz = numbers(&mut c, binary, ty, n.saturating_mul(3), "point coordinates")?;
                raw.points = xyz.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            }
            "CELLS" => {
                let n: u64 = c.parse("number of cells")?;
                let size: u64 = c.parse("cell list size")?;
                c.skip_line();
                let save = c.pos;
                if c.word().ok().flatten() == Some("OFFSETS") {
                    let ty = type_word(&mut c, "the offsets type")?;
                    c.skip_line();
                    let offsets = numbers(&mut c, binary, ty, n, "offsets")?;
                    if c.expect_word("CONNECTIVITY")? != "CONNECTIVITY" {
                        return Err(c.error("expected CONNECTIVITY after the offsets"));
                    }
                    let ty = type_word(&mut c, "the connectivity type")?;
                    c.skip_line();
                    let connectivity = numbers(&mut c, binary, ty, size, "connectivity")?;
                    raw.nodes = to_indices(&c, &connectivity)?;
                    for &end in offsets.iter().skip(1) {
                        let end = as_index(end).map(|e| e as usize).filter(|&e| e <= raw.nodes.len());
                        let previous = raw.ends.last().copied().unwrap_or(0);
                        raw.ends
                            .push(end.filter(|&e| e >= previous).ok_or_else(|| c.error("offsets are not increasing"))?);
                    }
                } else {
                    c.pos = save;
                    let list = numbers(&mut c, binary, Scalar::I32, size, "cell list")?;
                    let mut rest = &list[..];
                    for _ in 0..n {
                        let (&k, tail) =
                            rest.split_first().ok_or_else(|| c.error("the cell list is shorter than its cells"))?;
                        let k = as_index(k).map(|k| k as usize).filter(|&k| k <= tail.len());
                        let k = k.ok_or_else(|| c.error("a cell's node count runs past the cell list"))?;
                        raw.nodes.extend(to_indices(&c, &tail[..k])?);
                        raw.ends.push(raw.nodes.len());
                        rest = &tail[k..];
                    }
                }
            }
            "CELL_TYPES" => {
                let n: u64 = c.parse("number of cell types")?;
                c.skip_line();
                types = Some(numbers(&mut c, binary, Scalar::I32, n, "cell types")?);
            }
            "CELL_DATA" | "POINT_DATA" => {
                let on_cells = keyword.eq_ignore_ascii_case("CELL_DATA");
                section = Some((on_cells, c.parse("number of values")?));
            }
            "SCALARS" => {
                let name = c.expect_word("the array name")?.to_owned();
                let ty = type_word(&mut c, "the array type")?;
                let rest = c.expect_line("the end of the SCALARS line")?;
                let components: u64 = rest.trim().parse().unwrap_or(1);
                let lookup = c.expect_word("LOOKUP_TABLE")?;
                if !lookup.eq_ignore_ascii_case("LOOKUP_TABLE") {
                    return Err(c.error(format!("expected LOOKUP_TABLE, found `{lookup}`")));
                }
                c.skip_line();
                store(&mut c, &mut raw, section, binary, ty, name, components)?;
            }
            "FIELD" => {
                c.expect_word("the field name")?;
                let arrays: u64 = c.parse("number of arrays")?;
                for _ in 0..c.bound(arrays, 8, "arrays")? {
                    let name = c.expect_word("the array name")?.to_owned();
                    let components: u64 = c.parse("number of components")?;
                    let tuples: u64 = c.parse("number of tuples")?;
                    let ty = type_word(&mut c, "the array type")?;
                    c.skip_line();
                    let in_section = section.filter(|&(_, n)| n as u64 == tuples);
                    store(&mut c, &mut raw, in_section, binary, ty, name, components)?;
                    skip_metadata(&mut c)?;
                }
            }
            "VECTORS" | "NORMALS" | "TENSORS" => {
                c.expect_word("the array name")?;
                let ty = type_word(&mut c, "the array type")?;
                c.skip_line();
                let per = if keyword.eq_ignore_ascii_case("TENSORS") { 9 } else { 3 };
                let n = section.map_or(0, |(_, n)| n as u64);
                numbers(&mut c, binary, ty, n.saturating_mul(per), "vector values")?;
            }
            "METADATA" => {
                c.skip_line();
                while !c.expect_line("the end of METADATA")?.trim().is_empty() {}
            }
            other => return Err(c.error(format!("unknown keyword `{other}`"))),
        }
    }
    let types = types.ok_or_else(|| c.error("no CELL_TYPES"))?;
    if types.len() != raw.ends.len() {
        return Err(c.error(format!("{} cell types for {} cells", types.len(), raw.ends.len())));
    }
    for t in types {
        let kind = as_index(t).and_then(|t| u8::try_from(t).ok()).and_then(vtk_kind);
        raw.kinds.push(kind.ok_or_else(|| c.error(format!("unknown cell type {t}")))?);
    }
    Ok(raw)
}

/// `METADATA` may follow a field array in 5.1 files.
fn skip_metadata(c: &mut Cursor) -> Result<(), MeshError> {
    let save = c.pos;
    if c.word().ok().flatten() == Some("METADATA") {
        c.skip_line();
        while !c.expect_line("the end of METADATA")?.trim().is_empty() {}
    } else {
        c.pos = save;
    }
    Ok(())
}

/// Reads an array and keeps it as a field when it is a scalar of the current section.
fn store(
    c: &mut Cursor,
    raw: &mut RawMesh,
    section: Option<(bool, usize)>,
    binary: bool,
    ty: Scalar,
    name: String,
    components: u64,
) -> Result<(), MeshError> {
    let n = section.map_or(0, |(_, n)| n as u64);
    let values = numbers(c, binary, ty, n.saturating_mul(components), "data values")?;
    if let Some((on_cells, _)) = section
        && components == 1
    {
        if on_cells {
            raw.cell_data.insert(name, values)
        } else {
            raw.point_data.insert(name, values)
        };
    }
    Ok(())
}

fn to_indices(c: &Cursor, values: &[f64]) -> Result<Vec<u32>, MeshError> {
    values.iter().map(|&v| as_index(v).ok_or_else(|| c.error(format!("{v} is not a point index")))).collect()
}

pub(super) fn write<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    binary: bool,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    if let Some(name) =
        data.cell.keys().chain(data.point.keys()).find(|n| n.is_empty() || n.contains(char::is_whitespace))
    {
        let message = format!("field name {name:?}: legacy VTK names cannot be empty or contain whitespace");
        return Err(MeshError::Format { path: path.to_owned(), message });
    }
    write_body(nodes, data, binary, w).map_err(write_error(path))
}

/// The VTK cell type of a simplex of `dimension`, linear or quadratic.
pub(super) fn cell_type(dimension: usize, quadratic: bool) -> u8 {
    match (dimension, quadratic) {
        (2, false) => 5,
        (2, true) => 22,
        (_, false) => 10,
        (_, true) => 24,
    }
}

fn write_body<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    binary: bool,
    w: &mut impl Write,
) -> std::io::Result<()> {
    let (np, ne, per_element) = (nodes.num_points(), nodes.mesh().num_elements(), nodes.nodes_per_element());
    let encoding = if binary { "BINARY" } else { "ASCII" };
    writeln!(w, "# vtk DataFile Version 2.0\namber mesh\n{encoding}\nDATASET UNSTRUCTURED_GRID")?;
    writeln!(w, "POINTS {np} double")?;
    let points = nodes.points().flat_map(|p| [p[0], p[1], if D == 3 { p[2] } else { 0.0 }]);
    values(w, binary, points, 3)?;
    writeln!(w, "CELLS {ne} {}", ne * (per_element + 1))?;
    let cells =
        nodes.elements().flat_map(|cell| std::iter::once(per_element as i32).chain(cell.into_iter().map(|v| v as i32)));
    values(w, binary, cells, per_element + 1)?;
    writeln!(w, "CELL_TYPES {ne}")?;
    values(w, binary, std::iter::repeat_n(i32::from(cell_type(D, nodes.is_quadratic())), ne), 1)?;
    if !data.cell.is_empty() {
        writeln!(w, "CELL_DATA {ne}")?;
    }
    for (name, field) in &data.cell {
        writeln!(w, "SCALARS {name} {} 1\nLOOKUP_TABLE default", f64::LEGACY)?;
        values(w, binary, field.iter().copied(), 1)?;
    }
    if !data.point.is_empty() {
        writeln!(w, "POINT_DATA {np}")?;
    }
    for (name, field) in &data.point {
        writeln!(w, "SCALARS {name} {} 1\nLOOKUP_TABLE default", f64::LEGACY)?;
        values(w, binary, nodes.point_field(field).into_iter(), 1)?;
    }
    Ok(())
}

/// Numbers as big-endian binary followed by a newline, or as text, `per_line` to a line.
fn values<T: Number>(
    w: &mut impl Write,
    binary: bool,
    items: impl Iterator<Item = T>,
    per_line: usize,
) -> std::io::Result<()> {
    if binary {
        let mut bytes = Vec::new();
        for v in items {
            v.put(true, &mut bytes);
        }
        w.write_all(&bytes)?;
        return writeln!(w);
    }
    for (i, v) in items.enumerate() {
        let end = if (i + 1) % per_line == 0 { "\n" } else { " " };
        write!(w, "{v:?}{end}")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;
    use crate::io::ElementOrder;
    use crate::{Mesh2, Mesh3};

    fn parse<const D: usize>(bytes: &[u8]) -> Result<(Mesh<D>, MeshData), MeshError> {
        let path = Path::new("inline.vtk");
        read(path, bytes)?.finish(path)
    }

    #[test]
    fn round_trips_in_both_encodings() {
        let mesh = Mesh3::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0 / 3.0]],
            vec![0, 1, 2, 3],
        )
        .unwrap();
        let data = MeshData::new().with_cell("h", vec![0.1 + 0.2]).with_point("u", vec![1.0, 2.0, 3.0, -0.5]);
        for binary in [false, true] {
            let mut bytes = Vec::new();
            write(&Nodes::new(&mesh, ElementOrder::Linear), &data, binary, &mut bytes, Path::new("x.vtk")).unwrap();
            assert_eq!(parse::<3>(&bytes).unwrap(), (mesh.clone(), data.clone()));
        }
        let err = write(
            &Nodes::new(&mesh, ElementOrder::Linear),
            &MeshData::new().with_cell("a b", vec![1.0]),
            false,
            &mut Vec::new(),
            Path::new("x.vtk"),
        );
        assert!(err.unwrap_err().to_string().contains("whitespace"));
    }

    /// Version 5.1 as VTK 9 writes it, with a boundary line, a FIELD array and METADATA.
    #[test]
    fn reads_the_offsets_layout_of_version_5_1() {
        let text = "# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET UNSTRUCTURED_GRID\n\
POINTS 3 float\n0 0 0 1 0 0 0 1 0\nMETADATA\nINFORMATION 0\n\n\
CELLS 3 5\nOFFSETS vtktypeint64\n0 2 5\nCONNECTIVITY vtktypeint64\n0 1 0 1 2\n\
CELL_TYPES 2\n3\n5\n\nCELL_DATA 2\nFIELD FieldData 1\nsize 1 2 double\n7 0.5\nMETADATA\nINFORMATION 0\n\n";
        let (mesh, data) = parse::<2>(text.as_bytes()).unwrap();
        assert_eq!(mesh, Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap());
        assert_eq!(data.cell["size"], vec![0.5]);
        assert_eq!(data.dropped["line"], 1);
    }

    #[test]
    fn malformed_files_name_the_line_or_byte() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let mut bytes = Vec::new();
        write(
            &Nodes::new(&mesh, ElementOrder::Linear),
            &MeshData::new().with_cell("h", vec![1.0]),
            true,
            &mut bytes,
            Path::new("x.vtk"),
        )
        .unwrap();
        for cut in 0..bytes.len() - 1 {
            if let Err(err) = parse::<2>(&bytes[..cut]) {
                assert!(err.to_string().starts_with("inline.vtk"), "{err}");
            }
        }
        let cases = [
            ("# vtk DataFile Version 2.0\nt\nASCII\nDATASET POLYDATA\n", "POLYDATA"),
            (
                "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1 double\n0 0 x\n",
                "inline.vtk:6",
            ),
            (
                "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 99999 double\n0 0\n",
                "announced",
            ),
            (
                "# vtk DataFile Version 2.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n99\n",
                "type 99",
            ),
            ("hello\n", "not a legacy VTK"),
        ];
        for (text, needle) in cases {
            let message = parse::<2>(text.as_bytes()).unwrap_err().to_string();
            assert!(message.contains(needle), "{message}");
        }
    }
}
