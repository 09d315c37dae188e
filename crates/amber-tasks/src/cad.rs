//! CAD geometry (STEP, IGES, OpenCASCADE BREP) read through gmsh: the part's faces tessellated
//! by gmsh's OpenCASCADE kernel, finer where they curve, one STL solid per CAD face, so that the
//! surface keeps the part's CAD faces and feature curves exactly. The settings are those of the
//! Console reference surfaces (`../shared/data/console/tools/make_ref.py`), so a model trained
//! on them reads a STEP file as the geometry it learnt from. gmsh is an external program (GPL,
//! with OpenCASCADE), run as `gmsh` from the `PATH`: `pip install gmsh` or a distribution's
//! package.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use amber_mesh::{StlFaceIds, TriangleSoup, read_surface};
use wait_timeout::ChildExt;

use crate::TaskError;

/// Extensions of the CAD files gmsh's OpenCASCADE kernel reads.
pub const CAD_EXTENSIONS: [&str; 5] = ["step", "stp", "iges", "igs", "brep"];

/// The tessellation's largest triangle per unit of M⁰'s element size: the Console reference
/// surfaces were made at 2.5 mm beside M⁰'s 4.3955 mm.
pub const TESSELLATION_SIZE_PER_INITIAL_SIZE: f64 = 2.5 / 4.3955;

/// Triangles per full turn of a curved face (gmsh's `Mesh.MeshSizeFromCurvature`), as in the
/// Console reference surfaces.
const TRIANGLES_PER_TURN: f64 = 48.0;

/// A CAD file of the parts amber meshes opens and tessellates in seconds; a gmsh that has not
/// finished by then is stuck.
const GMSH_TIMEOUT: Duration = Duration::from_secs(600);

/// Whether `path` names a CAD file (by extension).
pub fn is_cad(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| CAD_EXTENSIONS.iter().any(|cad| e.eq_ignore_ascii_case(cad)))
}

/// The gmsh program that tessellates CAD files: by default `gmsh` on the `PATH`.
#[derive(Clone, Debug)]
pub struct Gmsh {
    program: PathBuf,
}

impl Default for Gmsh {
    fn default() -> Self {
        Self { program: PathBuf::from("gmsh") }
    }
}

impl Gmsh {
    /// gmsh's version, or `None` when the program does not run.
    pub fn version(&self) -> Option<String> {
        let output = Command::new(&self.program).arg("-version").stdin(Stdio::null()).output().ok()?;
        let text = [output.stdout, output.stderr].concat();
        let version = String::from_utf8_lossy(&text).trim().to_owned();
        (output.status.success() && !version.is_empty()).then_some(version)
    }

    /// The surface of the CAD file `path`: gmsh's tessellation with triangles at most
    /// `max_size` long on flat faces (finer on curved ones), one face id per CAD face, corners
    /// rounded to `f32`. Errors name the file: gmsh absent, failing or stuck, or a file from
    /// which it made no surface.
    pub fn tessellate(&self, path: &Path, max_size: f64) -> Result<TriangleSoup, TaskError> {
        let geometry = |message: String| TaskError::Geometry { path: path.into(), message };
        if !(max_size.is_finite() && max_size > 0.0) {
            return Err(geometry(format!("tessellation size {max_size} is not positive")));
        }
        // gmsh would take a relative name starting with `-` for an option.
        let source = path.canonicalize().map_err(|source| TaskError::Io { path: path.into(), source })?;
        let scratch = tempfile::tempdir().map_err(|source| TaskError::Io { path: std::env::temp_dir(), source })?;
        let (surface, log) = (scratch.path().join("surface.stl"), scratch.path().join("gmsh.log"));
        let log_file = std::fs::File::create(&log).map_err(|source| TaskError::Io { path: log.clone(), source })?;
        let stderr = log_file.try_clone().map_err(|source| TaskError::Io { path: log.clone(), source })?;
        let mut command = Command::new(&self.program);
        command.arg(&source).args(["-2", "-format", "stl", "-nt", "1", "-v", "2", "-o"]).arg(&surface);
        for (option, value) in [
            ("Mesh.MeshSizeMax", max_size),
            ("Mesh.MeshSizeMin", max_size / 250.0),
            ("Mesh.MeshSizeFromCurvature", TRIANGLES_PER_TURN),
            ("Mesh.MeshSizeExtendFromBoundary", 0.0),
            ("Mesh.Algorithm", 6.0),
            ("Mesh.StlOneSolidPerSurface", 1.0),
            ("Mesh.Binary", 0.0),
        ] {
            command.args(["-setnumber", option, &value.to_string()]);
        }
        let mut child = command.stdin(Stdio::null()).stdout(log_file).stderr(stderr).spawn().map_err(|e| {
            geometry(format!(
                "reading a CAD file needs gmsh, which did not start ({}: {e}): `pip install gmsh` or install your \
                 distribution's gmsh package and put it on the PATH, or export the part as STL",
                self.program.display()
            ))
        })?;
        let status = child.wait_timeout(GMSH_TIMEOUT).map_err(|source| TaskError::Io { path: path.into(), source })?;
        let log_text = || std::fs::read(&log).map(|b| errors_of(&String::from_utf8_lossy(&b))).unwrap_or_default();
        let Some(status) = status else {
            // Best effort: the child is abandoned either way.
            let _ = child.kill();
            let _ = child.wait();
            return Err(geometry(format!("gmsh did not finish within {} s", GMSH_TIMEOUT.as_secs())));
        };
        if !status.success() {
            return Err(geometry(format!("gmsh failed ({status}){}", log_text())));
        }
        let mut soup = match read_surface(&surface, StlFaceIds::FromFile) {
            Ok(soup) if !soup.face_ids.is_empty() => soup,
            _ => return Err(geometry(format!("gmsh made no surface of it{}", log_text()))),
        };
        // Rounded as binary STL stores them, so that the part's STL export (and the Console
        // reference surfaces a model learnt from) give the same surface, and so the same mesh.
        soup.corners.iter_mut().flatten().for_each(|x| *x = f64::from(*x as f32));
        // gmsh names its solids `Gmsh Surface <id>`, which says no more than the face id.
        soup.face_names.clear();
        Ok(soup)
    }
}

