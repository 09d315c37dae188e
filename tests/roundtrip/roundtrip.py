#!/usr/bin/env python3
"""Round trips of `amber convert` against the real tools, meshio and gmsh.

read:  meshio and gmsh write a 2D triangle mesh and a 3D tetrahedral mesh (with a cell array
       `size`) in every format and encoding they have; `amber convert` turns each into JSON,
       which must hold the same vertices (to 1e-12), the same elements and the same `size`.
       The same for gmsh's second-order meshes (triangle6, tetra10), which amber reads as the
       linear simplices of their corners.
write: `amber convert` writes a reference mesh (JSON with `size`) in every format and encoding
       it has; meshio and gmsh read each back: same vertex and element counts, same coordinates
       (to 1e-12), `size` preserved (meshio, where the format stores cell data), physical groups
       present (.msh), the boundary's node set (.inp). Then again as second-order elements
       (`--order 2`): their corners are the reference's elements, each edge node sits at its
       edge's midpoint in the reader's node order, the .inp node set has the edge nodes too.

Prints a table format x encoding x direction x tool -> pass/fail (the tool that wrote the file
for `read`, the one that read amber's file for `write`) and exits non-zero on any failure.
Usage: roundtrip.py [AMBER_BINARY] (default: $AMBER_BIN, else target/debug/amber).
"""

import contextlib
import io
import json
import os
import subprocess
import sys
import tempfile
import traceback

import gmsh
import meshio
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
AMBER = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("AMBER_BIN", os.path.join(ROOT, "target/debug/amber"))
TOL = 1e-12
# amber writes NASTRAN coordinates in at most 16 characters: exact when they fit, else to 5e-11.
NAS_TOL = 1e-10


def tol_for(path):
    return NAS_TOL if path.endswith(".nas") else TOL
SIMPLEX = {2: "triangle", 3: "tetra"}


def gmsh_model(dim):
    """A unit square or cube meshed by gmsh, with physical groups `domain` and `boundary`."""
    gmsh.model.add(f"m{dim}")
    if dim == 2:
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
    else:
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3 if dim == 2 else 0.45)
    domain = [t for _, t in gmsh.model.getEntities(dim)]
    boundary = [t for _, t in gmsh.model.getEntities(dim - 1)]
    gmsh.model.addPhysicalGroup(dim, domain, 1, "domain")
    gmsh.model.addPhysicalGroup(dim - 1, boundary, 2, "boundary")
    gmsh.model.mesh.generate(dim)


def reference(dim, directory):
    """The gmsh mesh as (points, cells, size), and the path of the same mesh as amber JSON."""
    restart_gmsh()
    gmsh_model(dim)
    path = os.path.join(directory, f"gmsh{dim}.msh")
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(path)
    m = meshio.read(path)
    cells = np.concatenate([c.data for c in m.cells if c.type == SIMPLEX[dim]])
    used = np.unique(cells)
    remap = -np.ones(len(m.points), dtype=np.int64)
    remap[used] = np.arange(len(used))
    points, cells = m.points[used], remap[cells]
    size = 0.1 + np.arange(len(cells)) / 7.0
    ref = os.path.join(directory, f"ref{dim}.json")
    with open(ref, "w") as f:
        json.dump({"dimension": dim, "vertices": points[:, :dim].tolist(), "elements": cells.tolist(),
                   "cell_data": {"size": size.tolist()}}, f)
    return points, cells, size, ref


def amber_convert(src, dst, *flags):
    env = dict(os.environ, RUST_BACKTRACE="0")
    run = subprocess.run([AMBER, "convert", src, dst, *flags], capture_output=True, text=True, env=env)
    if run.returncode != 0:
        raise RuntimeError(run.stderr.strip())


def same_points(expected, got, tol=TOL):
    """Same points to TOL, in order or (for tools that renumber) as sorted sets."""
    expected, got = np.asarray(expected, float), np.asarray(got, float)
    if expected.shape != got.shape:
        raise AssertionError(f"{len(got)} points, expected {len(expected)}")
    if np.abs(expected - got).max() <= tol:
        return
    order = lambda p: p[np.lexsort(np.round(p, 5).T[::-1])]
    diff = np.abs(order(expected) - order(got)).max()
    if diff > tol:
        raise AssertionError(f"coordinates differ by {diff}")


