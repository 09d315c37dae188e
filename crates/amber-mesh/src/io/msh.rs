//! gmsh `.msh`, versions 2.2 and 4.1, ASCII and binary (little-endian, 8-byte `size_t`).
//!
//! The reader is our own rather than the `mshio` crate's: mshio reads 4.1 only, skips
//! `$ElementData` and `$PhysicalNames`, and panics on some inputs. It accepts what gmsh and
//! meshio write: entity blocks with physical groups (a lower-dimensional simplex in a physical
//! group becomes a facet tag), non-contiguous node tags, elements of every type (the raw mesh
//! keeps them all; [`RawMesh::finish`] picks), sections it does not know (skipped), and scalar
//! `$NodeData` / `$ElementData` (other component counts are skipped; a value missing for an
//! element or node is NaN).
//!
//! The writer writes 4.1 with `$Entities` and `$PhysicalNames`: the domain in physical group 1
//! `domain`, the boundary facets (and any other tagged facet) in one physical group per tag, each
//! in an entity of its own, and the fields as `$NodeData` / `$ElementData` (NaN on the facets).

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::io::Write;
use std::path::Path;

use super::cursor::{Cursor, Scalar};
use super::nodes::Nodes;
use super::raw::{Kind, RawMesh};
use super::{MeshData, require_positive_tags, tagged_facets, write_error, writer_adjacency};
use crate::MeshError;

/// The kind and node count of a gmsh element type.
fn element_type(t: i64) -> Option<(Kind, usize)> {
    let other = |dim, name| Kind { dim, name };
    Some(match t {
        1 => (Kind::LINE, 2),
        2 => (Kind::TRIANGLE, 3),
        3 => (other(2, "quad"), 4),
        4 => (Kind::TETRA, 4),
        5 => (other(3, "hexahedron"), 8),
        6 => (other(3, "wedge"), 6),
        7 => (other(3, "pyramid"), 5),
        8 => (Kind::LINE3, 3),
        9 => (Kind::TRIANGLE6, 6),
        10 => (other(2, "quad9"), 9),
        11 => (Kind::TETRA10, 10),
        12 => (other(3, "hexahedron27"), 27),
        13 => (other(3, "wedge18"), 18),
        14 => (other(3, "pyramid14"), 14),
        15 => (Kind::VERTEX, 1),
        16 => (other(2, "quad8"), 8),
        17 => (other(3, "hexahedron20"), 20),
        18 => (other(3, "wedge15"), 15),
        19 => (other(3, "pyramid13"), 13),
        20 => (other(2, "triangle9"), 9),
        21 => (other(2, "triangle10"), 10),
        26 => (other(1, "line4"), 4),
        29 => (other(3, "tetra20"), 20),
        _ => return None,
    })
}

/// The gmsh type of the simplex of dimension `dim` (1 to 3), linear or quadratic: point, (3-node)
/// line, (6-node) triangle, (10-node) tetrahedron.
fn simplex_type(dim: usize, quadratic: bool) -> i32 {
    if quadratic { [15, 8, 9, 11][dim] } else { [15, 1, 2, 4][dim] }
}

/// The numbers of a section body: words in an ASCII file, `int` / `size_t` / `double` in a
/// binary one.
struct Body<'a> {
    c: Cursor<'a>,
    binary: bool,
}

impl Body<'_> {
    fn int(&mut self, what: &str) -> Result<i64, MeshError> {
        if self.binary { Ok(self.c.value(Scalar::I32, what)? as i64) } else { self.c.parse(what) }
    }

    fn size(&mut self, what: &str) -> Result<u64, MeshError> {
        if self.binary { Ok(self.c.value(Scalar::U64, what)? as u64) } else { self.c.parse(what) }
    }

    /// A coordinate, which must be finite.
    fn real(&mut self, what: &str) -> Result<f64, MeshError> {
        if self.binary { self.c.value(Scalar::F64, what) } else { self.c.real(what) }
    }

    /// A data value, which may be NaN or infinite.
    fn value(&mut self, what: &str) -> Result<f64, MeshError> {
        if self.binary { self.c.value(Scalar::F64, what) } else { self.c.parse(what) }
    }

    /// A count of items of at least `ascii_bytes` / `binary_bytes` each, bounded by the file.
    fn count(&mut self, n: u64, ascii_bytes: usize, binary_bytes: usize, what: &str) -> Result<usize, MeshError> {
        self.c.bound(n, if self.binary { binary_bytes } else { ascii_bytes }, what)
    }

    /// Consumes `$End{name}`.
    fn end(&mut self, name: &str) -> Result<(), MeshError> {
        let end = format!("$End{name}");
        match self.c.word()? {
            Some(word) if word == end => Ok(()),
            Some(word) => Err(self.c.error(format!("expected {end}, found `{word}`"))),
            None => Err(self.c.error(format!("unexpected end of file, expected {end}"))),
        }
    }
}

