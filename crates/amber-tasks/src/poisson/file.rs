//! The JSON file of one Poisson problem. The layout is the reference implementation's —
//! `domain.polygon`, `load.{means, covariances, weights}`, `initial_mesh` and `mesh` with
//! `vertices` and `triangles` — plus our `metadata`, so one reader serves both. The same layout
//! without the meshes (and with any polygon, holes allowed) describes a [`PoissonPart`].

use std::path::{Path, PathBuf};

use amber_fem::GaussianMixture;
use amber_mesh::Mesh2;
use serde::{Deserialize, Serialize};

use super::{PoissonPart, PoissonProblem, ProblemMetadata, lshape_polygon};
use crate::TaskError;

#[derive(Serialize, Deserialize)]
struct ProblemFile {
    domain: DomainFile,
    load: GaussianMixture,
    initial_mesh: MeshFile,
    mesh: MeshFile,
    #[serde(default)]
    metadata: ProblemMetadata,
}

#[derive(Serialize, Deserialize)]
struct DomainFile {
    polygon: Vec<[f64; 2]>,
    /// Holes of a part's domain (problems are L-shapes without holes).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    holes: Vec<Vec<[f64; 2]>>,
}

/// A problem file read as a part: M⁰ and the expert mesh are optional.
#[derive(Deserialize)]
struct PartFile {
    domain: DomainFile,
    load: GaussianMixture,
    initial_mesh: Option<MeshFile>,
    mesh: Option<MeshFile>,
    #[serde(default)]
    metadata: ProblemMetadata,
}

#[derive(Serialize, Deserialize)]
struct MeshFile {
    vertices: Vec<[f64; 2]>,
    triangles: Vec<[u32; 3]>,
}

impl MeshFile {
    fn from_mesh(mesh: &Mesh2) -> Self {
        Self { vertices: mesh.vertices().to_vec(), triangles: mesh.elements().map(|c| [c[0], c[1], c[2]]).collect() }
    }

    /// Triangles may be listed clockwise (the reference's are unoriented): orient them.
    fn into_mesh(self, path: &Path, field: &'static str) -> Result<Mesh2, TaskError> {
        let cells = self.triangles.into_iter().flatten().collect();
        Mesh2::new_reoriented(self.vertices, cells).map_err(|source| TaskError::Mesh {
            path: path.into(),
            field,
            source,
        })
    }
}

impl PoissonProblem {
    /// The problem as JSON bytes (deterministic: the same problem gives the same bytes).
    pub fn to_json(&self) -> Vec<u8> {
        let file = ProblemFile {
            domain: DomainFile { polygon: self.polygon().to_vec(), holes: Vec::new() },
            load: self.load.clone(),
            initial_mesh: MeshFile::from_mesh(&self.initial_mesh),
            mesh: MeshFile::from_mesh(&self.expert_mesh),
            metadata: self.metadata.clone(),
        };
        serde_json::to_vec(&file).expect("plain data with finite numbers always serialises")
    }

    /// Parses a problem from JSON; `path` names the source in errors.
    pub fn from_json(bytes: &[u8], path: &Path) -> Result<Self, TaskError> {
        let file: ProblemFile =
            serde_json::from_slice(bytes).map_err(|source| TaskError::Json { path: path.into(), source })?;
        let corner =
            lshape_corner(&file.domain.polygon).map_err(|message| TaskError::Polygon { path: path.into(), message })?;
        Ok(Self {
            corner,
            load: file.load,
            initial_mesh: file.initial_mesh.into_mesh(path, "initial_mesh")?,
            expert_mesh: file.mesh.into_mesh(path, "mesh")?,
            metadata: file.metadata,
        })
    }

    /// Writes the problem to `path`.
    pub fn write(&self, path: &Path) -> Result<(), TaskError> {
        std::fs::write(path, self.to_json()).map_err(|source| TaskError::Io { path: path.into(), source })
    }
}

/// Reads one problem file (ours or the reference's).
pub fn read_problem(path: &Path) -> Result<PoissonProblem, TaskError> {
    let bytes = std::fs::read(path).map_err(|source| TaskError::Io { path: path.into(), source })?;
    PoissonProblem::from_json(&bytes, path)
}

/// Reads a problem file (ours or the reference's) as a [`PoissonPart`]: its domain (any polygon,
/// with optional `domain.holes`), load and, when present, initial mesh; with the expert `mesh`
/// when the file has one (checked as the problem's meshes are, not yet against the domain).
pub fn read_part(path: &Path) -> Result<(PoissonPart, Option<Mesh2>), TaskError> {
    let bytes = std::fs::read(path).map_err(|source| TaskError::Io { path: path.into(), source })?;
    let file: PartFile =
        serde_json::from_slice(&bytes).map_err(|source| TaskError::Json { path: path.into(), source })?;
    let domain = amber_meshgen::PolygonDomain::new(file.domain.polygon, file.domain.holes)
        .map_err(|e| TaskError::Polygon { path: path.into(), message: e.to_string() })?;
    let initial_mesh = file.initial_mesh.map(|m| m.into_mesh(path, "initial_mesh")).transpose()?;
    let expert_mesh = file.mesh.map(|m| m.into_mesh(path, "mesh")).transpose()?;
    let order =
        file.metadata.heuristic.map_or(amber_fem::ExpertHeuristic::default().quadrature_order, |h| h.quadrature_order);
    let part = PoissonPart::new(domain, file.load, initial_mesh, order)
        .map_err(|e| TaskError::Polygon { path: path.into(), message: format!("initial mesh: {e}") })?;
    Ok((part, expert_mesh))
}