def same_cells(expected_points, expected, got_points, got):
    """Same elements, each matched through its nearest expected vertices (independent of
    numbering and orientation)."""
    if len(expected) != len(got):
        raise AssertionError(f"{len(got)} elements, expected {len(expected)}")
    expected_points, got_points = np.asarray(expected_points), np.asarray(got_points)
    nearest = np.array([np.argmin(((expected_points - p) ** 2).sum(axis=1)) for p in got_points])
    key = lambda cells: sorted(tuple(sorted(c)) for c in np.asarray(cells).tolist())
    if key(expected) != key(nearest[np.asarray(got)]):
        raise AssertionError("different elements")


def same_values(expected, got, what):
    if got is None:
        raise AssertionError(f"no {what}")
    if len(got) != len(expected) or np.abs(np.asarray(got) - expected).max() > TOL:
        raise AssertionError(f"{what} differs")


def check_amber_json(path, dim, points, cells, size, tol=TOL):
    with open(path) as f:
        m = json.load(f)
    if m["dimension"] != dim:
        raise AssertionError(f"dimension {m['dimension']}")
    got_points = np.zeros((len(m["vertices"]), 3))
    got_points[:, :dim] = m["vertices"]
    same_points(points, got_points, tol)
    same_cells(points, cells, got_points, np.array(m["elements"]))
    if size is not None:
        same_values(size, m.get("cell_data", {}).get("size"), "cell data `size`")


def as_read_by_meshio(path, dim):
    """What meshio reads from a file (points, simplices, `size`), the truth for files that round
    their numbers (meshio's ASCII .vtu keeps 12 digits); None where meshio cannot read it."""
    try:
        quiet = io.StringIO()  # meshio prints its failures
        with contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
            m = meshio_read(path)
    except (Exception, SystemExit):  # noqa: BLE001 - fall back to the reference mesh
        return None
    got = np.concatenate([c.data for c in m.cells if c.type == SIMPLEX[dim]])
    points = np.zeros((len(m.points), 3))
    points[:, : m.points.shape[1]] = m.points
    used = np.unique(got)
    remap = -np.ones(len(points), dtype=np.int64)
    remap[used] = np.arange(len(used))
    blocks = [np.ravel(d) for c, d in zip(m.cells, m.cell_data.get("size", [])) if c.type == SIMPLEX[dim]]
    return points[used], remap[got], np.concatenate(blocks) if blocks else None


def meshio_inputs(dim, points, cells, size, directory):
    """(format, encoding, path, carries cell data) for every file meshio writes."""
    pts = points if dim == 3 else points[:, :2]
    mesh = meshio.Mesh(pts, [(SIMPLEX[dim], cells)], cell_data={"size": [size]})
    mesh3 = meshio.Mesh(points, [(SIMPLEX[dim], cells)], cell_data={"size": [size]})
    out = []

    def add(fmt, encoding, name, write, data=True):
        path = os.path.join(directory, f"meshio{dim}-{name}")
        write(path)
        out.append((fmt, encoding, path, data))

    add("vtu", "ascii", "a.vtu", lambda p: meshio.vtu.write(p, mesh3, binary=False))
    add("vtu", "binary", "b.vtu", lambda p: meshio.vtu.write(p, mesh3, binary=True, compression=None))
    add("vtu", "binary zlib", "z.vtu", lambda p: meshio.vtu.write(p, mesh3, binary=True, compression="zlib"))
    add("vtu", "binary UInt64", "u64.vtu",
        lambda p: meshio.vtu.write(p, mesh3, binary=True, compression=None, header_type="UInt64"))
    add("vtk", "ascii 5.1", "a.vtk", lambda p: meshio.vtk.write(p, mesh3, binary=False))
    add("vtk", "binary 5.1", "b.vtk", lambda p: meshio.vtk.write(p, mesh3, binary=True))
    add("vtk", "ascii 4.2", "a42.vtk", lambda p: meshio.vtk.write(p, mesh3, binary=False, fmt_version="4.2"))
    add("vtk", "binary 4.2", "b42.vtk", lambda p: meshio.vtk.write(p, mesh3, binary=True, fmt_version="4.2"))
    # meshio 5.3 writes ASCII $ElementData values as `np.float64(0.1)` under numpy 2: those
    # files carry no cell data here.
    bare = meshio.Mesh(points, [(SIMPLEX[dim], cells)])
    for version, name in [("gmsh22", "2.2"), ("gmsh", "4.1")]:
        for binary in [False, True]:
            enc = f"{name} {'binary' if binary else 'ascii'}"
            add("msh", enc, f"{version}-{int(binary)}.msh",
                lambda p, v=version, b=binary: meshio.write(p, mesh3 if b else bare, file_format=v, binary=b), binary)
    add("nas", "ascii", "a.nas", lambda p: meshio.write(p, mesh3, file_format="nastran"), data=False)
    add("inp", "ascii", "a.inp", lambda p: meshio.write(p, mesh, file_format="abaqus"), data=False)
    add("mesh", "ascii", "a.mesh", lambda p: meshio.write(p, mesh, file_format="medit"), data=False)
    return out