/// Tag → index: a vector when the tags are dense (gmsh numbers 1..n), else a hash map; a
/// million-element file resolves its three million node references several times faster so.
enum TagIndex {
    Dense(Vec<u32>),
    Sparse(HashMap<u64, u32>),
}

impl TagIndex {
    /// Fails with the first tag given twice.
    fn new(tags: &[u64]) -> Result<Self, u64> {
        let max = tags.iter().copied().max().unwrap_or(0);
        if max <= 2 * tags.len() as u64 + 16 {
            let mut index = vec![u32::MAX; max as usize + 1];
            for (i, &tag) in tags.iter().enumerate() {
                if std::mem::replace(&mut index[tag as usize], i as u32) != u32::MAX {
                    return Err(tag);
                }
            }
            return Ok(TagIndex::Dense(index));
        }
        let mut index = HashMap::with_capacity(tags.len());
        for (i, &tag) in tags.iter().enumerate() {
            if index.insert(tag, i as u32).is_some() {
                return Err(tag);
            }
        }
        Ok(TagIndex::Sparse(index))
    }

    /// The same, the last of repeated tags winning.
    fn last_wins(tags: &[u64]) -> Self {
        TagIndex::Sparse(tags.iter().enumerate().map(|(i, &t)| (t, i as u32)).collect())
    }

    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagIndex::Dense(index) => index.get(tag as usize).copied().filter(|&i| i != u32::MAX),
            TagIndex::Sparse(index) => index.get(&tag).copied(),
        }
    }
}

/// A `$NodeData` / `$ElementData` section with the tags it gives values for.
struct DataSection {
    on_elements: bool,
    name: String,
    values: Vec<(i64, f64)>,
}

/// Parses a whole `.msh` file into a raw mesh.
pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let mut body = Body { c: Cursor::new(path, bytes), binary: false };
    let mut version = None;
    let mut raw = RawMesh::default();
    let mut node_tags: Vec<u64> = Vec::new();
    let mut element_tags: Vec<u64> = Vec::new();
    // Element nodes as node tags, resolved once every node is known.
    let mut element_nodes: Vec<u64> = Vec::new();
    let mut entity_physical: HashMap<(i64, i64), i32> = HashMap::new();
    let mut sections = Vec::new();
    while let Some(word) = body.c.word()? {
        let Some(name) = word.strip_prefix('$') else {
            return Err(body.c.error(format!("expected a section header, found `{word}`")));
        };
        if version.is_none() && name != "MeshFormat" {
            return Err(body.c.error("not a gmsh file: it must start with $MeshFormat"));
        }
        body.c.skip_line();
        match name {
            "MeshFormat" => {
                let v = body.c.expect_word("the format version")?;
                if !matches!(v, "4.1" | "2.2") {
                    return Err(body.c.error(format!("gmsh format version {v} is not supported, only 2.2 and 4.1")));
                }
                body.binary = body.c.parse::<u8>("the file type")? == 1;
                if body.c.parse::<u8>("the data size")? != 8 {
                    return Err(body.c.error("the data size must be 8 (bytes in a size_t)"));
                }
                body.c.skip_line();
                if body.binary && body.int("the endianness check")? != 1 {
                    return Err(body.c.byte_error("big-endian binary .msh files are not supported"));
                }
                version = Some(v == "4.1");
                body.end(name)?;
            }
            "Entities" if version == Some(true) => read_entities(&mut body, &mut entity_physical)?,
            "Nodes" => read_nodes(&mut body, version == Some(true), &mut raw.points, &mut node_tags)?,
            "Elements" => read_elements(
                &mut body,
                version == Some(true),
                &entity_physical,
                &mut raw,
                &mut element_tags,
                &mut element_nodes,
            )?,
            "PhysicalNames" => read_physical_names(&mut body, &mut raw.tag_names)?,
            "NodeData" | "ElementData" => sections.extend(read_data(&mut body, name == "ElementData")?),
            _ => {
                let end = format!("$End{name}");
                let skip = body.c.rest().windows(end.len()).position(|w| w == end.as_bytes());
                let skip = skip.ok_or_else(|| body.c.error(format!("no $End{name} after ${name}")))?;
                body.c.take(skip, "the skipped section")?;
                body.end(name)?;
            }
        }
    }
    if version.is_none() {
        return Err(body.c.error("empty file"));
    }
    let node_index = TagIndex::new(&node_tags)
        .map_err(|tag| MeshError::Format { path: path.to_owned(), message: format!("node {tag} is defined twice") })?;
    raw.nodes = element_nodes
        .iter()
        .map(|&tag| {
            node_index.get(tag).ok_or_else(|| MeshError::Format {
                path: path.to_owned(),
                message: format!("an element references node {tag}, which $Nodes does not define"),
            })
        })
        .collect::<Result<_, _>>()?;
    // Element tags are unique within a file that gmsh reads; the last one wins otherwise.
    let element_index = TagIndex::new(&element_tags).unwrap_or_else(|_| TagIndex::last_wins(&element_tags));
    for s in sections {
        let (len, index) =
            if s.on_elements { (element_tags.len(), &element_index) } else { (node_tags.len(), &node_index) };
        let mut field = vec![f64::NAN; len];
        for (tag, value) in s.values {
            if let Some(i) = u64::try_from(tag).ok().and_then(|t| index.get(t)) {
                field[i as usize] = value;
            }
        }
        if s.on_elements {
            raw.cell_data.insert(s.name, field)
        } else {
            raw.point_data.insert(s.name, field)
        };
    }
    Ok(raw)
}

