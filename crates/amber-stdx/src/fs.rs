//! Files that appear atomically: a reader sees the old file, no file, or the complete new one,
//! also after a crash or power loss. Every writer writes a temporary file beside the target
//! (`dir/.name.<pid>-<n>.tmp`: unique per process and write, so concurrent writers of one target
//! never share it), fsyncs it, renames it over the target and fsyncs the directory where the
//! platform allows (best effort: some file systems refuse to sync a directory). A failed write
//! removes its temporary file and leaves the target untouched.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// A file that could not be read or written, by path.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// Creating, writing, syncing, renaming or reading the file failed.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The file is not JSON of the expected shape, or the value cannot be written as JSON.
    #[error("{path}: {source}")]
    Json { path: PathBuf, source: serde_json::Error },
}

impl FileError {
    /// The file at fault.
    pub fn path(&self) -> &Path {
        match self {
            FileError::Io { path, .. } | FileError::Json { path, .. } => path,
        }
    }

    fn io(path: &Path) -> impl FnOnce(std::io::Error) -> FileError + '_ {
        move |source| FileError::Io { path: path.to_owned(), source }
    }
}

/// Writes `bytes` to `path` atomically (see the module docs). The directory must exist.
///
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("table.md");
/// amber_stdx::write_atomic(&path, b"| a | b |\n")?;
/// assert_eq!(std::fs::read(&path)?, b"| a | b |\n");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_atomic_with(path, |w| w.write_all(bytes).map_err(FileError::io(path)))
}

/// Writes `path` atomically through `write`, which streams the content into a buffered
/// temporary file. `write`'s error comes back unchanged; file errors become `E` through
/// `From<FileError>`, so each crate keeps its own error type.
pub fn write_atomic_with<E: From<FileError>>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E> {
    write_atomic_via(path, |tmp| {
        let mut w = BufWriter::new(File::create(tmp).map_err(FileError::io(path))?);
        write(&mut w)?;
        w.into_inner().map_err(|e| FileError::io(path)(e.into_error()))?;
        Ok(())
    })
}

