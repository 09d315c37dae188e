//! Shewchuk's predicates as vendored, built with AddressSanitizer and run on exactly coplanar
//! points that drive `orient3d` to its last adaptive stage: no out-of-bounds access (the
//! unguarded loads of the expansion sums read one element past their inputs there), and every
//! coplanar quadruple reported as coplanar. Needs `g++` with libasan, as the crate's build needs
//! a C++ compiler.

use std::path::Path;
use std::process::Command;

#[test]
fn predicates_stay_in_bounds_and_exact_under_address_sanitizer() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let binary = dir.path().join("predicates_harness");
    let built = Command::new("g++")
        .args(["-O1", "-g", "-fsanitize=address", "-fno-omit-frame-pointer", "-ffp-contract=off", "-w"])
        .arg(crate_dir.join("tests/predicates_harness.cpp"))
        .arg(crate_dir.join("tetgen/predicates.cxx"))
        .arg("-o")
        .arg(&binary)
        .output()
        .expect("g++ runs (the crate's build needs it too)");
    assert!(built.status.success(), "g++ -fsanitize=address failed:\n{}", String::from_utf8_lossy(&built.stderr));
    let run = Command::new(&binary).output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        run.status.success() && !stderr.contains("AddressSanitizer"),
        "{}{stderr}",
        String::from_utf8_lossy(&run.stdout)
    );
    assert!(String::from_utf8_lossy(&run.stdout).starts_with("0 coplanar quadruples not found coplanar"));
}
