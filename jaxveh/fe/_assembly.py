"""Mesh generation and dense assembly of the global stiffness and mass matrices.

Members are split into ``member_divisions`` beam elements; the extra mesh nodes lie on
the straight line between the member's end nodes, so every mesh position is a
differentiable function of the user node coordinates. Topology (element connectivity,
DOF indices) is computed once per frame structure in NumPy and cached.

Global DOF ordering: mesh node ``k`` owns DOF ``6k .. 6k+5`` = (ux, uy, uz, rx, ry, rz)
(m, rad) in the frame's global axes. User nodes come first, in file order, so user node
``k`` is mesh node ``k``. Dense matrices: memory ``8 (6 n)^2`` bytes and an eigen-solve
``O((6 n)^3)``; practical up to a few thousand nodes (see docs/fe.md).
"""

import functools
from dataclasses import dataclass

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError
from ._beam import (
    CircularTube,
    RectangularTube,
    SectionProperties,
    direction_cosines,
    local_consistent_mass,
    local_stiffness,
    lumped_node_inertia,
    transformation,
)
from ._frame import Frame
from ._validate import check_nonnegative


@dataclass(frozen=True)
class Mesh:
    """Static mesh topology (NumPy, never traced).

    Attributes:
        node_a, node_b, node_s: mesh node ``k`` sits at ``(1-s) x[a] + s x[b]`` (user nodes).
        elements: (n_elements, 2) mesh node indices.
        element_member: member index of every element.
        dof_index: (n_elements, 12) global DOF of the element DOF.
    """

    node_a: np.ndarray
    node_b: np.ndarray
    node_s: np.ndarray
    elements: np.ndarray
    element_member: np.ndarray
    dof_index: np.ndarray

    @property
    def n_nodes(self) -> int:
        return len(self.node_a)

    @property
    def n_dof(self) -> int:
        return 6 * self.n_nodes


@functools.lru_cache(maxsize=64)
def _mesh(n_nodes: int, members: tuple, divisions: tuple) -> Mesh:
    a = list(range(n_nodes))
    b = list(range(n_nodes))
    s = [0.0] * n_nodes
    elements, owner = [], []
    for m, ((i, j), d) in enumerate(zip(members, divisions)):
        chain = [i]
        for k in range(1, d):
            a.append(i)
            b.append(j)
            s.append(k / d)
            chain.append(len(a) - 1)
        chain.append(j)
        for p, q in zip(chain[:-1], chain[1:]):
            elements.append((p, q))
            owner.append(m)
    elements = np.asarray(elements, dtype=np.int64)
    dof = (6 * elements[:, :, None] + np.arange(6)[None, None, :]).reshape(-1, 12)
    return Mesh(np.asarray(a), np.asarray(b), np.asarray(s), elements, np.asarray(owner), dof)


def frame_mesh(frame: Frame) -> Mesh:
    """The (cached) static mesh of a frame."""
    return _mesh(frame.n_nodes, frame.member_nodes, frame.member_divisions)


def mesh_xyz(frame: Frame) -> Float[Array, "n_mesh 3"]:
    """Positions (m) of all mesh nodes, user nodes first."""
    mesh = frame_mesh(frame)
    s = jnp.asarray(mesh.node_s)[:, None]
    return (1.0 - s) * frame.node_xyz[mesh.node_a] + s * frame.node_xyz[mesh.node_b]


def _element_data(frame: Frame):
    """Per-element length (m), rotation, section properties and material (stacked)."""
    mesh = frame_mesh(frame)
    xyz = mesh_xyz(frame)
    x1 = xyz[mesh.elements[:, 0]]
    x2 = xyz[mesh.elements[:, 1]]
    orient = frame.member_orientation[mesh.element_member]
    length, rot = jax.vmap(direction_cosines)(x1, x2, orient)
    props = [s.properties() for s in frame.sections]  # checks the section sizes
    sec_idx = np.asarray(frame.member_section)[mesh.element_member]
    sec = jax.tree.map(lambda *v: jnp.stack(v)[sec_idx], *props)
    mat_idx = np.asarray(frame.member_material)[mesh.element_member]
    mat = jax.tree.map(lambda *v: jnp.stack(v)[mat_idx], *(m.validated() for m in frame.materials))
    return length, rot, sec, mat


def _point_masses(frame: Frame) -> Float[Array, " k"]:
    """The frame's point masses (kg), checked >= 0."""
    return check_nonnegative("Frame.point_masses", frame.point_masses, "kg")


