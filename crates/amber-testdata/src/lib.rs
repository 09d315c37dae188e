//! Where the tests find the shared data and fixtures (`../shared/` beside the workspace: the
//! Console bundle, the independently computed reference values), and the one message a test
//! prints when it skips because they (or a tool CI installs, such as gmsh) are absent. `$AMBER_SHARED` points elsewhere, e.g. from a
//! checkout that does not sit next to `shared/`; `AMBER_REQUIRE_SHARED=1` (set by CI, which has
//! the folder) turns every such skip into a failure. A dev-dependency only: no shipped code reads
//! data from a fixed place.

use std::path::{Path, PathBuf};

/// The shared folder: `$AMBER_SHARED`, else `shared/` beside the workspace.
fn shared_root() -> PathBuf {
    std::env::var_os("AMBER_SHARED")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared"))
}

/// `relative` (e.g. `data/console`) under the shared folder, or `None` after printing why the
/// calling test skips; with `AMBER_REQUIRE_SHARED` set to anything but `0` an absent folder fails
/// the calling test instead.
pub fn shared(relative: &str) -> Option<PathBuf> {
    let path = shared_root().join(relative);
    if path.exists() {
        return Some(path);
    }
    skip(&format!("{} is absent (set AMBER_SHARED to the folder holding data/ and fixtures/)", path.display()));
    None
}

/// Prints why the calling test skips (something CI has is absent here, `why` says what); with
/// `AMBER_REQUIRE_SHARED` set to anything but `0` fails the calling test instead.
pub fn skip(why: &str) {
    assert!(!required(), "AMBER_REQUIRE_SHARED is set: {why}");
    println!("skipping: {why}");
}

fn required() -> bool {
    std::env::var_os("AMBER_REQUIRE_SHARED").is_some_and(|v| v != "0")
}
