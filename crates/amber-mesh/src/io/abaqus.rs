//! Abaqus input (`.inp`): `*NODE` and `*ELEMENT, TYPE=...` blocks (data lines continue while
//! they end with a comma; keywords are case-insensitive; `**` starts a comment), and the named
//! groups of facets: element-side `*SURFACE`s (`element or element set, S<k>`) and the `ELSET=` of
//! facet elements (`S3` skins); `*ELSET` blocks (listed or `GENERATE`d) are read for the
//! surfaces that name them, and every other keyword's data is skipped. Element types are
//! classified by their family prefix and node count (`C3D4` tetrahedron, `CPS3`/`CPE3`/`S3`/...
//! triangle, `C3D10` and `CPS6`/... read by their corners, ...).
//! The writer writes `*NODE` and one `*ELEMENT` block, `C3D4` or `CPS3` (second order: `C3D10`,
//! `CPS6`, their edge nodes at the edges' midpoints), in ELSET `domain`, and
//! the boundary as one `*NSET` (for boundary conditions) and one element-side `*SURFACE` (for
//! loads) per facet tag, `boundary_<tag>` (`boundary` when nothing is tagged), as the `.msh`
//! writer groups it; tagged facets inside the mesh are left out, a surface being one-sided.

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

use super::nodes::Nodes;
use super::raw::{Kind, RawMesh};
use super::{Lines, MeshData, tagged_facets, write_error, writer_adjacency};
use crate::MeshError;

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
    /// Elements of a kind, in the element set of a tag (0: none).
    Elements(Kind, i32),
    /// Members of an element set: element numbers or earlier sets, or `first, last, step` with
    /// `GENERATE`.
    ElementSet {
        name: String,
        generate: bool,
    },
    /// Element sides (`element or set, S<k>`) of a surface's tag.
    Surface(i32),
    Skipped,
}

/// The value of `key=` among a keyword line's parameters, unquoted.
fn parameter<'a>(parts: &[&'a str], key: &str) -> Option<&'a str> {
    parts
        .iter()
        .filter_map(|p| p.split_once('='))
        .find(|(k, _)| k.trim().eq_ignore_ascii_case(key))
        .map(|(_, v)| v.trim().trim_matches('"'))
}

/// Tags for the names of element sets and surfaces (Abaqus names ignore case), 1-based in order
/// of appearance.
#[derive(Default)]
struct Names {
    tags: HashMap<String, i32>,
    names: Vec<String>,
}

