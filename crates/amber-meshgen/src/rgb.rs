//! Red-green-blue refinement with longest-edge closure and one Jacobi Laplacian smoothing sweep:
//! the two mesh operations of the Poisson expert heuristic (spec §1).
//!
//! [`refine_rgb`] follows scikit-fem 9.0 `MeshTri1._adaptive` (Carstensen 2004) step for step,
//! including its vertex and element numbering, so that ties between equally long edges are
//! broken as the reference broke them: every triangle is relabelled (from ascending vertex order)
//! so that its longest edge is (0, 2); all edges of marked triangles are split; a triangle with
//! any split edge also splits its longest edge, until nothing changes; then triangles with three
//! split edges become 4 (red), longest + one other 3 (blue), longest only 2 (green). New vertices
//! sit at edge midpoints and are numbered after the old ones in lexicographic edge order.

use amber_mesh::{Mesh2, MeshError, signed_volume};
use amber_stdx::Buckets;

/// Why a refinement or smoothing step failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RgbError {
    /// A marked element index does not exist.
    #[error("marked element {element} does not exist (the mesh has {num_elements} elements)")]
    MarkedOutOfRange { element: usize, num_elements: usize },
    /// The input mesh is not conforming (an edge is shared by more than two triangles).
    #[error("cannot refine a non-conforming mesh: {0}")]
    NonConforming(MeshError),
    /// A child triangle came out degenerate in floating point (a parent thinner than round-off).
    #[error("refinement produced a degenerate element: {0}")]
    Refinement(MeshError),
    /// Smoothing produced an invalid mesh (cannot happen for a valid input: moves that would
    /// invert an element are undone).
    #[error("Laplacian smoothing produced an invalid element: {0}")]
    Smoothing(MeshError),
}

/// Refines the `marked` triangles by red-green-blue refinement with longest-edge closure.
///
/// The result is conforming and positively oriented; elements untouched by the closure keep
/// their vertices, old vertices keep their indices.
///
/// ```
/// use amber_mesh::Mesh2;
/// let square = Mesh2::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], vec![0, 1, 2, 0, 2, 3])?;
/// let refined = amber_meshgen::rgb::refine_rgb(&square, &[0])?;
/// // Element 0 is split red (4 children); the diagonal is also element 1's longest edge, so the
/// // closure splits element 1 green (2 children).
/// assert_eq!(refined.num_elements(), 6);
/// assert!((refined.total_volume() - 1.0).abs() < 1e-15);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn refine_rgb(mesh: &Mesh2, marked: &[usize]) -> Result<Mesh2, RgbError> {
    let num_elements = mesh.num_elements();
    if let Some(&element) = marked.iter().find(|&&e| e >= num_elements) {
        return Err(RgbError::MarkedOutOfRange { element, num_elements });
    }
    let p = mesh.vertices();
    let t: Vec<[u32; 3]> = mesh.elements().map(|c| longest_edge_last(p, [c[0], c[1], c[2]])).collect();
    let edges = EdgeTable::new(&t, p.len())?;

    let mut split = vec![false; edges.len()];
    let mut queue: Vec<u32> = Vec::new();
    for &e in marked {
        for &edge in &edges.t2e[e] {
            if !split[edge as usize] {
                split[edge as usize] = true;
                queue.push(edge);
            }
        }
    }
    // Closure: a triangle with a split edge (0,1) or (1,2) must also split its longest edge (0,2).
    while let Some(edge) = queue.pop() {
        for &e in edges.elements_of(edge) {
            let [e01, e12, e02] = edges.t2e[e as usize];
            if (split[e01 as usize] || split[e12 as usize]) && !split[e02 as usize] {
                split[e02 as usize] = true;
                queue.push(e02);
            }
        }
    }

    let mut vertices = p.to_vec();
    let mut midpoint = vec![u32::MAX; edges.len()];
    for (edge, &[a, b]) in edges.vertices.iter().enumerate() {
        if split[edge] {
            midpoint[edge] = vertices.len() as u32;
            let (pa, pb) = (p[a as usize], p[b as usize]);
            vertices.push([0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]);
        }
    }

    // Children in scikit-fem's order: unrefined, red, blue (longest + (1,2)), blue (longest +
    // (0,1)), green.
    let mut kinds: [Vec<[u32; 3]>; 5] = Default::default();
    for (e, &[t0, t1, t2]) in t.iter().enumerate() {
        let m = edges.t2e[e].map(|edge| midpoint[edge as usize]);
        let [m01, m12, m02] = m.map(|v| (v != u32::MAX).then_some(v));
        match (m01, m12, m02) {
            (None, None, None) => kinds[0].push([t0, t1, t2]),
            (Some(a), Some(b), Some(c)) => kinds[1].extend([[t0, a, c], [t1, a, b], [t2, b, c], [b, c, a]]),
            (None, Some(b), Some(c)) => kinds[2].extend([[t1, t0, c], [t1, b, c], [t2, c, b]]),
            (Some(a), None, Some(c)) => kinds[3].extend([[t0, a, c], [c, a, t1], [t2, c, t1]]),
            (None, None, Some(c)) => kinds[4].extend([[t1, c, t0], [t2, c, t1]]),
            _ => unreachable!("the closure splits the longest edge of every triangle with a split edge"),
        }
    }
    let cells: Vec<u32> = kinds.iter().flatten().flat_map(|&tri| oriented(&vertices, tri)).collect();
    Mesh2::new(vertices, cells).map_err(RgbError::Refinement)
}

