//! STL (`.stl`) → triangle soup: binary STL (a facet count after the 80-byte header, 50 bytes
//! per facet) when the file size matches that count, ASCII STL (`solid` … `endsolid`) otherwise.
//! The per-facet normals are skipped; face ids come from the binary facet attribute or the
//! ASCII `solid` block, or are all 1 ([`StlFaceIds`]).

use std::collections::BTreeMap;
use std::path::Path;

use super::{StlFaceIds, TriangleSoup, parse_point};
use crate::MeshError;

pub(super) fn read(path: &Path, bytes: &[u8], face_ids: StlFaceIds) -> Result<TriangleSoup, MeshError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() as u64 == 84 + 50 * n as u64 {
            return Ok(read_binary(&bytes[84..], n, face_ids));
        }
    }
    let format_error = |message| MeshError::Format { path: path.to_owned(), message };
    if bytes.trim_ascii_start().starts_with(b"solid") {
        let text =
            std::str::from_utf8(bytes).map_err(|e| format_error(format!("ASCII STL is not valid UTF-8: {e}")))?;
        return read_ascii(path, text, face_ids);
    }
    Err(format_error(format!(
        "not an STL file: {} bytes match no binary facet count and the text does not start with `solid`",
        bytes.len()
    )))
}

fn read_binary(facets: &[u8], n: usize, face_ids: StlFaceIds) -> TriangleSoup {
    let f32_at = |b: &[u8], i: usize| f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]) as f64;
    let mut corners = Vec::with_capacity(3 * n);
    let mut ids = Vec::with_capacity(n);
    for facet in facets.chunks_exact(50) {
        // Bytes 0..12 hold the normal, which is recomputed from the corners when needed.
        for k in 0..3 {
            let at = 12 + 12 * k;
            corners.push([f32_at(facet, at), f32_at(facet, at + 4), f32_at(facet, at + 8)]);
        }
        ids.push(match face_ids {
            StlFaceIds::FromFile => u16::from_le_bytes([facet[48], facet[49]]) as i32,
            StlFaceIds::Single => 1,
        });
    }
    TriangleSoup { corners, face_ids: ids, face_names: BTreeMap::new() }
}

fn read_ascii(path: &Path, text: &str, face_ids: StlFaceIds) -> Result<TriangleSoup, MeshError> {
    let mut corners = Vec::new();
    let mut ids = Vec::new();
    let mut solid = 0;
    let mut face_names = BTreeMap::new();
    let mut facet: Vec<[f64; 3]> = Vec::with_capacity(3);
    for (number, line) in text.lines().enumerate() {
        let at = |message| MeshError::Parse { path: path.to_owned(), line: number + 1, message };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("solid") => {
                solid += 1;
                let name = words.collect::<Vec<_>>().join(" ");
                if face_ids == StlFaceIds::FromFile && !name.is_empty() {
                    face_names.insert(solid, name);
                }
            }
            Some("facet") => facet.clear(),
            Some("vertex") => facet.push(parse_point(words).map_err(at)?),
            Some("endfacet") => {
                if facet.len() != 3 {
                    return Err(at(format!("facet with {} vertices (only triangles are supported)", facet.len())));
                }
                corners.append(&mut facet);
                ids.push(if face_ids == StlFaceIds::FromFile { solid } else { 1 });
            }
            _ => {}
        }
    }
    Ok(TriangleSoup { corners, face_ids: ids, face_names })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::obj;

    /// Binary STL bytes of the given triangles with the given attributes.
    fn binary_stl(corners: &[[f64; 3]], attributes: &[u16]) -> Vec<u8> {
        let mut bytes = vec![b' '; 80];
        bytes.extend((attributes.len() as u32).to_le_bytes());
        for (t, a) in attributes.iter().enumerate() {
            bytes.extend([0u8; 12]);
            for p in &corners[3 * t..3 * t + 3] {
                p.iter().for_each(|&x| bytes.extend((x as f32).to_le_bytes()));
            }
            bytes.extend(a.to_le_bytes());
        }
        bytes
    }

    #[test]
    fn binary_and_ascii_stl_carry_face_ids() {
        let path = Path::new("cube.stl");
        let corners = obj::read(path, obj::tests::CUBE_OBJ.as_bytes()).unwrap().corners;
        let attributes: Vec<u16> = (0..12).map(|t| t / 2 + 1).collect();
        let soup = read(path, &binary_stl(&corners, &attributes), StlFaceIds::FromFile).unwrap();
        let expected_ids: Vec<i32> = attributes.iter().map(|&a| a as i32).collect();
        assert_eq!(
            soup,
            TriangleSoup { corners: corners.clone(), face_ids: expected_ids, face_names: BTreeMap::new() }
        );
        let single = read(path, &binary_stl(&corners, &attributes), StlFaceIds::Single).unwrap();
        assert!(single.face_ids.iter().all(|&i| i == 1));
        let mut ascii = String::from("solid a\n");
        for (t, tri) in corners.chunks(3).enumerate() {
            if t == 6 {
                ascii += "endsolid a\nsolid b\n";
            }
            ascii += "  facet normal 0 0 0\n    outer loop\n";
            tri.iter().for_each(|p| ascii += &format!("      vertex {} {} {}\n", p[0], p[1], p[2]));
            ascii += "    endloop\n  endfacet\n";
        }
        ascii += "endsolid b\n";
        let soup = read(path, ascii.as_bytes(), StlFaceIds::FromFile).unwrap();
        assert_eq!(soup.corners, corners);
        assert_eq!(soup.face_ids, [1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2]);
        assert_eq!(soup.face_names, BTreeMap::from([(1, "a".into()), (2, "b".into())]));
        assert!(read(path, ascii.as_bytes(), StlFaceIds::Single).unwrap().face_names.is_empty());
    }

    #[test]
    fn malformed_stl_errors_name_the_file_and_line() {
        let path = Path::new("bad.stl");
        let quad = "solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n\
            endloop\nendfacet\nendsolid q\n";
        let err = read(path, quad.as_bytes(), StlFaceIds::FromFile).unwrap_err();
        assert!(matches!(err, MeshError::Parse { line: 9, .. }), "{err}");
        assert!(err.to_string().starts_with("bad.stl:9: facet with 4 vertices"), "{err}");
        let err = read(path, b"solid q\nvertex 0 x 0\n", StlFaceIds::FromFile).unwrap_err();
        assert!(err.to_string().starts_with("bad.stl:2: `x` is not a number"), "{err}");
        let err = read(path, &[7; 100], StlFaceIds::FromFile).unwrap_err();
        assert!(matches!(err, MeshError::Format { .. }) && err.to_string().contains("not an STL file"), "{err}");
    }
}
