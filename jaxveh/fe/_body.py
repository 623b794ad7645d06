"""From a frame to a :class:`ModalBody`: nodal lumped masses, modes, invariants."""

import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, as_float
from ._assembly import assemble, frame_mesh, mesh_xyz
from ._beam import CircularTube, Material
from ._frame import Frame, frame_from_dict
from ._invariants import ModalBody, damping_parameters, modal_body
from ._modal import N_RIGID, check_mode_count, free_free_modes


def nodal_mass_data(M: Float[Array, "n6 n6"]) -> tuple[Float[Array, " n"], Float[Array, "n 3 3"]]:
    """Nodal masses (kg) and inertia tensors (kg m²) from a lumped (6×6 block-diagonal)
    mass matrix: ``m_k = M[6k, 6k]``, ``J_k = M[6k+3:6k+6, 6k+3:6k+6]``."""
    n = M.shape[0] // 6
    blocks = M.reshape(n, 6, n, 6)[np.arange(n), :, np.arange(n), :]  # (n, 6, 6)
    return blocks[:, 0, 0], blocks[:, 3:, 3:]


def split_modes(phi: Float[Array, "n6 N"]) -> tuple[Float[Array, "n 3 N"], Float[Array, "n 3 N"]]:
    """Nodal translations (m) and rotations (rad) of mode shapes in global DOF order."""
    n = phi.shape[0] // 6
    r = phi.reshape(n, 6, phi.shape[1])
    return r[:, :3, :], r[:, 3:, :]


def frame_modal_body(
    frame: Frame,
    n_modes: int,
    points: tuple[str, ...] | None = None,
    origin: Float[Array, "3"] | None = None,
    alpha=None,
    beta=None,
    damping_ratio=None,
) -> ModalBody:
    """Free-free modal truncation of ``frame`` packaged for the multibody library.

    Args:
        frame: a lumped-mass frame (the thesis's assumption).
        n_modes: number of elastic modes kept, 1 <= n_modes <= 6 n - 6 for n mesh nodes.
        points: names of the nodes whose mode shapes are kept (default: the frame's
            interface nodes, e.g. the 32 hard points; all user nodes if it has none).
        origin: body-frame origin in frame coordinates (m); default the frame's origin.
        alpha, beta, damping_ratio: damping, as :func:`~jaxveh.fe.damping_parameters`:
            by default modal damping ζ = 0.025 on every mode (thesis section 7.3); giving
            ``alpha`` (1/s) and/or ``beta`` (s) alone selects Rayleigh damping
            ``α Me + β K``; ``damping_ratio`` with them adds both.

    Body frame: the frame's axes, origin at ``origin``. Damping values and the origin are
    passed to the jitted computation as arrays: new values never recompile.
    """
    if not frame.lumped_mass:
        raise ParameterError("frame_modal_body needs lumped_mass = true (nodal masses and inertias, section 5.4.2)")
    names = tuple(points) if points is not None else (frame.interface or frame.node_names)
    index = tuple(frame.node_index(n) for n in names)
    check_mode_count(n_modes, frame_mesh(frame).n_dof - N_RIGID)
    zeta, alpha, beta = damping_parameters(n_modes, damping_ratio, alpha, beta)
    origin = jnp.zeros(3) if origin is None else as_float(origin)
    if origin.shape != (3,):
        raise ParameterError(f"origin must be 3 coordinates (m), got shape {origin.shape}")
    return _frame_modal_body(frame, n_modes, names, index, origin, zeta, alpha, beta)


@eqx.filter_jit
def _frame_modal_body(frame, n_modes, names, index, origin, zeta, alpha, beta) -> ModalBody:
    K, M = assemble(frame)
    _, phi = free_free_modes(K, M, n_modes)
    return _body_of_modes(frame, K, M, phi, origin, names, index, damping_ratio=zeta, alpha=alpha, beta=beta)


def _body_of_modes(frame, K, M, phi, origin, names, index, **damping) -> ModalBody:
    """The :class:`ModalBody` of ``frame``'s mode shapes ``phi`` (columns, global DOF)."""
    xyz = mesh_xyz(frame) - origin[None, :]
    mass, inertia = nodal_mass_data(M)
    pt, pr = split_modes(phi)
    ke = phi.T @ K @ phi
    return modal_body(xyz, mass, inertia, pt, pr, 0.5 * (ke + ke.T), names, index, **damping)


def frame_modal_body_like(frame: Frame, like: ModalBody) -> ModalBody:
    """The modal body of ``frame`` (new tube sizes, say) built as ``like`` was: the same
    points, mode count, damping and stiffness multipliers µ, and body origin, with each
    modal coordinate kept on the same physical mode as the frame changes. The lowest
    ``like.n_modes`` elastic modes of ``frame`` are put in the order of ``like``'s modes
    they resemble most (greedily, ``like``'s first mode first, by the MAC of their
    translations at the points), so that two modes that cross in frequency keep their
    coordinates (and their multipliers µ), and each mode's sign is chosen so that its
    translations at the points agree with its ``like`` mode's (positive sum of products).

    ``frame`` must have ``like``'s points as named nodes (the same frame topology). Pure
    and differentiable in ``frame``'s sizes: a design study's chassis (``optimise``)."""
    if not frame.lumped_mass:
        raise ParameterError("frame_modal_body_like needs lumped_mass = true (nodal masses and inertias, "
                             "section 5.4.2)")
    index = tuple(frame.node_index(n) for n in like.point_names)
    check_mode_count(like.n_modes, frame_mesh(frame).n_dof - N_RIGID)
    return _frame_modal_body_like(frame, like, index)


