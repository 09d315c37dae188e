//! medit / INRIA `.mesh` (ASCII): `Vertices`, `Edges`, `Triangles`, `Quadrilaterals`,
//! `Tetrahedra`, `Hexahedra`, `Prisms`, `Pyramids` with a reference per entry (the reference of a
//! facet becomes its facet tag; 0 means none), and the index-only sections (`Corners`, `Ridges`,
//! `Required*`, `Normals`, ...) skipped. The writer writes the vertices, the tagged facets (the
//! boundary in reference 1 unless the caller tagged facets) and the elements in reference 1.

use std::io::Write;
use std::path::Path;

use super::cursor::Cursor;
use super::raw::{Kind, RawMesh};
use super::{MeshData, tagged_facets, write_error, writer_adjacency};
use crate::{Mesh, MeshError};

/// Element sections: kind and nodes per entry.
fn element_section(keyword: &str) -> Option<(Kind, usize)> {
    let other = |dim, name, n| Some((Kind { dim, name }, n));
    match keyword {
        "Edges" => Some((Kind::LINE, 2)),
        "Triangles" => Some((Kind::TRIANGLE, 3)),
        "Quadrilaterals" => other(2, "quad", 4),
        "Tetrahedra" => Some((Kind::TETRA, 4)),
        "EdgesP2" => Some((Kind::LINE3, 3)),
        "TrianglesP2" => Some((Kind::TRIANGLE6, 6)),
        "TetrahedraP2" => Some((Kind::TETRA10, 10)),
        "Hexahedra" => other(3, "hexahedron", 8),
        "Prisms" => other(3, "wedge", 6),
        "Pyramids" => other(3, "pyramid", 5),
        _ => None,
    }
}

/// Sections skipped, with the numbers per entry (`None`: the dimension).
fn skipped_section(keyword: &str) -> Option<Option<usize>> {
    match keyword {
        "Corners" | "Ridges" | "RequiredVertices" | "RequiredEdges" | "RequiredTriangles" => Some(Some(1)),
        "NormalAtVertices" | "TangentAtVertices" | "TangentAtEdges" => Some(Some(2)),
        "NormalAtTriangleVertices" => Some(Some(3)),
        "Normals" | "Tangents" => Some(None),
        _ => None,
    }
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut c = Cursor::new(path, bytes);
    let mut raw = RawMesh::default();
    let mut dim = None;
    while let Some(keyword) = c.word()? {
        if keyword.starts_with('#') {
            c.skip_line();
            continue;
        }
        match keyword {
            "MeshVersionFormatted" => {
                c.parse::<u32>("the version")?;
            }
            "Dimension" => {
                dim = Some(c.parse::<usize>("the dimension").and_then(|d| match d {
                    2 | 3 => Ok(d),
                    _ => Err(c.error(format!("dimension {d}"))),
                })?)
            }
            "Vertices" => {
                let d = dim.ok_or_else(|| c.error("Vertices before Dimension"))?;
                let n: u64 = c.parse("number of vertices")?;
                for _ in 0..c.bound(n, 2 * (d + 1), "vertices")? {
                    let mut p = [0.0; 3];
                    for x in &mut p[..d] {
                        *x = c.real("a coordinate")?;
                    }
                    c.parse::<i64>("a vertex reference")?;
                    raw.points.push(p);
                }
            }
            "End" => break,
            keyword => {
                if let Some((kind, nodes)) = element_section(keyword) {
                    let n: u64 = c.parse("number of elements")?;
                    for _ in 0..c.bound(n, 2 * (nodes + 1), "elements")? {
                        for _ in 0..nodes {
                            let v: u32 = c.parse("a vertex index")?;
                            raw.nodes
                                .push(v.checked_sub(1).ok_or_else(|| c.error("vertex index 0 (indices start at 1)"))?);
                        }
                        raw.tags.push(c.parse("an element reference")?);
                        raw.kinds.push(kind);
                        raw.ends.push(raw.nodes.len());
                    }
                } else if let Some(per) = skipped_section(keyword) {
                    let per = per.or(dim).ok_or_else(|| c.error(format!("{keyword} before Dimension")))?;
                    let n: u64 = c.parse("number of entries")?;
                    for _ in 0..c.bound(n, 2 * per, "entries")? * per {
                        c.expect_word("an entry")?;
                    }
                } else {
                    return Err(c.error(format!("unknown section `{keyword}`")));
                }
            }
        }
    }
    Ok(raw)
}

pub(super) fn write<const D: usize>(
    mesh: &Mesh<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    let facets = tagged_facets(mesh, &writer_adjacency(mesh, path)?, data, path)?;
    write_body(mesh, &facets, w).map_err(write_error(path))
}

fn write_body<const D: usize>(mesh: &Mesh<D>, facets: &[(Vec<u32>, i32)], w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "MeshVersionFormatted 2\nDimension {D}\nVertices\n{}", mesh.num_vertices())?;
    for p in mesh.vertices() {
        for x in p {
            write!(w, "{x:?} ")?;
        }
        writeln!(w, "0")?;
    }
    let entries = |w: &mut dyn Write, keyword: &str, items: &mut dyn Iterator<Item = (&[u32], i32)>| {
        let items: Vec<_> = items.collect();
        writeln!(w, "{keyword}\n{}", items.len())?;
        for (nodes, tag) in items {
            for v in nodes {
                write!(w, "{} ", v + 1)?;
            }
            writeln!(w, "{tag}")?;
        }
        Ok::<(), std::io::Error>(())
    };
    let (facet_keyword, element_keyword) = if D == 3 { ("Triangles", "Tetrahedra") } else { ("Edges", "Triangles") };
    entries(w, facet_keyword, &mut facets.iter().map(|(f, t)| (&f[..], *t)))?;
    entries(w, element_keyword, &mut mesh.elements().map(|cell| (cell, 1)))?;
    writeln!(w, "End")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh3;

    #[test]
    fn round_trips_with_facet_references() {
        let mesh =
            Mesh3::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.1]], vec![0, 1, 2, 3])
                .unwrap();
        let data = MeshData::new().with_facet_tag([2, 1, 0], 5);
        let mut bytes = Vec::new();
        write(&mesh, &data, &mut bytes, Path::new("x.mesh")).unwrap();
        let path = Path::new("x.mesh");
        let (back, back_data) = read(path, &bytes).unwrap().finish::<3>(path).unwrap();
        assert_eq!(back, mesh);
        assert_eq!(back_data.facet_tags[&vec![0, 1, 2]], 5);
        assert_eq!(back_data.facet_tags.values().filter(|&&t| t == 6).count(), 3);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases = [
            ("MeshVersionFormatted 2\nDimension 3\nVertices\n1\n0 0 x 0\n", "inline.mesh:5"),
            ("MeshVersionFormatted 2\nDimension 2\nVertices\n100000\n0 0 0\n", "announced"),
            ("MeshVersionFormatted 2\nDimension 2\nFoo\n", "unknown section `Foo`"),
            ("MeshVersionFormatted 2\nDimension 2\nTriangles\n1\n0 1 2 0\n", "index 0"),
        ];
        for (text, needle) in cases {
            let path = Path::new("inline.mesh");
            let message = read(path, text.as_bytes()).err().unwrap().to_string();
            assert!(message.contains(needle), "{message}");
        }
    }
}