def gmsh_inputs(dim, size, directory):
    """Files gmsh writes from the reference model; .msh files get `size` appended as a view."""
    out = []
    gmsh.option.setNumber("PostProcessing.SaveMesh", 0)
    for version in ["2.2", "4.1"]:
        for binary in [0, 1]:
            path = os.path.join(directory, f"gmsh{dim}-{version}-{binary}.msh")
            gmsh.option.setNumber("Mesh.MshFileVersion", float(version))
            gmsh.option.setNumber("Mesh.Binary", binary)
            gmsh.write(path)
            types, tags, _ = gmsh.model.mesh.getElements(dim)
            view = gmsh.view.add("size")
            simplex_tags = [t for ty, t in zip(types, tags) if ty in (2, 4)][0]
            gmsh.view.addHomogeneousModelData(view, 0, gmsh.model.getCurrent(), "ElementData", simplex_tags, size)
            gmsh.view.write(view, path, append=True)
            gmsh.view.remove(view)
            out.append(("msh", f"{version} {'binary' if binary else 'ascii'}", path, True))
    gmsh.option.setNumber("Mesh.Binary", 0)
    for ext, enc, binary in [("vtk", "ascii", 0), ("vtk", "binary", 1), ("mesh", "ascii", 0), ("bdf", "ascii", 0)]:
        path = os.path.join(directory, f"gmsh{dim}-{enc}.{ext}")
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(path)
        out.append((ext if ext != "bdf" else "nas", enc, path, False))
    gmsh.option.setNumber("Mesh.Binary", 0)
    return out


QUADRATIC = {2: "triangle6", 3: "tetra10"}


def quadratic_inputs(dim, directory):
    """gmsh's second-order mesh of the reference model, written by gmsh and meshio in every format
    that stores it, and the mesh of its corners (points, cells): what amber reads from each."""
    restart_gmsh()
    gmsh_model(dim)
    gmsh.model.mesh.setOrder(2)
    out = []
    for version in ["2.2", "4.1"]:
        for binary in [0, 1]:
            path = os.path.join(directory, f"quadratic{dim}-{version}-{binary}.msh")
            gmsh.option.setNumber("Mesh.MshFileVersion", float(version))
            gmsh.option.setNumber("Mesh.Binary", binary)
            gmsh.write(path)
            out.append(("gmsh", "msh", f"{version} {'binary' if binary else 'ascii'}", path))
    gmsh.option.setNumber("Mesh.Binary", 0)
    # gmsh's .bdf has 8-character fields: its coordinates carry 7 digits.
    for ext in ["vtk", "mesh", "bdf"]:
        path = os.path.join(directory, f"quadratic{dim}.{ext}")
        gmsh.write(path)
        out.append(("gmsh", ext if ext != "bdf" else "nas", "ascii", path))
    m = meshio_read(out[0][3])
    full = np.concatenate([c.data for c in m.cells if c.type == QUADRATIC[dim]])
    corners = full[:, : dim + 1]
    used = np.unique(corners)
    remap = -np.ones(len(m.points), dtype=np.int64)
    remap[used] = np.arange(len(used))
    points = np.zeros((len(used), 3))
    points[:, : m.points.shape[1]] = m.points[used]
    # meshio's medit writer skips second-order cells, and its NASTRAN writer names the card
    # `CTETRA_`, which no NASTRAN reads.
    mesh = meshio.Mesh(m.points if dim == 3 else m.points[:, :2], [(QUADRATIC[dim], full)])
    for fmt, name, write in [("vtu", "b.vtu", lambda p: meshio.vtu.write(p, mesh, binary=True)),
                             ("vtk", "a.vtk", lambda p: meshio.vtk.write(p, mesh, binary=False)),
                             ("inp", "a.inp", lambda p: meshio.write(p, mesh, file_format="abaqus"))]:
        path = os.path.join(directory, f"meshio-quadratic{dim}-{name}")
        write(path)
        out.append(("meshio", fmt, "binary" if name.startswith("b") else "ascii", path))
    return points, remap[corners], out


