//! VTK XML unstructured grid (`.vtu`), read in every encoding VTK and meshio write: `ascii`,
//! inline `binary` (base64, the header and the data encoded together or apart), `appended` raw or
//! base64 data, each optionally zlib-compressed (`vtkZLibDataCompressor`), with `UInt32` or
//! `UInt64` block headers, either byte order and any integer or float array type. The XML is
//! parsed with quick-xml up to `<AppendedData>`, whose raw bytes are never XML.
//!
//! The writer writes one piece: f64 points (z = 0 in 2D), Int64 connectivity and offsets, UInt8
//! types and the scalar fields as f64 arrays, inline base64 with `UInt64` headers (binary) or
//! ASCII.

use std::collections::BTreeMap;
use std::io::{Read, Write};
use std::path::Path;

use base64::Engine;
use quick_xml::events::{BytesStart, Event};

use super::cursor::{Number, Scalar, as_index};
use super::nodes::Nodes;
use super::raw::RawMesh;
use super::vtk::{cell_type, vtk_kind};
use super::{Encoding, MeshData};
use crate::MeshError;

#[derive(Clone, Copy, PartialEq, Eq)]
enum Section {
    Points,
    Cells,
    PointData,
    CellData,
    Other,
}

/// How a `DataArray` holds its values.
enum Payload {
    Ascii,
    Binary,
    Appended(usize),
}

struct Array {
    section: Section,
    name: String,
    ty: Scalar,
    components: usize,
    payload: Payload,
    text: String,
}

/// The file-wide settings of `<VTKFile>`.
struct Header {
    big_endian: bool,
    header: Scalar,
    compressed: bool,
}

