"""Peer of `cargo xtask bench mesher`: gmsh's Frontal-Delaunay (Mesh.Algorithm 6) meshing our
graded case's polygon with the same sizing field.

Input (from xtask): `outer.npy` (the polygon's vertices, n × 2, counter-clockwise),
`input.json` with `field` (the sizing field as a gmsh MathEval expression of x and y, the very
formula our bench evaluates) and `repeats`. Only the field sets sizes: sizes from points,
curvature and boundary extension are off. Timed (median of `repeats`): the geometry and the 2D
mesh, from an empty model. The last mesh goes back to xtask as `vertices.npy` (float64, n × 2)
and `triangles.npy` (uint32, m × 3), which measures its sizes and angles as it does ours.
"""

import amber_peer

import gmsh
import numpy as np

case = amber_peer.Case()
outer = case.array("outer")

gmsh.initialize(["-noenv"], readConfigFiles=False)
gmsh.option.setNumber("General.Verbosity", 1)
gmsh.option.setNumber("General.NumThreads", amber_peer.THREADS)
gmsh.option.setNumber("Mesh.Algorithm", 6)
gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)


def mesh():
    gmsh.clear()
    points = [gmsh.model.geo.addPoint(x, y, 0.0) for x, y in outer]
    lines = [gmsh.model.geo.addLine(points[i], points[(i + 1) % len(points)]) for i in range(len(points))]
    gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
    gmsh.model.geo.synchronize()
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(field, "F", case.input["field"])
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    gmsh.model.mesh.generate(2)


seconds, seconds_all, cpu_seconds, _ = amber_peer.timed(mesh, case.input["repeats"])

tags, coordinates, _ = gmsh.model.mesh.getNodes()
_, triangle_nodes = gmsh.model.mesh.getElementsByType(2)
index = np.zeros(int(tags.max()) + 1, dtype=np.uint32)
index[tags] = np.arange(len(tags), dtype=np.uint32)
case.save("vertices", coordinates.reshape(-1, 3)[:, :2].astype(np.float64))
case.save("triangles", index[triangle_nodes].reshape(-1, 3))
triangles = len(triangle_nodes) // 3
gmsh.finalize()

case.finish(
    {
        "library": "gmsh",
        "algorithm": "Frontal-Delaunay (Mesh.Algorithm 6)",
        "triangles": triangles,
        "seconds": seconds,
        "seconds_all": seconds_all,
        "cpu_seconds": cpu_seconds,
        "triangles_per_second": triangles / seconds,
    },
    ["gmsh", "numpy"],
)
