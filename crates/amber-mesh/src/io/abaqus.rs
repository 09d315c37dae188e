//! Abaqus input (`.inp`): `*NODE` and `*ELEMENT, TYPE=...` blocks (data lines continue while
//! they end with a comma; keywords are case-insensitive; `**` starts a comment; every other
//! keyword's data is skipped). Element types are classified by their family prefix and node
//! count (`C3D4` tetrahedron, `CPS3`/`CPE3`/`S3`/... triangle, `C3D10` and `CPS6`/... read by their
//! corners, ...).
//! The writer writes `*NODE` and one `*ELEMENT` block, `C3D4` or `CPS3`, in ELSET `domain`.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use super::Lines;
use super::raw::{Kind, RawMesh};
use crate::{Mesh, MeshError};

/// The kind of an Abaqus element type: the family prefix gives the dimension, the digits after it
/// the node count.
fn element_kind(ty: &str) -> Option<Kind> {
    const FAMILIES: [(&str, usize); 19] = [
        ("C3D", 3),
        ("DC3D", 3),
        ("M3D", 2),
        ("R3D", 2),
        ("SFM3D", 2),
        ("DC2D", 2),
        ("DCAX", 2),
        ("CPEG", 2),
        ("CPS", 2),
        ("CPE", 2),
        ("CAX", 2),
        ("STRI", 2),
        ("DS", 2),
        ("S", 2),
        ("T2D", 1),
        ("T3D", 1),
        ("B2", 1),
        ("B3", 1),
        ("DC1D", 1),
    ];
    let ty = ty.to_ascii_uppercase();
    let (prefix, dim) = FAMILIES.iter().find(|(p, _)| ty.starts_with(p))?;
    let digits: String = ty[prefix.len()..].chars().take_while(char::is_ascii_digit).collect();
    let other = |name| Some(Kind { dim: *dim, name });
    match (dim, digits.parse::<usize>().ok()?) {
        (1, _) => other("line_element"),
        (2, 3) => Some(Kind::TRIANGLE),
        (2, 4) => other("quad"),
        (2, 6) => Some(Kind::TRIANGLE6),
        (2, 8) => other("quad8"),
        (2, _) => other("surface_element"),
        (_, 4) => Some(Kind::TETRA),
        (_, 5) => other("pyramid"),
        (_, 6) => other("wedge"),
        (_, 8) => other("hexahedron"),
        (_, 10) => Some(Kind::TETRA10),
        (_, 15) => other("wedge15"),
        (_, 20) => other("hexahedron20"),
        _ => other("solid_element"),
    }
}

/// What the data lines under the current keyword are.
enum Block {
    Nodes,
    Elements(Kind),
    Skipped,
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut lines = Lines::new(path, bytes);
    let mut raw = RawMesh::default();
    let mut node_index: HashMap<u64, u32> = HashMap::new();
    let mut elements: Vec<(Kind, Vec<u64>, usize)> = Vec::new();
    let mut block = Block::Skipped;
    let mut pending: Option<(Vec<u64>, usize)> = None;
    while let Some(line) = lines.next()? {
        let line = line.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        if let Some(keyword) = line.strip_prefix('*') {
            let mut parts = keyword.split(',').map(str::trim);
            let name = parts.next().unwrap_or("").to_ascii_uppercase();
            block = match name.as_str() {
                "NODE" => Block::Nodes,
                "ELEMENT" => {
                    let ty = parts
                        .filter_map(|p| p.split_once('='))
                        .find(|(k, _)| k.trim().eq_ignore_ascii_case("TYPE"))
                        .map(|(_, v)| v.trim())
                        .ok_or_else(|| lines.error("*ELEMENT without TYPE="))?;
                    Block::Elements(
                        element_kind(ty).ok_or_else(|| lines.error(format!("element type {ty} is unknown")))?,
                    )
                }
                _ => Block::Skipped,
            };
            continue;
        }
        let words: Vec<&str> = line.split(',').map(str::trim).filter(|w| !w.is_empty()).collect();
        match block {
            Block::Nodes => {
                let id: u64 = lines.parse(words.first().copied(), "node id")?;
                let mut p = [0.0; 3];
                for (k, x) in p.iter_mut().enumerate() {
                    if let Some(&word) = words.get(k + 1) {
                        *x = lines.parse(Some(word), "coordinate")?;
                    }
                }
                if node_index.insert(id, raw.points.len() as u32).is_some() {
                    return Err(lines.error(format!("node {id} is defined twice")));
                }
                raw.points.push(p);
            }
            Block::Elements(kind) => {
                let (mut ids, line_no) = pending.take().unwrap_or((Vec::new(), lines.line));
                for word in &words {
                    ids.push(lines.parse(Some(word), "node id")?);
                }
                if line.ends_with(',') {
                    pending = Some((ids, line_no));
                } else {
                    elements.push((kind, ids, line_no));
                }
            }
            Block::Skipped => {}
        }
    }
    for (kind, ids, line) in elements {
        let nodes = ids.iter().skip(1).map(|id| {
            node_index.get(id).copied().ok_or_else(|| MeshError::Parse {
                path: path.to_owned(),
                line,
                message: format!("element {} references node {id}, which *NODE does not define", ids[0]),
            })
        });
        raw.push_cell(kind, nodes.collect::<Result<Vec<u32>, _>>()?);
    }
    Ok(raw)
}

pub(super) fn write<const D: usize>(mesh: &Mesh<D>, w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "*HEADING\nwritten by amber\n*NODE")?;
    for (i, p) in mesh.vertices().iter().enumerate() {
        write!(w, "{}", i + 1)?;
        for x in p {
            write!(w, ", {x:?}")?;
        }
        writeln!(w)?;
    }
    writeln!(w, "*ELEMENT, TYPE={}, ELSET=domain", if D == 3 { "C3D4" } else { "CPS3" })?;
    for (e, cell) in mesh.elements().enumerate() {
        write!(w, "{}", e + 1)?;
        for &v in cell {
            write!(w, ", {}", v + 1)?;
        }
        writeln!(w)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Mesh2, MeshData};

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        let path = Path::new("inline.inp");
        read(path, text.as_bytes())?.finish(path)
    }

    #[test]
    fn reads_blocks_continuations_and_drops_other_elements() {
        let text = "*Heading\n** comment\n*Node, nset=all\n 10, 0., 0., 0.\n20, 1., 0., 0.\n30, 0., 1., 0.\n40, 0., 0., 1.\n\
*Element, type=C3D4, elset=solid\n1, 10, 30,\n20, 40\n*ELEMENT, TYPE=S3\n2, 10, 20, 30\n*Nset, nset=x\n1, 2\n";
        let (mesh, data) = parse::<3>(text).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert!(mesh.volume(0) > 0.0);
        assert_eq!(data.dropped["triangle"], 1);
        assert!(parse::<3>("*NODE\n1, 0, 0\n*ELEMENT, TYPE=XYZ9\n").unwrap_err().to_string().contains("inline.inp:3"));
        let missing = parse::<2>("*NODE\n1, 0, 0\n*ELEMENT, TYPE=CPS3\n1, 1, 2, 3\n").unwrap_err().to_string();
        assert!(missing.contains("inline.inp:4") && missing.contains("node 2"), "{missing}");
    }

    #[test]
    fn writes_what_it_reads() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0 / 3.0, 1.0]], vec![0, 1, 2]).unwrap();
        let mut bytes = Vec::new();
        write(&mesh, &mut bytes).unwrap();
        assert_eq!(parse::<2>(std::str::from_utf8(&bytes).unwrap()).unwrap().0, mesh);
    }
}