@eqx.filter_jit
def _frame_modal_body_like(frame, like, index) -> ModalBody:
    K, M = assemble(frame)
    _, phi = free_free_modes(K, M, like.n_modes)
    pt, _ = split_modes(phi)
    new, old = pt[np.asarray(index)].reshape(-1, like.n_modes), like.point_phi_translation.reshape(-1, like.n_modes)
    products = old.T @ new  # (like's mode, frame's mode)
    mac = products**2 / (jnp.sum(old**2, axis=0)[:, None] * jnp.sum(new**2, axis=0)[None, :])
    order = _greedy_assignment(mac)
    phi = phi[:, order] * jnp.where(products[jnp.arange(like.n_modes), order] < 0.0, -1.0, 1.0)[None, :]
    origin = mesh_xyz(frame)[index[0]] - like.point_xyz[0]
    body = _body_of_modes(frame, K, M, phi, origin, like.point_names, index)
    return eqx.tree_at(lambda b: (b.alpha, b.beta, b.damping_ratio, b.stiffness_scale), body,
                       (like.alpha, like.beta, like.damping_ratio, like.stiffness_scale))


def _greedy_assignment(score):
    """For each row in turn, the column of highest ``score`` not taken by an earlier row."""
    n = score.shape[0]
    order = []
    taken = jnp.zeros(score.shape[1], bool)
    for row in range(n):
        k = jnp.argmax(jnp.where(taken, -jnp.inf, score[row]))
        order.append(k)
        taken = taken.at[k].set(True)
    return jnp.stack(order)


def straight_tube_frame(
    length: float = 1.0,
    n_elements: int = 10,
    diameter: float = 0.03,
    thickness: float = 0.002,
    youngs_modulus: float = 210e9,
    shear_modulus: float = 80.8e9,
    density: float = 7850.0,
) -> Frame:
    """A straight circular steel tube along global x from ``(0, 0, 0)`` (SI inputs).

    User nodes ``"start"``, ``"mid"`` (if ``n_elements`` is even) and ``"end"`` plus
    ``"n<k>"`` for the intermediate element nodes; one element per member.
    """
    if n_elements < 1:
        raise ParameterError(f"n_elements = {n_elements} is out of range: allowed >= 1")
    names = []
    for k in range(n_elements + 1):
        if k == 0:
            names.append("start")
        elif k == n_elements:
            names.append("end")
        elif 2 * k == n_elements:
            names.append("mid")
        else:
            names.append(f"n{k}")
    length = float(length)  # node positions are built in Python (static topology)
    if not 0.0 < length < math.inf:
        raise ParameterError(f"length = {length!r} m is out of range: allowed (0, inf)")
    # checked before the frame is built (ParameterError naming the field; run-time
    # checks for traced values)
    section = CircularTube(diameter, thickness)
    material = Material(youngs_modulus, shear_modulus, density)
    table = {
        "frame": {"interface": ["start", "end"]},
        "materials": {"steel": {"E": 210.0, "G": 80.0, "density": 7850.0}},
        "sections": {"tube": {"shape": "circular", "diameter": 30.0, "thickness": 2.0}},
        "nodes": {n: [1e3 * length * k / n_elements, 0.0, 0.0] for k, n in enumerate(names)},
        "members": [{"nodes": [a, b], "section": "tube"} for a, b in zip(names[:-1], names[1:])],
    }
    frame = frame_from_dict(table, "<straight tube>")
    # sizes and material enter as leaves (they may be traced values)
    return eqx.tree_at(
        lambda f: (f.sections, f.materials),
        frame,
        ((section,), (material,)),
    )


def straight_beam_body(
    length: float = 1.0,
    n_modes: int = 4,
    n_elements: int = 10,
    diameter: float = 0.03,
    thickness: float = 0.002,
    beta=None,
    *,
    alpha=None,
    damping_ratio=None,
) -> ModalBody:
    """A free-free straight steel tube as a :class:`ModalBody` (e.g. a flexible pendulum).

    Body frame: origin at the ``"start"`` end, x along the tube. Named points ``"start"``,
    ``"end"`` (and ``"mid"`` for even ``n_elements``). The circular section gives pairs of
    equal bending frequencies (y and z); the first elastic modes are bending pairs, then
    torsion and axial modes. Damping as :func:`frame_modal_body` (default ζ = 0.025 per
    mode; ``beta`` alone, e.g. ``beta=0.0``, selects Rayleigh damping).
    """
    frame = straight_tube_frame(length, n_elements, diameter, thickness)
    points = tuple(n for n in ("start", "mid", "end") if n in frame.node_names)
    return frame_modal_body(frame, n_modes, points=points, alpha=alpha, beta=beta, damping_ratio=damping_ratio)