def meshio_read(path):
    """meshio.read, told that .msh is gmsh (else a failure tries ANSYS and exits the process)."""
    return meshio.read(path, file_format="gmsh" if path.endswith(".msh") else None)


def meshio_elements(path, kind):
    """meshio's mesh of `path`, its points in 3D and its elements of `kind`."""
    m = meshio_read(path)
    got = np.concatenate([c.data for c in m.cells if c.type == kind])
    got_points = np.zeros((len(m.points), 3))
    got_points[:, : m.points.shape[1]] = m.points
    return m, got_points, got


def same_size_field(m, kind, size):
    blocks = [np.ravel(d) for c, d in zip(m.cells, m.cell_data.get("size", [])) if c.type == kind]
    same_values(size, np.concatenate(blocks) if blocks else None, "cell data `size`")


def read_with_meshio(path, dim, points, cells, size, has_data, physical):
    m, got_points, got = meshio_elements(path, SIMPLEX[dim])
    same_points(points, got_points, tol_for(path))
    same_cells(points, cells, got_points, got)
    if has_data:
        same_size_field(m, SIMPLEX[dim], size)
    if physical and not {"domain", "boundary"} <= set(m.field_data):
        raise AssertionError(f"physical names {sorted(m.field_data)}")
    if path.endswith(".nas") and dim == 3:
        # The boundary as skin triangles (amber keeps the point order), each facet once.
        skin = sorted(tuple(sorted(t)) for c in m.cells if c.type == "triangle" for t in c.data.tolist())
        if skin != sorted(boundary_facets(cells, dim)):
            raise AssertionError(f"{len(skin)} skin triangles, not the {len(boundary_facets(cells, dim))} boundary facets")
    if path.endswith(".inp"):
        boundary = sorted({v for f in boundary_facets(cells, dim) for v in f})
        if "boundary" not in m.point_sets:
            raise AssertionError(f"node sets {sorted(m.point_sets)}")
        same_points(np.asarray(points)[boundary], got_points[np.asarray(m.point_sets["boundary"])])


# The edges of a second-order element, in the order of its edge nodes: meshio's (VTK's, also
# NASTRAN's and Abaqus's) and gmsh's, which differ in a tetra10's last two.
EDGES = {"vtk": {2: [(0, 1), (1, 2), (2, 0)], 3: [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]}}
EDGES["gmsh"] = {2: EDGES["vtk"][2], 3: [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)]}


def same_quadratic(points, cells, got_points, got, edges, tol=TOL):
    """Second-order elements: their corners are the reference's elements, each edge node lies at
    its edge's midpoint (to `tol`), and there is one node per vertex and per edge."""
    got = np.asarray(got, dtype=int)
    corners = got[:, : got.shape[1] - len(edges)]
    same_cells(points, cells, got_points, corners)
    for k, (a, b) in enumerate(edges):
        midpoint = 0.5 * (got_points[corners[:, a]] + got_points[corners[:, b]])
        diff = np.abs(got_points[got[:, corners.shape[1] + k]] - midpoint).max()
        if diff > tol:
            raise AssertionError(f"edge node {k} lies {diff} off its edge's midpoint")
    edge_count = len({tuple(sorted((c[a], c[b]))) for c in corners.tolist() for a, b in edges})
    if len(got_points) != len(points) + edge_count:
        raise AssertionError(f"{len(got_points)} nodes for {len(points)} vertices and {edge_count} edges")