/// One Jacobi sweep of Laplacian smoothing: every vertex not on the boundary moves to the mean of
/// its edge neighbours' old positions (scikit-fem `Mesh.smoothed()`); boundary vertices stay.
///
/// One guard the reference lacks: scikit-fem lets a sweep turn thin elements over (and then
/// integrates with |det J|), but our meshes stay positively oriented, so the vertices of every
/// element the sweep would invert or flatten keep their old positions (repeated until no element
/// does; the unmoved mesh is valid, so this ends). Elsewhere the sweep is exactly the reference's.
pub fn smooth_laplacian(mesh: &Mesh2) -> Result<Mesh2, RgbError> {
    let t: Vec<[u32; 3]> = mesh.elements().map(|c| [c[0], c[1], c[2]]).collect();
    let edges = EdgeTable::new(&t, mesh.num_vertices())?;
    let old = mesh.vertices();
    let mut boundary = vec![false; old.len()];
    let mut sum = vec![[0.0; 2]; old.len()];
    let mut count = vec![0u32; old.len()];
    for (&[a, b], owners) in edges.vertices.iter().zip(&edges.e2t) {
        let (a, b) = (a as usize, b as usize);
        if owners[1] == u32::MAX {
            boundary[a] = true;
            boundary[b] = true;
        }
        for k in 0..2 {
            sum[a][k] += old[b][k];
            sum[b][k] += old[a][k];
        }
        count[a] += 1;
        count[b] += 1;
    }
    let mut vertices: Vec<[f64; 2]> = (0..old.len())
        .map(|v| if boundary[v] || count[v] == 0 { old[v] } else { sum[v].map(|s| s / f64::from(count[v])) })
        .collect();
    loop {
        let mut reverted = false;
        for cell in mesh.elements() {
            if signed_volume::<2>(&vertices, cell) <= 0.0 {
                for &v in cell {
                    reverted |= vertices[v as usize] != old[v as usize];
                    vertices[v as usize] = old[v as usize];
                }
            }
        }
        if !reverted {
            break;
        }
    }
    Mesh2::new(vertices, mesh.cells().to_vec()).map_err(RgbError::Smoothing)
}

/// Relabels a triangle, from ascending vertex order, so that (0, 2) is its longest edge; strict
/// comparisons, so ties keep the earlier labelling exactly as scikit-fem does.
fn longest_edge_last(p: &[[f64; 2]], mut tri: [u32; 3]) -> [u32; 3] {
    tri.sort_unstable();
    let len = |a: u32, b: u32| {
        let (pa, pb) = (p[a as usize], p[b as usize]);
        ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2)).sqrt()
    };
    let (l01, l12, l02) = (len(tri[0], tri[1]), len(tri[1], tri[2]), len(tri[0], tri[2]));
    if l01 > l02 && l01 > l12 {
        tri.swap(1, 2);
    } else if l12 > l01 && l12 > l02 {
        tri.swap(0, 1);
    }
    tri
}

/// The triangle with its last two vertices swapped if it was clockwise.
fn oriented(p: &[[f64; 2]], [a, b, c]: [u32; 3]) -> [u32; 3] {
    let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
    let cross = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
    if cross < 0.0 { [a, c, b] } else { [a, b, c] }
}

/// Edges of a triangle mesh numbered in lexicographic order, with both incidence directions.
struct EdgeTable {
    /// Sorted vertex pair of each edge.
    vertices: Vec<[u32; 2]>,
    /// Edges (0,1), (1,2), (0,2) of each triangle.
    t2e: Vec<[u32; 3]>,
    /// The one or two triangles of each edge (`u32::MAX` pads boundary edges).
    e2t: Vec<[u32; 2]>,
}

