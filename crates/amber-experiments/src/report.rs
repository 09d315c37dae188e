//! Writing results: files that appear atomically in directories created on the way (amber-stdx's
//! writers), and the record of where numbers came from (commit, machine).

use std::path::Path;

use anyhow::Context;

/// Writes pretty JSON to `path` atomically (amber-stdx's `write_json_atomic`), creating parent
/// directories.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    create_parent(path)?;
    Ok(amber_stdx::write_json_atomic(path, value)?)
}

/// Writes bytes to `path` atomically (amber-stdx's `write_atomic`), creating parent directories.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    create_parent(path)?;
    Ok(amber_stdx::write_atomic(path, bytes)?)
}

fn create_parent(path: &Path) -> anyhow::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create directory", dir.display()))?;
    }
    Ok(())
}

/// CPU model, clock, widest vector instructions, core count, thread count, memory and load
/// average, for the record: the one machine description of every results file, benchmarks
/// included. The model name alone does not tell machines apart whose matmul speeds differ.
pub fn machine() -> serde_json::Value {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        cpuinfo.lines().find_map(|l| l.strip_prefix(name).map(|r| r.trim_start_matches([' ', '\t', ':']).to_string()))
    };
    let cpu = field("model name");
    let mhz = field("cpu MHz").and_then(|m| m.parse::<f64>().ok());
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let mem_kb = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))
        .and_then(|r| r.trim().trim_end_matches(" kB").parse::<u64>().ok());
    serde_json::json!({
        "cpu": cpu,
        "cpu_mhz": mhz,
        "vector_instructions": vector_instructions(),
        "cores": std::thread::available_parallelism().map(|n| n.get()).ok(),
        "threads": rayon::current_num_threads(),
        "memory_gib": mem_kb.map(|kb| kb as f64 / 1048576.0),
        "load_average": std::fs::read_to_string("/proc/loadavg").ok().map(|s| s.trim().to_string()),
    })
}

/// The widest SIMD extension the CPU offers that the matmul kernels use.
fn vector_instructions() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return "avx512f";
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            return "avx2+fma";
        }
        "sse2"
    }
    #[cfg(target_arch = "aarch64")]
    {
        "neon"
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        "unknown"
    }
}

/// The commit the running code was built from: its hash, with `-dirty` when tracked files outside
/// `results/` had local changes at build time (`unknown` outside a git checkout). Embedded at
/// build time, so it names the binary's code wherever it runs.
pub fn commit() -> &'static str {
    env!("AMBER_COMMIT")
}

/// Whether [`commit`] names a clean commit, the only code whose numbers may go to `results/`.
pub fn built_from_a_clean_commit() -> bool {
    let commit = commit();
    commit != "unknown" && !commit.ends_with("-dirty")
}

/// Short hex SHA-256 of a JSON value's canonical text (object keys are sorted by serde_json's
/// map), used to key cached runs by their full configuration.
pub fn config_hash(value: &serde_json::Value) -> String {
    use sha2::{Digest, Sha256};
    let digest = Sha256::digest(value.to_string().as_bytes());
    digest.iter().take(6).map(|b| format!("{b:02x}")).collect()
}

/// Overwrites fields of `base` with those of `overrides`, recursively for objects (a JSON merge
/// patch without deletions): how variants and config files change a profile.
pub fn merge_json(base: &mut serde_json::Value, overrides: &serde_json::Value) {
    match (base, overrides) {
        (serde_json::Value::Object(b), serde_json::Value::Object(o)) => {
            for (k, v) in o {
                merge_json(b.entry(k.clone()).or_insert(serde_json::Value::Null), v);
            }
        }
        (b, o) => *b = o.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merge_overrides_nested_fields_only() {
        let mut base = serde_json::json!({"a": 1, "n": {"x": 1, "y": 2}});
        merge_json(&mut base, &serde_json::json!({"n": {"y": 3}, "b": true}));
        assert_eq!(base, serde_json::json!({"a": 1, "n": {"x": 1, "y": 3}, "b": true}));
    }

    #[test]
    fn config_hash_ignores_key_order_but_not_values() {
        let a: serde_json::Value = serde_json::from_str(r#"{"x": 1, "y": 2}"#).unwrap();
        let b: serde_json::Value = serde_json::from_str(r#"{"y": 2, "x": 1}"#).unwrap();
        let c: serde_json::Value = serde_json::from_str(r#"{"y": 2, "x": 2}"#).unwrap();
        assert_eq!(config_hash(&a), config_hash(&b));
        assert_ne!(config_hash(&a), config_hash(&c));
    }
}
