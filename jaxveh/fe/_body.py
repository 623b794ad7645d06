"""From a frame to a :class:`ModalBody`: nodal lumped masses, modes, invariants."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..params import ParameterError
from ._assembly import assemble, mesh_xyz
from ._beam import CircularTube, Material
from ._frame import Frame, frame_from_dict
from ._invariants import ModalBody, modal_body
from ._modal import free_free_modes


def nodal_mass_data(M: Float[Array, "n6 n6"]) -> tuple[Float[Array, "n"], Float[Array, "n 3 3"]]:
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


@eqx.filter_jit
def frame_modal_body(
    frame: Frame,
    n_modes: int,
    points: tuple[str, ...] | None = None,
    origin: Float[Array, "3"] | None = None,
    alpha: float = 0.0,
    beta: float = 0.01,
) -> ModalBody:
    """Free-free modal truncation of ``frame`` packaged for the multibody library.

    Args:
        frame: a lumped-mass frame (the thesis's assumption).
        n_modes: number of elastic modes kept.
        points: names of the nodes whose mode shapes are kept (default: the frame's
            interface nodes, e.g. the 32 hard points; all user nodes if it has none).
        origin: body-frame origin in frame coordinates (m); default the frame's origin.
        alpha, beta: proportional damping ``D = α M + β K``.

    Body frame: the frame's axes, origin at ``origin``.
    """
    if not frame.lumped_mass:
        raise ParameterError("frame_modal_body needs lumped_mass = true (nodal masses and inertias, section 5.4.2)")
    K, M = assemble(frame)
    freq, phi = free_free_modes(K, M, n_modes)
    xyz = mesh_xyz(frame)
    if origin is not None:
        xyz = xyz - jnp.asarray(origin)[None, :]
    mass, inertia = nodal_mass_data(M)
    pt, pr = split_modes(phi)
    names = points if points is not None else (frame.interface or frame.node_names)
    ke = phi.T @ K @ phi
    return modal_body(
        xyz, mass, inertia, pt, pr, 0.5 * (ke + ke.T), freq, tuple(names),
        tuple(frame.node_index(n) for n in names), alpha, beta,
    )


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
    for name, v in (("diameter", diameter), ("thickness", thickness), ("youngs_modulus", youngs_modulus),
                    ("shear_modulus", shear_modulus), ("density", density)):
        if isinstance(v, (int, float)) and not v > 0.0:
            raise ParameterError(f"{name} = {v!r} is out of range: allowed > 0")
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
        ((CircularTube(diameter, thickness),), (Material(youngs_modulus, shear_modulus, density),)),
    )


def straight_beam_body(
    length: float = 1.0,
    n_modes: int = 4,
    n_elements: int = 10,
    diameter: float = 0.03,
    thickness: float = 0.002,
    beta: float = 0.01,
) -> ModalBody:
    """A free-free straight steel tube as a :class:`ModalBody` (e.g. a flexible pendulum).

    Body frame: origin at the ``"start"`` end, x along the tube. Named points ``"start"``,
    ``"end"`` (and ``"mid"`` for even ``n_elements``). The circular section gives pairs of
    equal bending frequencies (y and z); the first elastic modes are bending pairs, then
    torsion and axial modes.
    """
    frame = straight_tube_frame(length, n_elements, diameter, thickness)
    points = tuple(n for n in ("start", "mid", "end") if n in frame.node_names)
    return frame_modal_body(frame, n_modes, points=points, beta=beta)