/// Reads `$PhysicalNames` (text in binary files too): `dimension tag "name"` per line.
fn read_physical_names(body: &mut Body, names: &mut Vec<(usize, i32, String)>) -> Result<(), MeshError> {
    let n: u64 = body.c.parse("number of physical names")?;
    // The shortest line is `1 1 ""` and its line ending.
    for _ in 0..body.c.bound(n, 7, "physical names")? {
        let dim: usize = body.c.parse("physical group dimension")?;
        let tag: i32 = body.c.parse("physical group tag")?;
        let line_start = body.c.pos;
        let line = body.c.expect_line("a physical name")?.trim();
        match line.strip_prefix('"').and_then(|l| l.strip_suffix('"')) {
            Some(name) => names.push((dim, tag, name.to_owned())),
            None => {
                body.c.pos = line_start;
                return Err(body.c.error(format!("physical name `{line}` is not in double quotes")));
            }
        }
    }
    body.end("PhysicalNames")
}

/// Reads `$Entities` (4.1): the physical group (the first, if several) of every entity.
fn read_entities(body: &mut Body, physical: &mut HashMap<(i64, i64), i32>) -> Result<(), MeshError> {
    let mut counts = [0; 4];
    for count in &mut counts {
        *count = body.size("an entity count")?;
    }
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..body.count(count, 2, 4, "entities")? {
            let tag = body.int("entity tag")?;
            for _ in 0..if dim == 0 { 3 } else { 6 } {
                body.value("entity bounding box")?;
            }
            let n = body.size("number of physical tags")?;
            for k in 0..body.count(n, 2, 4, "physical tags")? {
                let group = body.int("physical tag")?;
                if k == 0 {
                    physical.insert((dim as i64, tag), group as i32);
                }
            }
            if dim > 0 {
                let n = body.size("number of bounding entities")?;
                for _ in 0..body.count(n, 2, 4, "bounding entities")? {
                    body.int("bounding entity")?;
                }
            }
        }
    }
    body.end("Entities")
}

fn read_nodes(body: &mut Body, v41: bool, points: &mut Vec<[f64; 3]>, tags: &mut Vec<u64>) -> Result<(), MeshError> {
    let mut add = |tag: u64, p: [f64; 3]| {
        tags.push(tag);
        points.push(p);
    };
    if v41 {
        let blocks = body.size("number of node blocks")?;
        let total = body.size("number of nodes")?;
        body.size("minimum node tag")?;
        body.size("maximum node tag")?;
        let mut read = 0u64;
        for _ in 0..body.count(blocks, 8, 20, "node blocks")? {
            body.int("entity dimension")?;
            body.int("entity tag")?;
            if body.int("parametric flag")? != 0 {
                return Err(body.c.error("parametric nodes are not supported"));
            }
            let announced = body.size("number of nodes in block")?;
            let count = body.count(announced, 8, 32, "nodes")?;
            let block_tags = (0..count).map(|_| body.size("node tag")).collect::<Result<Vec<_>, _>>()?;
            for tag in block_tags {
                let p = [body.real("x coordinate")?, body.real("y coordinate")?, body.real("z coordinate")?];
                add(tag, p);
            }
            read += announced;
        }
        if read != total {
            return Err(body.c.error(format!("the $Nodes header announces {total} nodes, the blocks hold {read}")));
        }
    } else {
        let announced = body.c.parse("number of nodes")?;
        body.c.skip_line();
        for _ in 0..body.count(announced, 8, 28, "nodes")? {
            let tag = body.int("node tag")? as u64;
            let p = [body.real("x coordinate")?, body.real("y coordinate")?, body.real("z coordinate")?];
            add(tag, p);
        }
    }
    body.end("Nodes")
}

