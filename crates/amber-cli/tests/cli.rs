//! End-to-end runs of the `amber` binary.

use std::process::Command;

fn amber() -> Command {
    Command::new(env!("CARGO_BIN_EXE_amber"))
}

#[test]
fn meshes_an_lshape_and_remeshes_from_the_result() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first.vtu");
    let status = amber().args(["mesh", "--corner", "0.3,0.6", "--size", "0.05", "-o"]).arg(&first).status().unwrap();
    assert!(status.success());
    let mesh = amber_mesh::read_mesh::<2>(&first).unwrap();
    assert!(mesh.num_elements() > 300);
    assert!((mesh.total_volume() - (1.0 - 0.7 * 0.4)).abs() < 1e-12);

    // The first mesh's element sizes as the field: the second mesh has about as many elements.
    let second = dir.path().join("second.msh");
    let status = amber().args(["mesh", "--corner", "0.3,0.6", "--size"]).arg(&first).arg("-o").arg(&second).status().unwrap();
    assert!(status.success());
    let remeshed = amber_mesh::read_mesh::<2>(&second).unwrap();
    let ratio = remeshed.num_elements() as f64 / mesh.num_elements() as f64;
    assert!((0.8..1.25).contains(&ratio), "{ratio}");

    let picture = dir.path().join("mesh.png");
    assert!(amber().args(["mesh", "--size", "0.1", "-o"]).arg(&picture).status().unwrap().success());
    assert!(std::fs::metadata(&picture).unwrap().len() > 1000);
}

#[test]
fn bad_input_fails_with_a_message_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.vtu");
    for args in [vec!["mesh", "--size", "-1"], vec!["mesh", "--size", "nan"], vec!["mesh", "--size", "/nonexistent.vtu"], vec!["mesh", "--corner", "1.5,0.5", "--size", "0.1"]] {
        let output = amber().args(&args).arg("-o").arg(&out).output().unwrap();
        assert!(!output.status.success(), "{args:?} succeeded");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(stderr.to_lowercase().contains("error") && !stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}
