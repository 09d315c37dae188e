//! Repository hygiene, enforced by plain `cargo test`: every Rust file starts with a `//!` doc
//! comment; no test is skipped with the ignore attribute or expects a panic; no crate depends on
//! a crate above it in the layering table of docs/ARCHITECTURE.md, nor on an external crate
//! confined to another layer there; every declared dependency is used; only the binaries read
//! environment variables.

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

/// The rows of the markdown table under `heading` in docs/ARCHITECTURE.md, as (first cell, the
/// back-quoted names of the second cell): the layering is written down once, for readers and for
/// these tests.
fn architecture_table(heading: &str) -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(root().join("docs/ARCHITECTURE.md")).unwrap();
    let section = text.split(heading).nth(1).unwrap_or_else(|| panic!("docs/ARCHITECTURE.md has no `{heading}`"));
    let names = |cell: &str| -> Vec<String> { cell.split('`').skip(1).step_by(2).map(str::to_string).collect() };
    section
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter(|l| l.contains('`'))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').collect();
            (names(cells[1]).join(","), names(cells[2]))
        })
        .collect()
}

/// The dependency names of one section (`[dependencies]`, `[dev-dependencies]`, ...) of a
/// manifest.
fn manifest_deps(manifest: &str, section: &str) -> Vec<String> {
    let header = format!("[{section}]");
    let Some(body) = manifest.split(&header).nth(1) else { return Vec::new() };
    body.split("\n[")
        .next()
        .unwrap_or("")
        .lines()
        .map(|l| l.split(['=', '.', '#']).next().unwrap().trim().to_string())
        .filter(|d| !d.is_empty())
        .collect()
}

/// Every crate of the workspace as (name, directory): crates/* and xtask.
fn workspace_crates() -> Vec<(String, PathBuf)> {
    let mut crates: Vec<(String, PathBuf)> = std::fs::read_dir(root().join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .map(|dir| (dir.file_name().unwrap().to_str().unwrap().to_string(), dir))
        .collect();
    crates.push(("xtask".into(), root().join("xtask")));
    crates.sort();
    crates
}

/// Only the binaries read environment variables (docs/ARCHITECTURE.md, cross-cutting concerns),
/// so what a library does follows from its arguments; amber-testdata, a dev-dependency, reads
/// where the shared data is.
#[test]
fn only_the_binaries_read_environment_variables() {
    let mut offenders = Vec::new();
    for (name, dir) in workspace_crates() {
        if ["amber-cli", "amber-testdata", "xtask"].contains(&name.as_str()) {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&dir.join("src"), &mut files);
        offenders.extend(files.into_iter().filter(|f| std::fs::read_to_string(f).unwrap().contains("env::var")));
    }
    assert!(offenders.is_empty(), "libraries that read environment variables: {offenders:#?}");
}

fn is_ours(dep: &str) -> bool {
    dep.starts_with("amber-") || dep == "tetgen-sys"
}

#[test]
fn crates_only_depend_downward() {
    let layering = architecture_table("## Layering");
    for (name, dir) in workspace_crates() {
        let allowed = layering.iter().find(|(n, _)| *n == name).map(|(_, a)| a);
        let allowed = allowed
            .unwrap_or_else(|| panic!("crate {name} is missing from the layering table of docs/ARCHITECTURE.md"));
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        for dep in manifest_deps(&manifest, "dependencies").into_iter().filter(|d| is_ours(d)) {
            assert!(allowed.contains(&dep), "{name} must not depend on {dep} (see docs/ARCHITECTURE.md, Layering)");
        }
    }
}

#[test]
fn external_crates_stay_in_their_layer() {
    let confined = architecture_table("## External crates");
    assert!(!confined.is_empty());
    for (name, dir) in workspace_crates() {
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        for dep in manifest_deps(&manifest, "dependencies") {
            for (externals, owners) in &confined {
                if externals.split(',').any(|e| e == dep) {
                    assert!(owners.contains(&name), "{name} must not depend on {dep}: only {owners:?} may");
                }
            }
        }
    }
}

#[test]
fn every_declared_dependency_is_used() {
    for (name, dir) in workspace_crates() {
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        let mut files = Vec::new();
        rust_files(&dir, &mut files);
        if name == "xtask" {
            rust_files(&root().join("tests"), &mut files);
        }
        let code: String = files.iter().map(|f| std::fs::read_to_string(f).unwrap()).collect();
        for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
            for dep in manifest_deps(&manifest, section) {
                let ident = dep.replace('-', "_");
                assert!(
                    code.contains(&format!("{ident}::"))
                        || code.contains(&format!("use {ident}"))
                        || code.contains(&format!("extern crate {ident}")),
                    "{name}: [{section}] {dep} is declared but never used"
                );
            }
        }
    }
}