fn read_elements(
    body: &mut Body,
    v41: bool,
    entity_physical: &HashMap<(i64, i64), i32>,
    raw: &mut RawMesh,
    element_tags: &mut Vec<u64>,
    element_nodes: &mut Vec<u64>,
) -> Result<(), MeshError> {
    let kind_of = |body: &Body, t: i64| {
        element_type(t).ok_or_else(|| body.c.error(format!("element type {t} is not a gmsh type this reader knows")))
    };
    let mut push = |raw: &mut RawMesh, kind: Kind, tag: u64, physical: i32, nodes: &[u64]| {
        raw.kinds.push(kind);
        raw.tags.push(physical);
        element_tags.push(tag);
        element_nodes.extend_from_slice(nodes);
        raw.ends.push(element_nodes.len());
    };
    let mut nodes = Vec::new();
    if v41 {
        let blocks = body.size("number of element blocks")?;
        let total = body.size("number of elements")?;
        body.size("minimum element tag")?;
        body.size("maximum element tag")?;
        let mut read = 0u64;
        for _ in 0..body.count(blocks, 8, 20, "element blocks")? {
            let dim = body.int("entity dimension")?;
            let entity = body.int("entity tag")?;
            let t = body.int("element type")?;
            let (kind, n) = kind_of(body, t)?;
            let physical = entity_physical.get(&(dim, entity)).copied().unwrap_or(0);
            let announced = body.size("number of elements in block")?;
            for _ in 0..body.count(announced, 2 * (n + 1), 8 * (n + 1), "elements")? {
                let tag = body.size("element tag")?;
                nodes.clear();
                for _ in 0..n {
                    nodes.push(body.size("node tag")?);
                }
                push(raw, kind, tag, physical, &nodes);
            }
            read += announced;
        }
        if read != total {
            return Err(body
                .c
                .error(format!("the $Elements header announces {total} elements, the blocks hold {read}")));
        }
    } else {
        let announced = body.c.parse("number of elements")?;
        body.c.skip_line();
        let total = body.count(announced, 8, 16, "elements")?;
        let mut read = 0;
        while read < total {
            // ASCII: one element per line; binary: blocks of elements of one type.
            let (t, count, num_tags) = if body.binary {
                (body.int("element type")?, body.int("elements in block")?, body.int("number of tags")?)
            } else {
                (-1, 1, 0)
            };
            for _ in 0..count {
                let tag = body.int("element tag")? as u64;
                let (t, num_tags) = if body.binary { (t, num_tags) } else { (body.int("type")?, body.int("tags")?) };
                let (kind, n) = kind_of(body, t)?;
                let mut physical = 0;
                for k in 0..num_tags {
                    let value = body.int("element tag")?;
                    if k == 0 {
                        physical = value as i32;
                    }
                }
                nodes.clear();
                for _ in 0..n {
                    nodes.push(body.int("node tag")? as u64);
                }
                push(raw, kind, tag, physical, &nodes);
            }
            read += usize::try_from(count).map_err(|_| body.c.error(format!("bad element count {count}")))?;
        }
    }
    body.end("Elements")
}

/// Reads a `$NodeData` / `$ElementData` section; `None` for fields of more than one component.
fn read_data(body: &mut Body, on_elements: bool) -> Result<Option<DataSection>, MeshError> {
    let header = |body: &mut Body| -> Result<Vec<String>, MeshError> {
        let n: usize = body.c.parse("number of tags")?;
        body.c.skip_line();
        let n = body.c.bound(n as u64, 2, "tags")?;
        (0..n).map(|_| body.c.expect_line("a tag").map(|s| s.trim().to_owned())).collect()
    };
    let strings = header(body)?;
    header(body)?;
    let integers = header(body)?;
    let integer = |i: usize, what: &str| -> Result<usize, MeshError> {
        let word = integers.get(i).map(String::as_str).unwrap_or("");
        word.parse().map_err(|_| body.c.error(format!("bad {what} `{word}`")))
    };
    let components = integer(1, "number of components")?;
    let announced = integer(2, "number of entities")?;
    let name = strings.first().map(|s| s.trim_matches('"').to_owned()).unwrap_or_default();
    let count = body.count(announced as u64, 2 * (1 + components), 4 + 8 * components, "data values")?;
    let mut values = Vec::with_capacity(count);
    for _ in 0..count {
        let tag = body.int("tag")?;
        let value = body.value("value")?;
        for _ in 1..components {
            body.value("value")?;
        }
        values.push((tag, value));
    }
    body.end(if on_elements { "ElementData" } else { "NodeData" })?;
    Ok((components == 1).then_some(DataSection { on_elements, name, values }))
}