/// Writes `path` atomically through `write`, which writes a complete file at the temporary
/// path it is given: for writers that only take a path (safetensors). `write`'s error comes
/// back unchanged; file errors become `E` through `From<FileError>`.
pub fn write_atomic_via<E: From<FileError>>(path: &Path, write: impl FnOnce(&Path) -> Result<(), E>) -> Result<(), E> {
    let tmp = tmp_path(path)?;
    let result = write(&tmp).and_then(|()| Ok(commit(&tmp, path)?));
    if result.is_err() {
        // Best effort: the temporary file may not even exist.
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Reads JSON of type `T` from `path`.
pub fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, FileError> {
    let bytes = std::fs::read(path).map_err(FileError::io(path))?;
    serde_json::from_slice(&bytes).map_err(|source| FileError::Json { path: path.to_owned(), source })
}

/// Writes `value` as pretty JSON (no trailing newline) to `path`, atomically.
///
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("state.json");
/// amber_stdx::write_json_atomic(&path, &serde_json::json!({ "step": 3 }))?;
/// let back: serde_json::Value = amber_stdx::read_json(&path)?;
/// assert_eq!(back["step"], 3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_json_atomic<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), FileError> {
    let json = serde_json::to_vec_pretty(value).map_err(|source| FileError::Json { path: path.to_owned(), source })?;
    write_atomic(path, &json)
}

/// `dir/.name.<pid>-<n>.tmp` for `dir/name`: beside the target (a rename within one file system
/// is atomic), hidden, and unique to this process and write.
fn tmp_path(path: &Path) -> Result<PathBuf, FileError> {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let name = path.file_name().ok_or_else(|| FileError::io(path)(std::io::ErrorKind::InvalidInput.into()))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    Ok(path.with_file_name(format!(".{}.{}-{n}.tmp", name.to_string_lossy(), std::process::id())))
}

/// Removes, under `dir` and its subdirectories, the temporary files of writes whose process is
/// gone (killed mid-write: `kill -9`, power loss), so that a resumed run does not accumulate them.
/// A process is gone when `/proc/<pid>` is absent; where there is no `/proc`, nothing is removed.
/// Returns how many were removed.
pub fn remove_stale_temporaries(dir: &Path) -> Result<usize, FileError> {
    if !Path::new("/proc/self").exists() {
        return Ok(0);
    }
    let mut removed = 0;
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(FileError::io(dir)(e)),
    };
    for entry in entries {
        let entry = entry.map_err(FileError::io(dir))?;
        let path = entry.path();
        if entry.file_type().map_err(FileError::io(&path))?.is_dir() {
            removed += remove_stale_temporaries(&path)?;
        } else if let Some(pid) = temporary_owner(&entry.file_name().to_string_lossy())
            && !Path::new("/proc").join(pid.to_string()).exists()
        {
            std::fs::remove_file(&path).map_err(FileError::io(&path))?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// The pid in the name of a temporary file of [`tmp_path`] (`.name.<pid>-<n>.tmp`).
fn temporary_owner(file_name: &str) -> Option<u32> {
    let stem = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (pid, n) = stem.rsplit_once('.')?.1.split_once('-')?;
    n.parse::<usize>().ok()?;
    pid.parse().ok()
}

/// Makes the complete temporary file durable and puts it in place.
fn commit(tmp: &Path, path: &Path) -> Result<(), FileError> {
    File::open(tmp).and_then(|f| f.sync_all()).map_err(FileError::io(path))?;
    std::fs::rename(tmp, path).map_err(FileError::io(path))?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    // Best effort: the rename is durable only once the directory is, but not every platform
    // or file system can sync a directory.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        names
    }

    #[test]
    fn writes_replace_the_file_and_leave_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_atomic(&path, b"old").unwrap();
        write_json_atomic(&path, &[1.5, 2.0]).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "[\n  1.5,\n  2.0\n]");
        assert_eq!(read_json::<Vec<f64>>(&path).unwrap(), vec![1.5, 2.0]);
        write_atomic_via(&path, |tmp| std::fs::write(tmp, "via").map_err(FileError::io(tmp))).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "via");
        assert_eq!(names(dir.path()), ["a.json"]);
    }

    #[test]
    fn a_failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.vtu");
        std::fs::write(&path, "old").unwrap();
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial").unwrap();
            Err(FileError::Io { path: path.clone(), source: std::io::Error::other("boom") })
        })
        .unwrap_err();
        assert!(err.to_string().contains("boom"), "{err}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(names(dir.path()), ["m.vtu"]);
    }

    #[test]
    fn errors_name_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let missing_dir = dir.path().join("missing").join("x.json");
        let err = write_atomic(&missing_dir, b"x").unwrap_err();
        assert!(matches!(err, FileError::Io { .. }) && err.path() == missing_dir, "{err}");
        assert!(err.to_string().contains("x.json"), "{err}");
        let bad = dir.path().join("bad.json");
        std::fs::write(&bad, "{").unwrap();
        let err = read_json::<serde_json::Value>(&bad).unwrap_err();
        assert!(matches!(err, FileError::Json { .. }) && err.to_string().contains("bad.json"), "{err}");
        assert!(matches!(read_json::<serde_json::Value>(&missing_dir), Err(FileError::Io { .. })));
        assert!(matches!(write_atomic(Path::new("/"), b"x"), Err(FileError::Io { .. })));
    }

    #[test]
    fn temporaries_of_dead_processes_are_removed_and_others_kept() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("checkpoints/step-00000010");
        std::fs::create_dir_all(&sub).unwrap();
        // pid 2^22 + 1 is above Linux's pid_max: never a live process.
        let dead = [dir.path().join(".state.json.4194305-0.tmp"), sub.join(".model.safetensors.4194305-17.tmp")];
        let live = dir.path().join(format!(".log.jsonl.{}-3.tmp", std::process::id()));
        let kept = [live, dir.path().join("state.json"), dir.path().join(".hidden.tmp"), sub.join("x.4194305-1.tmp")];
        for path in dead.iter().chain(&kept) {
            std::fs::write(path, "").unwrap();
        }
        assert_eq!(remove_stale_temporaries(dir.path()).unwrap(), 2);
        assert!(dead.iter().all(|p| !p.exists()) && kept.iter().all(|p| p.exists()));
        assert_eq!(remove_stale_temporaries(&dir.path().join("missing")).unwrap(), 0);
    }

    #[test]
    fn temporary_files_sit_beside_the_target_and_are_unique() {
        let (a, b) = (tmp_path(Path::new("out/r.json")).unwrap(), tmp_path(Path::new("out/r.json")).unwrap());
        assert_ne!(a, b);
        assert_eq!(a.parent(), Some(Path::new("out")));
        let name = a.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with(".r.json.") && name.ends_with(".tmp"), "{name}");
    }
}
