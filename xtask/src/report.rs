//! Writing results from the command line: the experiments crate's atomic JSON writer, saying
//! what it wrote, and its machine description.

use std::path::Path;

pub use amber_experiments::machine;

/// Writes pretty JSON to `path` atomically and says so.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    amber_experiments::write_json(path, value)?;
    println!("wrote {}", path.display());
    Ok(())
}