/// The numbers of a section body as [`Body`] reads them: words separated by spaces with a line
/// per record, or little-endian binary.
struct Out<'w, W: Write> {
    w: &'w mut W,
    binary: bool,
    first: bool,
}

impl<W: Write> Out<'_, W> {
    fn word(&mut self, text: std::fmt::Arguments) -> std::io::Result<()> {
        if !std::mem::take(&mut self.first) {
            self.w.write_all(b" ")?;
        }
        self.w.write_fmt(text)
    }

    fn int(&mut self, v: i32) -> std::io::Result<()> {
        if self.binary { self.w.write_all(&v.to_le_bytes()) } else { self.word(format_args!("{v}")) }
    }

    fn size(&mut self, v: usize) -> std::io::Result<()> {
        if self.binary { self.w.write_all(&(v as u64).to_le_bytes()) } else { self.word(format_args!("{v}")) }
    }

    /// Shortest round-trip form in ASCII.
    fn real(&mut self, v: f64) -> std::io::Result<()> {
        if self.binary { self.w.write_all(&v.to_le_bytes()) } else { self.word(format_args!("{v:?}")) }
    }

    fn end_record(&mut self) -> std::io::Result<()> {
        self.first = true;
        if self.binary { Ok(()) } else { self.w.write_all(b"\n") }
    }

    /// The ASCII line `text` (section headers, names and data-section tags are text even in a
    /// binary file).
    fn line(&mut self, text: &str) -> std::io::Result<()> {
        self.first = true;
        writeln!(self.w, "{text}")
    }
}

pub(super) fn write<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    binary: bool,
    w: &mut impl Write,
    path: &Path,
) -> Result<(), MeshError> {
    let names = data.cell.keys().chain(data.point.keys()).map(|n| ("field", n));
    let groups = data.facet_names.values().map(|n| ("facet group name", n));
    let domain = data.domain_name.iter().map(|n| ("domain name", n));
    for (what, name) in names.chain(groups).chain(domain) {
        if name.contains(['"', '\n', '\r']) {
            return Err(MeshError::Format {
                path: path.to_owned(),
                message: format!("{what} {name:?} cannot be stored in a .msh string"),
            });
        }
    }
    let facets = tagged_facets(nodes.mesh(), &writer_adjacency(nodes.mesh(), path)?, data, path)?;
    require_positive_tags(&facets, path, "gmsh physical groups")?;
    write_body(nodes, data, &facets, &mut Out { w, binary, first: true }).map_err(write_error(path))
}