impl EdgeTable {
    /// Buckets the edge slots by their smaller vertex (counting sort), then sorts each small
    /// bucket by the larger vertex: lexicographic edge order in linear time.
    fn new(t: &[[u32; 3]], num_vertices: usize) -> Result<Self, RgbError> {
        const LOCAL: [(usize, usize); 3] = [(0, 1), (1, 2), (0, 2)];
        let key = |tri: &[u32; 3], (i, j): (usize, usize)| (tri[i].min(tri[j]), tri[i].max(tri[j]));
        let slot_key = |slot: usize| key(&t[slot / 3], LOCAL[slot % 3]);
        let mut buckets =
            Buckets::new(num_vertices, 3 * t.len(), |slot| slot_key(slot).0, |slot| (slot_key(slot).1, slot as u32));
        let mut vertices = Vec::with_capacity(3 * t.len() / 2 + 1);
        let mut t2e = vec![[0u32; 3]; t.len()];
        let mut e2t: Vec<[u32; 2]> = Vec::with_capacity(3 * t.len() / 2 + 1);
        for a in 0..num_vertices {
            let slots = buckets.bucket_mut(a);
            slots.sort_unstable();
            for group in slots.chunk_by(|x, y| x.0 == y.0) {
                if group.len() > 2 {
                    let facet = vec![a as u32, group[0].0];
                    return Err(RgbError::NonConforming(MeshError::NonManifoldFacet { facet }));
                }
                let edge = vertices.len() as u32;
                vertices.push([a as u32, group[0].0]);
                let mut owners = [u32::MAX; 2];
                for (k, &(_, slot)) in group.iter().enumerate() {
                    t2e[slot as usize / 3][slot as usize % 3] = edge;
                    owners[k] = slot / 3;
                }
                e2t.push(owners);
            }
        }
        Ok(Self { vertices, t2e, e2t })
    }

    fn len(&self) -> usize {
        self.vertices.len()
    }

