//! VTK XML unstructured grid (`.vtu`) through vtkio: inline base64 binary, f64 points (z = 0 in
//! 2D) and f64 scalar point / cell fields. The reader keeps the triangles (2D) or tetrahedra (3D)
//! of a single-piece grid and drops lower-dimensional cells with their cell data.

use std::io::Write;
use std::path::Path;

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer, Piece,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use super::{MeshData, assemble, write_error};
use crate::{Mesh, MeshError};

fn simplex_type(dim: usize) -> CellType {
    if dim == 2 { CellType::Triangle } else { CellType::Tetra }
}

/// Topological dimension of a VTK cell type.
fn cell_dim(t: CellType) -> usize {
    use CellType::*;
    match t {
        Vertex | PolyVertex => 0,
        Line | PolyLine | QuadraticEdge | CubicLine | ParametricCurve | HigherOrderEdge | LagrangeCurve
        | BezierCurve => 1,
        Triangle
        | TriangleStrip
        | Polygon
        | Pixel
        | Quad
        | QuadraticTriangle
        | QuadraticQuad
        | BiquadraticQuad
        | QuadraticLinearQuad
        | BiquadraticTriangle
        | ParametricSurface
        | ParametricTriSurface
        | ParametricQuadSurface
        | HigherOrderTriangle
        | HigherOrderQuad
        | HigherOrderPolygon
        | LagrangeTriangle
        | LagrangeQuadrilateral
        | BezierTriangle
        | BezierQuadrilateral => 2,
        _ => 3,
    }
}

pub(super) fn read<const D: usize>(path: &Path, bytes: &[u8]) -> Result<(Mesh<D>, MeshData), MeshError> {
    let format_error = |message: String| MeshError::Format { path: path.to_owned(), message };
    let vtk = Vtk::parse_xml(bytes).map_err(|e| format_error(format!("not a readable VTK XML file: {e}")))?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(format_error("not an UnstructuredGrid".into()));
    };
    let piece = match <[Piece<UnstructuredGridPiece>; 1]>::try_from(pieces) {
        Ok([Piece::Inline(piece)]) => *piece,
        Ok(_) => return Err(format_error("the piece is not inline (parallel files are not supported)".into())),
        Err(pieces) => return Err(format_error(format!("{} pieces, expected exactly one", pieces.len()))),
    };
    let UnstructuredGridPiece { points, cells, data } = piece;
    let Cells { cell_verts, types } = cells;
    let VertexNumbers::XML { connectivity, offsets } = cell_verts else {
        return Err(format_error("cells are not in XML layout".into()));
    };
    if offsets.len() != types.len() {
        return Err(format_error(format!("{} cell offsets but {} cell types", offsets.len(), types.len())));
    }
    let found = types.iter().map(|&t| cell_dim(t)).max().unwrap_or(0);
    if found != D {
        return Err(MeshError::DimensionMismatch { path: path.to_owned(), expected: D, found });
    }
    let mut kept = Vec::new();
    let mut cells = Vec::new();
    let mut start = 0usize;
    for (i, (&t, &end)) in types.iter().zip(&offsets).enumerate() {
        let end = end as usize;
        let nodes = connectivity
            .get(start..end)
            .ok_or_else(|| format_error(format!("cell {i} has offsets {start}..{end} outside the connectivity")))?;
        start = end;
        if cell_dim(t) < D {
            continue;
        }
        if t != simplex_type(D) || nodes.len() != D + 1 {
            return Err(format_error(format!("cell {i} is a {t:?}; only linear {D}D simplices are supported")));
        }
        kept.push(i);
        // Out-of-range indices become u32::MAX and are reported by `assemble`.
        cells.extend(nodes.iter().map(|&v| u32::try_from(v).unwrap_or(u32::MAX)));
    }

    let points: Vec<f64> = points.cast_into().ok_or_else(|| format_error("unreadable point coordinates".into()))?;
    if !points.len().is_multiple_of(3) {
        return Err(format_error(format!("{} point coordinates, not a multiple of 3", points.len())));
    }
    let vertices = points
        .chunks_exact(3)
        .enumerate()
        .map(|(i, p)| {
            if D == 2 && p[2] != 0.0 {
                Err(format_error(format!("point {i} has z = {}; a 2D mesh must lie in the plane z = 0", p[2])))
            } else {
                Ok(std::array::from_fn(|k| p[k]))
            }
        })
        .collect::<Result<Vec<[f64; D]>, _>>()?;

    let mut mesh_data = MeshData::new();
    let scalar_fields = |attributes: Vec<Attribute>, expected: usize, kind: &str| {
        let mut fields = Vec::new();
        for attribute in attributes {
            let Attribute::DataArray(DataArray { name, elem, data }) = attribute else { continue };
            if !matches!(elem, ElementType::Scalars { num_comp: 1, .. } | ElementType::Generic(1)) {
                continue;
            }
            let values: Vec<f64> =
                data.cast_into().ok_or_else(|| format_error(format!("{kind} field `{name}` is not numeric")))?;
            if values.len() != expected {
                return Err(MeshError::DataLength {
                    path: path.to_owned(),
                    field: format!("{kind} field `{name}`"),
                    len: values.len(),
                    expected,
                });
            }
            fields.push((name, values));
        }
        Ok(fields)
    };
    let Attributes { point, cell } = data;
    mesh_data.point.extend(scalar_fields(point, vertices.len(), "vertex")?);
    for (name, values) in scalar_fields(cell, types.len(), "element")? {
        mesh_data.cell.insert(name, kept.iter().map(|&i| values[i]).collect());
    }
    assemble(path, vertices, cells, mesh_data)
}