/// Node tags are 1-based node indices (the vertices, then any edge nodes), the domain elements
/// come first (tags 1..=n, which the data sections refer to), then the facets group by group.
fn write_body<const D: usize, W: Write>(
    nodes: &Nodes<D>,
    data: &MeshData,
    facets: &[(Vec<u32>, i32)],
    out: &mut Out<W>,
) -> std::io::Result<()> {
    let mesh = nodes.mesh();
    let (nv, ne) = (nodes.num_points(), mesh.num_elements());
    let mut groups: BTreeMap<i32, Vec<Vec<u32>>> = BTreeMap::new();
    for (facet, tag) in facets {
        groups.entry(*tag).or_default().push(nodes.facet(facet));
    }
    out.line("$MeshFormat")?;
    out.line(if out.binary { "4.1 1 8" } else { "4.1 0 8" })?;
    if out.binary {
        out.int(1)?;
        out.line("")?;
    }
    out.line("$EndMeshFormat")?;

    out.line("$PhysicalNames")?;
    out.line(&format!("{}\n{D} 1 \"{}\"", groups.len() + 1, data.domain_group_name()))?;
    for &tag in groups.keys() {
        out.line(&format!("{} {tag} \"{}\"", D - 1, data.group_name(tag, groups.len())))?;
    }
    out.line("$EndPhysicalNames")?;

    // Entities: one per facet group (entity tag = 1, 2, ... in group order), one for the domain.
    let (lo, hi) = mesh.bounding_box().unwrap_or(([0.0; D], [0.0; D]));
    let corner = |p: [f64; D]| [p[0], p[1], if D == 3 { p[2] } else { 0.0 }];
    let (lo, hi) = (corner(lo), corner(hi));
    out.line("$Entities")?;
    let mut counts = [0, 0, 0, 0];
    counts[D - 1] = groups.len();
    counts[D] = 1;
    for c in counts {
        out.size(c)?;
    }
    out.end_record()?;
    let entity = |out: &mut Out<W>, tag: i32, physical: i32, bounding: &mut dyn Iterator<Item = i32>| {
        out.int(tag)?;
        for x in lo.iter().chain(&hi) {
            out.real(*x)?;
        }
        out.size(1)?;
        out.int(physical)?;
        let bounding: Vec<i32> = bounding.collect();
        out.size(bounding.len())?;
        for b in bounding {
            out.int(b)?;
        }
        out.end_record()
    };
    for (k, &tag) in groups.keys().enumerate() {
        entity(out, k as i32 + 1, tag, &mut std::iter::empty())?;
    }
    entity(out, 1, 1, &mut (1..=groups.len() as i32))?;
    if out.binary {
        out.line("")?;
    }
    out.line("$EndEntities")?;

    out.line("$Nodes")?;
    for v in [1, nv, 1, nv] {
        out.size(v)?;
    }
    out.end_record()?;
    out.int(D as i32)?;
    out.int(1)?;
    out.int(0)?;
    out.size(nv)?;
    out.end_record()?;
    for tag in 1..=nv {
        out.size(tag)?;
        out.end_record()?;
    }
    for p in nodes.points() {
        out.real(p[0])?;
        out.real(p[1])?;
        out.real(if D == 3 { p[2] } else { 0.0 })?;
        out.end_record()?;
    }
    if out.binary {
        out.line("")?;
    }
    out.line("$EndNodes")?;

    let total = ne + facets.len();
    out.line("$Elements")?;
    for v in [groups.len() + 1, total, 1, total] {
        out.size(v)?;
    }
    out.end_record()?;
    let quadratic = nodes.is_quadratic();
    let block = |out: &mut Out<W>,
                 dim: usize,
                 entity: i32,
                 elements: &mut dyn ExactSizeIterator<Item = Vec<u32>>,
                 first_tag| {
        let count = elements.len();
        out.int(dim as i32)?;
        out.int(entity)?;
        out.int(simplex_type(dim, quadratic))?;
        out.size(count)?;
        out.end_record()?;
        for (k, element) in elements.enumerate() {
            out.size(first_tag + k)?;
            for v in element {
                out.size(v as usize + 1)?;
            }
            out.end_record()?;
        }
        Ok::<usize, std::io::Error>(first_tag + count)
    };
    // gmsh numbers a 10-node tetrahedron's last two edges 2-3, 1-3; VTK's order (the nodes') 1-3, 2-3.
    let mut domain = nodes.elements().map(|mut element| {
        if element.len() == 10 {
            element.swap(8, 9);
        }
        element
    });
    let mut next_tag = block(out, D, 1, &mut domain, 1)?;
    for (k, members) in groups.values().enumerate() {
        next_tag = block(out, D - 1, k as i32 + 1, &mut members.iter().cloned(), next_tag)?;
    }
    if out.binary {
        out.line("")?;
    }
    out.line("$EndElements")?;

    let sections = data.point.iter().map(|f| ("NodeData", f)).chain(data.cell.iter().map(|f| ("ElementData", f)));
    for (section, (name, values)) in sections {
        // Element fields give the facets NaN: meshio rejects a field that skips elements.
        let (values, padding): (Cow<[f64]>, usize) = if section == "ElementData" {
            (Cow::Borrowed(values), facets.len())
        } else {
            (Cow::Owned(nodes.point_field(values)), 0)
        };
        let all = values.iter().copied().chain(std::iter::repeat_n(f64::NAN, padding));
        out.line(&format!("${section}\n1\n\"{name}\"\n1\n0.0\n3\n0\n1\n{}", values.len() + padding))?;
        for (i, v) in all.enumerate() {
            out.int(i as i32 + 1)?;
            out.real(v)?;
            out.end_record()?;
        }
        if out.binary {
            out.line("")?;
        }
        out.line(&format!("$End{section}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;
    use crate::io::ElementOrder;
    use crate::{Mesh2, Mesh3};

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        let path = Path::new("inline.msh");
        read(path, text.as_bytes())?.finish(path)
    }

    /// A unit square as gmsh 4.15 writes it (two triangles, clockwise as gmsh may list them),
    /// with entities, boundary lines in physical group 5, corner points and non-contiguous node
    /// tags.
    const GMSH_2D: &str = "$MeshFormat\r\n4.1 0 8\r\n$EndMeshFormat\r\n\
$PhysicalNames\r\n1\r\n2 1 \"domain\"\r\n$EndPhysicalNames\r\n\
$Entities\r\n4 4 1 0\r\n1 0 0 0 0\r\n2 1 0 0 0\r\n3 1 1 0 0\r\n4 0 1 0 0\r\n\
1 0 0 0 1 0 0 1 5 2 1 -2\r\n2 1 0 0 1 1 0 0 2 2 -3\r\n3 0 1 0 1 1 0 0 2 3 -4\r\n4 0 0 0 0 1 0 0 2 4 -1\r\n\
1 0 0 0 1 1 0 1 1 4 1 2 3 4\r\n$EndEntities\r\n\
$Nodes\r\n2 4 10 40\r\n0 1 0 1\r\n10\r\n0 0 0\r\n2 1 0 3\r\n20\r\n30\r\n40\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n$EndNodes\r\n\
$Elements\r\n3 5 1 9\r\n0 1 15 1\r\n1 10\r\n1 1 1 2\r\n2 10 20\r\n3 20 30\r\n2 1 2 2\r\n8 10 30 20\r\n9 10 40 30\r\n$EndElements\r\n";

    #[test]
    fn reads_what_gmsh_writes() {
        let (mesh, data) = parse::<2>(GMSH_2D).unwrap();
        assert_eq!(mesh.num_vertices(), 4);
        assert_eq!(mesh.num_elements(), 2);
        assert!(mesh.volumes().iter().all(|&v| (v - 0.5).abs() < 1e-15));
        assert_eq!(data.facet_tags, BTreeMap::from([(vec![0, 1], 5), (vec![1, 2], 5)]));
        assert_eq!(data.dropped, BTreeMap::from([("vertex".into(), 1)]));
        assert!(matches!(parse::<3>(GMSH_2D), Err(MeshError::DimensionMismatch { expected: 3, found: 2, .. })));
    }

    #[test]
    fn reads_version_2_2_with_physical_tags_and_data() {
        let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n\
$Elements\n3\n1 2 2 7 1 1 2 3\n2 4 2 1 1 1 3 2 4\n3 15 0 4\n$EndElements\n\
$ElementData\n1\n\"h\"\n1\n0.0\n3\n0\n1\n1\n2 0.25\n$EndElementData\n";
        let (mesh, data) = parse::<3>(text).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert!(mesh.volume(0) > 0.0, "the negative tetrahedron is flipped");
        assert_eq!(data.cell["h"], vec![0.25]);
        assert_eq!(data.facet_tags, BTreeMap::from([(vec![0, 1, 2], 7)]));
    }

    #[test]
    fn drops_surface_triangles_of_a_3d_mesh_and_reads_data() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n\
0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n2 2 1 7\n2 1 2 1\n3 1 2 3\n3 1 4 1\n7 1 3 2 4\n$EndElements\n\
$ElementData\n1\n\"h\"\n1\n0.0\n3\n0\n1\n2\n3 9.5\n7 0.25\n$EndElementData\n\
$NodeData\n1\n\"vec\"\n1\n0.0\n3\n0\n3\n1\n1 1 2 3\n$EndNodeData\n";
        let (mesh, data) = parse::<3>(text).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert_eq!(data.cell["h"], vec![0.25]);
        assert!(data.point.is_empty(), "vector fields are skipped");
        assert!(data.facet_tags.is_empty(), "no physical groups");
        assert!(matches!(parse::<2>(text), Err(MeshError::DimensionMismatch { expected: 2, found: 3, .. })));
    }

    fn written<const D: usize>(mesh: &Mesh<D>, data: &MeshData, binary: bool) -> Vec<u8> {
        let mut bytes = Vec::new();
        write(&Nodes::new(mesh, ElementOrder::Linear), data, binary, &mut bytes, Path::new("x.msh")).unwrap();
        bytes
    }

    #[test]
    fn writer_round_trips_bit_exactly_in_both_encodings() {
        let vertices = vec![[-0.0, 0.1, 0.2], [1.0 / 3.0, 0.1, 0.2], [0.0, 2f64.sqrt(), 0.2], [1e-7, 0.1, 0.3 + 0.6]];
        let mesh = Mesh3::new_reoriented(vertices, vec![0, 1, 2, 3]).unwrap();
        let data = MeshData::new()
            .with_cell("h", vec![f64::NAN])
            .with_point("u", vec![5e-324, 1e300, -2.5, -0.0])
            .with_facet_tag([0, 1, 2], 3)
            .with_facet_name(3, "inlet wall");
        let data = MeshData { domain_name: Some("steel bracket".into()), ..data };
        for binary in [false, true] {
            let bytes = written(&mesh, &data, binary);
            let path = Path::new("x.msh");
            let (back, back_data) = read(path, &bytes).unwrap().finish::<3>(path).unwrap();
            assert_eq!(back, mesh);
            assert!(back_data.cell["h"][0].is_nan());
            assert_eq!(back_data.point, data.point);
            // The three untagged boundary triangles get the next tag.
            assert_eq!(back_data.facet_tags.len(), 4);
            assert_eq!(back_data.facet_tags[&vec![0, 1, 2]], 3);
            assert_eq!(back_data.facet_tags.values().filter(|&&t| t == 4).count(), 3);
            assert_eq!(back_data.facet_names, BTreeMap::from([(3, "inlet wall".into()), (4, "boundary_4".into())]));
            assert_eq!(back_data.domain_name.as_deref(), Some("steel bracket"));
        }
        let linear = Nodes::new(&mesh, ElementOrder::Linear);
        let quoted = data.with_facet_name(3, "say \"hi\"");
        let err = write(&linear, &quoted, false, &mut Vec::new(), Path::new("x.msh")).unwrap_err().to_string();
        assert!(err.contains("facet group name") && err.contains("x.msh"), "{err}");
        let quoted = MeshData { domain_name: Some("a \"b\"".into()), ..MeshData::new() };
        let err = write(&linear, &quoted, false, &mut Vec::new(), Path::new("x.msh")).unwrap_err().to_string();
        assert!(err.contains("domain name") && err.contains("x.msh"), "{err}");
    }

    #[test]
    fn physical_names_must_be_quoted() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 5 inlet\n$EndPhysicalNames\n";
        let err = read(Path::new("x.msh"), text.as_bytes()).err().unwrap().to_string();
        assert!(err.contains("x.msh:6:") && err.contains("`inlet` is not in double quotes"), "{err}");
    }

    #[test]
    fn writes_one_boundary_group_by_default() {
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let text = String::from_utf8(written(&mesh, &MeshData::new(), false)).unwrap();
        assert!(text.contains("$PhysicalNames\n2\n2 1 \"domain\"\n1 1 \"boundary\"\n"), "{text}");
        assert!(text.contains("\n2 1 0 3\n") && text.contains("\n2 1 2 1\n1 1 2 3\n"), "{text}");
        let (back, data) = parse::<2>(&text).unwrap();
        assert_eq!(back, mesh);
        assert_eq!(data.facet_tags.len(), 3);
        assert_eq!(data.domain_name.as_deref(), Some("domain"));
        let linear = Nodes::new(&mesh, ElementOrder::Linear);
        let err =
            write(&linear, &MeshData::new().with_facet_tag([0, 1], 0), false, &mut Vec::new(), Path::new("x.msh"));
        assert!(err.unwrap_err().to_string().contains("positive"));
        let err =
            write(&linear, &MeshData::new().with_facet_tag([0, 7], 2), false, &mut Vec::new(), Path::new("x.msh"));
        assert!(err.unwrap_err().to_string().contains("[0, 7]"));
    }

    #[test]
    fn malformed_files_name_the_line_or_byte() {
        let cases: [(&str, usize, &str); 7] = [
            ("", 0, "empty"),
            ("$Nodes\n", 1, "$MeshFormat"),
            ("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", 2, "version 3.0"),
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
            ("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n2 1 0 2000000\n1\n", 6, "2000000 nodes announced"),
            (
                "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Elements\n1 1 1 1\n2 1 99 1\n1 1 2 3 4\n$EndElements\n",
                6,
                "element type 99",
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
        let twice = missing.replace("1 1 1 1\n2 1 0 1\n1\n0 0 0\n", "1 2 1 1\n2 1 0 2\n1\n1\n0 0 0\n1 0 0\n");
        assert!(parse::<2>(&twice).unwrap_err().to_string().contains("node 1 is defined twice"));
        let off_plane = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0.5\n1 0 0\n0 1 0\n\
$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n";
        assert!(parse::<2>(off_plane).unwrap_err().to_string().contains("plane z = 0"));
        // Every truncation of a binary file is an error naming the file, never a panic.
        let mesh = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], vec![0, 1, 2]).unwrap();
        let bytes = written(&mesh, &MeshData::new().with_cell("h", vec![1.0]), true);
        // A cut between sections leaves a shorter valid file; any other cut is an error.
        let path = Path::new("cut.msh");
        for cut in 0..bytes.len() - 1 {
            if let Err(err) = read(path, &bytes[..cut]).and_then(|raw| raw.finish::<2>(path)) {
                assert!(err.to_string().starts_with("cut.msh"), "{err}");
            }
        }
        let in_nodes = bytes.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 100;
        let err = read(path, &bytes[..in_nodes]).err().unwrap();
        assert!(err.to_string().contains("3 nodes announced, but only 41 bytes are left"), "{err}");
    }
}
