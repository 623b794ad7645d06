"""Kinematics: body poses, points (eqs. 5.6, 5.12-5.13), the velocity recursion ``v = T y``
(eqs. 5.47-5.49), ``q_dot = B T y`` (eq. 5.31) and the constraints ``Phi`` (eqs. 5.15-5.17).

All functions are pure in ``(system, params, q, ...)``; the loops below run over the static
topology and are unrolled once at trace time.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ._rotations import angular_velocity_matrix, axis_angle, rotation_matrix, skew
from ._system import FREE, System, SystemParams


def _split(system: System, x, offsets):
    return [x[offsets[i] : offsets[i + 1]] for i in range(system.n_bodies)]


def _free_groups(system: System) -> dict[str, list[int]]:
    """Free bodies grouped by rotation sequence (static), for one vmapped call per group."""
    groups: dict[str, list[int]] = {}
    for i in range(system.n_bodies):
        if system.tree_kind[i] == FREE:
            groups.setdefault(system.sequence[i], []).append(i)
    return groups


def _angle_rows(system: System, bodies: list[int]) -> np.ndarray:
    """Static ``(n, 3)`` indices of the rotation angles of ``bodies`` in ``q``."""
    return np.asarray([[system.q_offsets[i] + 3 + k for k in range(3)] for i in bodies], dtype=int)


def body_poses(system: System, params: SystemParams, q: Float[Array, " nq"]) -> list[tuple]:
    """``[(r_i, A_i, p_i)]`` for every body: origin (m, global), rotation, modal coordinates.

    Rotation matrices of free bodies are computed in one vmapped call per sequence."""
    rotations = {}
    for seq, bodies in _free_groups(system).items():
        mats = jax.vmap(lambda a, seq=seq: rotation_matrix(seq, a))(q[_angle_rows(system, bodies)])
        rotations.update({i: mats[k] for k, i in enumerate(bodies)})
    poses = []
    for i, qi in enumerate(_split(system, q, system.q_offsets)):
        if system.tree_kind[i] == FREE:
            poses.append((qi[:3], rotations[i], qi[6:]))
        else:
            rp, ap = _parent_pose(poses, system.parent[i], q.dtype)
            joint = params.tree[i]
            poses.append((rp + ap @ joint.offset, ap @ axis_angle(joint.axis, qi[0]), qi[1:]))
    return poses


def _parent_pose(poses, parent: int, dtype):
    if parent < 0:
        return jnp.zeros((3,), dtype), jnp.eye(3, dtype=dtype)
    return poses[parent][0], poses[parent][1]


def _inputs_or_empty(u, dtype):
    return jnp.zeros((0,), dtype) if u is None else u


def point_local(system: System, params: SystemParams, poses, k: int, u) -> Float[Array, "3"]:
    """Position of point ``k`` in its body frame including deformation and input (m)."""
    point, body = params.points[k], system.point_body[k]
    x = point.position
    if body >= 0 and system.n_modes[body] > 0:
        x = x + params.bodies[body].coupling * (point.shapes @ poses[body][2])
    if system.point_input[k] >= 0:
        x = x + u[system.point_input[k]] * point.input_direction
    return x


def _frames(poses, dtype):
    """Stacked origins ``(nb + 1, 3)`` and rotations ``(nb + 1, 3, 3)``; row 0 is the ground."""
    rs = jnp.stack([jnp.zeros((3,), dtype)] + [p[0] for p in poses])
    rots = jnp.stack([jnp.eye(3, dtype=dtype)] + [p[1] for p in poses])
    return rs, rots


def _body_rows(system: System):
    """Static row of every point's body in the stacked frames (ground = 0)."""
    return np.asarray(system.point_body, dtype=int) + 1


def _points_on(system: System, body: int) -> list[int]:
    return [k for k, b in enumerate(system.point_body) if b == body]


def _add_modal(system: System, params: SystemParams, x, modal_values):
    """``x[k] += coupling * Psi_k @ modal_values[body(k)]`` for points on flexible bodies."""
    for b in range(system.n_bodies):
        idx = _points_on(system, b)
        if system.n_modes[b] == 0 or not idx:
            continue
        shapes = jnp.stack([params.points[k].shapes for k in idx])
        x = x.at[np.asarray(idx)].add(params.bodies[b].coupling * jnp.einsum("kim,m->ki", shapes, modal_values[b]))
    return x


