//! 2D geometry: polygons with holes, and the L-shape of the Poisson task.

use std::collections::{HashMap, HashSet};

use amber_mesh::{FacetAdjacency, Mesh2};
use rstar::primitives::{GeomWithData, Line};
use rstar::{PointDistance, RTree};
use serde::{Deserialize, Serialize};

use crate::MeshgenError;
use crate::ray::{chord, ray_segment};

/// A polygonal domain: one outer ring and any number of holes (each a closed ring of at least
/// three vertices, the closing edge implied).
///
/// Invariant (checked by [`PolygonDomain::new`]): finite coordinates, no repeated consecutive
/// vertices, no two edges intersect except consecutive edges at their shared vertex, every hole
/// lies inside the outer ring.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "PolygonRings")]
pub struct PolygonDomain {
    outer: Vec<[f64; 2]>,
    holes: Vec<Vec<[f64; 2]>>,
}

/// The unchecked serialised form; deserialising a [`PolygonDomain`] validates it.
#[derive(Deserialize)]
struct PolygonRings {
    outer: Vec<[f64; 2]>,
    #[serde(default)]
    holes: Vec<Vec<[f64; 2]>>,
}

impl TryFrom<PolygonRings> for PolygonDomain {
    type Error = MeshgenError;

    fn try_from(rings: PolygonRings) -> Result<Self, MeshgenError> {
        Self::new(rings.outer, rings.holes)
    }
}

impl PolygonDomain {
    /// Validates and builds a domain.
    pub fn new(outer: Vec<[f64; 2]>, holes: Vec<Vec<[f64; 2]>>) -> Result<Self, MeshgenError> {
        let domain = Self { outer, holes };
        domain.validate()?;
        Ok(domain)
    }

    /// The L-shape of spec §1: the unit square minus the top-right rectangle [px,1]×[py,1].
    pub fn lshape(corner: [f64; 2]) -> Result<Self, MeshgenError> {
        let [px, py] = corner;
        if !(px > 0.0 && px < 1.0 && py > 0.0 && py < 1.0) {
            return Err(MeshgenError::InvalidDomain(format!("L-shape corner {corner:?} must lie inside (0, 1)²")));
        }
        Self::new(vec![[0.0, 0.0], [1.0, 0.0], [1.0, py], [px, py], [px, 1.0], [0.0, 1.0]], vec![])
    }

    /// The domain a mesh covers: its boundary edges chained into rings, vertices where the
    /// boundary runs straight on dropped (so a polygon meshed finely gives back its corners, and
    /// the old mesh's boundary spacing does not constrain a new one), the ring of largest area the
    /// outer one and the others its holes. A boundary that is not a set of disjoint simple loops
    /// (two components, a vertex where rings touch) is an error.
    pub fn from_mesh_boundary(mesh: &Mesh2) -> Result<Self, MeshgenError> {
        let edges = FacetAdjacency::new(mesh)?.oriented_boundary_facets(mesh);
        let mut next = HashMap::with_capacity(edges.len());
        for &[a, b] in &edges {
            if next.insert(a, b).is_some() {
                let at = mesh.vertices()[a as usize];
                return Err(MeshgenError::InvalidDomain(format!(
                    "the mesh boundary touches itself at vertex {a} {at:?}: not a set of simple loops"
                )));
            }
        }
        let mut rings: Vec<Vec<[f64; 2]>> = Vec::new();
        let mut visited = HashSet::with_capacity(edges.len());
        for &[start, _] in &edges {
            if !visited.insert(start) {
                continue;
            }
            let mut ring = vec![start];
            let mut v = next[&start];
            while v != start {
                visited.insert(v);
                ring.push(v);
                v = next[&v];
            }
            rings.push(drop_straight_vertices(ring.iter().map(|&v| mesh.vertices()[v as usize]).collect()));
        }
        let outer = (0..rings.len()).max_by(|&a, &b| ring_area(&rings[a]).total_cmp(&ring_area(&rings[b])));
        let Some(outer) = outer.map(|outer| rings.swap_remove(outer)) else {
            // Every edge has two elements: they overlap (a planar mesh cannot be closed).
            return Err(MeshgenError::InvalidDomain("the mesh has no boundary edge: its elements overlap".into()));
        };
        if let Some(ring) = rings.iter().find(|ring| ring_area(ring) > 0.0) {
            return Err(MeshgenError::InvalidDomain(format!(
                "the mesh has more than one component (a second outer boundary starts at {:?})",
                ring[0]
            )));
        }
        Self::new(outer, rings)
    }

