//! NASTRAN bulk data (`.nas`, `.bdf`): GRID points (small fixed-field, free-field, and
//! large-field `GRID*` with its `*` continuation line), CTETRA and CTRIA3 elements, and 10-node
//! CTETRA and CTRIA6 by their corner grids (the edge grids, some on continuation lines, are not
//! needed); other element cards (CQUAD4, CHEXA, CPENTA, CPYRAM, CBAR, CBEAM, CROD) are counted as
//! dropped and every other card is skipped. Reading stops at ENDDATA, which must be
//! there: a file without it is truncated, and a partial mesh is never returned. Reals may use
//! NASTRAN's implicit exponent (`-7.11-15` = -7.11e-15). GRID ids may have gaps.
//!
//! An element's property id (PID) is its tag: in a tet mesh, the CTRIA3 (CTRIA6) skin
//! triangles become facet tags by their PID, as the physical groups of a `.msh` do, named by the
//! comments pre-processors write for their properties (ANSA's `$ANSA_NAME_COMMENT;PID;PSHELL;NAME;`,
//! HyperMesh's `$HMNAME PROP PID "NAME"`); NASTRAN itself has no place for a name.
//!
//! The writer writes free-field cards (GRID, CTETRA or CTRIA3; second order: CTETRA with its six
//! edge grids, four of them on a `+` continuation line, or CTRIA6) with coordinates in their
//! shortest round-trip form where it fits a large field (16 characters), so such a mesh reads
//! back bit-exactly, and else to 5e-11 relative (a coordinate's exponent of one or two digits).
//! The model is laid out as the Console experts' ANSA files are: a tet mesh's CTETRA under one
//! PSOLID, and its boundary as CTRIA3 (CTRIA6) skin triangles, outward, one PSHELL per facet tag
//! (PID = tag; the untagged boundary one past the largest tag), the solid's PID one past those;
//! a named facet group's PSHELL carries its name in both pre-processors' comments.
//! The skin's PSHELLs name no material, so in MSC Nastran they add no stiffness: they carry the
//! faces' groups for loads and constraints. The PSOLID (and a triangle mesh's PSHELL, thickness
//! 1) reference material 1, which the file does not define: the user's solver deck does.

use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

use super::nodes::Nodes;
use super::raw::{Kind, RawMesh};
use super::{Lines, MeshData, MeshError, require_positive_tags, tagged_facets, write_error, writer_adjacency};