impl Names {
    fn tag(&mut self, name: &str) -> i32 {
        let next = self.names.len() as i32 + 1;
        *self.tags.entry(name.to_ascii_uppercase()).or_insert_with(|| {
            self.names.push(name.to_owned());
            next
        })
    }
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut lines = Lines::new(path, bytes);
    let mut raw = RawMesh::default();
    let mut node_index: HashMap<u64, u32> = HashMap::new();
    // (kind, element number and node numbers, line, tag).
    let mut elements: Vec<(Kind, Vec<u64>, usize, i32)> = Vec::new();
    let mut names = Names::default();
    let mut sets: HashMap<String, Vec<u64>> = HashMap::new();
    // (element number, side 1-based, tag, line).
    let mut sides: Vec<(u64, usize, i32, usize)> = Vec::new();
    // Sets and surfaces name sets again and again; expanded, they never need more entries than
    // four per byte of the file (an element takes more than a byte, and has at most four sides).
    let mut expanded = 0usize;
    let mut expand = |n: usize, lines: &Lines| -> Result<(), MeshError> {
        expanded += n;
        if expanded > 4 * bytes.len() {
            return Err(lines.error("element sets and surfaces list more entries than the file could have elements"));
        }
        Ok(())
    };
    let mut block = Block::Skipped;
    let mut pending: Option<(Vec<u64>, usize)> = None;
    while let Some(line) = lines.next()? {
        let line = line.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        if let Some(keyword) = line.strip_prefix('*') {
            let parts: Vec<&str> = keyword.split(',').map(str::trim).collect();
            let flag = |flag: &str| parts.iter().any(|p| p.eq_ignore_ascii_case(flag));
            block = match parts[0].to_ascii_uppercase().as_str() {
                "NODE" => Block::Nodes,
                "ELEMENT" => {
                    let ty = parameter(&parts, "TYPE").ok_or_else(|| lines.error("*ELEMENT without TYPE="))?;
                    let kind = element_kind(ty).ok_or_else(|| lines.error(format!("element type {ty} is unknown")))?;
                    Block::Elements(kind, parameter(&parts, "ELSET").map_or(0, |set| names.tag(set)))
                }
                "ELSET" => match parameter(&parts, "ELSET") {
                    Some(name) => Block::ElementSet { name: name.to_ascii_uppercase(), generate: flag("GENERATE") },
                    None => return Err(lines.error("*ELSET without ELSET=")),
                },
                "SURFACE" => match (parameter(&parts, "NAME"), parameter(&parts, "TYPE")) {
                    (Some(name), None) => Block::Surface(names.tag(name)),
                    (Some(name), Some(ty)) if ty.eq_ignore_ascii_case("ELEMENT") => Block::Surface(names.tag(name)),
                    (None, _) => return Err(lines.error("*SURFACE without NAME=")),
                    _ => Block::Skipped,
                },
                _ => Block::Skipped,
            };
            continue;
        }
        let words: Vec<&str> = line.split(',').map(str::trim).filter(|w| !w.is_empty()).collect();
        match &block {
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
            &Block::Elements(kind, tag) => {
                let (mut ids, line_no) = pending.take().unwrap_or((Vec::new(), lines.line));
                for word in &words {
                    ids.push(lines.parse(Some(word), "node id")?);
                }
                if line.ends_with(',') {
                    pending = Some((ids, line_no));
                } else {
                    elements.push((kind, ids, line_no, tag));
                }
            }
            Block::ElementSet { name, generate: true } => {
                let [first, last, step] =
                    [0, 1, 2].map(|k| lines.parse::<u64>(words.get(k).copied(), "element number"));
                let (first, last, step) = (first?, last?, if words.len() > 2 { step? } else { 1 });
                if step == 0 || last < first || (last - first) / step >= bytes.len() as u64 {
                    return Err(lines.error(format!("bad GENERATE range {first}, {last}, {step}")));
                }
                expand(((last - first) / step + 1) as usize, &lines)?;
                sets.entry(name.clone()).or_default().extend((first..=last).step_by(step as usize));
            }
            Block::ElementSet { name, generate: false } => {
                let mut members = Vec::new();
                for word in &words {
                    match word.parse::<u64>() {
                        Ok(id) => members.push(id),
                        Err(_) => members.extend(set_members(&sets, word).map_err(|e| lines.error(e))?),
                    }
                }
                expand(members.len(), &lines)?;
                sets.entry(name.clone()).or_default().extend(members);
            }
            &Block::Surface(tag) => {
                let side = words.get(1).and_then(|w| w.strip_prefix(['S', 's'])).map(str::parse::<usize>);
                let side = match side {
                    Some(Ok(side @ 1..=4)) => side,
                    // SPOS/SNEG: a side of a shell, whose own elements are the facets.
                    None if words.len() == 2 => continue,
                    _ => return Err(lines.error(format!("expected `element or set, S<1-4>`, found `{line}`"))),
                };
                match words[0].parse::<u64>() {
                    Ok(id) => sides.push((id, side, tag, lines.line)),
                    Err(_) => {
                        let members = set_members(&sets, words[0]).map_err(|e| lines.error(e))?;
                        expand(members.len(), &lines)?;
                        sides.extend(members.iter().map(|&id| (id, side, tag, lines.line)));
                    }
                }
            }
            Block::Skipped => {}
        }
    }
    let resolve = |id: &u64, element: u64, line: usize| {
        node_index.get(id).copied().ok_or_else(|| MeshError::Parse {
            path: path.to_owned(),
            line,
            message: format!("element {element} references node {id}, which *NODE does not define"),
        })
    };
    let mut element_index: HashMap<u64, usize> = HashMap::new();
    for (k, (kind, ids, line, tag)) in elements.iter().enumerate() {
        let nodes = ids.iter().skip(1).map(|id| resolve(id, ids[0], *line));
        raw.push_cell(*kind, nodes.collect::<Result<Vec<u32>, _>>()?);
        raw.tags.push(*tag);
        element_index.insert(ids[0], k);
    }
    for (element, side, tag, line) in sides {
        let error = |message: String| MeshError::Parse { path: path.to_owned(), line, message };
        let &k = element_index
            .get(&element)
            .ok_or_else(|| error(format!("surface side of element {element}, which *ELEMENT does not define")))?;
        let (kind, ids, _, _) = &elements[k];
        // Sides of other elements are dropped with them; one with too few nodes fails in `finish`.
        let simplex = matches!(*kind, Kind::TETRA | Kind::TETRA10 | Kind::TRIANGLE | Kind::TRIANGLE6);
        if !simplex || ids.len() < kind.dim + 2 {
            continue;
        }
        let local: &[usize] = match (kind.dim, side) {
            (3, 1..=4) => &[[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]][side - 1],
            (2, 1..=3) => &[[0, 1], [1, 2], [2, 0]][side - 1],
            _ => return Err(error(format!("element {element} ({}) has no side S{side}", kind.name))),
        };
        let nodes = local.iter().map(|&j| resolve(&ids[1 + j], element, line));
        raw.push_cell(Kind::simplex(kind.dim - 1), nodes.collect::<Result<Vec<u32>, _>>()?);
        raw.tags.push(tag);
    }
    let tagged: std::collections::BTreeSet<(usize, i32)> =
        raw.kinds.iter().zip(&raw.tags).filter(|(_, t)| **t != 0).map(|(kind, &t)| (kind.dim, t)).collect();
    raw.tag_names = tagged.into_iter().map(|(dim, t)| (dim, t, names.names[t as usize - 1].clone())).collect();
    Ok(raw)
}