    /// The outer ring.
    pub fn outer(&self) -> &[[f64; 2]] {
        &self.outer
    }

    /// The holes.
    pub fn holes(&self) -> &[Vec<[f64; 2]>] {
        &self.holes
    }

    /// All rings, outer first.
    pub fn rings(&self) -> impl Iterator<Item = &[[f64; 2]]> {
        std::iter::once(self.outer.as_slice()).chain(self.holes.iter().map(Vec::as_slice))
    }

    /// Enclosed area (outer minus holes).
    pub fn area(&self) -> f64 {
        ring_area(&self.outer).abs() - self.holes.iter().map(|h| ring_area(h).abs()).sum::<f64>()
    }

    /// Whether `p` lies strictly inside the domain (even-odd rule over all rings).
    pub fn contains(&self, p: [f64; 2]) -> bool {
        self.rings().filter(|ring| ring_contains(ring, p)).count() % 2 == 1
    }

    /// Axis-aligned bounding box `(min, max)`.
    pub fn bounding_box(&self) -> ([f64; 2], [f64; 2]) {
        amber_mesh::bounding_box(&self.outer).expect("a validated domain's outer ring has at least 3 vertices")
    }

    fn validate(&self) -> Result<(), MeshgenError> {
        // The range of spade's exact predicates (also where squared lengths stay finite).
        const MAX_COORDINATE: f64 = spade::MAX_ALLOWED_VALUE;
        let invalid = |msg: String| Err(MeshgenError::InvalidDomain(msg));
        for (r, ring) in self.rings().enumerate() {
            if ring.len() < 3 {
                return invalid(format!("ring {r} has {} vertices, at least 3 are needed", ring.len()));
            }
            if let Some(i) = ring.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
                return invalid(format!("ring {r}, vertex {i} has a non-finite coordinate"));
            }
            if let Some(i) = ring.iter().position(|p| p[0].abs().max(p[1].abs()) > MAX_COORDINATE) {
                return invalid(format!(
                    "ring {r}, vertex {i} lies beyond ±{MAX_COORDINATE:e}, where the triangulation's exact predicates overflow"
                ));
            }
            if let Some(i) = ring.iter().position(|p| p.iter().any(|&c| c != 0.0 && c.abs() < spade::MIN_ALLOWED_VALUE))
            {
                return invalid(format!(
                    "ring {r}, vertex {i} has a coordinate nearer 0 than ±{:e}, where the triangulation's exact \
                     predicates underflow",
                    spade::MIN_ALLOWED_VALUE
                ));
            }
            for i in 0..ring.len() {
                if ring[i] == ring[(i + 1) % ring.len()] {
                    return invalid(format!("ring {r}, vertices {i} and {} coincide", (i + 1) % ring.len()));
                }
            }
        }
        self.check_no_intersections()?;
        for (r, ring) in self.rings().enumerate() {
            if ring_area(ring) == 0.0 {
                return invalid(format!("ring {r} encloses no area"));
            }
        }
        for (h, hole) in self.holes.iter().enumerate() {
            if !ring_contains(&self.outer, hole[0]) {
                return invalid(format!("hole {h} lies outside the outer ring"));
            }
            // Rings do not cross, so one vertex tells whether a hole lies inside another.
            if let Some(outer) =
                self.holes.iter().position(|other| !std::ptr::eq(other, hole) && ring_contains(other, hole[0]))
            {
                return invalid(format!(
                    "hole {h} lies inside hole {outer} (an island: mesh it as a domain of its own)"
                ));
            }
        }
        Ok(())
    }

    /// Sweep over edges sorted by their lowest x: only edges whose x-ranges overlap are tested.
    fn check_no_intersections(&self) -> Result<(), MeshgenError> {
        struct Edge {
            ring: usize,
            index: usize,
            ring_len: usize,
            a: [f64; 2],
            b: [f64; 2],
        }
        let mut edges: Vec<Edge> = self
            .rings()
            .enumerate()
            .flat_map(|(ring, pts)| {
                (0..pts.len()).map(move |index| Edge {
                    ring,
                    index,
                    ring_len: pts.len(),
                    a: pts[index],
                    b: pts[(index + 1) % pts.len()],
                })
            })
            .collect();
        edges.sort_by(|e, f| e.a[0].min(e.b[0]).total_cmp(&f.a[0].min(f.b[0])));
        for i in 0..edges.len() {
            let e = &edges[i];
            let e_max = e.a[0].max(e.b[0]);
            for f in &edges[i + 1..] {
                if f.a[0].min(f.b[0]) > e_max {
                    break;
                }
                let adjacent = e.ring == f.ring
                    && ((e.index + 1) % e.ring_len == f.index || (f.index + 1) % f.ring_len == e.index);
                let hit = if adjacent {
                    segments_overlap_beyond_shared_vertex(e, f)
                } else {
                    segments_intersect(e.a, e.b, f.a, f.b)
                };
                if hit {
                    return Err(MeshgenError::SelfIntersecting {
                        ring_a: e.ring,
                        edge_a: e.index,
                        ring_b: f.ring,
                        edge_b: f.index,
                    });
                }
            }
        }
        return Ok(());

        fn segments_overlap_beyond_shared_vertex(e: &Edge, f: &Edge) -> bool {
            // Consecutive edges share one vertex; they only conflict if collinear and folding back.
            let (shared, p, q) = if e.b == f.a { (e.b, e.a, f.b) } else { (e.a, e.b, f.a) };
            let (u, v) = ([p[0] - shared[0], p[1] - shared[1]], [q[0] - shared[0], q[1] - shared[1]]);
            u[0] * v[1] - u[1] * v[0] == 0.0 && u[0] * v[0] + u[1] * v[1] > 0.0
        }
    }
}

