"""Peer of `cargo xtask bench mesher3d`: gmsh re-meshing each Console part with the expert's own
sizing field, the reference code's way.

Input (from xtask): per part, `<file>.vertices.npy` (n × 3) and `<file>.tets.npy` (m × 4, uint32):
the expert mesh; `<file>.sizes.npy` (m): the size of each expert tet, the piecewise-constant field
ours meshes with; `input.json` lists the parts (`name`, `file`, and `step`, the part's CAD file,
which gmsh's OpenCASCADE reads where ours reads the reference surface gmsh made from it).

Per part, as the reference code does it: the field as an in-memory list view (`SS`, the tet's
size on its four vertices) behind a PostView background field, only the field sets sizes
(points, curvature and boundary extension off), Mesh.Algorithm 6 (Frontal-Delaunay) on the
surfaces, the default 3D Delaunay, no optimisation, MeshSizeMax 10. The view is built before the
clock starts (ours builds its field's point locator untimed too), and the first CAD file is read
once untimed before any part (OpenCASCADE initialises then); timed once per part, as ours:
reading the CAD, the surface mesh (`generate(2)`) and the volume mesh (`generate(3)`). Each tet
mesh goes back to xtask as `<file>.gmsh_vertices.npy` and `<file>.gmsh_tets.npy`, which
measures it as it does ours.
"""

import time

import amber_peer

import gmsh
import numpy as np

OPTIONS = {
    "General.Verbosity": 1,
    "General.NumThreads": amber_peer.THREADS,
    "Mesh.Algorithm": 6,
    "Mesh.MeshSizeExtendFromBoundary": 0,
    "Mesh.MeshSizeFromPoints": 0,
    "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.Optimize": 0,
    "Mesh.MeshSizeMax": 10,
}

case = amber_peer.Case()
gmsh.initialize(["-noenv"], readConfigFiles=False)
for name, value in OPTIONS.items():
    gmsh.option.setNumber(name, value)

# Untimed: OpenCASCADE's first read of a file initialises it.
gmsh.model.occ.importShapes(case.input["parts"][0]["step"])

parts = []
for part in case.input["parts"]:
    vertices = case.array(f"{part['file']}.vertices")
    tets = case.array(f"{part['file']}.tets")
    sizes = case.array(f"{part['file']}.sizes")
    gmsh.clear()
    # Per tet: x of its 4 vertices, then y, then z, then the value at each vertex.
    corners = vertices[tets]  # m × 4 × 3
    data = np.hstack([corners.transpose(0, 2, 1).reshape(-1, 12), np.repeat(sizes[:, None], 4, axis=1)])
    view = gmsh.view.add("sizing")
    gmsh.view.addListData(view, "SS", len(tets), data.ravel())

    start, start_cpu = time.perf_counter(), time.process_time()
    gmsh.model.occ.importShapes(part["step"])
    gmsh.model.occ.synchronize()
    field = gmsh.model.mesh.field.add("PostView")
    gmsh.model.mesh.field.setNumber(field, "ViewTag", view)
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    gmsh.model.mesh.generate(2)
    surface = time.perf_counter()
    gmsh.model.mesh.generate(3)
    total = time.perf_counter()
    cpu = time.process_time() - start_cpu

    tags, coordinates, _ = gmsh.model.mesh.getNodes()
    _, tet_nodes = gmsh.model.mesh.getElementsByType(4)
    used, tet_indices = np.unique(tet_nodes, return_inverse=True)
    position = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    position[tags] = np.arange(len(tags))
    case.save(f"{part['file']}.gmsh_vertices", coordinates.reshape(-1, 3)[position[used]])
    case.save(f"{part['file']}.gmsh_tets", tet_indices.astype(np.uint32).reshape(-1, 4))
    parts.append(
        {
            "name": part["name"],
            "tets": len(tet_nodes) // 4,
            "seconds_surface": surface - start,
            "seconds_volume": total - surface,
            "seconds_total": total - start,
            "cpu_seconds_total": cpu,
        }
    )
    amber_peer.log(f"{part['name']}: {len(tet_nodes) // 4} tets in {total - start:.2f} s")
gmsh.finalize()

case.finish({"library": "gmsh", "options": OPTIONS, "parts": parts}, ["gmsh", "numpy"])