def points_local(system: System, params: SystemParams, poses, u) -> Float[Array, "np 3"]:
    """Body-frame positions of all points with deformation and inputs (m), vectorised."""
    x = jnp.stack([pt.position for pt in params.points])
    x = _add_modal(system, params, x, [p[2] for p in poses])
    idx = [k for k, i in enumerate(system.point_input) if i >= 0]
    if idx:
        dirs = jnp.stack([params.points[k].input_direction for k in idx])
        vals = u[np.asarray([system.point_input[k] for k in idx])]
        x = x.at[np.asarray(idx)].add(vals[:, None] * dirs)
    return x


def points_global(system: System, frames, local) -> Float[Array, "np 3"]:
    """Global positions (m) of all points from their body-frame positions."""
    rs, rots = frames
    rows = _body_rows(system)
    return rs[rows] + jnp.einsum("kij,kj->ki", rots[rows], local)


def points_velocity(system: System, params: SystemParams, frames, vs, local) -> Float[Array, "np 3"]:
    """Global velocities (m/s) of all points from the body velocities (linear in ``vs``;
    input rates excluded, they enter through ``Phi_t``)."""
    _, rots = frames
    zero = jnp.zeros((3,), local.dtype)
    us = jnp.stack([zero] + [v[:3] for v in vs])
    ws = jnp.stack([zero] + [v[3:6] for v in vs])
    rows = _body_rows(system)
    rel = us[rows] + jnp.cross(ws[rows], local)
    rel = _add_modal(system, params, rel, [v[6:] for v in vs])
    return jnp.einsum("kij,kj->ki", rots[rows], rel)


def marker_positions(system: System, params: SystemParams, q, u=None) -> Float[Array, "np 3"]:
    """``pX``: global positions (m) of all points, one row per point."""
    if not system.point_names:
        return jnp.zeros((0, 3), q.dtype)
    poses = body_poses(system, params, q)
    u = _inputs_or_empty(u, q.dtype)
    return points_global(system, _frames(poses, q.dtype), points_local(system, params, poses, u))


def body_rotation(system: System, params: SystemParams, q, body: str) -> Float[Array, "3 3"]:
    """Body-to-global rotation matrix of ``body``."""
    return body_poses(system, params, q)[system.body_names.index(body)][1]


def _orthonormal_pair(n1):
    """Two unit vectors orthogonal to the unit ``n1`` and to each other (smooth away from the
    switching planes; the helper axis is the coordinate axis least aligned with ``n1``)."""
    helpers = jnp.eye(3, dtype=n1.dtype)
    h = helpers[jnp.argmin(jnp.abs(n1))]
    n2 = jnp.cross(n1, h)
    n2 = n2 / jnp.linalg.norm(n2)
    return n2, jnp.cross(n1, n2)


def _joint_layout(system: System):
    """Static layout: point indices of every joint, link joints, spherical (joint, component)
    pairs, revolute joints, and the permutation that puts the kind-grouped rows in joint
    order (the order of :attr:`System.constraint_names`)."""
    p_idx = np.asarray([jp[0] for jp in system.joint_points], dtype=int)
    q_idx = np.asarray([jp[1] for jp in system.joint_points], dtype=int)
    links = [k for k, kind in enumerate(system.joint_kind) if kind == "link"]
    sph = [
        (k, c) for k, kind in enumerate(system.joint_kind) if kind == "spherical" for c in system.joint_components[k]
    ]
    revs = [k for k, kind in enumerate(system.joint_kind) if kind == "revolute"]
    grouped = [(k, 0) for k in links] + sph + [(k, r) for k in revs for r in range(5)]
    ordered = [(k, c) for k, kind in enumerate(system.joint_kind) for c in (
        (0,) if kind == "link" else system.joint_components[k] if kind == "spherical" else range(5))]
    perm = np.asarray([grouped.index(key) for key in ordered], dtype=int)
    return p_idx, q_idx, links, sph, revs, perm


