//! Checks that an expert's mesh is a mesh of the geometry it is paired with: a geometry file of
//! a dataset folder, or the domain a model meshes and scores against the expert.

use std::path::Path;

use amber_mesh::{FacetAdjacency, Mesh};

use crate::TaskError;

/// A geometry and a mesh of it may enclose volumes (areas) differing by this fraction: a geometry
/// of another part, or in other units, differs by far more; a faceted CAD surface and its mesh
/// by far less.
const VOLUME_TOLERANCE: f64 = 0.01;

/// The corners of the geometry's and the mesh's bounding boxes may lie this fraction of the
/// mesh's box diagonal apart: a part of about the same volume placed elsewhere or shaped
/// otherwise moves them by far more, while Console's expert meshes and their reference surfaces
/// differ by at most 0.19 % (train/006).
const BOX_TOLERANCE: f64 = 0.01;

/// Why a geometry that encloses `volume` within `bounds` is not the region `mesh` covers, if it
/// is not: the volumes or the bounding boxes differ by more than the tolerances.
pub(crate) fn extent_mismatch<const D: usize>(
    bounds: ([f64; D], [f64; D]),
    volume: f64,
    mesh: &Mesh<D>,
) -> Option<String> {
    let mesh_volume = mesh.total_volume();
    let deviation = (volume / mesh_volume - 1.0).abs();
    if deviation.is_nan() || deviation > VOLUME_TOLERANCE {
        let what = if D == 3 { "volume" } else { "area" };
        return Some(format!("encloses {what} {volume:.6e}, but the mesh covers {mesh_volume:.6e}"));
    }
    let mesh_bounds = mesh.bounding_box()?;
    let diagonal = (0..D).map(|k| (mesh_bounds.1[k] - mesh_bounds.0[k]).powi(2)).sum::<f64>().sqrt();
    let offset = (0..D)
        .map(|k| (bounds.0[k] - mesh_bounds.0[k]).abs().max((bounds.1[k] - mesh_bounds.1[k]).abs()))
        .fold(0.0, f64::max);
    (offset > BOX_TOLERANCE * diagonal).then(|| {
        format!(
            "bounding box {:?}–{:?} is {offset:.4e} away from the mesh's {:?}–{:?} (tolerance {:.4e})",
            bounds.0,
            bounds.1,
            mesh_bounds.0,
            mesh_bounds.1,
            BOX_TOLERANCE * diagonal
        )
    })
}

/// Checks that `expert`, read from `path`, meshes the region `initial` (a domain's M⁰) covers:
/// conforming (no facet shared by more than two elements, or by two from the same side, as a
/// duplicated or overlapping element is), with as many boundary components as M⁰ (a missing
/// element inside leaves a hole), and M⁰'s volume and bounding box within the tolerances of a
/// geometry and its mesh (elements outside the domain, or missing at its boundary, change them).
pub(crate) fn check_expert_mesh<const D: usize>(
    path: &Path,
    expert: &Mesh<D>,
    initial: &Mesh<D>,
) -> Result<(), TaskError> {
    let error = |message: String| TaskError::Dataset { path: path.into(), message: format!("expert mesh: {message}") };
    let expert_boundary = boundary_components(expert).map_err(|e| error(e.to_string()))?;
    let initial_boundary = boundary_components(initial).map_err(|e| error(format!("M⁰: {e}")))?;
    if expert_boundary != initial_boundary {
        return Err(error(format!(
            "its boundary has {expert_boundary} connected components, the domain's {initial_boundary} \
             (elements are missing, or it meshes another geometry)"
        )));
    }
    let bounds = initial.bounding_box().expect("a mesh has elements");
    match extent_mismatch(bounds, initial.total_volume(), expert) {
        Some(mismatch) => Err(error(format!("not a mesh of the domain: the domain {mismatch}"))),
        None => Ok(()),
    }
}

/// The number of connected components of `mesh`'s boundary (rings in 2D, closed surfaces in 3D,
/// connected through shared vertices); an error where the mesh does not conform.
fn boundary_components<const D: usize>(mesh: &Mesh<D>) -> Result<usize, amber_mesh::MeshError> {
    let facets = FacetAdjacency::new(mesh)?.oriented_boundary_facets(mesh);
    let mut parent: Vec<u32> = (0..mesh.num_vertices() as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    let mut components = 0usize;
    let mut seen = vec![false; mesh.num_vertices()];
    for facet in &facets {
        for &v in facet {
            if !std::mem::replace(&mut seen[v as usize], true) {
                components += 1;
            }
        }
        for &v in &facet[1..] {
            let (a, b) = (root(&mut parent, facet[0]), root(&mut parent, v));
            if a != b {
                parent[a as usize] = b;
                components -= 1;
            }
        }
    }
    Ok(components)
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::Mesh2;

    /// A 4×4-square grid of the unit square (32 triangles), with `drop` elements left out.
    fn grid(drop: &[usize]) -> Mesh2 {
        let n = 4;
        let vertices = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64 / n as f64, j as f64 / n as f64])).collect();
        let at = |i: u32, j: u32| j * (n + 1) + i;
        let cells: Vec<[u32; 3]> = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
                })
            })
            .collect();
        let cells = cells.into_iter().enumerate().filter(|(k, _)| !drop.contains(k)).flat_map(|(_, c)| c).collect();
        Mesh2::new(vertices, cells).unwrap()
    }

    #[test]
    fn an_expert_mesh_must_cover_its_domain_once() {
        let domain = grid(&[]);
        let path = Path::new("expert.msh");
        check_expert_mesh(path, &grid(&[]), &domain).unwrap();
        // Element 10 lies inside: leaving it out makes a hole; leaving out the corner element 0
        // changes the area by 1/32.
        for (drop, says) in [(10, "2 connected components"), (0, "area")] {
            let err = check_expert_mesh(path, &grid(&[drop]), &domain).unwrap_err().to_string();
            assert!(err.starts_with("expert.msh: expert mesh: ") && err.contains(says), "{err}");
        }
        let mut vertices = grid(&[]).vertices().to_vec();
        let mut cells = grid(&[]).cells().to_vec();
        cells.extend_from_within(..3);
        let err = check_expert_mesh(path, &Mesh2::new(vertices.clone(), cells.clone()).unwrap(), &domain);
        assert!(err.unwrap_err().to_string().contains("overlap"));
        cells.truncate(cells.len() - 3);
        vertices.extend([[2.0, 2.0], [3.0, 2.0], [2.0, 3.0]]);
        cells.extend([25, 26, 27]);
        let err = check_expert_mesh(path, &Mesh2::new(vertices, cells).unwrap(), &domain).unwrap_err().to_string();
        assert!(err.contains("2 connected components"), "{err}");
    }
}
