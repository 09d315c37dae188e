//! JSON: `{"dimension": 2, "vertices": [[x, y], ...], "elements": [[a, b, c], ...]}`, plus
//! optional `"cell_data"` / `"point_data"` objects of named value arrays. Floats are written in
//! their shortest round-trip form and parsed exactly (serde_json `float_roundtrip`).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize, Serializer};

use super::{MeshData, assemble, write_error};
use crate::{Mesh, MeshError};

#[derive(Deserialize)]
struct JsonMesh {
    dimension: usize,
    vertices: Vec<Vec<f64>>,
    elements: Vec<Vec<u32>>,
    #[serde(default)]
    cell_data: BTreeMap<String, Vec<f64>>,
    #[serde(default)]
    point_data: BTreeMap<String, Vec<f64>>,
}

/// The same layout, borrowed from a mesh for writing.
#[derive(Serialize)]
struct JsonMeshRef<'a> {
    dimension: usize,
    vertices: Rows<'a, f64>,
    elements: Rows<'a, u32>,
    #[serde(skip_serializing_if = "is_empty")]
    cell_data: &'a BTreeMap<String, Vec<f64>>,
    #[serde(skip_serializing_if = "is_empty")]
    point_data: &'a BTreeMap<String, Vec<f64>>,
}

fn is_empty(fields: &&BTreeMap<String, Vec<f64>>) -> bool {
    fields.is_empty()
}

/// A flat slice serialised as rows of `width` values (serde has no impl for `[T; D]` with a
/// generic `D`).
struct Rows<'a, T>(&'a [T], usize);

impl<T: Serialize> Serialize for Rows<'_, T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.0.chunks_exact(self.1))
    }
}

pub(super) fn read<const D: usize>(path: &Path, bytes: &[u8]) -> Result<(Mesh<D>, MeshData), MeshError> {
    let json: JsonMesh = serde_json::from_slice(bytes).map_err(|e| MeshError::Parse {
        path: path.to_owned(),
        line: e.line(),
        message: e.to_string(),
    })?;
    if json.dimension != D {
        return Err(MeshError::DimensionMismatch { path: path.to_owned(), expected: D, found: json.dimension });
    }
    let format_error = |message: String| MeshError::Format { path: path.to_owned(), message };
    let vertices = json
        .vertices
        .iter()
        .enumerate()
        .map(|(i, p)| {
            <[f64; D]>::try_from(p.as_slice())
                .map_err(|_| format_error(format!("vertex {i} has {} coordinates, expected {D}", p.len())))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut cells = Vec::with_capacity(json.elements.len() * (D + 1));
    for (i, element) in json.elements.iter().enumerate() {
        if element.len() != D + 1 {
            return Err(format_error(format!("element {i} has {} vertices, expected {}", element.len(), D + 1)));
        }
        cells.extend_from_slice(element);
    }
    assemble(path, vertices, cells, MeshData { cell: json.cell_data, point: json.point_data, ..MeshData::default() })
}

pub(super) fn write<const D: usize>(
    mesh: &Mesh<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    // serde_json would write NaN and infinities as `null`, which does not read back.
    for (name, values) in data.cell.iter().chain(&data.point) {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(MeshError::Format {
                path: path.to_owned(),
                message: format!("field `{name}` has the non-finite value {} at {i}; JSON cannot store it", values[i]),
            });
        }
    }
    let json = JsonMeshRef {
        dimension: D,
        vertices: Rows(mesh.vertices().as_flattened(), D),
        elements: Rows(mesh.cells(), D + 1),
        cell_data: &data.cell,
        point_data: &data.point,
    };
    serde_json::to_writer(&mut *w, &json).map_err(|e| write_error(path)(e.into()))?;
    writeln!(w).map_err(write_error(path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, Mesh3};

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        read(Path::new("inline.json"), text.as_bytes())
    }

    #[test]
    fn reads_the_documented_layout_and_reorients() {
        let (mesh, data) =
            parse::<2>(r#"{"dimension": 2, "vertices": [[0, 0], [1, 0], [0, 1]], "elements": [[0, 2, 1]]}"#).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert!(mesh.volume(0) > 0.0);
        assert!(data.is_empty());
    }

    #[test]
    fn floats_round_trip_bit_exactly() {
        let awkward = [0.1 + 0.2, 1.0 / 3.0, 2f64.sqrt(), 1e-300, 5e-324, 1.7976931348623157e308, -0.0, 123456.789e-20];
        let vertices =
            vec![[awkward[0], awkward[1], 0.0], [1.0, awkward[3], awkward[2]], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let mesh = Mesh3::new_reoriented(vertices, vec![0, 1, 2, 3]).unwrap();
        let data = MeshData::new().with_cell("h", vec![awkward[7]]).with_point("u", awkward[3..7].to_vec());
        let mut bytes = Vec::new();
        write(&mesh, &data, &mut bytes, Path::new("x.json")).unwrap();
        let (back, back_data) = parse::<3>(std::str::from_utf8(&bytes).unwrap()).unwrap();
        let bits = |m: &Mesh3| m.vertices().as_flattened().iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&mesh));
        assert_eq!(back.cells(), mesh.cells());
        let data_bits = |d: &MeshData| d.point["u"].iter().chain(&d.cell["h"]).map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(data_bits(&back_data), data_bits(&data));
    }

    #[test]
    fn malformed_files_are_errors() {
        let err =
            parse::<2>("{\"dimension\": 2,\n \"vertices\": [[0, 0], [1, 0]],\n \"elements\": [[0, 1").unwrap_err();
        assert!(err.to_string().starts_with("inline.json:3:"), "{err}");
        let err = parse::<2>(r#"{"dimension": 3, "vertices": [], "elements": []}"#).unwrap_err();
        assert!(matches!(err, MeshError::DimensionMismatch { expected: 2, found: 3, .. }), "{err}");
        let err = parse::<2>(r#"{"dimension": 2, "vertices": [[0, 0, 0]], "elements": []}"#).unwrap_err();
        assert!(err.to_string().contains("vertex 0 has 3 coordinates"), "{err}");
        let err = parse::<2>(r#"{"dimension": 2, "vertices": [[0, 0]], "elements": [[0, 0]]}"#).unwrap_err();
        assert!(err.to_string().contains("element 0 has 2 vertices"), "{err}");
        let err = parse::<2>(r#"{"dimension": 2, "vertices": [[0, 0]], "elements": [[0, 1, 2]]}"#).unwrap_err();
        assert!(matches!(err, MeshError::InvalidMesh { .. }), "{err}");
        let err = parse::<2>(r#"{"dimension": 2, "vertices": [[0, "a"]], "elements": []}"#).unwrap_err();
        assert!(matches!(err, MeshError::Parse { line: 1, .. }), "{err}");
        let text = r#"{"dimension": 2, "vertices": [[0, 0], [1, 0], [0, 1]], "elements": [[0, 1, 2]], "cell_data": {"h": [1, 2]}}"#;
        assert!(matches!(parse::<2>(text), Err(MeshError::DataLength { len: 2, expected: 1, .. })));
    }

    #[test]
    fn non_finite_fields_are_refused() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let data = MeshData::new().with_cell("h", vec![f64::INFINITY]);
        let err = write(&mesh, &data, &mut Vec::new(), Path::new("x.json")).unwrap_err();
        assert!(err.to_string().contains("field `h`"), "{err}");
    }
}