def _assemble_rows(system, d_rows_links, sph_rows, rev_rows, dtype):
    _, _, _, _, _, perm = _joint_layout(system)
    pieces = [r for r in (d_rows_links, sph_rows) if r is not None] + rev_rows
    if not pieces:
        return jnp.zeros((0,), dtype)
    return jnp.concatenate(pieces)[perm]


def _sph_rows(sph, d):
    if not sph:
        return None
    return d[np.asarray([k for k, _ in sph]), np.asarray([c for _, c in sph])]


def constraints(system: System, params: SystemParams, q, u=None) -> Float[Array, " m"]:
    """``pPhi``: constraint residuals (eqs. 5.15-5.17), m for positions, dimensionless for axes.

    Link rows use ``(|d|^2 - l^2) / (2 l)``, equal to ``|d| - l`` to first order and smooth.
    Vectorised over joints (one gather per joint kind).
    """
    if system.n_constraints == 0:
        return jnp.zeros((0,), q.dtype)
    poses = body_poses(system, params, q)
    u = _inputs_or_empty(u, q.dtype)
    x = points_global(system, _frames(poses, q.dtype), points_local(system, params, poses, u))
    p_idx, q_idx, links, sph, revs, _ = _joint_layout(system)
    d = x[p_idx] - x[q_idx]
    link_rows = None
    if links:
        lengths = jnp.stack([params.joints[k].length for k in links])
        dl = d[np.asarray(links)]
        link_rows = (jnp.sum(dl * dl, axis=1) - lengths**2) / (2.0 * lengths)
    rev_rows = []
    for k in revs:
        i, j = system.joint_points[k]
        jp = params.joints[k]
        ai, aj = _point_rotation(system, params, poses, i), _point_rotation(system, params, poses, j)
        n2, n3 = _orthonormal_pair(jp.axis_i)
        n1j = aj @ jp.axis_j
        rev_rows.append(jnp.concatenate([d[k], jnp.stack([(ai @ n2) @ n1j, (ai @ n3) @ n1j])]))
    return _assemble_rows(system, link_rows, _sph_rows(sph, d), rev_rows, q.dtype)


def point_small_rotation(system: System, params: SystemParams, k: int, modal_values):
    """Small rotation (rad, body axes) of the material at point ``k`` from the body's
    deformation: ``coupling * Psi_r p`` (zero on rigid bodies and ground)."""
    body = system.point_body[k]
    if body < 0 or system.n_modes[body] == 0:
        return None
    return params.bodies[body].coupling * (params.points[k].rotation_shapes @ modal_values)


def _point_rotation(system: System, params: SystemParams, poses, k: int):
    """Orientation of the material frame at point ``k``: the body rotation, times
    ``I + skew(Psi_r p)`` on flexible bodies (first order in the modal coordinates, as the
    modal displacement field itself)."""
    body = system.point_body[k]
    if body < 0:
        return jnp.eye(3, dtype=poses[0][0].dtype)
    a = poses[body][1]
    theta = point_small_rotation(system, params, k, poses[body][2])
    return a if theta is None else a + a @ skew(theta)


def _point_rotation_rate(system: System, params: SystemParams, poses, vs, k: int, dtype):
    """Time derivative of :func:`_point_rotation`:
    ``d/dt [A (I + skew(theta))] = A (skew(w) (I + skew(theta)) + skew(theta_dot))``."""
    body = system.point_body[k]
    if body < 0:
        return jnp.zeros((3, 3), dtype)
    a, w = poses[body][1], vs[body][3:6]
    theta = point_small_rotation(system, params, k, poses[body][2])
    if theta is None:
        return a @ skew(w)
    theta_dot = point_small_rotation(system, params, k, vs[body][6:])
    eye = jnp.eye(3, dtype=dtype)
    return a @ (skew(w) @ (eye + skew(theta)) + skew(theta_dot))