/// The members of the element set `name`, defined earlier in the file.
fn set_members<'a>(sets: &'a HashMap<String, Vec<u64>>, name: &str) -> Result<&'a [u64], String> {
    sets.get(&name.trim_matches('"').to_ascii_uppercase())
        .map(Vec::as_slice)
        .ok_or_else(|| format!("`{name}` is neither an element number nor an element set defined before"))
}

/// Abaqus's number of the side of a `C3D4` or `CPS3` opposite each local node: `C3D4` faces are
/// S1 = 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1; `CPS3` edges S1 = 1-2, S2 = 2-3, S3 = 3-1.
fn side_opposite<const D: usize>(local: usize) -> usize {
    if D == 3 { [3, 4, 2, 1][local] } else { [2, 3, 1][local] }
}

pub(super) fn write<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    let mesh = nodes.mesh();
    let adjacency = writer_adjacency(mesh, path)?;
    let side_of: HashMap<Vec<u32>, (usize, usize)> = adjacency
        .boundary_facets()
        .map(|(e, local)| {
            let mut facet: Vec<u32> =
                (mesh.element(e).iter().enumerate()).filter_map(|(k, &v)| (k != local).then_some(v)).collect();
            facet.sort_unstable();
            (facet, (e, local))
        })
        .collect();
    let mut groups: BTreeMap<i32, Vec<(usize, usize)>> = BTreeMap::new();
    for (facet, tag) in tagged_facets(mesh, &adjacency, data, path)? {
        let mut key = facet;
        key.sort_unstable();
        if let Some(&side) = side_of.get(&key) {
            groups.entry(tag).or_default().push(side);
        }
    }
    let names = groups
        .keys()
        .map(|&tag| abaqus_label(&data.group_name(tag, groups.len())).map(|label| (tag, label)))
        .collect::<Result<BTreeMap<i32, String>, String>>()
        .map_err(|message| MeshError::Format { path: path.to_owned(), message })?;
    let domain = abaqus_label(data.domain_group_name())
        .map_err(|message| MeshError::Format { path: path.to_owned(), message })?;
    write_body(nodes, &groups, &names, &domain, w).map_err(write_error(path))
}

/// `name` as an Abaqus set or surface name: as it is when it is a plain label (a letter, then
/// letters, digits and underscores), else in double quotes, which Abaqus needs around spaces
/// and other characters; an error for what a quoted name cannot hold.
fn abaqus_label(name: &str) -> Result<String, String> {
    let plain = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    let label = if plain { name.to_owned() } else { format!("\"{name}\"") };
    if name.is_empty() || name.contains(['"', '\n', '\r']) || label.chars().count() > 80 {
        Err(format!(
            "group name {name:?} cannot be an Abaqus set name (at most 80 characters with its quotes, \
             no quotes or line breaks)"
        ))
    } else {
        Ok(label)
    }
}

