//! Repository hygiene, enforced by plain `cargo test`: every Rust file starts with a `//!`
//! doc comment; no test is skipped with the ignore attribute or expects a panic; no crate depends on a crate above
//! it in the layering of docs/ARCHITECTURE.md.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if !path.ends_with("target") {
                rust_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn all_rust_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["crates", "xtask", "tests"] {
        rust_files(&root().join(dir), &mut files);
    }
    files
}

#[test]
fn every_rust_file_starts_with_a_module_doc() {
    let missing: Vec<_> = all_rust_files()
        .into_iter()
        .filter(|f| !std::fs::read_to_string(f).unwrap().trim_start().starts_with("//!"))
        .collect();
    assert!(missing.is_empty(), "files without a leading `//!` doc comment: {missing:#?}");
}

#[test]
fn no_ignored_or_should_panic_tests() {
    let banned = [concat!("#[", "ignore"), concat!("#[", "should_panic")];
    let offenders: Vec<_> = all_rust_files()
        .into_iter()
        .filter(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            banned.iter().any(|b| text.contains(b))
        })
        .collect();
    assert!(offenders.is_empty(), "tests must run and assert real behaviour: {offenders:#?}");
}

/// Which workspace crates each crate may depend on (normal dependencies). The graph reads as
/// the data flow; nothing points upward.
const ALLOWED: &[(&str, &[&str])] = &[
    ("tetgen-sys", &[]),
    ("amber-mesh", &[]),
    ("amber-testdata", &[]),
    ("amber-plot", &["amber-mesh"]),
    ("amber-meshgen", &["amber-mesh", "tetgen-sys"]),
    ("amber-fem", &["amber-mesh", "amber-meshgen"]),
    ("amber-graph", &["amber-mesh"]),
    ("amber-metrics", &["amber-mesh"]),
    ("amber-mpn", &["amber-graph"]),
    ("amber-cnn", &["amber-mesh", "amber-meshgen", "amber-graph"]),
    ("amber-tasks", &["amber-mesh", "amber-meshgen", "amber-fem", "amber-graph", "amber-metrics"]),
    (
        "amber-train",
        &[
            "amber-mesh",
            "amber-meshgen",
            "amber-fem",
            "amber-graph",
            "amber-metrics",
            "amber-mpn",
            "amber-cnn",
            "amber-tasks",
        ],
    ),
    (
        "amber-experiments",
        &[
            "amber-mesh",
            "amber-meshgen",
            "amber-fem",
            "amber-graph",
            "amber-metrics",
            "amber-mpn",
            "amber-cnn",
            "amber-tasks",
            "amber-train",
            "amber-plot",
        ],
    ),
    (
        "amber-cli",
        &[
            "amber-mesh",
            "amber-meshgen",
            "amber-fem",
            "amber-graph",
            "amber-metrics",
            "amber-tasks",
            "amber-train",
            "amber-experiments",
            "amber-plot",
        ],
    ),
];

#[test]
fn crates_only_depend_downward() {
    for entry in std::fs::read_dir(root().join("crates")).unwrap() {
        let dir = entry.unwrap().path();
        let name = dir.file_name().unwrap().to_str().unwrap().to_string();
        let allowed = ALLOWED.iter().find(|(n, _)| *n == name).map(|(_, a)| *a);
        let allowed =
            allowed.unwrap_or_else(|| panic!("crate {name} is missing from the layering table in tests/tidy.rs"));
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        let deps = manifest.split("[dependencies]").nth(1).unwrap_or("").split("\n[").next().unwrap_or("");
        for line in deps.lines() {
            let dep = line.split(['=', '.']).next().unwrap().trim();
            let is_ours = dep.starts_with("amber-") || dep == "tetgen-sys";
            assert!(!is_ours || allowed.contains(&dep), "{name} must not depend on {dep} (see docs/ARCHITECTURE.md)");
        }
    }
}