pub(super) fn read(path: &Path, bytes: &[u8]) -> Result<RawMesh, MeshError> {
    let error = |message: String| MeshError::Format { path: path.to_owned(), message };
    let (xml, appended) = split_appended(bytes).map_err(|m| error(m.into()))?;
    let mut reader = quick_xml::Reader::from_reader(xml);
    let mut header = Header { big_endian: false, header: Scalar::U32, compressed: false };
    let mut section = Section::Other;
    let mut arrays: Vec<Array> = Vec::new();
    let mut current: Option<Array> = None;
    let mut counts: Option<(usize, usize)> = None;
    let mut grid = false;
    loop {
        let at = reader.buffer_position();
        let event = reader.read_event().map_err(|e| error(format!("byte {at}: not well-formed XML: {e}")))?;
        let xml_error = |message: String| MeshError::AtByte { path: path.to_owned(), offset: at as usize, message };
        match event {
            Event::Empty(e) if e.local_name().as_ref() == "DataArray" => {
                arrays.push(attributes(&e).and_then(|attrs| new_array(section, &attrs)).map_err(xml_error)?);
            }
            Event::Start(e) if e.local_name().as_ref() == "DataArray" => {
                current = Some(attributes(&e).and_then(|attrs| new_array(section, &attrs)).map_err(xml_error)?);
            }
            Event::Start(e) | Event::Empty(e) => {
                let attrs = attributes(&e).map_err(xml_error)?;
                let get = |key: &str| attrs.get(key).map(String::as_str);
                match e.local_name().as_ref() {
                    "VTKFile" => {
                        if get("type") != Some("UnstructuredGrid") {
                            return Err(error(format!(
                                "a VTK {} file, not an UnstructuredGrid",
                                get("type").unwrap_or("?")
                            )));
                        }
                        header.big_endian = get("byte_order") == Some("BigEndian");
                        header.header = match get("header_type") {
                            None | Some("UInt32") => Scalar::U32,
                            Some("UInt64") => Scalar::U64,
                            Some(other) => return Err(xml_error(format!("header_type {other} is not supported"))),
                        };
                        header.compressed = match get("compressor") {
                            None | Some("") => false,
                            Some("vtkZLibDataCompressor") => true,
                            Some(other) => {
                                return Err(xml_error(format!("compressor {other} is not supported, only zlib")));
                            }
                        };
                    }
                    "UnstructuredGrid" => grid = true,
                    "Piece" => {
                        if counts.is_some() {
                            return Err(xml_error("more than one piece: only single-piece grids are supported".into()));
                        }
                        let count = |key: &str| -> Result<usize, MeshError> {
                            let text = get(key).unwrap_or("");
                            text.parse().map_err(|_| xml_error(format!("{key}=\"{text}\" is not a count")))
                        };
                        counts = Some((count("NumberOfPoints")?, count("NumberOfCells")?));
                    }
                    "Points" => section = Section::Points,
                    "Cells" => section = Section::Cells,
                    "PointData" => section = Section::PointData,
                    "CellData" => section = Section::CellData,
                    _ => {}
                }
            }
            Event::Text(t) => {
                if let Some(array) = &mut current {
                    array.text.push_str(&t);
                }
            }
            Event::End(e) => match e.local_name().as_ref() {
                "DataArray" => arrays.extend(current.take()),
                "Points" | "Cells" | "PointData" | "CellData" => section = Section::Other,
                _ => {}
            },
            Event::Eof => break,
            _ => {}
        }
    }
    if !grid {
        return Err(error("no <UnstructuredGrid>".into()));
    }
    let (num_points, num_cells) = counts.ok_or_else(|| error("no <Piece>".into()))?;
    let appended_offsets: Vec<usize> =
        arrays.iter().filter_map(|a| if let Payload::Appended(o) = a.payload { Some(o) } else { None }).collect();
    let mut raw = RawMesh::default();
    let mut cell_arrays: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for array in &arrays {
        let values = decode(array, &header, &appended, &appended_offsets)
            .map_err(|m| error(format!("DataArray `{}`: {m}", array.name)))?;
        let expected = |n: usize| {
            if values.len() == n * array.components {
                Ok(())
            } else {
                let expected = n * array.components;
                Err(error(format!("DataArray `{}` has {} values, expected {expected}", array.name, values.len())))
            }
        };
        match array.section {
            Section::Points => {
                expected(num_points)?;
                if array.components != 3 {
                    return Err(error(format!("points have {} components, expected 3", array.components)));
                }
                raw.points = values.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
            }
            Section::Cells => {
                cell_arrays.insert(array.name.as_str(), values);
            }
            Section::PointData | Section::CellData if array.components == 1 => {
                let (n, fields) = if array.section == Section::PointData {
                    (num_points, &mut raw.point_data)
                } else {
                    (num_cells, &mut raw.cell_data)
                };
                expected(n)?;
                fields.insert(array.name.clone(), values);
            }
            _ => {}
        }
    }
    let mut cell_array =
        |name: &str| cell_arrays.remove(name).ok_or_else(|| error(format!("no `{name}` array in <Cells>")));
    let (connectivity, offsets, types) = (cell_array("connectivity")?, cell_array("offsets")?, cell_array("types")?);
    if offsets.len() != num_cells || types.len() != num_cells {
        let message = format!("{} offsets and {} types for {num_cells} cells", offsets.len(), types.len());
        return Err(error(message));
    }
    raw.nodes = connectivity
        .iter()
        .map(|&v| as_index(v).ok_or_else(|| error(format!("connectivity entry {v} is not a point index"))))
        .collect::<Result<_, _>>()?;
    let mut start = 0;
    for (i, (&t, &end)) in types.iter().zip(&offsets).enumerate() {
        let kind =
            as_index(t).and_then(|t| vtk_kind(t as u8)).ok_or_else(|| error(format!("cell {i}: unknown type {t}")))?;
        let end = as_index(end).map(|e| e as usize).filter(|&e| e >= start && e <= raw.nodes.len());
        let end = end.ok_or_else(|| error(format!("cell {i}: offset outside the connectivity")))?;
        raw.kinds.push(kind);
        raw.ends.push(end);
        start = end;
    }
    Ok(raw)
}

/// The attributes of an element, unescaped.
fn attributes(e: &BytesStart) -> Result<BTreeMap<String, String>, String> {
    let mut map = BTreeMap::new();
    for attr in e.attributes() {
        let attr = attr.map_err(|err| format!("bad attribute: {err}"))?;
        let key = attr.key.as_ref().to_owned();
        let value = quick_xml::escape::unescape(&attr.value).map_err(|err| format!("attribute {key}: {err}"))?;
        map.insert(key, value.into_owned());
    }
    Ok(map)
}