/// Signed area of a closed ring (positive when counter-clockwise).
/// R-trees over a polygon domain's edges and corners, for exact nearest-distance queries: the
/// 2D counterpart of [`crate::mesh3d::SurfaceDistance`].
#[derive(Clone, Debug)]
pub struct PolygonDistance {
    /// Every boundary edge with the boundary's radius of curvature there (see
    /// [`PolygonDistance::to_boundary`]) and the side it belongs to (see
    /// [`PolygonDistance::nearest_side`]).
    edges: RTree<GeomWithData<Line<[f64; 2]>, EdgeData>>,
    /// The vertices where the boundary turns by more than [`CORNER_TURN`], each with its turn
    /// (positive where the domain is convex, negative at a re-entrant corner).
    corners: RTree<GeomWithData<[f64; 2], f64>>,
}

/// What [`PolygonDistance`] knows of a boundary edge.
#[derive(Clone, Copy, Debug)]
struct EdgeData {
    /// The boundary's radius of curvature along the edge.
    radius: f64,
    /// The side of the boundary the edge belongs to.
    side: i32,
}

/// The smallest turn of the boundary that makes a vertex a corner: a polygon that approximates
/// a circle with 12 or more vertices has no corners.
const CORNER_TURN: f64 = std::f64::consts::PI / 6.0;