def _solve3(m, b):
    """``m^-1 b`` for a 3 x 3 matrix by the adjugate (cheap elementwise ops, no LU call)."""
    c0, c1, c2 = m[:, 0], m[:, 1], m[:, 2]
    adj = jnp.stack([jnp.cross(c1, c2), jnp.cross(c2, c0), jnp.cross(c0, c1)])
    return (adj @ b) / jnp.dot(c0, jnp.cross(c1, c2))


def constraint_rates(system: System, params: SystemParams, poses, vs, u) -> Float[Array, " m"]:
    """``Phi_q q_dot`` written explicitly in the body velocities (``Phi_q B`` applied to ``v``):
    linear in ``vs``, so its Jacobian needs no derivative of the rotation matrices."""
    dtype = vs[0].dtype
    if system.n_constraints == 0:
        return jnp.zeros((0,), dtype)
    frames = _frames(poses, dtype)
    local = points_local(system, params, poses, u)
    x = points_global(system, frames, local)
    xv = points_velocity(system, params, frames, vs, local)
    p_idx, q_idx, links, sph, revs, _ = _joint_layout(system)
    d, dv = x[p_idx] - x[q_idx], xv[p_idx] - xv[q_idx]
    link_rows = None
    if links:
        lengths = jnp.stack([params.joints[k].length for k in links])
        li = np.asarray(links)
        link_rows = jnp.sum(d[li] * dv[li], axis=1) / lengths
    rev_rows = []
    for k in revs:
        i, j = system.joint_points[k]
        jp = params.joints[k]
        ai, aj = _point_rotation(system, params, poses, i), _point_rotation(system, params, poses, j)
        ai_dot = _point_rotation_rate(system, params, poses, vs, i, dtype)
        aj_dot = _point_rotation_rate(system, params, poses, vs, j, dtype)
        n2, n3 = _orthonormal_pair(jp.axis_i)
        n1j, dn1j = aj @ jp.axis_j, aj_dot @ jp.axis_j
        rate = [(ai_dot @ n) @ n1j + (ai @ n) @ dn1j for n in (n2, n3)]
        rev_rows.append(jnp.concatenate([dv[k], jnp.stack(rate)]))
    return _assemble_rows(system, link_rows, _sph_rows(sph, dv), rev_rows, dtype)


def body_velocities(system: System, params: SystemParams, q, y, poses=None) -> list:
    """``v = T y`` (eq. 5.49): body-frame velocities ``[u, omega, p_dot]`` of every body."""
    poses = body_poses(system, params, q) if poses is None else poses
    vs = []
    for i, yi in enumerate(_split(system, y, system.q_offsets)):
        parent = system.parent[i]
        r, a, _ = poses[i]
        if parent < 0:
            u_p = jnp.zeros((3,), q.dtype)
            w_p = jnp.zeros((3,), q.dtype)
            a_rel = a.T
            r_rel = r
        else:
            rp, ap, _ = poses[parent]
            u_p, w_p = vs[parent][:3], vs[parent][3:6]
            a_rel = a.T @ ap  # parent axes -> child axes, A(i, i-1) of eq. (5.48)
            r_rel = ap.T @ (r - rp)  # child origin from parent origin, parent axes
        u_c = a_rel @ (u_p + jnp.cross(w_p, r_rel))
        w_c = a_rel @ w_p
        if system.tree_kind[i] == FREE:
            vs.append(jnp.concatenate([u_c + yi[:3], w_c + yi[3:6], yi[6:]]))
        else:
            axis = params.tree[i].axis
            vs.append(jnp.concatenate([u_c, w_c + yi[0] * axis, yi[1:]]))
    return vs


def qdot_from_velocities(system: System, params: SystemParams, q, y, vs, poses) -> Float[Array, " nq"]:
    """``q_dot = B v`` for free bodies (eq. 5.31) and the joint rates for tree joints."""
    ys = _split(system, y, system.q_offsets)
    rates = {}
    for seq, bodies in _free_groups(system).items():
        w = jnp.stack([vs[i][3:6] for i in bodies])
        r = jax.vmap(lambda a, wi, seq=seq: _solve3(angular_velocity_matrix(seq, a), wi))(
            q[_angle_rows(system, bodies)], w
        )
        rates.update({i: r[k] for k, i in enumerate(bodies)})
    out = []
    for i in range(system.n_bodies):
        if system.tree_kind[i] == FREE:
            out.append(jnp.concatenate([poses[i][1] @ vs[i][:3], rates[i], vs[i][6:]]))
        else:
            out.append(ys[i])
    return jnp.concatenate(out)