/// The kind of an element card (a CTETRA with edge grids is found by its fields).
fn element_card(card: &str) -> Option<Kind> {
    let other = |dim, name| Some(Kind { dim, name });
    match card {
        "CTETRA" => Some(Kind::TETRA),
        "CTRIA3" => Some(Kind::TRIANGLE),
        "CTRIA6" => Some(Kind::TRIANGLE6),
        "CQUAD4" => other(2, "quad"),
        "CHEXA" => other(3, "hexahedron"),
        "CPENTA" => other(3, "wedge"),
        "CPYRAM" => other(3, "pyramid"),
        "CBAR" | "CBEAM" | "CROD" => other(1, "bar"),
        _ => None,
    }
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut lines = Lines::new(path, bytes);
    let mut grid_index: HashMap<u64, u32> = HashMap::new();
    let mut raw = RawMesh::default();
    // Element grid ids with their PID and line, resolved once every GRID is known (cards may come
    // in any order).
    let mut elements: Vec<(Kind, Vec<u64>, i32, usize)> = Vec::new();
    let mut names = BTreeMap::new();
    let mut complete = false;
    while let Some(line) = lines.next()? {
        if line.starts_with('$') {
            names.extend(property_name(line));
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        let name = line.split(',').next().unwrap_or(line);
        let large = name.get(..name.len().min(8)).unwrap_or(name).trim_end().ends_with('*');
        let fields = Fields::split(line, if large { 16 } else { 8 })
            .ok_or_else(|| lines.error("non-ASCII text inside a fixed-width field"))?;
        let card = fields.get(0).to_ascii_uppercase();
        match card.as_str() {
            "GRID" | "GRID*" => {
                let id: u64 = lines.parse(Some(fields.get(1)), "GRID id")?;
                if !matches!(fields.get(2), "" | "0") {
                    return Err(lines.error(format!("GRID {id} uses coordinate system {}", fields.get(2))));
                }
                let coordinate = |fields: &Fields, i: usize, lines: &Lines| {
                    real(fields.get(i))
                        .ok_or_else(|| lines.error(format!("bad coordinate `{}` in GRID {id}", fields.get(i))))
                };
                let (x, y) = (coordinate(&fields, 3, &lines)?, coordinate(&fields, 4, &lines)?);
                let z = if large {
                    let next = lines.expect("the continuation of GRID*")?;
                    let more = Fields::split(next, 16).filter(|_| next.starts_with('*'));
                    let more = more.ok_or_else(|| lines.error(format!("GRID* {id} has no `*` continuation line")))?;
                    coordinate(&more, 1, &lines)?
                } else {
                    coordinate(&fields, 5, &lines)?
                };
                if grid_index.insert(id, raw.points.len() as u32).is_some() {
                    return Err(lines.error(format!("GRID {id} is defined twice")));
                }
                raw.points.push([x, y, z]);
            }
            "ENDDATA" => {
                complete = true;
                break;
            }
            card => {
                if let Some(mut kind) = element_card(card) {
                    if kind == Kind::TETRA && !(fields.get(7).is_empty() && fields.get(8).is_empty()) {
                        kind = Kind::TETRA10;
                    }
                    // The simplices' corner grids; the other cards are only counted.
                    let ids = if [Kind::TETRA, Kind::TRIANGLE, Kind::TETRA10, Kind::TRIANGLE6].contains(&kind) {
                        (0..=kind.dim)
                            .map(|k| lines.parse(Some(fields.get(3 + k)), &format!("{card} grid id")))
                            .collect::<Result<Vec<u64>, _>>()?
                    } else {
                        Vec::new()
                    };
                    // A PID that is no positive integer tags nothing.
                    let pid = fields.get(2).trim().parse::<i32>().ok().filter(|&p| p > 0).unwrap_or(0);
                    elements.push((kind, ids, pid, lines.line));
                }
            }
        }
    }
    for (kind, ids, pid, line) in elements {
        let nodes = ids.iter().map(|id| {
            grid_index.get(id).copied().ok_or_else(|| MeshError::Parse {
                path: path.to_owned(),
                line,
                message: format!("{} references GRID {id}, which is not defined", kind.name),
            })
        });
        raw.push_cell(kind, nodes.collect::<Result<Vec<u32>, _>>()?);
        raw.tags.push(pid);
    }
    // A property may name triangles or tets; `finish` keeps the names of the tags in use.
    raw.tag_names = (names.into_iter()).flat_map(|(pid, name)| [(2, pid, name.clone()), (3, pid, name)]).collect();
    if !complete {
        let message = format!("no ENDDATA after line {}: the file is truncated", lines.line);
        return Err(MeshError::Format { path: path.to_owned(), message });
    }
    Ok(raw)
}

/// A property's name from the comment a pre-processor writes beside it: ANSA's
/// `$ANSA_NAME_COMMENT;PID;CARD;NAME;...` for a property card (`PSHELL`, `PSOLID`, ...) or
/// HyperMesh's `$HMNAME PROP PID"NAME"`. Any other comment, or one cut short before the name
/// ends (a wrapped line), names nothing: a comment never makes a deck unreadable.
fn property_name(line: &str) -> Option<(i32, String)> {
    let (pid, name) = if let Some(rest) = line.strip_prefix("$ANSA_NAME_COMMENT;") {
        // Four pieces: the name's own `;` must be there for the name to be whole.
        let fields: Vec<&str> = rest.splitn(4, ';').collect();
        match fields[..] {
            [pid, card, name, _] if card.starts_with('P') => (pid, name),
            _ => return None,
        }
    } else {
        let rest = line.strip_prefix("$HMNAME PROP")?;
        let (pid, quoted) = rest.split_once('"')?;
        (pid, quoted.split_once('"')?.0)
    };
    let pid = pid.trim().parse::<i32>().ok().filter(|&p| p > 0)?;
    let name = name.trim();
    (!name.is_empty()).then(|| (pid, name.to_owned()))
}

pub(super) fn write<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    let mesh = nodes.mesh();
    let skin = if D == 3 { tagged_facets(mesh, &writer_adjacency(mesh, path)?, data, path)? } else { Vec::new() };
    require_positive_tags(&skin, path, "NASTRAN property ids")?;
    let solid = skin.iter().map(|&(_, t)| t).max().map_or(1, |t| t.saturating_add(1));
    let names: BTreeMap<i32, &str> = (data.facet_names.iter())
        // `tagged_facets` sorts the skin by tag.
        .filter(|(tag, _)| skin.binary_search_by_key(*tag, |(_, t)| *t).is_ok())
        .chain(data.domain_name.iter().map(|name| (&solid, name)))
        .map(|(&tag, name)| {
            if name.contains(['"', ';', '\n', '\r']) {
                let message = format!(
                    "group name {name:?} cannot be a NASTRAN property's name comment (no quotes, semicolons or line breaks)"
                );
                return Err(MeshError::Format { path: path.to_owned(), message });
            }
            Ok((tag, name.as_str()))
        })
        .collect::<Result<_, _>>()?;
    write_body(nodes, &skin, &names, solid, w).map_err(write_error(path))
}