/// gmsh's first error lines from its log, without terminal colours, each on a line of its own
/// after the message (empty when there are none).
fn errors_of(log: &str) -> String {
    log.lines()
        .map(strip_colours)
        .filter(|line| line.contains("Error") || line.contains("ERR"))
        .take(ERROR_LINES)
        .map(|line| format!("\n  {}", line.trim()))
        .collect()
}

/// The error lines of gmsh's log an error message quotes: the first say what went wrong, and a
/// broken file can make thousands.
const ERROR_LINES: usize = 8;

fn strip_colours(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // An SGR sequence: ESC '[' parameters 'm'.
            chars.by_ref().find(|&c| c == 'm');
        } else {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cad_files_are_known_by_extension() {
        assert!(is_cad(Path::new("part.STEP")) && is_cad(Path::new("a/b.stp")) && is_cad(Path::new("x.igs")));
        assert!(!is_cad(Path::new("part.stl")) && !is_cad(Path::new("step")));
    }

    #[test]
    fn the_log_keeps_gmsh_errors_without_colours() {
        let log = "Info    : Reading 'x.step'\n\u{1b}[31;1m**** ERR StepFile : Undefined Parsing ****\u{1b}[0m\n\
                   Error   : Could not read file 'x.step'\n";
        assert_eq!(
            errors_of(log),
            "\n  **** ERR StepFile : Undefined Parsing ****\n  Error   : Could not read file 'x.step'"
        );
    }

    #[test]
    fn a_missing_gmsh_is_an_error_that_says_how_to_install_it() {
        let dir = tempfile::tempdir().unwrap();
        let step = dir.path().join("part.step");
        std::fs::write(&step, "ISO-10303-21;").unwrap();
        let absent = Gmsh { program: dir.path().join("no-gmsh") };
        let err = absent.tessellate(&step, 1.0).unwrap_err().to_string();
        assert!(err.contains("part.step") && err.contains("pip install gmsh") && err.contains("PATH"), "{err}");
        assert!(absent.version().is_none());
    }

    /// gmsh, or `None` after the skip message (a failure under `AMBER_REQUIRE_SHARED`: CI
    /// installs it).
    fn gmsh() -> Option<Gmsh> {
        let gmsh = Gmsh::default();
        gmsh.version().is_some().then_some(gmsh).or_else(|| {
            amber_testdata::skip("gmsh is not on the PATH (`pip install gmsh`)");
            None
        })
    }

    /// gmsh with the reference surfaces' settings makes them again, to the last bit: the tool
    /// that made them (`make_ref.py`) called the same gmsh. Reads `../shared/data/console`.
    #[test]
    fn a_console_step_file_gives_the_reference_surface_of_the_part() {
        let (Some(data), Some(gmsh)) = (amber_testdata::shared("data/console"), gmsh()) else { return };
        let max_size = TESSELLATION_SIZE_PER_INITIAL_SIZE * crate::console::INITIAL_SIZE;
        let soup = gmsh.tessellate(&data.join("train/014.step"), max_size).unwrap();
        let reference = read_surface(data.join("reference_surface/train/014.stl"), StlFaceIds::FromFile).unwrap();
        // The same triangles in the same CAD faces, corner for corner (orientation aside).
        let triangles = |soup: &TriangleSoup| {
            let mut triangles: Vec<_> = (soup.corners.chunks_exact(3).zip(&soup.face_ids))
                .map(|(t, &face)| {
                    let mut corners = [t[0], t[1], t[2]].map(|p| p.map(f64::to_bits));
                    corners.sort();
                    (face, corners)
                })
                .collect();
            triangles.sort();
            triangles
        };
        let ours = triangles(&soup);
        assert_eq!(ours.len(), 11_038);
        assert_eq!(ours.iter().map(|t| t.0).max(), Some(11), "the part's CAD faces");
        assert!(ours == triangles(&reference), "the tessellation differs from the reference surface's");
    }

    #[test]
    fn a_file_gmsh_cannot_read_is_an_error_with_its_messages() {
        let Some(gmsh) = gmsh() else { return };
        let dir = tempfile::tempdir().unwrap();
        let step = dir.path().join("bad.step");
        std::fs::write(&step, "not a STEP file\n").unwrap();
        let err = gmsh.tessellate(&step, 1.0).unwrap_err().to_string();
        assert!(err.contains("bad.step") && err.contains("no surface") && err.contains("ERR"), "{err}");
    }

    #[test]
    fn an_absent_file_is_an_error_naming_it() {
        let err = Gmsh::default().tessellate(Path::new("/nonexistent/part.step"), 1.0).unwrap_err().to_string();
        assert!(err.contains("/nonexistent/part.step"), "{err}");
    }
}