fn new_array(section: Section, attrs: &BTreeMap<String, String>) -> Result<Array, String> {
    let get = |key: &str| attrs.get(key).map(String::as_str);
    let type_name = get("type").unwrap_or("");
    let ty = Scalar::from_vtk_xml(type_name).ok_or_else(|| format!("DataArray type `{type_name}` is not supported"))?;
    let components = match get("NumberOfComponents") {
        None => 1,
        Some(text) => text.parse().ok().filter(|&n| n > 0).ok_or(format!("NumberOfComponents=\"{text}\""))?,
    };
    let payload = match get("format") {
        Some("ascii") => Payload::Ascii,
        Some("binary") => Payload::Binary,
        Some("appended") => {
            let text = get("offset").unwrap_or("");
            Payload::Appended(text.parse().map_err(|_| format!("appended DataArray with offset=\"{text}\""))?)
        }
        other => return Err(format!("DataArray format {other:?} is not supported")),
    };
    let name = get("Name").unwrap_or("").to_owned();
    Ok(Array { section, name, ty, components, payload, text: String::new() })
}

/// The appended data after the `_` marker of `<AppendedData>`.
struct Appended<'a> {
    bytes: &'a [u8],
    base64: bool,
}

/// The XML before `<AppendedData>`, and the appended data (empty if none).
fn split_appended(bytes: &[u8]) -> Result<(&[u8], Appended<'_>), &'static str> {
    let tag = b"<AppendedData";
    let Some(start) = bytes.windows(tag.len()).position(|w| w == tag) else {
        return Ok((bytes, Appended { bytes: &[], base64: false }));
    };
    let marker = bytes[start..].iter().position(|&b| b == b'_').ok_or("<AppendedData> without the `_` marker")?;
    let base64 = bytes[start..start + marker].windows(8).any(|w| w == b"\"base64\"");
    let data = &bytes[start + marker + 1..];
    let end = data.windows(15).rposition(|w| w == b"</AppendedData>").unwrap_or(data.len());
    Ok((&bytes[..start], Appended { bytes: &data[..end], base64 }))
}

/// The values of one array, as f64.
fn decode(array: &Array, header: &Header, appended: &Appended, offsets: &[usize]) -> Result<Vec<f64>, String> {
    let data = match array.payload {
        Payload::Ascii => {
            return array
                .text
                .split_ascii_whitespace()
                .map(|w| w.parse::<f64>().map_err(|_| format!("`{w}` is not a number")))
                .collect();
        }
        Payload::Binary => block(&base64_segments(array.text.as_bytes())?, header)?,
        Payload::Appended(offset) => {
            let rest = appended.bytes.get(offset..).ok_or(format!("offset {offset} is past the appended data"))?;
            if appended.base64 {
                // Appended base64: this array's text runs to the next offset.
                let end = offsets.iter().filter(|&&o| o > offset).min().map_or(rest.len(), |&o| o - offset);
                block(&base64_segments(&rest[..end])?, header)?
            } else {
                block(rest, header)?
            }
        }
    };
    if data.len() % array.ty.size() != 0 {
        return Err(format!("{} bytes, not a whole number of {:?} values", data.len(), array.ty));
    }
    Ok(array.ty.decode(&data, header.big_endian))
}

/// Decodes base64 that may be several streams back to back (VTK and meshio encode the block
/// header and the data apart, each with its own padding), ignoring whitespace.
fn base64_segments(text: &[u8]) -> Result<Vec<u8>, String> {
    let text: Vec<u8> = text.iter().copied().filter(|b| !b.is_ascii_whitespace()).collect();
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut rest = &text[..];
    while !rest.is_empty() {
        let pad = rest.iter().position(|&b| b == b'=');
        let end = pad.map_or(rest.len(), |p| p + rest[p..].iter().take_while(|&&b| b == b'=').count());
        base64::engine::general_purpose::STANDARD
            .decode_vec(&rest[..end], &mut out)
            .map_err(|e| format!("bad base64: {e}"))?;
        rest = &rest[end..];
    }
    Ok(out)
}

/// The data of one block-headed payload: `[n][data]` uncompressed, or `[blocks][block size]
/// [last size][compressed sizes...][zlib blocks...]`. Counts are checked against the bytes
/// present, and no block inflates past its announced size.
fn block(bytes: &[u8], header: &Header) -> Result<Vec<u8>, String> {
    let h = header.header.size();
    let word = |i: usize| -> Result<usize, String> {
        let b = bytes.get(i * h..(i + 1) * h).ok_or("truncated block header")?;
        let x = header.header.decode(b, header.big_endian)[0];
        // Header words are unsigned; anything near 2^50 is corrupt, not a size.
        (x < 1e15).then_some(x as usize).ok_or(format!("block header value {x}"))
    };
    if !header.compressed {
        let n = word(0)?;
        return bytes
            .get(h..h + n)
            .map(<[u8]>::to_vec)
            .ok_or(format!("{n} bytes announced, {} present", bytes.len() - h));
    }
    let blocks = word(0)?;
    if blocks.saturating_add(3).saturating_mul(h) > bytes.len() {
        return Err(format!("{blocks} compressed blocks announced in {} bytes", bytes.len()));
    }
    let (size, last) = (word(1)?, word(2)?);
    let mut start = (3 + blocks) * h;
    let mut out = Vec::new();
    for b in 0..blocks {
        let compressed = word(3 + b)?;
        let data = bytes.get(start..start + compressed).ok_or(format!("compressed block {b} is truncated"))?;
        start += compressed;
        let expected = if b + 1 == blocks && last != 0 { last } else { size };
        let before = out.len();
        flate2::read::ZlibDecoder::new(data)
            .take(expected as u64)
            .read_to_end(&mut out)
            .map_err(|e| format!("block {b} is not valid zlib data: {e}"))?;
        if out.len() - before != expected {
            return Err(format!("block {b} inflates to {} bytes, expected {expected}", out.len() - before));
        }
    }
    Ok(out)
}

pub(super) fn write<const D: usize>(
    nodes: &Nodes<D>,
    data: &MeshData,
    binary: bool,
    w: &mut impl Write,
) -> std::io::Result<()> {
    let encoding = if binary { Encoding::Binary } else { Encoding::Ascii };
    let (np, ne, per_element) = (nodes.num_points(), nodes.mesh().num_elements(), nodes.nodes_per_element());
    writeln!(w, "<?xml version=\"1.0\"?>")?;
    writeln!(
        w,
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">"
    )?;
    writeln!(w, "<UnstructuredGrid>\n<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{ne}\">")?;
    writeln!(w, "<PointData>")?;
    for (name, values) in &data.point {
        data_array(w, name, 1, &nodes.point_field(values), encoding)?;
    }
    writeln!(w, "</PointData>\n<CellData>")?;
    for (name, values) in &data.cell {
        data_array(w, name, 1, values, encoding)?;
    }
    writeln!(w, "</CellData>")?;
    let points: Vec<f64> = nodes.points().flat_map(|p| [p[0], p[1], if D == 3 { p[2] } else { 0.0 }]).collect();
    writeln!(w, "<Points>")?;
    data_array(w, "Points", 3, &points, encoding)?;
    writeln!(w, "</Points>\n<Cells>")?;
    let connectivity: Vec<i64> = nodes.elements().flatten().map(i64::from).collect();
    let offsets: Vec<i64> = (1..=ne as i64).map(|e| e * per_element as i64).collect();
    data_array(w, "connectivity", 1, &connectivity, encoding)?;
    data_array(w, "offsets", 1, &offsets, encoding)?;
    data_array(w, "types", 1, &vec![cell_type(D, nodes.is_quadratic()); ne], encoding)?;
    writeln!(w, "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>")
}

/// One `<DataArray>`: base64 of the UInt64 byte count, then base64 of the little-endian values
/// (encoded apart, as VTK does), or the values as text.
fn data_array<T: Number>(
    w: &mut impl Write,
    name: &str,
    components: usize,
    values: &[T],
    encoding: Encoding,
) -> std::io::Result<()> {
    let name = quick_xml::escape::escape(name);
    let format = if encoding == Encoding::Binary { "binary" } else { "ascii" };
    write!(
        w,
        "<DataArray type=\"{}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"{format}\">",
        T::VTK
    )?;
    if encoding == Encoding::Binary {
        let mut bytes = Vec::with_capacity(size_of_val(values));
        for v in values {
            v.put(false, &mut bytes);
        }
        let b64 = base64::engine::general_purpose::STANDARD;
        w.write_all(b64.encode((bytes.len() as u64).to_le_bytes()).as_bytes())?;
        w.write_all(b64.encode(&bytes).as_bytes())?;
    } else {
        for (i, v) in values.iter().enumerate() {
            write!(w, "{}{v:?}", if i == 0 { "" } else { " " })?;
        }
    }
    writeln!(w, "</DataArray>")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh;
    use crate::Mesh2;
    use crate::io::ElementOrder;

    fn square() -> Mesh2 {
        Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3]).unwrap()
    }

    fn to_text<const D: usize>(mesh: &Mesh<D>, data: &MeshData, binary: bool) -> String {
        let mut bytes = Vec::new();
        write(&Nodes::new(mesh, ElementOrder::Linear), data, binary, &mut bytes).unwrap();
        String::from_utf8(bytes).unwrap()
    }

    fn parse<const D: usize>(text: &str) -> Result<(Mesh<D>, MeshData), MeshError> {
        let path = Path::new("inline.vtu");
        read(path, text.as_bytes())?.finish(path)
    }

    #[test]
    fn writes_binary_and_ascii_f64_that_read_back_exactly() {
        let mesh = square();
        let data =
            MeshData::new().with_cell("h", vec![0.1 + 0.2, 1.0 / 3.0]).with_point("u", vec![1e-300, 2.0, 3.0, 4.0]);
        for binary in [true, false] {
            let text = to_text(&mesh, &data, binary);
            assert!(text.contains("type=\"Float64\""), "{text}");
            assert_eq!(parse::<2>(&text).unwrap(), (mesh.clone(), data.clone()));
        }
    }

    #[test]
    fn drops_lower_dimensional_cells_with_their_data() {
        let text = "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"2\">\
<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0</DataArray></Points>\
<CellData><DataArray type=\"Float64\" Name=\"h\" format=\"ascii\">9 1</DataArray></CellData>\
<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 0 1 2</DataArray>\
<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">2 5</DataArray>\
<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">3 5</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>";
        let (mesh, data) = parse::<2>(text).unwrap();
        assert_eq!(mesh.num_elements(), 1);
        assert_eq!(data.cell["h"], vec![1.0]);
        assert_eq!(data.dropped, BTreeMap::from([("line".into(), 1)]));
        assert!(matches!(parse::<3>(text), Err(MeshError::DimensionMismatch { found: 2, .. })));
    }

    #[test]
    fn reads_compressed_blocks_and_rejects_bad_ones() {
        let header = Header { big_endian: false, header: Scalar::U32, compressed: true };
        let payload: Vec<u8> = (0..100u8).collect();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&payload[..64]).unwrap();
        let first = z.finish().unwrap();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&payload[64..]).unwrap();
        let second = z.finish().unwrap();
        let mut bytes = Vec::new();
        for word in [2, 64, 36, first.len() as u32, second.len() as u32] {
            bytes.extend_from_slice(&word.to_le_bytes());
        }
        bytes.extend_from_slice(&first);
        bytes.extend_from_slice(&second);
        assert_eq!(block(&bytes, &header).unwrap(), payload);
        let mut bad = bytes.clone();
        let last = bad.len() - 3;
        bad[last] ^= 0xff;
        assert!(block(&bad, &header).unwrap_err().contains("block 1"));
        assert!(block(&bytes[..30], &header).unwrap_err().contains("truncated"));
        let mut huge = bytes.clone();
        huge[..4].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(block(&huge, &header).unwrap_err().contains("blocks announced"));
    }

    #[test]
    fn malformed_files_are_errors_not_panics() {
        let text = to_text(&square(), &MeshData::new().with_cell("h", vec![1.0, 2.0]), true);
        for cut in [0, 10, text.len() / 2, text.len() - 20] {
            let err = parse::<2>(&text[..cut]).unwrap_err();
            assert!(err.to_string().starts_with("inline.vtu"), "{err}");
        }
        assert!(parse::<2>("<VTKFile type=\"PolyData\"></VTKFile>").is_err());
        let garbles = [
            ("EAAAAAAAAAA=AAAAAAAA8D8AAAAAAAAAQA==", "EAAAAAAAAAA=AAAA!!AA8D8AAAAAAAAAQA==", "bad base64"),
            ("NumberOfPoints=\"4\"", "NumberOfPoints=\"5\"", "expected 15"),
            ("NumberOfCells=\"2\"", "NumberOfCells=\"x\"", "not a count"),
            ("AgAAAAAAAAA=BQU=", "AgAAAAAAAAA=BQo=", "3D mesh"),
            ("AgAAAAAAAAA=BQU=", "AgAAAAAAAAA=Bf8=", "unknown type 255"),
            ("AgAAAAAAAAA=BQU=", "AwAAAAAAAAA=BQU=", "3 bytes announced"),
        ];
        for (from, to, needle) in garbles {
            assert!(text.contains(from), "{from}");
            let message = parse::<2>(&text.replacen(from, to, 1)).unwrap_err().to_string();
            assert!(message.starts_with("inline.vtu") && message.contains(needle), "{message}");
        }
    }
}