def boundary_facets(cells, dim):
    """The facets (sorted vertex tuples) that one element alone has."""
    faces = [tuple(sorted(np.delete(c, k))) for c in np.asarray(cells).tolist() for k in range(dim + 1)]
    counts = {}
    for f in faces:
        counts[f] = counts.get(f, 0) + 1
    return [f for f, n in counts.items() if n == 1]


def read_quadratic_with_meshio(path, dim, points, cells, size, has_data):
    if path.endswith(".inp") and dim == 2:
        # meshio 5.3 lacks CPS6, Abaqus's plane-stress 6-node triangle; its plane-strain CPE6 has
        # the same nodes.
        with open(path) as f:
            text = f.read()
        path = path[: -len(".inp")] + "-cpe6.inp"
        with open(path, "w") as f:
            f.write(text.replace("TYPE=CPS6", "TYPE=CPE6"))
    m, got_points, got = meshio_elements(path, QUADRATIC[dim])
    same_quadratic(points, cells, got_points, got, EDGES["vtk"][dim], tol_for(path))
    if has_data:
        same_size_field(m, QUADRATIC[dim], size)
    if path.endswith(".inp"):
        # The boundary's node set holds the edge nodes of the boundary facets too.
        facets = boundary_facets(cells, dim)
        points = np.asarray(points)
        corners = points[sorted({v for f in facets for v in f})]
        midpoints = {tuple(0.5 * (points[a] + points[b])) for f in facets for a in f for b in f if a < b}
        same_points(np.vstack([corners, sorted(midpoints)]), got_points[np.asarray(m.point_sets["boundary"])])


def gmsh_elements(path, dim, types, nodes_per_element):
    """gmsh's nodes of `path` and its elements of dimension `dim` and of the gmsh `types`."""
    restart_gmsh()
    gmsh.open(path)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    got_points = np.asarray(coords).reshape(-1, 3)
    index = {t: i for i, t in enumerate(tags)}
    found, _, nodes = gmsh.model.mesh.getElements(dim)
    blocks = [n for t, n in zip(found, nodes) if t in types]
    if not blocks:
        raise AssertionError(f"element types {list(found)}, none of {types}")
    return got_points, np.array([index[t] for t in np.concatenate(blocks)]).reshape(-1, nodes_per_element)


def read_quadratic_with_gmsh(path, dim, points, cells):
    edges = EDGES["gmsh"][dim]
    got_points, got = gmsh_elements(path, dim, (9, 11), dim + 1 + len(edges))
    same_quadratic(points, cells, got_points, got, edges, tol_for(path))


def restart_gmsh():
    """A fresh gmsh: after a failed open gmsh 4.15 stays "busy" and ignores the next ones."""
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)


def read_with_gmsh(path, dim, points, cells, physical):
    got_points, got = gmsh_elements(path, dim, (2, 4), dim + 1)
    same_points(points, got_points, tol_for(path))
    same_cells(points, cells, got_points, got)
    if physical:
        groups = set(gmsh.model.getPhysicalGroups())
        if not {(dim, 1), (dim - 1, 1)} <= groups:
            raise AssertionError(f"physical groups {sorted(groups)}")


