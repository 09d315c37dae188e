//! NASTRAN bulk data (`.nas`) → tetrahedral mesh: GRID points and 4-node CTETRA elements, in
//! small fixed-field (8 characters) or free-field (comma-separated) form. Surface elements
//! (CTRIA3) and every other card are skipped; reading stops at ENDDATA, which must be there: a
//! file without it is truncated, and a partial mesh is never returned. Reals may use NASTRAN's
//! implicit exponent (`-7.11-15` = -7.11e-15). GRID ids may have gaps.

use std::collections::HashMap;
use std::path::Path;

use super::{Lines, MeshData, assemble};
use crate::{Mesh, MeshError};

pub(super) fn read<const D: usize>(path: &Path, bytes: &[u8]) -> Result<(Mesh<D>, MeshData), MeshError> {
    if D != 3 {
        return Err(MeshError::DimensionMismatch { path: path.to_owned(), expected: D, found: 3 });
    }
    let mut lines = Lines::new(path, bytes);
    let mut grid_index: HashMap<u64, u32> = HashMap::new();
    let mut vertices: Vec<[f64; D]> = Vec::new();
    // CTETRA grid ids with their line, resolved once every GRID is known (cards may come in any order).
    let mut tets: Vec<([u64; 4], usize)> = Vec::new();
    let mut complete = false;
    while let Some(line) = lines.next()? {
        if line.starts_with('$') || line.trim().is_empty() {
            continue;
        }
        let fields = Fields::split(line).ok_or_else(|| lines.error("non-ASCII text inside a fixed-width field"))?;
        let card = fields.get(0).to_ascii_uppercase();
        if card.ends_with('*') {
            return Err(lines.error(format!("large-field card `{card}` is not supported")));
        }
        match card.as_str() {
            "GRID" => {
                let id: u64 = lines.parse(Some(fields.get(1)), "GRID id")?;
                if !matches!(fields.get(2), "" | "0") {
                    return Err(lines.error(format!("GRID {id} uses coordinate system {}", fields.get(2))));
                }
                let coordinate = |i: usize| {
                    real(fields.get(i))
                        .ok_or_else(|| lines.error(format!("bad coordinate `{}` in GRID {id}", fields.get(i))))
                };
                let p = [coordinate(3)?, coordinate(4)?, coordinate(5)?];
                if grid_index.insert(id, vertices.len() as u32).is_some() {
                    return Err(lines.error(format!("GRID {id} is defined twice")));
                }
                vertices.push(std::array::from_fn(|k| p[k]));
            }
            "CTETRA" => {
                if !fields.get(7).is_empty() || !fields.get(8).is_empty() {
                    return Err(lines.error("10-node CTETRA is not supported"));
                }
                let mut ids = [0u64; 4];
                for (k, id) in ids.iter_mut().enumerate() {
                    *id = lines.parse(Some(fields.get(3 + k)), "CTETRA grid id")?;
                }
                tets.push((ids, lines.line));
            }
            "ENDDATA" => {
                complete = true;
                break;
            }
            _ => {}
        }
    }
    if tets.is_empty() {
        return Err(MeshError::Format { path: path.to_owned(), message: "no CTETRA elements".into() });
    }
    let mut cells = Vec::with_capacity(4 * tets.len());
    for (ids, line) in tets {
        for id in ids {
            let v = grid_index.get(&id).ok_or_else(|| MeshError::Parse {
                path: path.to_owned(),
                line,
                message: format!("CTETRA references GRID {id}, which is not defined"),
            })?;
            cells.push(*v);
        }
    }
    if !complete {
        let message = format!("no ENDDATA after line {}: the file is truncated", lines.line);
        return Err(MeshError::Format { path: path.to_owned(), message });
    }
    assemble(path, vertices, cells, MeshData::new())
}

/// The fields of one card: fixed 8-character columns, or comma-separated when the line has a
/// comma. Field 0 is the card name; missing fields are empty.
enum Fields<'a> {
    Fixed(&'a str),
    Free(Vec<&'a str>),
}

impl<'a> Fields<'a> {
    /// `None` if a fixed-width field would split a multi-byte character.
    fn split(line: &'a str) -> Option<Self> {
        if line.contains(',') {
            return Some(Fields::Free(line.split(',').map(str::trim).collect()));
        }
        // Validate every column boundary once so that `get` cannot fail later.
        (0..=line.len()).step_by(8).all(|i| line.is_char_boundary(i)).then_some(Fields::Fixed(line))
    }

    fn get(&self, i: usize) -> &'a str {
        match self {
            Fields::Fixed(line) => {
                let start = (8 * i).min(line.len());
                let end = (8 * i + 8).min(line.len());
                line.get(start..end).unwrap_or("").trim()
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
        // The exponent sign is the last sign that is not the leading one.
        let i = explicit[1..].rfind(['+', '-'])? + 1;
        format!("{}E{}", &explicit[..i], &explicit[i..]).parse().ok()
    })?;
    value.is_finite().then_some(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Mesh3;

    fn parse(text: &str) -> Result<Mesh3, MeshError> {
        read::<3>(Path::new("inline.nas"), text.as_bytes()).map(|(mesh, _)| mesh)
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
            ("GRID*                  1\n", 1, "large-field"),
            (
                "GRID           1              0.      0.      0.\nGRID           1              0.      0.      0.\n",
                2,
                "defined twice",
            ),
            ("CTETRA         1       1       1       2       3       4\n", 1, "GRID 1"),
            ("CTETRA         1       1       1       2       3\n", 1, "CTETRA grid id"),
            ("CTETRA         1       1       1       2       3       4       5       6\n", 1, "10-node"),
            ("GRID          1é      0.      0.      0.\n", 1, "non-ASCII"),
        ];
        for (text, line, needle) in cases {
            let message = parse(text).unwrap_err().to_string();
            assert!(message.starts_with(&format!("inline.nas:{line}:")) && message.contains(needle), "{message}");
        }
        assert!(parse("GRID 1 0. 0. 0.\n").unwrap_err().to_string().contains("no CTETRA"));
        let truncated = &TWO_TETS[..TWO_TETS.find("CTETRA         2").unwrap()];
        let message = parse(truncated).unwrap_err().to_string();
        assert!(message.contains("no ENDDATA after line 9") && message.contains("truncated"), "{message}");
        let degenerate = TWO_TETS.replace("0.25    0.25     -1.", "  0.      0.      0.");
        assert!(matches!(parse(&degenerate), Err(MeshError::InvalidMesh { .. })));
        assert!(matches!(
            read::<2>(Path::new("x.nas"), TWO_TETS.as_bytes()),
            Err(MeshError::DimensionMismatch { expected: 2, found: 3, .. })
        ));
    }

    /// Reads every console expert mesh shipped in shared/data (19 train + 2 val): positive
    /// volumes after reorientation, and the published range of 7,800–41,856 tetrahedra.
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
                        let mesh: Mesh3 = crate::read_mesh(path).unwrap_or_else(|e| panic!("{e}"));
                        assert!(mesh.volumes().iter().all(|&v| v > 0.0), "{}", path.display());
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