fn write_body<const D: usize>(
    nodes: &Nodes<D>,
    skin: &[(Vec<u32>, i32)],
    names: &BTreeMap<i32, &str>,
    solid: i32,
    w: &mut impl Write,
) -> std::io::Result<()> {
    writeln!(w, "$ written by amber\nBEGIN BULK")?;
    for (i, p) in nodes.points().enumerate() {
        let [x, y, z] = [p[0], p[1], if D == 3 { p[2] } else { 0.0 }].map(large_field_real);
        writeln!(w, "GRID,{},,{x},{y},{z}", i + 1)?;
    }
    let (card, facet_card) = match (D, nodes.is_quadratic()) {
        (2, false) => ("CTRIA3", ""),
        (2, true) => ("CTRIA6", ""),
        (_, false) => ("CTETRA", "CTRIA3"),
        (_, true) => ("CTETRA", "CTRIA6"),
    };
    let mut write_element = |card: &str, id: usize, pid: i32, grids: &[u32]| {
        write!(w, "{card},{id},{pid}")?;
        for (k, v) in grids.iter().enumerate() {
            // A free-field card holds eight fields after its name; a 10-node CTETRA continues.
            if k == 6 {
                write!(w, ",+\n+")?;
            }
            write!(w, ",{}", v + 1)?;
        }
        writeln!(w)
    };
    let elements = nodes.mesh().num_elements();
    for (e, cell) in nodes.elements().enumerate() {
        write_element(card, e + 1, solid, &cell)?;
    }
    for (k, (facet, tag)) in skin.iter().enumerate() {
        write_element(facet_card, elements + k + 1, *tag, &nodes.facet(facet))?;
    }
    let mut tags: Vec<i32> = skin.iter().map(|&(_, t)| t).collect();
    tags.dedup();
    let solid_card = if D == 3 { "PSOLID" } else { "PSHELL" };
    let properties = std::iter::once((solid, solid_card)).chain(tags.into_iter().map(|tag| (tag, "PSHELL")));
    // Each pre-processor's own way: HyperMesh's before the card, ANSA's at the end of the model.
    let mut ansa = String::new();
    for (pid, card) in properties {
        if let Some(name) = names.get(&pid) {
            writeln!(w, "$HMNAME PROP {pid} \"{name}\"")?;
            ansa.push_str(&format!("$ANSA_NAME_COMMENT;{pid};{card};{name};;NO;NO;NO;NO;\n"));
        }
        match (pid == solid, D) {
            (true, 3) => writeln!(w, "PSOLID,{pid},1")?,
            (true, _) => writeln!(w, "PSHELL,{pid},1,1.")?,
            (false, _) => writeln!(w, "PSHELL,{pid}")?,
        }
    }
    w.write_all(ansa.as_bytes())?;
    writeln!(w, "ENDDATA")
}

