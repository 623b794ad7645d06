"""Body dynamics in moving frames (eqs. 5.30-5.36 rigid, 5.37-5.45 flexible) and energy.

Each body contributes ``M_i(p) v_i_dot = Q_i`` in its own axes with ``v_i = [u, omega,
p_dot]``. The quadratic velocity (gyroscopic, centrifugal, Coriolis) forces come from the
Boltzmann-Hamel (Kirchhoff) equations of the kinetic energy ``T = v^T M(p) v / 2``::

    d/dt(dT/du) + omega x dT/du                    = F
    d/dt(dT/domega) + omega x dT/domega + u x dT/du = tau
    d/dt(dT/dp_dot) - dT/dp                         = Q_p

which for a rigid body are exactly eq. (5.35) and for a modal body reproduce every term of
eq. (5.45) (``Gr``, ``Ge``, ``Oe`` included) for the mass matrix of eq. (5.37), so energy is
conserved to integration accuracy. ``jax.jvp`` / ``jax.grad`` of ``M(p)`` replace the
symbolic invariants ``Gr``, ``Ge``, ``Oe``.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ._bodies import FlexOptions
from ._kinematics import _split, body_poses, body_velocities, point_local
from ._system import System, SystemParams


def body_quadratic_forces(body, options: FlexOptions, p, v) -> Float[Array, " nv_i"]:
    """Quadratic velocity forces of one body (body axes), Hamel/Kirchhoff form."""
    u, w, p_dot = v[:3], v[3:6], v[6:]
    mass_matrix = lambda pp: body.mass_matrix(pp, options)  # noqa: E731
    m = mass_matrix(p)
    mom = m @ v
    if body.n_modes > 0 and not options.constant_mass:
        dmom = jax.jvp(lambda pp: mass_matrix(pp) @ v, (p,), (p_dot,))[1]
        dt_dp = jax.grad(lambda pp: 0.5 * v @ (mass_matrix(pp) @ v))(p)
    else:
        dmom = jnp.zeros_like(mom)
        dt_dp = jnp.zeros_like(p)
    l_u, l_w = mom[:3], mom[3:6]
    return -jnp.concatenate(
        [dmom[:3] + jnp.cross(w, l_u), dmom[3:6] + jnp.cross(w, l_w) + jnp.cross(u, l_u), dmom[6:] - dt_dp]
    )


def _gyroscopic_cross(body, options, p, v):
    """Terms of the quadratic forces bilinear in ``omega`` and ``p_dot`` in the rotational
    and elastic rows: the ``Gr`` / ``Ge`` terms of eq. (5.45), by polarisation."""
    zeros3 = jnp.zeros((3,), v.dtype)
    w, p_dot = v[3:6], v[6:]
    f = lambda vv: body_quadratic_forces(body, options, p, vv)  # noqa: E731
    both = f(jnp.concatenate([zeros3, w, p_dot]))
    only_w = f(jnp.concatenate([zeros3, w, jnp.zeros_like(p_dot)]))
    only_p = f(jnp.concatenate([zeros3, zeros3, p_dot]))
    cross = both - only_w - only_p
    return jnp.concatenate([jnp.zeros((3,), v.dtype), cross[3:]])


def body_forces(system: System, params: SystemParams, i: int, pose, v):
    """Internal (velocity, elastic) and gravity forces of body ``i`` in its axes."""
    body, options = params.bodies[i], system.options
    r, a, p = pose
    quad = body_quadratic_forces(body, options, p, v)
    if body.n_modes > 0 and options.neglect_gyroscopic:
        quad = quad - _gyroscopic_cross(body, options, p, v)
    elastic = jnp.concatenate([jnp.zeros((6,), v.dtype), body.elastic(p, v[6:])])
    gravity = body.gravity(a.T @ params.gravity, p, options)
    return quad + elastic, gravity


def mass_matrix(system: System, params: SystemParams, q) -> Float[Array, "nv nv"]:
    """``pM``: block-diagonal mass matrix in body-frame velocities ``v`` (eqs. 5.25, 5.37)."""
    poses = body_poses(system, params, q)
    blocks = [params.bodies[i].mass_matrix(poses[i][2], system.options) for i in range(system.n_bodies)]
    return jax.scipy.linalg.block_diag(*blocks)


def _mass_blocks(system, params, poses):
    return [params.bodies[i].mass_matrix(poses[i][2], system.options) for i in range(system.n_bodies)]


def internal_forces(system: System, params: SystemParams, q, v) -> tuple[Float[Array, " nv"], Float[Array, " nv"]]:
    """``pQi`` split in two: ``(velocity + elastic + damping forces, gravity forces)`` in
    body-frame velocity coordinates ``v`` (eqs. 5.35, 5.43-5.45)."""
    poses = body_poses(system, params, q)
    vs = _split(system, v, system.v_offsets)
    parts = [body_forces(system, params, i, poses[i], vs[i]) for i in range(system.n_bodies)]
    return jnp.concatenate([p[0] for p in parts]), jnp.concatenate([p[1] for p in parts])


def point_force(system: System, params: SystemParams, q, point: str, force, frame: str = "global", u=None):
    """Generalised force (``v`` coordinates) of a force (N) applied at ``point``.

    ``frame`` is ``"global"`` or ``"body"`` (axes of the point's body). The force enters each
    row as ``G^T F`` with ``G`` the map from the body velocity to the point velocity.
    """
    k = system.point_index(point)
    body = system.point_body[k]
    out = jnp.zeros((system.n_v,), q.dtype)
    if body < 0:
        return out
    poses = body_poses(system, params, q)
    u = jnp.zeros((0,), q.dtype) if u is None else u
    x = point_local(system, params, poses, k, u)
    f_body = force if frame == "body" else poses[body][1].T @ force
    parts = [f_body, jnp.cross(x, f_body)]
    if system.n_modes[body] > 0:
        parts.append(params.bodies[body].coupling * (params.points[k].shapes.T @ f_body))
    gen = jnp.concatenate(parts)
    start = system.v_offsets[body]
    return out.at[start : start + gen.shape[0]].add(gen)


def body_torque(system: System, params: SystemParams, q, body: str, torque, frame: str = "global"):
    """Generalised force of a pure torque (N m) on ``body`` (global or body axes)."""
    i = system.body_names.index(body)
    a = body_poses(system, params, q)[i][1]
    t_body = torque if frame == "body" else a.T @ torque
    start = system.v_offsets[i]
    return jnp.zeros((system.n_v,), q.dtype).at[start + 3 : start + 6].add(t_body)


def energy(system: System, params: SystemParams, q, y) -> dict[str, Float[Array, ""]]:
    """Kinetic, gravitational and elastic energy (J) at coordinates ``q``, joint velocities ``y``."""
    poses = body_poses(system, params, q)
    vs = body_velocities(system, params, q, y, poses)
    blocks = _mass_blocks(system, params, poses)
    kinetic = sum(0.5 * vs[i] @ (blocks[i] @ vs[i]) for i in range(system.n_bodies))
    grav = sum(
        params.bodies[i].potential_gravity(poses[i][0], poses[i][1], poses[i][2], params.gravity)
        for i in range(system.n_bodies)
    )
    elastic = sum(params.bodies[i].potential_elastic(poses[i][2]) for i in range(system.n_bodies))
    return {"kinetic": kinetic, "gravity": grav, "elastic": elastic, "total": kinetic + grav + elastic}
