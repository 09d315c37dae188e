//! The target of amber-tasks' own reader: a Poisson problem JSON, read as training and
//! evaluation read it (`PoissonProblem::from_json`) and as `amber mesh --problem` reads it
//! (`read_part`, from a file), then the task's inputs computed on its M⁰.

use std::path::Path;

use amber_mesh::Mesh2;
use amber_tasks::Domain;
use amber_tasks::poisson::{INITIAL_SIZE, PoissonProblem, read_part};

use crate::{ELEMENT_CAP, assert_names, assert_valid, scratch_dir};

/// A Poisson problem file (`domain`, `load`, `initial_mesh`, `mesh`, `metadata`), read both ways.
/// A problem that reads has valid meshes, its corner inside the unit square, and finite inputs on
/// its own M⁰ (the P1 solution, the load, the error indicator): a load the reader accepts is one
/// the network can read.
pub fn problem_file(data: &[u8]) {
    let path = Path::new("fuzz.json");
    match PoissonProblem::from_json(data, path) {
        Ok(problem) => {
            assert_valid(&problem.initial_mesh);
            assert_valid(&problem.expert_mesh);
            assert!(problem.corner.iter().all(|&p| p > 0.0 && p < 1.0), "corner {:?}", problem.corner);
            assert_finite_inputs(&problem, &problem.initial_mesh);
        }
        Err(e) => assert_names(&e.to_string(), "fuzz.json"),
    }
    if !m0_fits_the_cap(data) {
        return;
    }
    let file = scratch_dir().join("problem.json");
    std::fs::write(&file, data).expect("the scratch directory is writable");
    match read_part(&file) {
        Ok((part, expert_mesh)) => {
            assert_valid(&part.initial_mesh);
            if let Some(mesh) = &expert_mesh {
                assert_valid(mesh);
            }
            let area = part.domain.area();
            assert!(area > 0.0 && area.is_finite(), "domain area {area}");
            assert_finite_inputs(&part, &part.initial_mesh);
        }
        Err(e) => assert_names(&e.to_string(), &file.display().to_string()),
    }
}

/// Every input column of `domain` on `mesh`, when it computes them, is finite and has one value
/// per element.
fn assert_finite_inputs(domain: &impl Domain<2>, mesh: &Mesh2) {
    let Ok(columns) = domain.columns(mesh) else { return };
    for column in columns {
        assert_eq!(column.values.len(), mesh.num_elements(), "column {}", column.name);
        let bad = column.values.iter().find(|v| !v.is_finite());
        assert!(bad.is_none(), "column {} has the value {bad:?}", column.name);
    }
}

/// Whether `read_part` would mesh M⁰ under the targets' element cap: without an `initial_mesh`,
/// it meshes the domain at [`INITIAL_SIZE`], which for a domain of a few thousand units is
/// millions of triangles under the generator's default cap of five million, and seconds of
/// legitimate work per input.
fn m0_fits_the_cap(data: &[u8]) -> bool {
    let Ok(value) = serde_json::from_slice::<serde_json::Value>(data) else { return true };
    if value.get("initial_mesh").is_some_and(|m| !m.is_null()) {
        return true;
    }
    let points: Vec<[f64; 2]> = value
        .pointer("/domain/polygon")
        .and_then(|p| p.as_array())
        .into_iter()
        .flatten()
        .filter_map(|p| Some([p.get(0)?.as_f64()?, p.get(1)?.as_f64()?]))
        .collect();
    let extent = |k: usize| {
        let (lo, hi) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p[k]), hi.max(p[k])));
        (hi - lo).max(0.0)
    };
    let triangle = 3f64.sqrt() / 4.0 * INITIAL_SIZE * INITIAL_SIZE;
    extent(0) * extent(1) / triangle <= ELEMENT_CAP as f64
}
