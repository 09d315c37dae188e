"""Peer of `cargo xtask bench fem`: scikit-fem's P1 assembly and two solves of -Δu = f, u = 0 on
the boundary, on the mesh and Gaussian-mixture load of our assemble + solve case.

Input (from xtask): `vertices.npy` (n × 2), `triangles.npy` (m × 3, uint32), `input.json` with
`load` (means, covariances, weights) and `repeats`.

Timed, each the median of `repeats` runs:
- assembly: the mesh object, the P1 basis (order-2 quadrature, as ours), the stiffness matrix,
  the load vector with f evaluated at the quadrature points, and the boundary's vertices and the
  condensation onto the interior degrees of freedom (ours finds the boundary and assembles those
  directly); each phase's median is reported too;
- spsolve: scipy's sparse direct solve (SuperLU), the path `skfem.solve` takes;
- AMG-CG: pyamg's smoothed-aggregation setup, and CG preconditioned by it to a relative
  residual of 1e-8.
"""

import amber_peer  # first: the thread settings must precede numpy

import statistics
import time

import numpy as np
import pyamg
import scipy.sparse.linalg
from skfem import Basis, ElementTriP1, LinearForm, MeshTri, condense
from skfem.models.poisson import laplace

# Relative residual at which CG stops.
TOLERANCE = 1e-8
PHASES = ["mesh_and_basis", "stiffness", "load_vector", "boundary_and_condense"]

case = amber_peer.Case()
vertices = case.array("vertices")
triangles = case.array("triangles")
repeats = case.input["repeats"]
load = case.input["load"]

# Per component: w / (2π sqrt(det Σ)), the mean, and Σ⁻¹.
components = [
    (w / (2 * np.pi * np.sqrt(np.linalg.det(cov))), np.asarray(mu), np.linalg.inv(cov))
    for mu, cov, w in zip(load["means"], load["covariances"], load["weights"])
]


def f(x):
    """The mixture density at points x (2 × ...)."""
    value = 0.0
    for scale, mu, inv in components:
        dx, dy = x[0] - mu[0], x[1] - mu[1]
        value = value + scale * np.exp(-0.5 * (inv[0, 0] * dx * dx + 2 * inv[0, 1] * dx * dy + inv[1, 1] * dy * dy))
    return value


@LinearForm
def load_form(v, w):
    return f(w.x) * v


# skfem's layout (coordinates × points), contiguous as it wants it, before any clock runs.
points, cells = np.ascontiguousarray(vertices.T), np.ascontiguousarray(triangles.T)
# Each assembly's phases, seconds.
phases = []


def assemble():
    clock = [time.perf_counter()]
    mesh = MeshTri(points, cells)
    basis = Basis(mesh, ElementTriP1(), intorder=2)
    clock.append(time.perf_counter())
    stiffness = laplace.assemble(basis)
    clock.append(time.perf_counter())
    rhs = load_form.assemble(basis)
    clock.append(time.perf_counter())
    # The boundary's vertices need skfem's facets (ours finds them in the same pass).
    matrix, vector, _, _ = condense(stiffness, rhs, D=mesh.boundary_nodes())
    matrix = matrix.tocsr()
    clock.append(time.perf_counter())
    phases.append(dict(zip(PHASES, np.diff(clock))))
    return matrix, vector


def residual(matrix, x, b):
    return float(np.linalg.norm(matrix @ x - b) / np.linalg.norm(b))


assemble_s, assemble_all, assemble_cpu_s, (matrix, b) = amber_peer.timed(assemble, repeats)
spsolve_s, spsolve_all, _, x = amber_peer.timed(lambda: scipy.sparse.linalg.spsolve(matrix, b), repeats)
spsolve_residual = residual(matrix, x, b)
amg_setup_s, amg_setup_all, _, hierarchy = amber_peer.timed(
    lambda: pyamg.smoothed_aggregation_solver(matrix), repeats
)


def amg_cg():
    residuals = []
    x = hierarchy.solve(b, tol=TOLERANCE, accel="cg", maxiter=500, residuals=residuals)
    return x, len(residuals) - 1


amg_solve_s, amg_solve_all, _, (x, iterations) = amber_peer.timed(amg_cg, repeats)
case.finish(
    {
        "library": "scikit-fem (P1 assembly) + scipy spsolve + pyamg smoothed-aggregation CG",
        "triangles": int(triangles.shape[0]),
        "dofs": int(matrix.shape[0]),
        "nnz": int(matrix.nnz),
        "assemble_seconds": assemble_s,
        "assemble_seconds_all": assemble_all,
        "assemble_cpu_seconds": assemble_cpu_s,
        "assemble_phase_seconds": {name: float(statistics.median(p[name] for p in phases)) for name in PHASES},
        "spsolve_seconds": spsolve_s,
        "spsolve_seconds_all": spsolve_all,
        "spsolve_relative_residual": spsolve_residual,
        "amg_setup_seconds": amg_setup_s,
        "amg_setup_seconds_all": amg_setup_all,
        "amg_cg_seconds": amg_solve_s,
        "amg_cg_seconds_all": amg_solve_all,
        "amg_cg_iterations": iterations,
        "amg_cg_relative_residual": residual(matrix, x, b),
        "amg_cg_tolerance": TOLERANCE,
    },
    ["scikit-fem", "scipy", "numpy", "pyamg"],
)
