"""Static analysis: linear solve with restrained DOFs and the chassis torsion test.

Torsion test (thesis section 6.2.2, after [151]): two rear points symmetric about the
centre plane and one front point are simply supported; a vertical load ``F`` acts at the
front point opposite the front support. The supports restrain translations only, in a
statically determinate pattern (rear support 1: x, y, z; rear support 2: x, z; front
support: z), so the frame carries a pure torque ``T = F w`` (``w``: lateral distance of the
two front points) and the rear support line stays level. The front twist is
``θ = δ / w`` (small angles) with ``δ`` the vertical deflection of the loaded node, and the
torsional stiffness is ``k = T / θ = F w² / δ``.
"""

import equinox as eqx
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError
from ._assembly import assemble, frame_mass
from ._frame import Frame
from ._validate import check_relation


class TorsionResult(eqx.Module):
    """Result of :func:`torsion_test`.

    Attributes:
        stiffness: torsional stiffness (Nm/rad).
        stiffness_nm_per_deg: torsional stiffness (Nm/deg).
        deflection: vertical deflection of the loaded node (m, along the load).
        torque: applied torque F w (Nm).
        displacement: all nodal displacements (m, rad), shape (n_mesh, 6).
        mass: frame mass (kg).
    """

    stiffness: Float[Array, ""]
    stiffness_nm_per_deg: Float[Array, ""]
    deflection: Float[Array, ""]
    torque: Float[Array, ""]
    displacement: Float[Array, "n 6"]
    mass: Float[Array, ""]


def solve_static(
    K: Float[Array, "n n"], f: Float[Array, " n"], fixed: tuple[int, ...]
) -> Float[Array, " n"]:
    """Displacements solving ``K u = f`` with the DOF in ``fixed`` held at zero
    (Cholesky of the free-free partition; differentiable)."""
    free = np.setdiff1d(np.arange(K.shape[0]), np.asarray(fixed, dtype=np.int64))
    kff = K[np.ix_(free, free)]
    u_free = jsl.cho_solve(jsl.cho_factor(kff), f[free])
    return jnp.zeros_like(f).at[free].set(u_free)


def torsion_dofs(frame: Frame) -> tuple[tuple[int, ...], int]:
    """Restrained DOF of the torsion test and the loaded vertical DOF (static)."""
    t = frame.torsion_test
    if t is None:
        raise ParameterError("the frame file has no [torsion_test] section (loaded, front_support, rear_supports)")
    r0, r1 = (frame.node_index(n) for n in t.rear_supports)
    fs = frame.node_index(t.front_support)
    fixed = (6 * r0, 6 * r0 + 1, 6 * r0 + 2, 6 * r1, 6 * r1 + 2, 6 * fs + 2)
    return fixed, 6 * frame.node_index(t.loaded) + 2


@eqx.filter_jit
def torsion_test(frame: Frame) -> TorsionResult:
    """Run the torsion test described by ``frame.torsion_test`` (module docstring)."""
    fixed, loaded = torsion_dofs(frame)
    K, _ = assemble(frame)
    t = frame.torsion_test
    load = check_relation(
        t.load,
        lambda xp, load: ~(xp.isfinite(load) & (load != 0.0)),
        "TorsionTest.load must be a non-zero finite force (N)",
        load=t.load,
    )
    f = jnp.zeros(K.shape[0]).at[loaded].set(load)
    u = solve_static(K, f, fixed)
    xyz = frame.node_xyz
    w = jnp.abs(xyz[frame.node_index(t.loaded), 1] - xyz[frame.node_index(t.front_support), 1])
    delta = u[loaded] * jnp.sign(load)
    stiffness = jnp.abs(load) * w**2 / delta
    return TorsionResult(
        stiffness=stiffness,
        stiffness_nm_per_deg=stiffness * (jnp.pi / 180.0),
        deflection=delta,
        torque=jnp.abs(load) * w,
        displacement=u.reshape(-1, 6),
        mass=frame_mass(frame),
    )