@eqx.filter_jit
def element_matrices(frame: Frame) -> tuple[Float[Array, "e 12 12"], Float[Array, "e 12 12"]]:
    """Global-axes element stiffness and mass matrices of every element."""
    length, rot, sec, mat = _element_data(frame)

    def one(L, R, s: SectionProperties, m):
        T = transformation(R)
        ke = T.T @ local_stiffness(L, s, m, frame.timoshenko) @ T
        if frame.lumped_mass:
            mn, inertia = lumped_node_inertia(L, s, m)
            jn = R.T @ (inertia[:, None] * R)
            blk = jax.scipy.linalg.block_diag(mn * jnp.eye(3), jn)
            me = jax.scipy.linalg.block_diag(blk, blk)
        else:
            me = T.T @ local_consistent_mass(L, s, m) @ T
        return ke, me

    return jax.vmap(one)(length, rot, sec, mat)


def _scatter(blocks: Float[Array, "e 12 12"], mesh: Mesh) -> Float[Array, "n n"]:
    rows = np.broadcast_to(mesh.dof_index[:, :, None], blocks.shape)
    cols = np.broadcast_to(mesh.dof_index[:, None, :], blocks.shape)
    out = jnp.zeros((mesh.n_dof, mesh.n_dof), dtype=blocks.dtype)
    return out.at[rows, cols].add(blocks)


def point_mass_matrix(frame: Frame) -> Float[Array, "n n"]:
    """Global mass matrix of the non-structural point masses (translational DOF only)."""
    mesh = frame_mesh(frame)
    diag = jnp.zeros(mesh.n_dof)
    idx = np.asarray([6 * k + c for k in frame.mass_nodes for c in range(3)], dtype=np.int64)
    vals = jnp.repeat(_point_masses(frame), 3)
    return jnp.diag(diag.at[idx].add(vals))


@eqx.filter_jit
def assemble(frame: Frame) -> tuple[Float[Array, "n n"], Float[Array, "n n"]]:
    """Global stiffness ``K`` (N/m, Nm/rad) and mass ``M`` (kg, kg m^2), dense, symmetric."""
    ke, me = element_matrices(frame)
    mesh = frame_mesh(frame)
    K = _scatter(ke, mesh)
    M = _scatter(me, mesh) + point_mass_matrix(frame)
    return 0.5 * (K + K.T), 0.5 * (M + M.T)


@eqx.filter_jit
def frame_mass(frame: Frame) -> Float[Array, ""]:
    """Total mass (kg): tubes (rho A L summed over members) plus point masses."""
    length, _, sec, mat = _element_data(frame)
    return jnp.sum(mat.density * sec.area * length) + jnp.sum(_point_masses(frame))


def with_sections(frame: Frame, sections) -> Frame:
    """Return ``frame`` with its tuple of sections replaced (for design studies).

    ``sections`` must give one :class:`CircularTube` or :class:`RectangularTube` per
    section of the frame (in ``frame.section_names`` order). Their sizes are checked
    (``ParameterError`` for concrete values, a run-time error for traced ones): diameters
    and widths > 0, 0 < wall <= diameter/2 (circular) or < min(width, height)/2.
    """
    sections = tuple(sections)
    if len(sections) != len(frame.sections):
        raise ParameterError(
            f"with_sections: the frame has {len(frame.sections)} sections {list(frame.section_names)}, "
            f"got {len(sections)}"
        )
    for name, s in zip(frame.section_names, sections):
        if not isinstance(s, (CircularTube, RectangularTube)):
            raise ParameterError(
                f"with_sections: section {name!r} must be a CircularTube or RectangularTube, got {type(s).__name__}"
            )
    return eqx.tree_at(lambda f: f.sections, frame, tuple(s.validated() for s in sections))


@eqx.filter_jit
def element_strain_energy(frame: Frame, u: Float[Array, " n"]) -> Float[Array, " e"]:
    """Strain energy ``½ u_eᵀ k_e u_e`` (J) of every element for global displacement ``u``."""
    ke, _ = element_matrices(frame)
    ue = u[frame_mesh(frame).dof_index]
    return 0.5 * jnp.einsum("ei,eij,ej->e", ue, ke, ue)


def element_centres(frame: Frame) -> Float[Array, "e 3"]:
    """Mid-points of all elements (m)."""
    xyz = mesh_xyz(frame)
    el = frame_mesh(frame).elements
    return 0.5 * (xyz[el[:, 0]] + xyz[el[:, 1]])
