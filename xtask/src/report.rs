//! Writing results from the command line: the experiments crate's atomic JSON writer, stamping
//! the commit, refusing `results/` from a dirty build, saying what it wrote, and its machine
//! description.

use std::path::Path;

pub use amber_experiments::machine;

/// Writes pretty JSON to `path` atomically, with the binary's commit as the object's `commit`
/// field, and says so; refuses `results/` from a dirty build ([`check_provenance`]).
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    check_provenance(path, None)?;
    let mut value = serde_json::to_value(value)?;
    if let Some(object) = value.as_object_mut() {
        object.insert("commit".into(), amber_experiments::commit().into());
    }
    amber_experiments::write_json(path, &value)?;
    println!("wrote {}", path.display());
    Ok(())
}

/// Refuses to write under `results/` (the committed evidence) from a binary built from a dirty
/// tree, unless the command takes `--allow-dirty` (`Some`) and it was given.
pub fn check_provenance(out: &Path, allow_dirty: Option<bool>) -> anyhow::Result<()> {
    if out.starts_with("results") && allow_dirty != Some(true) && !amber_experiments::built_from_a_clean_commit() {
        anyhow::bail!(
            "{}: this binary was built from {}, not a clean commit; commit first or write elsewhere (--out){}",
            out.display(),
            amber_experiments::commit(),
            if allow_dirty.is_some() { ", or pass --allow-dirty" } else { "" }
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_files_carry_the_commit_and_only_a_clean_one_writes_under_results() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bench.json");
        write_json(&path, &serde_json::json!({ "cases": [1, 2] })).unwrap();
        let written: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(written["commit"], amber_experiments::commit());
        assert_eq!(written["cases"], serde_json::json!([1, 2]));
        let results = Path::new("results/bench/x.json");
        check_provenance(results, Some(true)).unwrap();
        let refused = check_provenance(results, None);
        assert_eq!(refused.is_ok(), amber_experiments::built_from_a_clean_commit(), "{refused:?}");
        if let Err(e) = check_provenance(results, Some(false)) {
            assert!(e.to_string().contains("--allow-dirty"), "{e}");
        }
    }
}