/// Reads every problem file (`*.json`, ours or the reference's format) of a directory in name
/// order, all but a generated split's `index.json`; a directory without any is an error.
pub fn read_split(dir: &Path) -> Result<Vec<PoissonProblem>, TaskError> {
    let io = |source| TaskError::Io { path: dir.into(), source };
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .map(|entry| entry.map(|e| e.path()))
        .collect::<Result<_, _>>()
        .map_err(io)?;
    // Every JSON file is a problem but the split's own index (a generated split's cache record).
    paths.retain(|p| p.extension().is_some_and(|e| e == "json") && !p.ends_with(super::dataset::INDEX_FILE));
    paths.sort();
    if paths.is_empty() {
        let source = std::io::Error::new(std::io::ErrorKind::NotFound, "no problem files (*.json) in this directory");
        return Err(TaskError::Io { path: dir.into(), source });
    }
    paths.iter().map(|p| read_problem(p)).collect()
}

/// The re-entrant corner of an axis-aligned L-shape given as the six polygon vertices of
/// [`lshape_polygon`] (either orientation, any starting vertex).
fn lshape_corner(polygon: &[[f64; 2]]) -> Result<[f64; 2], String> {
    if polygon.len() != 6 {
        return Err(format!("expected the 6 vertices of an L-shape, found {}", polygon.len()));
    }
    let candidates: Vec<[f64; 2]> =
        polygon.iter().copied().filter(|&[x, y]| x > 0.0 && x < 1.0 && y > 0.0 && y < 1.0).collect();
    let [corner] = candidates[..] else {
        return Err(format!("expected exactly one vertex inside the unit square, found {}", candidates.len()));
    };
    let mut expected = lshape_polygon(corner).to_vec();
    let mut given = polygon.to_vec();
    let key = |p: &[f64; 2]| (p[0].to_bits(), p[1].to_bits());
    expected.sort_by_key(key);
    given.sort_by_key(key);
    if expected == given {
        Ok(corner)
    } else {
        Err(format!("{polygon:?} is not the unit square minus [px,1]×[py,1] with corner {corner:?}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_fem::GaussianMixtureParams;

    fn problem() -> PoissonProblem {
        let square = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.5, 0.5], [0.5, 1.0], [0.0, 1.0]],
            vec![0, 1, 2, 0, 2, 3, 0, 3, 5, 3, 4, 5],
        )
        .unwrap();
        PoissonProblem {
            corner: [0.5, 0.5],
            load: GaussianMixture::new(GaussianMixtureParams {
                means: vec![[0.3, 0.3]],
                covariances: vec![[[1e-3, 0.0], [0.0, 1e-3]]],
                weights: vec![1.0],
            })
            .unwrap(),
            initial_mesh: square.clone(),
            expert_mesh: square,
            metadata: ProblemMetadata { seed: Some(3), ..Default::default() },
        }
    }

    #[test]
    fn round_trip_is_exact() {
        let p = problem();
        let json = p.to_json();
        let back = PoissonProblem::from_json(&json, Path::new("x.json")).unwrap();
        assert_eq!(back, p);
        assert_eq!(back.to_json(), json);
    }

    #[test]
    fn reference_files_with_clockwise_triangles_load() {
        let text = r#"{"domain": {"polygon": [[0.5,0.5],[0.5,1],[0,1],[0,0],[1,0],[1,0.5]]},
            "load": {"means": [[0.3,0.3]], "covariances": [[[0.001,0],[0,0.001]]], "weights": [1.0]},
            "initial_mesh": {"vertices": [[0,0],[1,0],[1,0.5],[0.5,0.5],[0.5,1],[0,1]],
                             "triangles": [[0,2,1],[0,3,2],[0,5,3],[3,5,4]]},
            "mesh": {"vertices": [[0,0],[1,0],[1,0.5],[0.5,0.5],[0.5,1],[0,1]],
                     "triangles": [[0,1,2],[0,2,3],[0,3,5],[3,4,5]]}}"#;
        let p = PoissonProblem::from_json(text.as_bytes(), Path::new("ref.json")).unwrap();
        assert_eq!(p.corner, [0.5, 0.5]);
        assert!((p.initial_mesh.total_volume() - 0.75).abs() < 1e-15);
        assert_eq!(p.metadata, ProblemMetadata::default());
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let good = String::from_utf8(problem().to_json()).unwrap();
        let not_pd = good.replacen("[[0.001,0.0],[0.0,0.001]]", "[[0.001,0.002],[0.002,0.001]]", 1);
        let err = PoissonProblem::from_json(not_pd.as_bytes(), Path::new("data/007.json")).unwrap_err();
        assert!(matches!(err, TaskError::Json { .. }));
        let msg = err.to_string();
        assert!(msg.contains("data/007.json") && msg.contains("positive definite"), "{msg}");

        let degenerate = good.replacen("[0,1,2]", "[0,1,1]", 1);
        let err = PoissonProblem::from_json(degenerate.as_bytes(), Path::new("a.json")).unwrap_err();
        assert!(matches!(err, TaskError::Mesh { field: "initial_mesh", .. }), "{err}");

        let err = read_problem(Path::new("/nonexistent/001.json")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/001.json"));
        let err = PoissonProblem::from_json(b"{\"domain\": 3}", Path::new("b.json")).unwrap_err();
        assert!(err.to_string().starts_with("b.json"));
    }

    #[test]
    fn a_directory_reads_every_problem_file_whatever_its_name() {
        let dir = std::env::temp_dir().join(format!("amber-read-split-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let err = read_split(&dir).unwrap_err().to_string();
        assert!(err.contains("no problem files"), "{err}");
        problem().write(&dir.join("hole-plate.json")).unwrap();
        problem().write(&dir.join("002.json")).unwrap();
        std::fs::write(dir.join("index.json"), "{}").unwrap();
        assert_eq!(read_split(&dir).unwrap().len(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