    fn elements_of(&self, edge: u32) -> impl Iterator<Item = &u32> {
        self.e2t[edge as usize].iter().filter(|&&e| e != u32::MAX)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use amber_mesh::FacetAdjacency;
    use proptest::prelude::*;

    /// An `n × n` grid of the unit square, each cell cut along a diagonal.
    fn grid(n: usize) -> Mesh2 {
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                v.push([i as f64 / n as f64, j as f64 / n as f64]);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut c = Vec::new();
        for j in 0..n {
            for i in 0..n {
                c.extend([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        Mesh2::new(v, c).unwrap()
    }

    /// A grid with its interior vertices jittered, so that edge lengths are all different. Each
    /// moves at most 0.15·√2·h, so no triangle can invert: the closest a vertex gets to the
    /// opposite edge of any triangle drops from h/√2 by at most 0.42·h.
    fn jittered(n: usize, jitter: &[f64]) -> Mesh2 {
        let g = grid(n);
        let h = 1.0 / n as f64;
        let v = g
            .vertices()
            .iter()
            .enumerate()
            .map(|(k, &[x, y])| {
                let interior = x > 0.0 && x < 1.0 && y > 0.0 && y < 1.0;
                let (dx, dy) = (jitter[(2 * k) % jitter.len()], jitter[(2 * k + 1) % jitter.len()]);
                if interior { [x + 0.15 * h * dx, y + 0.15 * h * dy] } else { [x, y] }
            })
            .collect();
        Mesh2::new(v, g.cells().to_vec()).unwrap()
    }

    fn sorted_cells(m: &Mesh2) -> Vec<[u32; 3]> {
        m.elements()
            .map(|c| {
                let mut t = [c[0], c[1], c[2]];
                t.sort_unstable();
                t
            })
            .collect()
    }

    fn boundary_length(m: &Mesh2) -> f64 {
        let adj = FacetAdjacency::new(m).unwrap();
        adj.boundary_facets()
            .map(|(e, i)| {
                let (a, b) = (m.corner(e, (i + 1) % 3), m.corner(e, (i + 2) % 3));
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
            })
            .sum()
    }

    /// The split edges predicted by the closure rule, computed by plain sweeps to a fixed point.
    fn closure_oracle(m: &Mesh2, marked: &[usize]) -> Vec<[u32; 2]> {
        let p = m.vertices();
        let t: Vec<[u32; 3]> = m.elements().map(|c| longest_edge_last(p, [c[0], c[1], c[2]])).collect();
        let key = |a: u32, b: u32| [a.min(b), a.max(b)];
        let mut split = std::collections::BTreeSet::new();
        for &e in marked {
            let [a, b, c] = t[e];
            split.extend([key(a, b), key(b, c), key(a, c)]);
        }
        loop {
            let before = split.len();
            for &[a, b, c] in &t {
                if split.contains(&key(a, b)) || split.contains(&key(b, c)) {
                    split.insert(key(a, c));
                }
            }
            if split.len() == before {
                return split.into_iter().collect();
            }
        }
    }

    fn check_refinement(m: &Mesh2, marked: &[usize]) {
        let r = refine_rgb(m, marked).unwrap();
        // Volume and boundary are conserved (no hanging node can hide on an interior edge: it
        // would add boundary length), and the adjacency is manifold.
        let (a0, a1) = (m.total_volume(), r.total_volume());
        assert!((a0 - a1).abs() <= 1e-12 * a0, "area {a0} -> {a1}");
        let (b0, b1) = (boundary_length(m), boundary_length(&r));
        assert!((b0 - b1).abs() <= 1e-12 * b0, "boundary {b0} -> {b1}");
        FacetAdjacency::new(&r).unwrap();
        assert!(r.volumes().iter().all(|&v| v > 0.0));
        // Exactly the closure's edges were split, at their midpoints.
        let split = closure_oracle(m, marked);
        assert_eq!(r.num_vertices(), m.num_vertices() + split.len());
        for (k, [a, b]) in split.iter().enumerate() {
            let (pa, pb) = (m.vertices()[*a as usize], m.vertices()[*b as usize]);
            assert_eq!(r.vertices()[m.num_vertices() + k], [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]);
        }
        // Exactly the triangles touching a split edge changed; marked ones always did.
        let kept: std::collections::HashSet<[u32; 3]> = sorted_cells(&r).into_iter().collect();
        for (e, tri) in sorted_cells(m).into_iter().enumerate() {
            let [a, b, c] = tri;
            let touched = [[a, b], [b, c], [a, c]].iter().any(|edge| split.binary_search(edge).is_ok());
            assert_eq!(kept.contains(&tri), !touched, "element {e}");
            assert!(!marked.contains(&e) || touched);
        }
    }

    #[test]
    fn single_marked_square_cell() {
        check_refinement(&grid(1), &[0]);
        let r = refine_rgb(&grid(1), &[0, 1]).unwrap();
        assert_eq!(r.num_elements(), 8);
    }

    #[test]
    fn out_of_range_marks_are_errors() {
        assert!(matches!(refine_rgb(&grid(1), &[2]), Err(RgbError::MarkedOutOfRange { element: 2, num_elements: 2 })));
    }

    #[test]
    fn smoothing_moves_interior_vertices_to_the_neighbour_mean() {
        // A 2×2 grid: the centre vertex has 6 neighbours whose mean is the centre itself.
        let g = grid(2);
        let mut v = g.vertices().to_vec();
        v[4] = [0.6, 0.45];
        let m = Mesh2::new(v, g.cells().to_vec()).unwrap();
        let s = smooth_laplacian(&m).unwrap();
        let c = s.vertices()[4];
        assert!((c[0] - 0.5).abs() < 1e-15 && (c[1] - 0.5).abs() < 1e-15);
        assert_eq!(&s.vertices()[..4], &m.vertices()[..4]);
    }

    #[test]
    fn smoothing_never_inverts_an_element() {
        // A fan around vertex 0 whose neighbour mean lies outside its star: (−1.2, 0) is beyond
        // the thin triangles on the left, so the unguarded sweep would turn them over.
        let v = vec![
            [0.0, 0.0],
            [1.0, -1.0],
            [1.0, 1.0],
            [-0.1, 1.0],
            [-0.1, 0.05],
            [-5.0, 0.0],
            [-0.1, -0.05],
            [-0.1, -1.0],
        ];
        let fan: Vec<u32> = (1..8).flat_map(|i| [0, i, i % 7 + 1]).collect();
        let m = Mesh2::new_reoriented(v, fan).unwrap();
        let s = smooth_laplacian(&m).unwrap();
        assert!(s.volumes().iter().all(|&a| a > 0.0));
        assert_eq!(s.vertices(), m.vertices());
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn refinement_is_conforming_and_local(
            n in 1usize..6,
            jitter in prop::collection::vec(-1.0f64..1.0, 8..40),
            marks in prop::collection::vec(0usize..1000, 0..6),
            rounds in 1usize..4,
        ) {
            let mut m = jittered(n, &jitter);
            for round in 0..rounds {
                let marked: Vec<usize> = marks.iter().map(|k| (k * (round + 1)) % m.num_elements()).collect();
                check_refinement(&m, &marked);
                m = refine_rgb(&m, &marked).unwrap();
            }
        }

        #[test]
        fn smoothing_keeps_the_boundary(n in 2usize..6, jitter in prop::collection::vec(-1.0f64..1.0, 8..40)) {
            let m = jittered(n, &jitter);
            let s = smooth_laplacian(&m).unwrap();
            prop_assert!((s.total_volume() - 1.0).abs() < 1e-12);
            let boundary = FacetAdjacency::new(&m).unwrap().boundary_vertices(&m);
            for (v, &b) in boundary.iter().enumerate() {
                prop_assert!(!b || s.vertices()[v] == m.vertices()[v]);
            }
        }
    }
}