impl PolygonDistance {
    /// Indexes the rings of `domain`.
    pub fn new(domain: &PolygonDomain) -> Self {
        let outer_sign = ring_area(domain.outer()).signum();
        let mut edges = Vec::new();
        let mut corners = Vec::new();
        let mut sides = 0i32;
        for (r, ring) in domain.rings().enumerate() {
            // Walking with the domain on the left: the outer ring anticlockwise, holes clockwise.
            let sign = if r == 0 { outer_sign } else { -ring_area(ring).signum() };
            let n = ring.len();
            let turns: Vec<f64> = (0..n)
                .map(|i| {
                    let (prev, v, next) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
                    let (a, b) = ([v[0] - prev[0], v[1] - prev[1]], [next[0] - v[0], next[1] - v[1]]);
                    sign * (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1])
                })
                .collect();
            let is_corner = |i: usize| turns[i].abs() > CORNER_TURN;
            corners.extend((0..n).filter(|&i| is_corner(i)).map(|i| GeomWithData::new(ring[i], turns[i])));
            // The curvature at each vertex of a smooth stretch: its turn over the mean length of
            // its two edges (1/r on a polygon inscribed in a circle of radius r); corners are
            // features, not curvature.
            let length = |i: usize| (ring[(i + 1) % n][0] - ring[i][0]).hypot(ring[(i + 1) % n][1] - ring[i][1]);
            let curvature: Vec<f64> = (0..n)
                .map(|i| if is_corner(i) { 0.0 } else { 2.0 * turns[i].abs() / (length((i + n - 1) % n) + length(i)) })
                .collect();
            // A side runs from corner to corner, a ring without corners is one side: numbered
            // from the ring's first corner, so that the side through vertex 0 is one side.
            let first = (0..n).find(|&i| is_corner(i)).unwrap_or(0);
            let mut side = sides;
            for k in 0..n {
                let i = (first + k) % n;
                if k == 0 || is_corner(i) {
                    side += 1;
                }
                let radius = 1.0 / curvature[i].max(curvature[(i + 1) % n]);
                edges.push(GeomWithData::new(Line::new(ring[i], ring[(i + 1) % n]), EdgeData { radius, side }));
            }
            sides = side;
        }
        Self { edges: RTree::bulk_load(edges), corners: RTree::bulk_load(corners) }
    }

    /// The distance from `p` to the boundary and the boundary's radius of curvature at the
    /// boundary point nearest to `p`: of the circle through the smooth (non-corner) vertices
    /// there, infinite along straight edges.
    pub fn to_boundary(&self, p: [f64; 2]) -> (f64, f64) {
        self.edges
            .nearest_neighbor(p)
            .map_or((f64::INFINITY, f64::INFINITY), |e| (e.distance_2(&p).sqrt(), e.data.radius))
    }

    /// The side of the boundary nearest to `p`: sides are the stretches of a ring between its
    /// corners (a ring without corners is one side), numbered from 1 along the outer ring from
    /// its first corner, then along each hole; `None` for an empty domain. The 2D counterpart of
    /// a solid's CAD faces, for boundary conditions.
    pub fn nearest_side(&self, p: [f64; 2]) -> Option<i32> {
        self.edges.nearest_neighbor(p).map(|e| e.data.side)
    }

    /// The distance from `p` to the nearest corner and how far the boundary turns there (in
    /// radians, negative at a re-entrant corner), or `None` for a domain without corners.
    pub fn to_corner(&self, p: [f64; 2]) -> Option<(f64, f64)> {
        self.corners.nearest_neighbor(p).map(|c| (c.distance_2(&p).sqrt(), c.data))
    }

    /// The width of the domain at `p`: the chord through `p` along the normal of the nearest
    /// boundary edge, from the boundary on one side to the boundary on the other. Infinite where
    /// a ray leaves without meeting the boundary (a point outside).
    pub fn wall_thickness(&self, p: [f64; 2]) -> f64 {
        let Some(nearest) = self.edges.nearest_neighbor(p) else {
            return f64::INFINITY;
        };
        let (a, b) = (nearest.geom().from, nearest.geom().to);
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        if length == 0.0 {
            return f64::INFINITY;
        }
        let normal = [(a[1] - b[1]) / length, (b[0] - a[0]) / length];
        chord(&self.edges, p, normal, nearest.distance_2(&p).sqrt(), |e, d, tolerance| {
            ray_segment(p, d, [e.geom().from, e.geom().to], tolerance)
        })
    }
}

fn ring_area(ring: &[[f64; 2]]) -> f64 {
    0.5 * (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
}

/// Crossing-number test.
fn ring_contains(ring: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut inside = false;
    for i in 0..ring.len() {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        if (a[1] > p[1]) != (b[1] > p[1]) && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
            inside = !inside;
        }
    }
    inside
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Closed-segment intersection (touching counts).
fn segments_intersect(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2, d3, d4) = (orient(c, d, a), orient(c, d, b), orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    let on = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        r[0] >= p[0].min(q[0]) && r[0] <= p[0].max(q[0]) && r[1] >= p[1].min(q[1]) && r[1] <= p[1].max(q[1])
    };
    (d1 == 0.0 && on(c, d, a)) || (d2 == 0.0 && on(c, d, b)) || (d3 == 0.0 && on(a, b, c)) || (d4 == 0.0 && on(a, b, d))
}