fn write_body<const D: usize>(
    nodes: &Nodes<D>,
    groups: &BTreeMap<i32, Vec<(usize, usize)>>,
    names: &BTreeMap<i32, String>,
    domain: &str,
    w: &mut impl Write,
) -> std::io::Result<()> {
    let mesh = nodes.mesh();
    writeln!(w, "*HEADING\nwritten by amber\n*NODE")?;
    for (i, p) in nodes.points().enumerate() {
        write!(w, "{}", i + 1)?;
        for x in p {
            write!(w, ", {x:?}")?;
        }
        writeln!(w)?;
    }
    let kind = match (D, nodes.is_quadratic()) {
        (2, false) => "CPS3",
        (2, true) => "CPS6",
        (_, false) => "C3D4",
        (_, true) => "C3D10",
    };
    writeln!(w, "*ELEMENT, TYPE={kind}, ELSET={domain}")?;
    for (e, cell) in nodes.elements().enumerate() {
        write!(w, "{}", e + 1)?;
        for v in cell {
            write!(w, ", {}", v + 1)?;
        }
        writeln!(w)?;
    }
    for (tag, sides) in groups {
        let name = &names[tag];
        // Every node on the group's faces, edge nodes too: a boundary condition holds them all.
        let mut on_faces: Vec<u32> = sides
            .iter()
            .flat_map(|&(e, local)| {
                let corners: Vec<u32> =
                    mesh.element(e).iter().enumerate().filter(|&(k, _)| k != local).map(|(_, &v)| v).collect();
                nodes.facet(&corners)
            })
            .collect();
        on_faces.sort_unstable();
        on_faces.dedup();
        writeln!(w, "*NSET, NSET={name}")?;
        // Abaqus reads at most 16 entries per data line.
        for line in on_faces.chunks(16) {
            let ids: Vec<String> = line.iter().map(|v| (v + 1).to_string()).collect();
            writeln!(w, "{}", ids.join(", "))?;
        }
        writeln!(w, "*SURFACE, TYPE=ELEMENT, NAME={name}")?;
        for &(e, local) in sides {
            writeln!(w, "{}, S{}", e + 1, side_opposite::<D>(local))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;
    use crate::io::ElementOrder;
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
        write(&Nodes::new(&mesh, ElementOrder::Linear), &MeshData::new(), &mut bytes, Path::new("x.inp")).unwrap();
        let text = std::str::from_utf8(&bytes).unwrap();
        assert_eq!(parse::<2>(text).unwrap().0, mesh);
        assert!(
            text.ends_with(
                "*NSET, NSET=boundary\n1, 2, 3\n*SURFACE, TYPE=ELEMENT, NAME=boundary\n1, S2\n1, S3\n1, S1\n"
            ),
            "{text}"
        );
    }

    /// A tet's four faces in three groups: each group's node set and the Abaqus side numbers of
    /// its faces (S1 = nodes 1-2-3, S2 = 1-4-2, S3 = 2-4-3, S4 = 3-4-1).
    #[test]
    fn writes_a_node_set_and_a_surface_per_facet_tag() {
        let tet =
            crate::Mesh3::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3])
                .unwrap();
        let tet = Nodes::new(&tet, ElementOrder::Linear);
        let data = MeshData::new()
            .with_facet_tag([0, 1, 2], 5)
            .with_facet_tag([0, 3, 1], 7)
            .with_facet_tag([1, 3, 2], 7)
            .with_facet_name(5, "outlet")
            .with_facet_name(7, "inlet wall");
        let mut bytes = Vec::new();
        write(&tet, &data, &mut bytes, Path::new("x.inp")).unwrap();
        let text = std::str::from_utf8(&bytes).unwrap();
        let groups = text.split_once("*NSET").unwrap().1;
        assert_eq!(
            groups,
            ", NSET=outlet\n1, 2, 3\n*SURFACE, TYPE=ELEMENT, NAME=outlet\n1, S1\n\
             *NSET, NSET=\"inlet wall\"\n1, 2, 3, 4\n*SURFACE, TYPE=ELEMENT, NAME=\"inlet wall\"\n1, S3\n1, S2\n\
             *NSET, NSET=boundary_8\n1, 3, 4\n*SURFACE, TYPE=ELEMENT, NAME=boundary_8\n1, S4\n"
        );
        let mut quoted = data.with_facet_name(8, "a \"b\"");
        let err = write(&tet, &quoted, &mut bytes, Path::new("x.inp"));
        assert!(err.unwrap_err().to_string().contains("x.inp"));
        quoted.facet_names.insert(8, "n".repeat(81));
        let err = write(&tet, &quoted, &mut bytes, Path::new("x.inp"));
        assert!(err.unwrap_err().to_string().contains("at most 80 characters"));
    }

    /// The named surfaces amber writes come back as named facet groups.
    #[test]
    fn reads_its_surfaces_back_as_named_facet_groups() {
        let tet =
            crate::Mesh3::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], vec![0, 1, 2, 3]);
        let tet = tet.unwrap();
        let data = MeshData::new()
            .with_facet_tag([0, 1, 2], 5)
            .with_facet_tag([0, 3, 1], 7)
            .with_facet_tag([1, 3, 2], 7)
            .with_facet_name(7, "inlet wall");
        let data = MeshData { domain_name: Some("BRACKET-1".into()), ..data };
        let mut bytes = Vec::new();
        write(&Nodes::new(&tet, ElementOrder::Linear), &data, &mut bytes, Path::new("x.inp")).unwrap();
        let text = std::str::from_utf8(&bytes).unwrap();
        assert!(text.contains("*ELEMENT, TYPE=C3D4, ELSET=\"BRACKET-1\"\n"), "{text}");
        let (back, back_data) = parse::<3>(text).unwrap();
        assert_eq!(back, tet);
        assert_eq!(back_data.domain_name.as_deref(), Some("BRACKET-1"));
        let name_of = |facet: &[u32]| back_data.facet_names[&back_data.facet_tags[facet]].as_str();
        assert_eq!(name_of(&[0, 1, 2]), "boundary_5");
        assert_eq!((name_of(&[0, 1, 3]), name_of(&[1, 2, 3])), ("inlet wall", "inlet wall"));
        assert_eq!(name_of(&[0, 2, 3]), "boundary_8");
    }

    /// Element sets (listed, generated, or of `*ELEMENT, ELSET=`) and surfaces over them.
    #[test]
    fn element_sets_and_surfaces_tag_facets() {
        let nodes = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n5, 1, 1, 1\n";
        let text = format!(
            "{nodes}*ELEMENT, TYPE=C3D4, ELSET=solid\n1, 1, 2, 3, 4\n2, 2, 3, 4, 5\n\
             *ELSET, ELSET=_first, GENERATE\n1, 1, 1\n*ELSET, ELSET=both\n_first, 2\n\
             *SURFACE, TYPE=ELEMENT, NAME=Bottom\n_FIRST, S1\n*SURFACE, NAME=tops\nboth, S3\n\
             *SURFACE, TYPE=NODE, NAME=ignored\n1, 1.0\n*ELEMENT, TYPE=S3, ELSET=skin\n9, 1, 2, 4\n"
        );
        let (mesh, data) = parse::<3>(&text).unwrap();
        assert_eq!(mesh.num_elements(), 2);
        let names: Vec<&str> = data.facet_names.values().map(String::as_str).collect();
        assert_eq!(names, ["Bottom", "tops", "skin"]);
        let tag = |name: &str| *data.facet_names.iter().find(|(_, n)| *n == name).unwrap().0;
        assert_eq!(data.facet_tags[&vec![0, 1, 2]], tag("Bottom"));
        // S3 of element 1 is nodes 2-4-3, of element 2 nodes 3-5-4 (0-based 1-3-2 and 2-4-3).
        assert_eq!(data.facet_tags[&vec![1, 2, 3]], tag("tops"));
        assert_eq!(data.facet_tags[&vec![2, 3, 4]], tag("tops"));
        assert_eq!(data.facet_tags[&vec![0, 1, 3]], tag("skin"));
        assert_eq!(data.domain_name.as_deref(), Some("solid"));
        // Elements in two sets: the domain has no one name.
        let two = format!(
            "{nodes}*ELEMENT, TYPE=C3D4, ELSET=a\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=C3D4, ELSET=b\n2, 2, 3, 4, 5\n"
        );
        assert_eq!(parse::<3>(&two).unwrap().1.domain_name, None);
        for (bad, expected) in [
            ("*SURFACE, NAME=s\nnowhere, S1\n", "neither an element number nor an element set"),
            ("*SURFACE, NAME=s\n1, S9\n", "S<1-4>"),
            ("*SURFACE, NAME=s\n3, S1\n", "element 3, which *ELEMENT does not define"),
            ("*ELSET, ELSET=g, GENERATE\n5, 1, 1\n", "bad GENERATE range"),
            (&"*ELSET, ELSET=g, GENERATE\n1, 100, 1\n*ELSET, ELSET=h\ng, g, g\n".repeat(8), "more entries than"),
        ] {
            let text = format!("{nodes}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n{bad}");
            let err = parse::<3>(&text).unwrap_err().to_string();
            assert!(err.contains("inline.inp:") && err.contains(expected), "{bad}: {err}");
        }
    }
}