def main():
    results = []

    def record(fmt, encoding, direction, tool, check):
        try:
            check()
            results.append((fmt, encoding, direction, tool, "pass", ""))
        except (Exception, SystemExit) as e:  # noqa: BLE001 - every failure is a table row
            detail = str(e).splitlines()[-1] if str(e) else traceback.format_exc().splitlines()[-1]
            results.append((fmt, encoding, direction, tool, "FAIL", detail[:90]))

    with tempfile.TemporaryDirectory() as directory:
        for dim in [2, 3]:
            points, cells, size, ref = reference(dim, directory)
            inputs = [("meshio", *i) for i in meshio_inputs(dim, points, cells, size, directory)]
            inputs += [("gmsh", *i) for i in gmsh_inputs(dim, size, directory)]
            for tool, fmt, encoding, path, has_data in inputs:
                out = path + ".json"

                def read_check(path=path, out=out, has_data=has_data):
                    amber_convert(path, out)
                    if path.endswith(".bdf"):
                        # gmsh writes 8-character fields (7 digits), which meshio misreads
                        # when they touch: compare with the reference to 1e-6.
                        check_amber_json(out, dim, points, cells, None, 1e-6)
                        return
                    expected = as_read_by_meshio(path, dim) or (points, cells, size)
                    expected_size = expected[2] if expected[2] is not None else size
                    check_amber_json(out, dim, *expected[:2], expected_size if has_data else None)

                record(fmt, f"{encoding} {dim}D", "read", tool, read_check)
            quadratic_points, quadratic_cells, quadratic = quadratic_inputs(dim, directory)
            for tool, fmt, encoding, path in quadratic:

                def quadratic_check(path=path):
                    amber_convert(path, path + ".json")
                    tol = 1e-6 if path.endswith(".bdf") else TOL
                    check_amber_json(path + ".json", dim, quadratic_points, quadratic_cells, None, tol)

                record(fmt, f"{encoding} {dim}D {QUADRATIC[dim]}", "read", tool, quadratic_check)
            outputs = [("vtu", "binary", ["--binary"]), ("vtu", "ascii", ["--ascii"]), ("vtk", "ascii", []),
                       ("vtk", "binary", ["--binary"]), ("msh", "ascii", []), ("msh", "binary", ["--binary"]),
                       ("nas", "ascii", []), ("inp", "ascii", []), ("mesh", "ascii", [])]
            for fmt, encoding, flags in outputs:
                path = os.path.join(directory, f"amber{dim}-{encoding}.{fmt}")
                has_data = fmt in ("vtu", "vtk", "msh")
                try:
                    amber_convert(ref, path, *flags)
                except Exception as e:  # noqa: BLE001
                    record(fmt, f"{encoding} {dim}D", "write", "amber", lambda e=e: (_ for _ in ()).throw(e))
                    continue
                record(fmt, f"{encoding} {dim}D", "write", "meshio",
                       lambda: read_with_meshio(path, dim, points, cells, size, has_data, fmt == "msh"))
                # gmsh 4.15 fails to read binary legacy VTK, even the files it writes itself.
                if fmt in ("msh", "mesh", "nas") or (fmt, encoding) == ("vtk", "ascii"):
                    record(fmt, f"{encoding} {dim}D", "write", "gmsh",
                           lambda: read_with_gmsh(path, dim, points, cells, fmt == "msh"))
            for fmt, encoding, flags in outputs:
                if fmt == "mesh":
                    continue
                path = os.path.join(directory, f"amber{dim}-{encoding}-order2.{fmt}")
                kind = f"{encoding} {dim}D {QUADRATIC[dim]}"
                try:
                    amber_convert(ref, path, "--order", "2", *flags)
                except Exception as e:  # noqa: BLE001
                    record(fmt, kind, "write", "amber", lambda e=e: (_ for _ in ()).throw(e))
                    continue
                has_data = fmt in ("vtu", "vtk", "msh")
                record(fmt, kind, "write", "meshio",
                       lambda: read_quadratic_with_meshio(path, dim, points, cells, size, has_data))
                if fmt in ("msh", "nas") or (fmt, encoding) == ("vtk", "ascii"):
                    record(fmt, kind, "write", "gmsh", lambda: read_quadratic_with_gmsh(path, dim, points, cells))
    gmsh.finalize()

    width = [max(len(r[i]) for r in results) for i in range(5)]
    header = ("format", "encoding", "direction", "tool", "result")
    width = [max(w, len(h)) for w, h in zip(width, header)]
    line = lambda r: "  ".join(c.ljust(w) for c, w in zip(r, width))
    print(line(header))
    for r in results:
        print(line(r[:5]) + (f"  {r[5]}" if r[5] else ""))
    failures = sum(r[4] != "pass" for r in results)
    print(f"\n{len(results) - failures} passed, {failures} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