/// `ring` without the vertices where it runs straight on: the turn there is below 1e-9 radians,
/// far below any corner a user draws, far above rounding in coordinates of a straight line.
fn drop_straight_vertices(ring: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let n = ring.len();
    let turns = |i: usize| {
        let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let cross = u[0] * v[1] - u[1] * v[0];
        let dot = u[0] * v[0] + u[1] * v[1];
        cross.atan2(dot).abs() > 1e-9
    };
    let kept: Vec<[f64; 2]> = (0..n).filter(|&i| turns(i)).map(|i| ring[i]).collect();
    if kept.len() >= 3 { kept } else { ring }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fine mesh of a polygon with a hole gives back the polygon: its corners only (the
    /// vertices along straight sides are dropped), the hole as a hole.
    #[test]
    fn mesh_boundaries_give_back_their_polygons() {
        let outer = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]];
        let hole = vec![[0.25, 0.25], [0.25, 0.5], [0.5, 0.5], [0.5, 0.25]];
        let domain = PolygonDomain::new(outer.clone(), vec![hole]).unwrap();
        let mesh = crate::uniform_mesh_2d(&domain, 0.05, &Default::default()).unwrap();
        let back = PolygonDomain::from_mesh_boundary(&mesh).unwrap();
        assert_eq!(back.outer().len(), 6);
        assert!(outer.iter().all(|p| back.outer().contains(p)));
        assert_eq!(back.holes().len(), 1);
        assert_eq!(back.holes()[0].len(), 4);
        assert!((back.area() - domain.area()).abs() < 1e-12);
        // Two separate squares are not one domain.
        let two = Mesh2::new(
            vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [2.0, 0.0], [3.0, 0.0], [2.0, 1.0]],
            vec![0, 1, 2, 3, 4, 5],
        )
        .unwrap();
        assert!(PolygonDomain::from_mesh_boundary(&two).unwrap_err().to_string().contains("more than one component"));
    }

    #[test]
    fn lshape_area_and_containment() {
        let d = PolygonDomain::lshape([0.5, 0.25]).unwrap();
        assert!((d.area() - (1.0 - 0.5 * 0.75)).abs() < 1e-15);
        assert!(d.contains([0.25, 0.75]));
        assert!(!d.contains([0.75, 0.75]));
        assert!(PolygonDomain::lshape([1.2, 0.5]).is_err());
    }

    #[test]
    fn bad_polygons_are_rejected() {
        let bowtie = vec![[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(PolygonDomain::new(bowtie, vec![]), Err(MeshgenError::SelfIntersecting { .. })));
        // A flat ring folds back onto itself.
        let degenerate = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]];
        assert!(matches!(PolygonDomain::new(degenerate, vec![]), Err(MeshgenError::SelfIntersecting { .. })));
        let repeated = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(PolygonDomain::new(repeated, vec![]), Err(MeshgenError::InvalidDomain(_))));
        let nan = vec![[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]];
        assert!(matches!(PolygonDomain::new(nan, vec![]), Err(MeshgenError::InvalidDomain(_))));
        // Beyond spade's range (the probe's 1e149 domain failed inside the triangulation).
        for (far, says) in [(1e149, "overflow"), (1e-50, "underflow")] {
            let square = vec![[0.0, 0.0], [far, 0.0], [far, far], [0.0, far]];
            let err = PolygonDomain::new(square, vec![]);
            assert!(matches!(err, Err(MeshgenError::InvalidDomain(ref m)) if m.contains(says)), "{far}: {err:?}");
        }
        let big = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]].to_vec();
        let hole = [[1.0, 1.0], [9.0, 1.0], [9.0, 9.0], [1.0, 9.0]].to_vec();
        let inner = [[4.0, 4.0], [6.0, 4.0], [6.0, 6.0], [4.0, 6.0]].to_vec();
        let nested = PolygonDomain::new(big, vec![hole, inner]);
        assert!(matches!(nested, Err(MeshgenError::InvalidDomain(m)) if m.contains("inside hole 0")));
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let outside_hole = vec![[2.0, 2.0], [3.0, 2.0], [3.0, 3.0]];
        assert!(PolygonDomain::new(square.clone(), vec![outside_hole]).is_err());
        let crossing_hole = vec![[0.5, 0.5], [1.5, 0.5], [0.5, 0.7]];
        assert!(matches!(
            PolygonDomain::new(square.clone(), vec![crossing_hole]),
            Err(MeshgenError::SelfIntersecting { .. })
        ));
        let hole = vec![[0.25, 0.25], [0.75, 0.25], [0.75, 0.75], [0.25, 0.75]];
        let d = PolygonDomain::new(square, vec![hole]).unwrap();
        assert!((d.area() - 0.75).abs() < 1e-15);
        assert!(!d.contains([0.5, 0.5]));
    }

    #[test]
    fn deserialising_validates() {
        let d: PolygonDomain = serde_json::from_str(r#"{"outer": [[0,0],[1,0],[0,1]]}"#).unwrap();
        assert!((d.area() - 0.5).abs() < 1e-15);
        let bowtie = r#"{"outer": [[0,0],[1,1],[1,0],[0,1]]}"#;
        assert!(serde_json::from_str::<PolygonDomain>(bowtie).unwrap_err().to_string().contains("self-intersecting"));
    }

    /// A square frame with walls 0.3 wide: the chord along the nearest side's normal crosses
    /// one wall; outside the frame no ray meets the boundary twice.
    #[test]
    fn a_frame_is_as_wide_as_its_walls() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let hole = vec![[0.3, 0.3], [0.3, 0.7], [0.7, 0.7], [0.7, 0.3]];
        let distance = PolygonDistance::new(&PolygonDomain::new(square, vec![hole]).unwrap());
        for p in [[0.1, 0.5], [0.5, 0.9], [0.5, 0.1], [0.25, 0.6]] {
            assert!((distance.wall_thickness(p) - 0.3).abs() < 1e-12, "{p:?}: {}", distance.wall_thickness(p));
        }
        assert_eq!(distance.wall_thickness([2.0, 0.5]), f64::INFINITY);
    }

    /// Near a round hole the boundary's radius of curvature is the hole's; along the square's
    /// straight sides (between corners) it is infinite.
    #[test]
    fn a_round_hole_has_its_radius_of_curvature() {
        let square = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let hole = (0..48)
            .map(|k| {
                let angle = std::f64::consts::TAU * f64::from(k) / 48.0;
                [0.5 + 0.1 * angle.cos(), 0.5 + 0.1 * angle.sin()]
            })
            .collect();
        let distance = PolygonDistance::new(&PolygonDomain::new(square, vec![hole]).unwrap());
        for p in [[0.65, 0.5], [0.5, 0.38], [0.4, 0.6]] {
            let (_, radius) = distance.to_boundary(p);
            assert!((radius - 0.1).abs() < 1e-3, "{p:?}: {radius}");
        }
        assert!(distance.to_corner([0.62, 0.5]).unwrap().0 > 0.3, "a 48-gon has no corners");
        assert_eq!(distance.to_boundary([0.5, 0.05]), (0.05, f64::INFINITY));
        // Sides: the square's four from its first corner, then the hole, one side all round.
        let sides = [[0.5, 0.02], [0.98, 0.5], [0.5, 0.98], [0.02, 0.5], [0.65, 0.5], [0.5, 0.35], [0.42, 0.55]];
        let found: Vec<i32> = sides.iter().map(|&p| distance.nearest_side(p).unwrap()).collect();
        assert_eq!(found, [1, 2, 3, 4, 5, 5, 5]);
        // A ring that starts in the middle of a side still has that side once.
        let outer = vec![[0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]];
        let distance = PolygonDistance::new(&PolygonDomain::new(outer, vec![]).unwrap());
        let found: Vec<i32> = sides[..4].iter().map(|&p| distance.nearest_side(p).unwrap()).collect();
        assert_eq!(found, [4, 1, 2, 3]);
        assert_eq!(distance.nearest_side([0.8, 0.01]), Some(4));
    }

    /// The L-shape turns a quarter left at its five convex corners and a quarter right at the
    /// re-entrant one, whichever way its rings run.
    #[test]
    fn distances_in_the_l_shape() {
        let lshape = PolygonDomain::lshape([0.5, 0.5]).unwrap();
        let reversed = PolygonDomain::new(lshape.outer().iter().rev().copied().collect(), vec![]).unwrap();
        for domain in [lshape, reversed] {
            let distance = PolygonDistance::new(&domain);
            let p = [0.45, 0.6];
            assert!((distance.to_boundary(p).0 - 0.05).abs() < 1e-12);
            let (to_corner, turn) = distance.to_corner(p).unwrap();
            assert!((to_corner - 0.0125f64.sqrt()).abs() < 1e-12);
            assert!((turn + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
            let (_, turn) = distance.to_corner([0.1, 0.1]).unwrap();
            assert!((turn - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        }
    }
}