/// `x` in at most 16 characters, a large field's width, which is what MSC Nastran reads a
/// free-field entry into (and some readers take only 8): the shortest form that reads back
/// bit-exactly when it fits, else the most significant digits that fit in scientific notation
/// (5e-11 relative at worst for exponents of one or two digits).
fn large_field_real(x: f64) -> String {
    let shortest = format!("{x:?}");
    if shortest.len() <= LARGE_FIELD {
        return shortest;
    }
    // Rounding near f64::MAX may overflow, which a shorter form avoids.
    let fits = |s: &String| s.len() <= LARGE_FIELD && s.parse::<f64>().is_ok_and(f64::is_finite);
    (1..=15).rev().map(|digits| format!("{x:.digits$e}")).find(fits).unwrap_or(shortest)
}

const LARGE_FIELD: usize = 16;

/// The fields of one card: fixed columns (8 characters for the name, then 8 or, in large-field
/// cards, 16 each), or comma-separated when the line has a comma. Field 0 is the card name;
/// missing fields are empty.
enum Fields<'a> {
    Fixed(&'a str, usize),
    Free(Vec<&'a str>),
}

impl<'a> Fields<'a> {
    /// `None` if a fixed-width field would split a multi-byte character.
    fn split(line: &'a str, width: usize) -> Option<Self> {
        if line.contains(',') {
            return Some(Fields::Free(line.split(',').map(str::trim).collect()));
        }
        // Validate every column boundary once so that `get` cannot fail later.
        let boundaries = std::iter::once(0).chain((8..=line.len()).step_by(width));
        boundaries.into_iter().all(|i| line.is_char_boundary(i)).then_some(Fields::Fixed(line, width))
    }

    fn get(&self, i: usize) -> &'a str {
        match self {
            Fields::Fixed(line, width) => {
                let (start, end) = if i == 0 { (0, 8) } else { (8 + width * (i - 1), 8 + width * i) };
                line.get(start.min(line.len())..end.min(line.len())).unwrap_or("").trim()
            }
            Fields::Free(fields) => fields.get(i).copied().unwrap_or(""),
        }
    }
}