def velocity_maps(system: System, params: SystemParams, q, y):
    """``(v, q_dot)`` for joint velocities ``y``: ``v = T y`` and ``q_dot = B T y``."""
    poses = body_poses(system, params, q)
    vs = body_velocities(system, params, q, y, poses)
    return jnp.concatenate(vs), qdot_from_velocities(system, params, q, y, vs, poses)


def recursion_matrix(system: System, params: SystemParams, q) -> Float[Array, "nv ny"]:
    """``pT``: the recursion matrix ``T`` of eq. (5.50), ``v = T y``."""
    return jax.jacfwd(lambda y: velocity_maps(system, params, q, y)[0])(jnp.zeros((system.n_y,), q.dtype))


def velocity_matrix(system: System, params: SystemParams, q) -> Float[Array, "nq ny"]:
    """``B T``: ``q_dot = (B T) y`` (eqs. 5.31, 5.49)."""
    return jax.jacfwd(lambda y: velocity_maps(system, params, q, y)[1])(jnp.zeros((system.n_y,), q.dtype))


def velocity_matrix_b(system: System, params: SystemParams, q) -> Float[Array, "nq nv"]:
    """``pB`` for systems of free bodies only: ``q_dot = B v`` (block diagonal, eq. 5.31)."""
    if any(k != FREE for k in system.tree_kind):
        raise ValueError("B (q_dot = B v) exists only for systems of free bodies; use velocity_matrix (B T)")
    poses = body_poses(system, params, q)
    y0 = jnp.zeros((system.n_y,), q.dtype)

    def qdot(v):
        return qdot_from_velocities(system, params, q, y0, _split(system, v, system.v_offsets), poses)

    return jax.jacfwd(qdot)(jnp.zeros((system.n_v,), q.dtype))


def recursion_matrix_dot(system: System, params: SystemParams, q, q_dot) -> Float[Array, "nv ny"]:
    """``pTdot``: time derivative of ``T`` along ``q_dot`` (forward-mode JVP)."""
    return jax.jvp(lambda qq: recursion_matrix(system, params, qq), (q,), (q_dot,))[1]


def velocity_matrix_dot(system: System, params: SystemParams, q, q_dot) -> Float[Array, "nq ny"]:
    """Time derivative of ``B T`` along ``q_dot`` (``pBdot`` combined with ``pTdot``)."""
    return jax.jvp(lambda qq: velocity_matrix(system, params, qq), (q,), (q_dot,))[1]


def constraint_jacobian(system: System, params: SystemParams, q, u=None) -> Float[Array, "m nq"]:
    """``Phi_q`` by forward-mode autodiff."""
    return jax.jacfwd(lambda qq: constraints(system, params, qq, u))(q)


def marker_jacobian(system: System, params: SystemParams, q, u=None) -> Float[Array, "np 3 nq"]:
    """``pdXdq``: derivative of the point positions versus ``q``."""
    return jax.jacfwd(lambda qq: marker_positions(system, params, qq, u))(q)


def marker_input_jacobian(system: System, params: SystemParams, q, u) -> Float[Array, "np 3 ni"]:
    """``pdXdd``: derivative of the point positions versus the rheonomic inputs."""
    return jax.jacfwd(lambda uu: marker_positions(system, params, q, uu))(u)


def point_velocity(system: System, params: SystemParams, q, y, point: str, u=None, u_dot=None):
    """Global velocity (m/s) of ``point`` for joint velocities ``y`` (and input rates)."""
    k = system.point_index(point)
    u = _inputs_or_empty(u, q.dtype)
    u_dot = jnp.zeros_like(u) if u_dot is None else u_dot
    _, q_dot = velocity_maps(system, params, q, y)
    f = lambda qq, uu: marker_positions(system, params, qq, uu)[k]  # noqa: E731
    return jax.jvp(f, (q, u), (q_dot, u_dot))[1]

