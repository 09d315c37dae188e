"""Reference surfaces for the Console data: STEP -> closed triangulation with the CAD face id per facet.

Usage: pip install gmsh numpy && python make_reference_surfaces.py DIR
For every DIR/{train,val,test}/NNN.step writes DIR/reference_surface/<split>/NNN.stl (binary, mm,
2-byte facet attribute = 1-based CAD face id in gmsh order) with the settings of the shipped bundle:
gmsh/OpenCASCADE, MeshSizeFromCurvature=48, MeshSizeMax=2.5 mm, MeshSizeMin=0.01 mm,
MeshSizeExtendFromBoundary=0, Mesh.Algorithm=6. Orientation is left to amber, which re-orients
and validates every surface it reads (closed, manifold, no self-intersections).
"""
import pathlib
import sys

import gmsh
import numpy as np

SETTINGS = {"Mesh.MeshSizeFromCurvature": 48, "Mesh.MeshSizeMax": 2.5, "Mesh.MeshSizeMin": 0.01,
            "Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.Algorithm": 6, "General.NumThreads": 1}


def reference_surface(step: pathlib.Path, stl: pathlib.Path) -> None:
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    for key, value in SETTINGS.items():
        gmsh.option.setNumber(key, value)
    gmsh.model.add(step.stem)
    gmsh.model.occ.importShapes(str(step))  # OpenCASCADE converts the STEP's metres to mm
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.generate(2)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    points = coords.reshape(-1, 3)
    index = np.full(int(tags.max()) + 1, -1)
    index[tags.astype(int)] = np.arange(len(tags))
    triangles, faces = [], []
    for _, face in gmsh.model.getEntities(2):
        _, _, nodes = gmsh.model.mesh.getElements(2, face)
        t = index[np.asarray(nodes[0]).astype(int)].reshape(-1, 3)
        triangles.append(t)
        faces.append(np.full(len(t), face))
    gmsh.finalize()
    t, f = np.concatenate(triangles), np.concatenate(faces)
    record = np.zeros(len(t), dtype=[("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("face", "<u2")])
    record["corners"], record["face"] = points[t], f
    stl.parent.mkdir(parents=True, exist_ok=True)
    with open(stl, "wb") as out:
        out.write(b"amber console reference surface (gmsh/OCC), mm, attribute = CAD face id".ljust(80, b" "))
        out.write(np.uint32(len(t)).tobytes())
        out.write(record.tobytes())
    print(f"{step} -> {stl}: {len(t)} triangles")


if __name__ == "__main__":
    root = pathlib.Path(sys.argv[1])
    for split in ("train", "val", "test"):
        for step in sorted((root / split).glob("*.step")):
            reference_surface(step, root / "reference_surface" / split / f"{step.stem}.stl")
