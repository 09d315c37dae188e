//! Wavefront OBJ (`.obj`) → triangle soup: `v` and `f` lines, polygons fanned into triangles (so
//! they must be convex), each `g`/`o` group a face id, 1-based in order of appearance. Texture
//! and normal indices of face corners are skipped; every other line is ignored.

use std::collections::HashMap;
use std::path::Path;

use super::{TriangleSoup, parse_point};
use crate::MeshError;

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<TriangleSoup, MeshError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| MeshError::Format { path: path.to_owned(), message: format!("OBJ is not valid UTF-8: {e}") })?;
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut corners = Vec::new();
    let mut ids = Vec::new();
    let mut group_ids: HashMap<String, i32> = HashMap::new();
    let mut group = String::new();
    for (number, line) in text.lines().enumerate() {
        let at = |message| MeshError::Parse { path: path.to_owned(), line: number + 1, message };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => vertices.push(parse_point(words).map_err(at)?),
            Some("g" | "o") => group = words.collect::<Vec<_>>().join(" "),
            Some("f") => {
                let polygon = words.map(|w| index(w, vertices.len())).collect::<Result<Vec<_>, _>>().map_err(at)?;
                if polygon.len() < 3 {
                    return Err(at(format!("face with {} vertices", polygon.len())));
                }
                let next_id = group_ids.len() as i32 + 1;
                let id = *group_ids.entry(group.clone()).or_insert(next_id);
                for k in 1..polygon.len() - 1 {
                    corners.extend([polygon[0], polygon[k], polygon[k + 1]].map(|v| vertices[v]));
                    ids.push(id);
                }
            }
            _ => {}
        }
    }
    let face_names = group_ids.into_iter().filter(|(name, _)| !name.is_empty()).map(|(name, id)| (id, name)).collect();
    Ok(TriangleSoup { corners, face_ids: ids, face_names })
}

/// A face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`; 1-based, negative counts back from the end.
fn index(word: &str, num_vertices: usize) -> Result<usize, String> {
    let v = word.split('/').next().unwrap_or(word);
    let i: i64 = v.parse().map_err(|_| format!("`{word}` is not a vertex index"))?;
    let index = if i < 0 { num_vertices as i64 + i } else { i - 1 };
    if (0..num_vertices as i64).contains(&index) {
        Ok(index as usize)
    } else {
        Err(format!("vertex index {i} out of range (1..={num_vertices})"))
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// The unit cube of quads in three groups, written every way OBJ allows; 'top' is inside out.
    pub(in crate::io) const CUBE_OBJ: &str = "# unit cube of quads in three groups; 'top' is inside out\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
        g bottom\nf 1 4 3 2\ng top\nf 5 8 7 6\n\
        g sides\nf 1 2 6 5\nf 2/1 3/2 7/3 6/4\nf 3//1 4//1 8//1 7//1\nf -1 -5 -8 -4\n";

    #[test]
    fn quads_are_fanned_and_groups_become_face_ids() {
        let soup = read(Path::new("cube.obj"), CUBE_OBJ.as_bytes()).unwrap();
        assert_eq!(soup.corners.len(), 36);
        assert_eq!(soup.face_ids, [1, 1, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3]);
        let names = soup.face_names.values().map(String::as_str).collect::<Vec<_>>();
        assert_eq!(names, ["bottom", "top", "sides"]);
        let [v1, v2, v3, v4, v5, _, _, v8] = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        // `f 1 4 3 2` → (1, 4, 3), (1, 3, 2); `f -1 -5 -8 -4` is `f 8 4 1 5`.
        assert_eq!(soup.corners[..6], [v1, v4, v3, v1, v3, v2]);
        assert_eq!(soup.corners[30..], [v8, v4, v1, v8, v1, v5]);
    }

    #[test]
    fn malformed_obj_errors_name_the_file_and_line() {
        let path = Path::new("bad.obj");
        let err = read(path, b"v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(err, MeshError::Parse { line: 3, .. }), "{err}");
        assert_eq!(err.to_string(), "bad.obj:3: vertex index 3 out of range (1..=2)");
        let err = read(path, b"v 0 0\n").unwrap_err();
        assert_eq!(err.to_string(), "bad.obj:1: expected 3 coordinates");
        let err = read(path, b"v 0 0 0\nf 1 1/x\n").unwrap_err();
        assert_eq!(err.to_string(), "bad.obj:2: face with 2 vertices");
        assert!(matches!(read(path, &[0xff, 0xfe]), Err(MeshError::Format { .. })));
    }
}