/// A NASTRAN real: blank is 0.0; accepts `1.5`, `1.5E+3`, `1.5D+3` and the implicit exponent
/// forms `1.5+3`, `-7.11-15`, `1.-3`. Non-finite values are rejected.
fn real(field: &str) -> Option<f64> {
    if field.is_empty() {
        return Some(0.0);
    }
    let explicit = field.replace(['D', 'd'], "E");
    let value = explicit.parse::<f64>().ok().or_else(|| {
        // The exponent sign is the last sign that is not the leading character (of any width).
        let first = explicit.chars().next()?.len_utf8();
        let i = explicit[first..].rfind(['+', '-'])? + first;
        format!("{}E{}", &explicit[..i], &explicit[i..]).parse().ok()
    })?;
    value.is_finite().then_some(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::ElementOrder;
    use crate::{Mesh2, Mesh3};

    /// Coordinates whose shortest form is longer than a large field are written to fit it and
    /// read back to 5e-11 relative (5e-9 with a three-digit exponent); short ones exactly.
    #[test]
    fn coordinates_fit_a_large_field() {
        for x in [0.5, -1.0, 1e-5, 0.1 + 0.2, 1.0 / 3.0, -2.0 / 3.0e-300, 123456.78901234567, -1e-7 / 3.0, f64::MAX] {
            let text = large_field_real(x);
            let back: f64 = text.parse().unwrap();
            let tolerance = if x.abs().log10().abs() >= 99.0 { 5e-9 } else { 5e-11 };
            assert!(text.len() <= LARGE_FIELD, "{x}: {text}");
            assert!((back - x).abs() <= tolerance * x.abs(), "{x}: {text}");
            if format!("{x:?}").len() <= LARGE_FIELD {
                assert_eq!(back, x, "{text}");
            }
        }
    }

    fn parse(text: &str) -> Result<Mesh3, MeshError> {
        let path = Path::new("inline.nas");
        read(path, text.as_bytes())?.finish(path).map(|(mesh, _)| mesh)
    }

    /// Two tetrahedra sharing a face, one listed with negative orientation, GRID ids with gaps,
    /// a boundary triangle, CRLF, a free-field GRID and implicit exponents.
    const TWO_TETS: &str = "$ comment\r\nBEGIN BULK\r\n\
GRID          10              0.      0.      0.\r\n\
GRID          20            1.+0 -1.0-15      0.\r\n\
GRID          30                     1.0      0.\r\n\
GRID,40,,0.,0.,1.D0\r\n\
GRID          55            0.25    0.25     -1.\r\n\
PSOLID       374       2\r\n\
CTETRA         1     374      10      20      30      40\r\n\
CTETRA         2     374      10      20      30      55\r\n\
CTRIA3         1     375      10      20      30\r\n\
ENDDATA\r\n\
GRID          99            junk\r\n";

    #[test]
    fn reads_fixed_and_free_fields_and_reorients() {
        let mesh = parse(TWO_TETS).unwrap();
        assert_eq!(mesh.num_vertices(), 5);
        assert_eq!(mesh.num_elements(), 2);
        assert_eq!(mesh.vertices()[1], [1.0, -1e-15, 0.0]);
        assert_eq!(mesh.vertices()[3], [0.0, 0.0, 1.0]);
        assert!((mesh.total_volume() - 2.0 / 6.0).abs() < 1e-12);
        assert!(mesh.volumes().iter().all(|&v| v > 0.0));
    }

    #[test]
    fn skin_triangles_are_facet_tags_by_property_id() {
        let path = Path::new("x.nas");
        let (_, data) = read(path, TWO_TETS.as_bytes()).unwrap().finish::<3>(path).unwrap();
        assert_eq!(data.facet_tags, std::collections::BTreeMap::from([(vec![0, 1, 2], 375)]));
        assert!(data.dropped.is_empty(), "a skin triangle is a facet tag, not a dropped element: {:?}", data.dropped);
    }

    /// A cube of six tets around its diagonal; two facets of the face z = 0 tagged 4 and one of
    /// x = 1 tagged 9, the rest of the boundary untagged.
    fn tagged_cube() -> (Mesh3, MeshData) {
        let vertices: Vec<[f64; 3]> =
            (0..8).map(|k| [(k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64]).collect();
        let cells = vec![0, 1, 3, 7, 0, 1, 5, 7, 0, 2, 3, 7, 0, 2, 6, 7, 0, 4, 5, 7, 0, 4, 6, 7];
        let data = MeshData::new()
            .with_facet_tag(vec![0, 1, 3], 4)
            .with_facet_tag(vec![0, 2, 3], 4)
            .with_facet_tag(vec![1, 3, 7], 9);
        (Mesh3::new_reoriented(vertices, cells).unwrap(), data)
    }

    #[test]
    fn writes_the_boundary_as_outward_skin_groups_under_their_own_properties() {
        let (mesh, data) = tagged_cube();
        let path = Path::new("cube.nas");
        for order in [ElementOrder::Linear, ElementOrder::Quadratic] {
            let mut bytes = Vec::new();
            write(&Nodes::new(&mesh, order), &data, &mut bytes, path).unwrap();
            let text = String::from_utf8(bytes.clone()).unwrap();
            // 12 boundary triangles: 3 tagged, 9 under one past the largest tag; the solid after them.
            assert!(
                text.contains("PSOLID,11,1\n") && text.contains("PSHELL,4\n") && text.contains("PSHELL,9\n"),
                "{text}"
            );
            assert!(text.contains("PSHELL,10\n"));
            let skin = if order == ElementOrder::Linear { "CTRIA3," } else { "CTRIA6," };
            assert_eq!(text.matches(skin).count(), 12);
            assert_eq!(
                text.lines().filter(|l| l.starts_with("CTETRA,") && l.split(',').nth(2) == Some("11")).count(),
                6
            );
            let (back, back_data) = read(path, &bytes).unwrap().finish::<3>(path).unwrap();
            assert_eq!((back.vertices(), back.cells()), (mesh.vertices(), mesh.cells()));
            assert_eq!(back_data.facet_tags.len(), 12);
            assert_eq!(back_data.facet_tags.values().filter(|&&t| t == 10).count(), 9);
            for (facet, tag) in &data.facet_tags {
                assert_eq!(back_data.facet_tags.get(facet), Some(tag));
            }
            // Each skin triangle's grids turn counter-clockwise seen from outside the cube.
            let centre = [0.5; 3];
            for line in text.lines().filter(|l| l.starts_with(skin)) {
                let grid: Vec<usize> =
                    line.split(',').skip(3).take(3).map(|g| g.parse::<usize>().unwrap() - 1).collect();
                let p = |i: usize| mesh.vertices()[grid[i]];
                let (a, b, c) = (p(0), p(1), p(2));
                let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
                let normal = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
                let outward: f64 = (0..3).map(|k| normal[k] * (a[k] - centre[k])).sum();
                assert!(outward > 0.0, "{line}");
            }
        }
        let negative = MeshData::new().with_facet_tag(vec![0, 1, 3], -2);
        let message =
            write(&Nodes::new(&mesh, ElementOrder::Linear), &negative, &mut Vec::new(), path).unwrap_err().to_string();
        assert!(message.contains("cube.nas") && message.contains("positive"), "{message}");
    }

    #[test]
    fn names_skin_properties_in_both_pre_processors_comments() {
        let (mesh, mut data) = tagged_cube();
        data.facet_names = BTreeMap::from([(4, "bolt seat".into()), (9, "weld-2".into()), (12, "unused".into())]);
        data.domain_name = Some("bracket".into());
        let path = Path::new("cube.nas");
        let mut bytes = Vec::new();
        write(&Nodes::new(&mesh, ElementOrder::Linear), &data, &mut bytes, path).unwrap();
        let text = String::from_utf8(bytes.clone()).unwrap();
        for line in [
            "$HMNAME PROP 4 \"bolt seat\"\nPSHELL,4\n",
            "$HMNAME PROP 9 \"weld-2\"\nPSHELL,9\n",
            "$ANSA_NAME_COMMENT;4;PSHELL;bolt seat;;NO;NO;NO;NO;\n",
            "$HMNAME PROP 11 \"bracket\"\nPSOLID,11,1\n",
            "$ANSA_NAME_COMMENT;11;PSOLID;bracket;;NO;NO;NO;NO;\n$ANSA_NAME_COMMENT;4;PSHELL;bolt seat;;NO;NO;NO;NO;\n",
            "$ANSA_NAME_COMMENT;9;PSHELL;weld-2;;NO;NO;NO;NO;\nENDDATA",
        ] {
            assert!(text.contains(line), "{line:?} in\n{text}");
        }
        assert!(!text.contains("unused"), "a name without facets is not written");
        let (_, back) = read(path, &bytes).unwrap().finish::<3>(path).unwrap();
        assert_eq!(back.facet_names, BTreeMap::from([(4, "bolt seat".into()), (9, "weld-2".into())]));
        assert_eq!(back.domain_name.as_deref(), Some("bracket"));
        // The untagged rest of the boundary (PSHELL 10) stays unnamed.
        assert_eq!(back.facet_tags.values().filter(|&&t| t == 10).count(), 9);
        for bad in ["a;b", "say \"hi\"", "two\nlines"] {
            data.facet_names.insert(4, bad.into());
            let message =
                write(&Nodes::new(&mesh, ElementOrder::Linear), &data, &mut Vec::new(), path).unwrap_err().to_string();
            assert!(message.contains("cube.nas") && message.contains("name comment"), "{message}");
        }
    }

    #[test]
    fn reads_property_names_from_ansa_and_hypermesh_comments() {
        let named = |comments: &str| {
            let text = TWO_TETS.replacen("BEGIN BULK", &format!("BEGIN BULK\r\n{comments}"), 1);
            let path = Path::new("named.nas");
            read(path, text.as_bytes()).unwrap().finish::<3>(path).unwrap().1.facet_names
        };
        let skin = |name: &str| BTreeMap::from([(375, name.to_owned())]);
        assert_eq!(named("$ANSA_NAME_COMMENT;375;PSHELL;Part 1;;NO;NO;NO;NO;"), skin("Part 1"));
        assert_eq!(named("$HMNAME PROP                 375\"clamp face\"       4"), skin("clamp face"));
        assert_eq!(named("$HMNAME PROP 375 \"clamp face\""), skin("clamp face"));
        // The solid's property name and a material's name no facet; the later comment wins.
        let both = "$ANSA_NAME_COMMENT;374;PSOLID;Part 1_Volume_375;;NO;NO;NO;NO;\n\
                    $ANSA_NAME_COMMENT;375;MAT1;steel;;NO;NO;NO;\n\
                    $HMNAME PROP 375 \"first\"\n$ANSA_NAME_COMMENT;375;PSHELL;second;;";
        assert_eq!(named(both), skin("second"));
        let path = Path::new("named.nas");
        let solid = TWO_TETS.replacen("BEGIN BULK", "BEGIN BULK\n$ANSA_NAME_COMMENT;374;PSOLID;Part 1_Volume_375;;", 1);
        let data = read(path, solid.as_bytes()).unwrap().finish::<3>(path).unwrap().1;
        assert_eq!((data.domain_name.as_deref(), data.facet_names), (Some("Part 1_Volume_375"), BTreeMap::new()));
        // Comments cut short or malformed name nothing, and the deck still reads.
        for comment in [
            "$ANSA_NAME_COMMENT;375;PSHELL;a name wrapped at column eighty without its",
            "$ANSA_NAME_COMMENT;x75;PSHELL;Part 1;;",
            "$ANSA_NAME_COMMENT;-375;PSHELL;Part 1;;",
            "$ANSA_NAME_COMMENT;375;PSHELL;  ;;",
            "$HMNAME PROP 375 \"no closing quote",
            "$HMNAME PROPERTIES 375\"an LS-DYNA comment\"",
            "$HMNAME COMP 375 \"a component\"",
        ] {
            assert_eq!(named(comment), BTreeMap::new(), "{comment}");
        }
    }

    #[test]
    fn nastran_reals() {
        let cases = [
            ("-7.11-15", -7.11e-15),
            ("1.5+3", 1.5e3),
            ("1.-3", 1e-3),
            ("-72.8988", -72.8988),
            (".5", 0.5),
            ("2.5E-2", 0.025),
            ("2.5d2", 250.0),
            ("", 0.0),
            ("7", 7.0),
        ];
        for (text, value) in cases {
            assert_eq!(real(text), Some(value), "{text}");
        }
        for bad in ["x", "1.5+", "--1", "inf", "NaN", "1e999"] {
            assert_eq!(real(bad), None, "{bad}");
        }
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases = [
            ("GRID           1            abc      0.      0.\n", 1, "bad coordinate `abc`"),
            ("GRID           1       5      0.      0.      0.\n", 1, "coordinate system 5"),
            ("GRID*                  1               0              0.              0.\nGRID,2\n", 2, "continuation"),
            (
                "GRID           1              0.      0.      0.\nGRID           1              0.      0.      0.\n",
                2,
                "defined twice",
            ),
            ("CTETRA         1       1       1       2       3       4\n", 1, "GRID 1"),
            ("CTETRA         1       1       1       2       3\n", 1, "CTETRA grid id"),
            ("GRID          1é      0.      0.      0.\n", 1, "non-ASCII"),
        ];
        for (text, line, needle) in cases {
            let message = parse(text).unwrap_err().to_string();
            assert!(message.starts_with(&format!("inline.nas:{line}:")) && message.contains(needle), "{message}");
        }
        assert!(matches!(parse("GRID,1,,0.,0.,0.\nENDDATA\n"), Err(MeshError::DimensionMismatch { found: 0, .. })));
        let truncated = &TWO_TETS[..TWO_TETS.find("CTETRA         2").unwrap()];
        let message = parse(truncated).unwrap_err().to_string();
        assert!(message.contains("no ENDDATA after line 9") && message.contains("truncated"), "{message}");
        let degenerate = TWO_TETS.replace("0.25    0.25     -1.", "  0.      0.      0.");
        assert!(matches!(parse(&degenerate), Err(MeshError::InvalidMesh { .. })));
        let path = Path::new("x.nas");
        assert!(matches!(
            read(path, TWO_TETS.as_bytes()).unwrap().finish::<2>(path),
            Err(MeshError::DimensionMismatch { expected: 2, found: 3, .. })
        ));
    }

    #[test]
    fn reads_large_field_grids_and_writes_what_it_reads() {
        let text = "GRID*                  1               0             0.0             0.0\n\
*                    0.0\nGRID*                  2               0             1.0            0.0\n*       -0.5\n\
GRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\nGRID,5,,1.,1.,1.\nCTETRA,1,1,1,2,3,4\nCTETRA,2,1,2,3,4,5,6,7,8,9,10,11\nCQUAD4,3,1,1,2,3,4\nENDDATA\n";
        let path = Path::new("large.nas");
        let (mesh, data) = read(path, text.as_bytes()).unwrap().finish::<3>(path).unwrap();
        assert_eq!(mesh.vertices()[1], [1.0, 0.0, -0.5]);
        assert_eq!(mesh.num_elements(), 2, "the 10-node CTETRA by its corners");
        assert_eq!(data.dropped, std::collections::BTreeMap::from([("quad".into(), 1)]));
        assert_eq!(data.linearised, std::collections::BTreeMap::from([("tetra10".into(), 1)]));
        let triangle = |x| Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [x, 1.0]], vec![0, 1, 2]).unwrap();
        for x in [0.25, 1.0 / 3.0] {
            let mut bytes = Vec::new();
            write(&Nodes::new(&triangle(x), ElementOrder::Linear), &MeshData::new(), &mut bytes, path).unwrap();
            let back = read(path, &bytes).unwrap().finish::<2>(path).unwrap().0;
            assert!((back.vertices()[2][0] - x).abs() <= 5e-11 * x, "{x}: {back:?}");
            assert_eq!((back.cells(), &back.vertices()[..2]), (triangle(x).cells(), &triangle(x).vertices()[..2]));
        }
    }

    /// Reads every console expert mesh shipped in shared/data (19 train + 2 val): positive
    /// volumes after reorientation, the published range of 7,800–41,856 tetrahedra, and the
    /// skin's name from ANSA's comment.
    #[test]
    fn reads_every_console_mesh() {
        let Some(root) = amber_testdata::shared("data/console") else { return };
        let mut files: Vec<_> = ["train", "val"]
            .iter()
            .filter_map(|split| std::fs::read_dir(root.join(split)).ok())
            .flatten()
            .filter_map(|entry| entry.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "nas"))
            .collect();
        files.sort();
        assert!(files.len() >= 21, "expected 19 train + 2 val meshes, found {}", files.len());
        let counts: Vec<usize> = std::thread::scope(|s| {
            let handles: Vec<_> = files
                .iter()
                .map(|path| {
                    s.spawn(move || {
                        let (mesh, data) = crate::read_mesh_with_data::<3>(path).unwrap_or_else(|e| panic!("{e}"));
                        assert!(mesh.volumes().iter().all(|&v| v > 0.0), "{}", path.display());
                        // ANSA names each part's one skin property and its solid's.
                        assert_eq!(data.facet_names.values().collect::<Vec<_>>(), ["Part 1"], "{}", path.display());
                        let solid = data.domain_name.unwrap_or_default();
                        assert!(solid.starts_with("Part 1_Volume_"), "{}: {solid}", path.display());
                        mesh.num_elements()
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        assert_eq!(counts.iter().min(), Some(&7_800));
        assert_eq!(counts.iter().max(), Some(&41_856));
    }
}