pub(super) fn write<const D: usize>(
    mesh: &Mesh<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    let points: Vec<f64> = mesh.vertices().iter().flat_map(|p| [p[0], p[1], if D == 3 { p[2] } else { 0.0 }]).collect();
    let n = (D + 1) as u64;
    let cells = Cells {
        cell_verts: VertexNumbers::XML {
            connectivity: mesh.cells().iter().map(|&v| u64::from(v)).collect(),
            offsets: (1..=mesh.num_elements() as u64).map(|e| e * n).collect(),
        },
        types: vec![simplex_type(D); mesh.num_elements()],
    };
    let scalars = |fields: &std::collections::BTreeMap<String, Vec<f64>>| {
        fields
            .iter()
            .map(|(name, values)| Attribute::DataArray(DataArray::scalars(name.as_str(), 1).with_data(values.clone())))
            .collect()
    };
    let vtk = Vtk {
        // Version 1.0 goes with the 64-bit block headers vtkio writes.
        version: Version::new((1, 0)),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: IOBuffer::F64(points),
            cells,
            data: Attributes { point: scalars(&data.point), cell: scalars(&data.cell) },
        }),
    };
    vtk.write_xml(&mut *w).map_err(|e| write_error(path)(std::io::Error::other(e.to_string())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh2;

    fn square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    fn to_text<const D: usize>(mesh: &Mesh<D>, data: &MeshData) -> String {
        let mut bytes = Vec::new();
        write(mesh, data, &mut bytes, Path::new("x.vtu")).unwrap();
        String::from_utf8(bytes).unwrap()
    }

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        read(Path::new("inline.vtu"), text.as_bytes())
    }

    #[test]
    fn writes_binary_f64_that_reads_back_exactly() {
        let mesh = square();
        let data =
            MeshData::new().with_cell("h", vec![0.1 + 0.2, 1.0 / 3.0]).with_point("u", vec![1e-300, 2.0, 3.0, 4.0]);
        let text = to_text(&mesh, &data);
        assert!(text.contains("format=\"binary\"") && text.contains("type=\"Float64\""), "{text}");
        assert_eq!(parse::<2>(&text).unwrap(), (mesh, data));
    }

    #[test]
    fn drops_lower_dimensional_cells_with_their_data() {
        // The same square with a boundary line cell added in front, as other tools write it.
        let text = to_text(&square(), &MeshData::new().with_cell("h", vec![1.0, 2.0]));
        let mut vtk = Vtk::parse_xml(text.as_bytes()).unwrap();
        let DataSet::UnstructuredGrid { pieces, .. } = &mut vtk.data else { unreachable!() };
        let Piece::Inline(piece) = &mut pieces[0] else { unreachable!() };
        piece.cells = Cells {
            cell_verts: VertexNumbers::XML { connectivity: vec![0, 1, 0, 1, 2, 0, 2, 3], offsets: vec![2, 5, 8] },
            types: vec![CellType::Line, CellType::Triangle, CellType::Triangle],
        };
        piece.data.cell = vec![Attribute::DataArray(DataArray::scalars("h", 1).with_data(vec![9.0, 1.0, 2.0]))];
        let mut bytes = Vec::new();
        vtk.write_xml(&mut bytes).unwrap();
        let (mesh, data) = read::<2>(Path::new("x.vtu"), &bytes).unwrap();
        assert_eq!(mesh, square());
        assert_eq!(data.cell["h"], vec![1.0, 2.0]);
        assert!(matches!(read::<3>(Path::new("x.vtu"), &bytes), Err(MeshError::DimensionMismatch { found: 2, .. })));
    }

    #[test]
    fn malformed_files_are_errors_not_panics() {
        let text = to_text(&square(), &MeshData::new().with_cell("h", vec![1.0, 2.0]));
        for cut in [0, 10, text.len() / 2, text.len() - 20] {
            let err = parse::<2>(&text[..cut]).unwrap_err();
            assert!(err.to_string().starts_with("inline.vtu: "), "{err}");
        }
        assert!(parse::<2>("<VTKFile type=\"PolyData\"></VTKFile>").is_err());
        let garbles = [
            (">YAAAAAAAAAA", ">YAAAA!!AAAA"), // not base64
            ("NumberOfPoints=\"4\"", "NumberOfPoints=\"5\""),
            ("NumberOfCells=\"2\"", "NumberOfCells=\"x\""),
            ("AgAAAAAAAAAFBQ==", "AgAAAAAAAAAFCg=="), // a tetrahedron among the triangles
            ("AgAAAAAAAAAFBQ==", "AgAAAAAAAAAFCQ=="), // a quad
            ("EAAAAAAAAAADAAAAAAAAAAYAAAAAAAAA", "EAAAAAAAAAADAAAAAAAAAAcAAAAAAAAA"), // offsets past the end
        ];
        for (from, to) in garbles {
            assert!(text.contains(from), "{from}");
            let result = parse::<2>(&text.replacen(from, to, 1));
            assert!(result.is_err(), "{to}: {result:?}");
        }
        // Points replaced by two coordinates (the payload of "h").
        let start = text.find("NumberOfComponents=\"3\">").unwrap() + 23;
        let end = start + text[start..].find('<').unwrap();
        let short = format!("{}EAAAAAAAAAAAAAAAAADwPwAAAAAAAABA{}", &text[..start], &text[end..]);
        let err = parse::<2>(&short).unwrap_err();
        assert!(err.to_string().contains("SizeMismatch"), "{err}");
    }
}
