//! Embeds the commit the code is built from as `AMBER_COMMIT` (`<sha>`, `<sha>-dirty` when
//! tracked files outside `results/` differ from it, `unknown` outside a git checkout), so a
//! results file names the code that made it, whatever directory the binary runs in.

use std::path::Path;
use std::process::Command;

fn git(workspace: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git").current_dir(workspace).args(args).output().ok().filter(|o| o.status.success())?;
    Some(String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // Rebuild when the commit, the index or any source changes.
    for (dir, files) in [("--absolute-git-dir", ["HEAD", "index"]), ("--git-common-dir", ["packed-refs", "refs"])] {
        if let Some(git_dir) = git(&workspace, &["rev-parse", dir]) {
            for file in files {
                println!("cargo:rerun-if-changed={}", workspace.join(&git_dir).join(file).display());
            }
        }
    }
    for path in ["crates", "xtask", "tests", "datasets", "Cargo.toml", "Cargo.lock", ".ci"] {
        println!("cargo:rerun-if-changed={}", workspace.join(path).display());
    }
    let commit = match git(&workspace, &["rev-parse", "HEAD"]) {
        Some(head) => {
            let status = git(&workspace, &["status", "--porcelain", "--untracked-files=no", "--", ".", ":!results"]);
            if status.is_some_and(|s| s.is_empty()) { head } else { format!("{head}-dirty") }
        }
        None => "unknown".into(),
    };
    println!("cargo:rustc-env=AMBER_COMMIT={commit}");
}
