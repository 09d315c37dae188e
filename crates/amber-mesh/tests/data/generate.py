#!/usr/bin/env python3
"""Writes the small fixtures beside this file (run once; the files are committed): a unit square
of 4 triangles around a centre vertex, with boundary lines and a cell array `size` = 1, 2, 3, 4,
in every encoding gmsh 4.15, meshio 5.3 and VTK (hand-assembled here as VTK 9 writes it: appended
raw, zlib, UInt64 headers) produce. meshio 5.3.5, gmsh 4.15.2."""

import struct
import zlib

import gmsh
import meshio
import numpy as np

POINTS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], dtype=float)
TRIANGLES = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
LINES = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
SIZE = np.array([1.0, 2.0, 3.0, 4.0])

# meshio: the triangles and the boundary lines, `size` on both blocks (NaN on the lines).
mesh = meshio.Mesh(POINTS, [("line", LINES), ("triangle", TRIANGLES)],
                   cell_data={"size": [np.full(4, np.nan), SIZE]})
meshio.vtu.write("meshio-ascii.vtu", mesh, binary=False)
meshio.vtu.write("meshio-binary.vtu", mesh, binary=True, compression=None)
meshio.vtu.write("meshio-zlib-uint64.vtu", mesh, binary=True, compression="zlib", header_type="UInt64")
meshio.vtk.write("meshio-ascii.vtk", mesh, binary=False)
meshio.vtk.write("meshio-binary.vtk", mesh, binary=True)
# meshio's 4.1 writer needs entity tags for more than one cell type: the triangles alone there.
triangles = meshio.Mesh(POINTS, [("triangle", TRIANGLES)], cell_data={"size": [SIZE]})
meshio.write("meshio-binary.msh", triangles, file_format="gmsh", binary=True)
meshio.write("meshio-22-binary.msh", mesh, file_format="gmsh22", binary=True)
plain = meshio.Mesh(POINTS, [("line", LINES), ("triangle", TRIANGLES)])
meshio.write("meshio.nas", plain, file_format="nastran")
meshio.write("meshio.inp", plain, file_format="abaqus")
meshio.write("meshio.mesh", plain, file_format="medit")

# gmsh: the same square, boundary in physical group 2, in both versions and encodings.
gmsh.initialize(readConfigFiles=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("square")
p = [gmsh.model.geo.addPoint(*xyz, 0.8) for xyz in POINTS[:4]]
lines = [gmsh.model.geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
surface = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
gmsh.model.geo.synchronize()
gmsh.model.addPhysicalGroup(2, [surface], 1, "domain")
gmsh.model.addPhysicalGroup(1, lines, 2, "boundary")
gmsh.option.setNumber("Mesh.MeshSizeMax", 10)
gmsh.model.mesh.generate(2)
for version in [2.2, 4.1]:
    for binary in [0, 1]:
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(f"gmsh-{version}-{'binary' if binary else 'ascii'}.msh")
gmsh.option.setNumber("Mesh.Binary", 0)
gmsh.write("gmsh-ascii.vtk")
gmsh.finalize()


def appended(arrays):
    """VTK 9's default: appended raw data, one zlib block per array, UInt64 headers."""
    xml, blob = [], b""
    for section, name, vtk_type, components, data in arrays:
        raw = data.tobytes()
        packed = zlib.compress(raw)
        xml.append((section, f'<DataArray type="{vtk_type}" Name="{name}" NumberOfComponents="{components}" '
                             f'format="appended" offset="{len(blob)}"/>'))
        blob += struct.pack("<4Q", 1, len(raw), len(raw), len(packed)) + packed
    part = lambda s: "".join(x for sec, x in xml if sec == s)
    return (f'<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            f'header_type="UInt64" compressor="vtkZLibDataCompressor">\n<UnstructuredGrid>\n'
            f'<Piece NumberOfPoints="5" NumberOfCells="8">\n<CellData Scalars="size">{part("cell")}</CellData>\n'
            f'<Points>{part("points")}</Points>\n<Cells>{part("cells")}</Cells>\n</Piece>\n</UnstructuredGrid>\n'
            f'<AppendedData encoding="raw">\n_').encode() + blob + b"\n</AppendedData>\n</VTKFile>\n"


cells = np.concatenate([LINES.ravel(), TRIANGLES.ravel()]).astype(np.int64)
offsets = np.concatenate([2 * np.arange(1, 5), 8 + 3 * np.arange(1, 5)]).astype(np.int64)
types = np.array([3] * 4 + [5] * 4, dtype=np.uint8)
with open("vtk-appended-zlib.vtu", "wb") as f:
    f.write(appended([("cell", "size", "Float64", 1, np.concatenate([np.full(4, np.nan), SIZE])),
                      ("points", "Points", "Float64", 3, POINTS),
                      ("cells", "connectivity", "Int64", 1, cells),
                      ("cells", "offsets", "Int64", 1, offsets),
                      ("cells", "types", "UInt8", 1, types)]))
