"""Import of mass and stiffness matrices exported by an external FE code.

A user with an Ansys or Nastran chassis model exports ``K``, ``M``, a node table and a DOF
map; jaxveh reorders them to its own DOF convention and runs the same modal reduction and
invariant computation as for its own frames. Accepted inputs:

* **NPZ** with arrays ``K``, ``M`` (n×n), ``node_ids`` (int), ``node_xyz`` (m, ×3),
  ``dof_map`` (n×2 rows ``[node_id, component]``, components 1-6 = ux, uy, uz, rx, ry, rz)
  and optionally ``node_names`` (strings). ``jaxveh chassis export`` writes this layout.
* **Matrix Market** ``K.mtx`` and ``M.mtx`` (e.g. from Ansys ``HBMAT``/Nastran ``DMIGPCH``
  converted with SciPy) plus two CSV files: nodes ``id,x,y,z`` (m) and DOF map
  ``node_id,component`` in matrix row order.

Every node must carry all six DOF (beam/shell models); the mass matrix is expected to be
lumped (6×6 nodal blocks) for the invariants of section 5.4.2, which use the nodal blocks.
"""

from pathlib import Path

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, float_field
from ._body import nodal_mass_data, split_modes
from ._invariants import ModalBody, modal_body
from ._modal import free_free_modes

#: Relative asymmetry tolerated in imported matrices (text exports round to ~1e-10).
SYMMETRY_RTOL = 1e-8


class ExternalModel(eqx.Module):
    """An imported FE model in jaxveh's DOF order (node ``k``: DOF ``6k..6k+5``).

    Attributes:
        K: stiffness (N/m, Nm/rad); M: mass (kg, kg m²), dense (6n, 6n).
        node_ids: external node numbers (static); node_names: names (static).
        node_xyz: node positions (m), (n, 3).
    """

    K: Float[Array, "n6 n6"] = float_field()
    M: Float[Array, "n6 n6"] = float_field()
    node_ids: tuple[int, ...] = eqx.field(static=True)
    node_names: tuple[str, ...] = eqx.field(static=True)
    node_xyz: Float[Array, "n 3"] = float_field()

    def node_index(self, name: str) -> int:
        if name in self.node_names:
            return self.node_names.index(name)
        raise ParameterError(f"imported model has no node named {name!r}")


def external_model_from_arrays(
    K, M, node_ids, node_xyz, dof_map, node_names=None, where: str = "<arrays>"
) -> ExternalModel:
    """Validate and reorder raw arrays (see module docstring) into an :class:`ExternalModel`."""
    K, M = np.asarray(K, dtype=float), np.asarray(M, dtype=float)
    node_ids = [int(i) for i in np.asarray(node_ids).reshape(-1)]
    node_xyz = np.asarray(node_xyz, dtype=float)
    dof_map = np.asarray(dof_map, dtype=np.int64)
    n = len(node_ids)
    if K.ndim != 2 or K.shape[0] != K.shape[1]:
        raise ParameterError(f"{where}: K must be a square matrix, got shape {K.shape}")
    if M.shape != K.shape:
        raise ParameterError(f"{where}: M has shape {M.shape} but K has {K.shape}")
    if node_xyz.shape != (n, 3):
        raise ParameterError(f"{where}: node_xyz must have shape ({n}, 3), got {node_xyz.shape}")
    if len(set(node_ids)) != n:
        raise ParameterError(f"{where}: node_ids contains duplicates")
    if dof_map.shape != (K.shape[0], 2):
        raise ParameterError(
            f"{where}: dof_map must have shape ({K.shape[0]}, 2) (node_id, component), got {dof_map.shape}"
        )
    if K.shape[0] != 6 * n:
        raise ParameterError(f"{where}: {K.shape[0]} DOF for {n} nodes; every node must carry six DOF (ux..rz)")
    for name, A in (("K", K), ("M", M)):
        if not np.all(np.isfinite(A)):
            raise ParameterError(f"{where}: {name} contains non-finite entries")
        if np.max(np.abs(A - A.T)) > SYMMETRY_RTOL * np.max(np.abs(A)):
            raise ParameterError(f"{where}: {name} is not symmetric")
    pos = {nid: k for k, nid in enumerate(node_ids)}
    perm = np.full(6 * n, -1)
    for row, (nid, comp) in enumerate(dof_map):
        if nid not in pos:
            raise ParameterError(f"{where}: dof_map row {row} refers to unknown node {nid}")
        if not 1 <= comp <= 6:
            raise ParameterError(f"{where}: dof_map row {row}: component {comp} is out of range: allowed 1..6")
        target = 6 * pos[nid] + comp - 1
        if perm[target] >= 0:
            raise ParameterError(f"{where}: dof_map lists node {nid} component {comp} twice")
        perm[target] = row
    if np.diag(M).min() < 0.0:
        raise ParameterError(f"{where}: M has negative diagonal entries")
    names = tuple(str(s) for s in node_names) if node_names is not None else tuple(str(i) for i in node_ids)
    return ExternalModel(
        K=K[np.ix_(perm, perm)], M=M[np.ix_(perm, perm)], node_ids=tuple(node_ids), node_names=names, node_xyz=node_xyz
    )


def load_external_model(
    path: str | Path, mass: str | Path | None = None, nodes: str | Path | None = None, dofs: str | Path | None = None
) -> ExternalModel:
    """Load an NPZ export, or Matrix Market ``K`` (``path``) + ``mass`` + CSV ``nodes`` and ``dofs``."""
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"model file {str(path)!r} does not exist")
    if path.suffix == ".npz":
        with np.load(path, allow_pickle=False) as d:
            missing = [k for k in ("K", "M", "node_ids", "node_xyz", "dof_map") if k not in d]
            if missing:
                raise ParameterError(f"{path}: missing array(s) {missing}")
            names = d["node_names"] if "node_names" in d else None
            return external_model_from_arrays(
                d["K"], d["M"], d["node_ids"], d["node_xyz"], d["dof_map"], names, str(path)
            )
    if mass is None or nodes is None or dofs is None:
        raise ParameterError("a Matrix Market stiffness file needs mass=, nodes= and dofs= files too")
    from scipy.io import mmread

    def dense(p):
        a = mmread(str(p))
        return a.toarray() if hasattr(a, "toarray") else np.asarray(a)

    K, M = dense(path), dense(mass)
    # Matrix Market "symmetric" files store one triangle; mmread restores both.
    table = np.loadtxt(nodes, delimiter=",", ndmin=2)
    dof_map = np.loadtxt(dofs, delimiter=",", ndmin=2, dtype=np.int64)
    return external_model_from_arrays(K, M, table[:, 0].astype(int), table[:, 1:4], dof_map, None, str(path))


def external_modal_body(
    model: ExternalModel,
    n_modes: int,
    points: tuple[str, ...],
    alpha=None,
    beta=None,
    damping_ratio=None,
) -> ModalBody:
    """Free-free modal truncation of an imported model as a :class:`ModalBody` (body
    frame = the model's axes and origin). Damping as
    :func:`~jaxveh.fe.frame_modal_body` (default ζ = 0.025 on every mode)."""
    _, phi = free_free_modes(model.K, model.M, n_modes)
    mass, inertia = nodal_mass_data(model.M)
    pt, pr = split_modes(phi)
    ke = phi.T @ model.K @ phi
    return modal_body(
        model.node_xyz, mass, inertia, pt, pr, 0.5 * (ke + ke.T), tuple(points),
        tuple(model.node_index(p) for p in points), damping_ratio=damping_ratio, alpha=alpha, beta=beta,
    )
