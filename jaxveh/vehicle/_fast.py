"""The fast car: the chapter-6 car's equations in minimal coordinates (thesis section 6.1,
the independent set of Table 6.1), the four corners vectorised.

Coordinates ``q = [chassis (x, y, z, yaw, pitch, roll, modes), travel (4), spin (4)]`` and
velocities ``u = [chassis body velocities (u, omega in chassis axes, modal rates),
travel rates (4), spin rates (4)]``: the chassis as the library's free flexible body, each
upright by its suspension travel (the wheel centre's height in the chassis frame from its
design position, m, positive in bump), each wheel by its spin angle about the upright's y
axis. Corner kinematics (:mod:`._corner_kinematics`) give every upright's pose from the
travel, the rack and the chassis deformation; every body's velocity is linear in ``u``,
``v = J(q) u + j(q) rack_rate``, by forward-mode autodiff of that kinematics.

The equations are Kane's: ``J^T (M (J u_dot + a0) - Q) = 0`` with the library's body mass
matrices ``M``, internal, elastic and gravity forces and the car's force elements
(:func:`jaxveh.vehicle.car_elements`, same code as the library car), ``a0`` the body
accelerations at ``u_dot = 0`` (one JVP along the motion). No constraint projection, no
drift: the links are closed exactly at every evaluation.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..multibody import (
    SystemParams,
    element_forces,
    generalised_forces,
    input_state,
    internal_forces_at,
    kinematics,
    mass_matrix_at,
    rotation_matrix,
)
from ..multibody._inputs import as_inputs
from ..multibody._rotations import angular_velocity_matrix, elementary
from ._car import CORNERS, Car, system_params, wheel_centres
from ._corner_kinematics import (
    CornerGeometry,
    KinematicMap,
    build_map,
    corner_geometry,
    corner_poses,
    pose_residual,
    relative_pose,
)


class FastModel(eqx.Module):
    """What the fast car's equations read, rebuilt from :class:`CarParams` by JAX operations:
    the library parameters, the corners' link geometry and the kinematic map (the Newton
    guess)."""

    params: SystemParams
    geometry: CornerGeometry
    kmap: KinematicMap


class FastState(eqx.Module):
    """State of the fast car: coordinates ``q``, velocities ``u`` (same layout, see the
    module docs) and the force elements' auxiliary states ``aux``."""

    q: Float[Array, " n"]
    u: Float[Array, " n"]
    aux: Float[Array, " na"]


def fast_model(car: Car) -> FastModel:
    """The fast car's model of ``car.params`` (differentiable; builds the kinematic map)."""
    params = system_params(car)
    geometry = corner_geometry(car.system, params, wheel_centres(car.params.vehicle))
    return FastModel(params=params, geometry=geometry, kmap=build_map(geometry))


def split(car: Car, x):
    """``(chassis, travel, spin)`` parts of a coordinate or velocity vector."""
    n = 6 + car.n_modes
    return x[:n], x[n : n + 4], x[n + 4 :]


def _rel_motion(model: FastModel, travel, rack, modes):
    """Upright origins (4, 3) and rotations (4, 3, 3) relative to the chassis frame."""
    w = corner_poses(model.geometry, model.kmap, travel, rack, modes)
    return jax.vmap(relative_pose)(w, travel, model.geometry.centre)


def _vee(m):
    return jnp.stack([m[..., 2, 1], m[..., 0, 2], m[..., 1, 0]], axis=-1)


def motion(car: Car, model: FastModel, q, u, rack, rack_rate):
    """Library body poses ``[(r, A, p)]`` and body velocities ``[v]`` (body axes, library
    order) of every body at ``(q, u)`` and rack travel / rate (m, m/s)."""
    qc, travel, spin = split(car, q)
    vc, travel_rate, spin_rate = split(car, u)
    r_c, a_c, modes = qc[:3], rotation_matrix("zyx", qc[3:6]), qc[6:]
    u_c, w_c = vc[:3], vc[3:6]
    (r_rel, a_rel), (dr_rel, da_rel) = jax.jvp(
        lambda t, r, p: _rel_motion(model, t, r, p), (travel, rack, modes), (travel_rate, rack_rate, vc[6:]))
    a_relt = jnp.swapaxes(a_rel, 1, 2)
    r_up = r_c + r_rel @ a_c.T
    a_up = jnp.einsum("ij,kjl->kil", a_c, a_rel)
    v_up = jnp.einsum("kij,kj->ki", a_relt, u_c + jnp.cross(w_c, r_rel) + dr_rel)
    w_up = jnp.einsum("kij,j->ki", a_relt, w_c) + _vee(jnp.einsum("kij,kjl->kil", a_relt, da_rel))
    spin_rot = jax.vmap(lambda a: elementary(1, a))(spin)  # upright -> wheel: R_y(spin)
    spin_rot_t = jnp.swapaxes(spin_rot, 1, 2)
    a_wh = jnp.einsum("kij,kjl->kil", a_up, spin_rot)
    v_wh = jnp.einsum("kij,kj->ki", spin_rot_t, v_up)
    w_wh = jnp.einsum("kij,kj->ki", spin_rot_t, w_up) + spin_rate[:, None] * jnp.asarray([0.0, 1.0, 0.0])
    poses, vs = {"chassis": (r_c, a_c, modes)}, {"chassis": vc}
    empty = jnp.zeros((0,))
    for k, corner in enumerate(CORNERS):
        poses[f"{corner}.upright"] = (r_up[k], a_up[k], empty)
        poses[f"{corner}.wheel"] = (r_up[k], a_wh[k], empty)
        vs[f"{corner}.upright"] = jnp.concatenate([v_up[k], w_up[k]])
        vs[f"{corner}.wheel"] = jnp.concatenate([v_wh[k], w_wh[k]])
    names = car.system.body_names
    return [poses[n] for n in names], [vs[n] for n in names]


def coordinate_rates(car: Car, q, u):
    """``q_dot`` from ``(q, u)``: chassis position rate in global axes, angle rates from the
    body angular velocity (``"zyx"``), modal, travel and spin rates."""
    qc, _, _ = split(car, q)
    vc = u[: 6 + car.n_modes]
    angles = qc[3:6]
    r_dot = rotation_matrix("zyx", angles) @ vc[:3]
    angle_rates = jnp.linalg.solve(angular_velocity_matrix("zyx", angles), vc[3:6])
    return jnp.concatenate([r_dot, angle_rates, u[6:]])


def _body_velocity_vector(car, model, q, u, rack, rack_rate):
    return jnp.concatenate(motion(car, model, q, u, rack, rack_rate)[1])


class FastDynamics(eqx.Module):
    """The fast car's equations at one state: ``q_dot``, ``u_dot``, ``aux_dot``, the body
    velocities ``v`` and accelerations ``v_dot`` (library layout), the rack travel and rate,
    the force elements' :class:`Kinematics`, and ``link_residual`` (m, what the corner
    solve left)."""

    q_dot: Float[Array, " n"]
    u_dot: Float[Array, " n"]
    aux_dot: Float[Array, " na"]
    v: Float[Array, " nv"]
    v_dot: Float[Array, " nv"]
    rack: Float[Array, ""]
    rack_rate: Float[Array, ""]
    kinematics: object
    link_residual: Float[Array, ""]


def fast_dynamics(car: Car, model: FastModel, q, u, aux, t, inputs, elements) -> FastDynamics:
    """Kane's equations of the fast car at ``(t, q, u, aux)`` (see the module docs).
    ``inputs``: the rack law (a function of time or a :class:`jaxveh.multibody.AbstractInputs`;
    closed-loop laws read the fast car's ``q``)."""
    system, params = car.system, model.params
    t = jnp.asarray(t, q.dtype)
    law = as_inputs(inputs)
    rack_v, rack_dot_v = input_state(system, law, t, q, aux)
    rack, rack_rate = rack_v[0], rack_dot_v[0]
    poses, vs = motion(car, model, q, u, rack, rack_rate)
    v = jnp.concatenate(vs)
    q_dot = coordinate_rates(car, q, u)
    kin = kinematics(system, params, q, vs, poses, rack_v, rack_dot_v, t)
    forces, torques, aux_dot = element_forces(system, params, elements, kin, aux)
    q_applied = generalised_forces(system, params, q, poses, forces, torques)
    q_int, q_grav = internal_forces_at(system, params, poses, vs)
    rack_acc = jax.jvp(lambda tt, qq, aa: law.rate(tt, qq, aa), (t, q, aux), (jnp.ones_like(t), q_dot, aux_dot))[1][0]
    jac = jax.jacfwd(lambda uu: _body_velocity_vector(car, model, q, uu, rack, jnp.zeros_like(rack)))(u)
    a0 = jax.jvp(lambda qq, r, rd: _body_velocity_vector(car, model, qq, u, r, rd), (q, rack, rack_rate),
                 (q_dot, rack_rate, rack_acc))[1]
    m_full = mass_matrix_at(system, params, poses)
    m_red = jac.T @ m_full @ jac
    rhs = jac.T @ (q_int + q_grav + q_applied - m_full @ a0)
    u_dot = jnp.linalg.solve(m_red, rhs)
    _, travel, _ = split(car, q)
    w = corner_poses(model.geometry, model.kmap, travel, rack, q[6:6 + car.n_modes])
    residual = pose_residual(model.geometry, travel, rack, q[6:6 + car.n_modes], w)
    return FastDynamics(q_dot=q_dot, u_dot=u_dot, aux_dot=aux_dot, v=v, v_dot=jac @ u_dot + a0, rack=rack,
                        rack_rate=rack_rate, kinematics=kin, link_residual=residual)


# ---- states of the library car ------------------------------------------------------------


def travel_from_library(car: Car, q_lib) -> Float[Array, "4"]:
    """Suspension travels (m) of a library-car coordinate vector: each wheel centre's height
    in the chassis frame from its design value."""
    sys = car.system
    c = sys.body_names.index("chassis")
    qc = q_lib[sys.q_offsets[c] : sys.q_offsets[c + 1]]
    a_c = rotation_matrix("zyx", qc[3:6])
    centres = wheel_centres(car.params.vehicle)
    out = []
    for k, corner in enumerate(CORNERS):
        i = sys.body_names.index(f"{corner}.upright")
        r_u = q_lib[sys.q_offsets[i] : sys.q_offsets[i] + 3]
        out.append((a_c.T @ (r_u - qc[:3]))[2] - centres[k, 2])
    return jnp.stack(out)


def state_from_library(car: Car, q_lib, y_lib, aux) -> FastState:
    """The fast car's state at a library-car state (assembled ``q_lib``, joint velocities
    ``y_lib`` that satisfy the velocity constraints)."""
    from ..multibody import velocity_maps

    sys = car.system
    params = system_params(car)
    c = sys.body_names.index("chassis")
    q_dot = velocity_maps(sys, params, q_lib, y_lib)[1]
    travel, travel_rate = jax.jvp(lambda qq: travel_from_library(car, qq), (q_lib,), (q_dot,))
    wheels = [sys.body_names.index(f"{corner}.wheel") for corner in CORNERS]
    spin = jnp.stack([q_lib[sys.q_offsets[i]] for i in wheels])
    spin_rate = jnp.stack([y_lib[sys.q_offsets[i]] for i in wheels])
    chassis = slice(sys.q_offsets[c], sys.q_offsets[c + 1])
    q = jnp.concatenate([q_lib[chassis], travel, spin])
    u = jnp.concatenate([y_lib[chassis], travel_rate, spin_rate])
    return FastState(q=q, u=u, aux=aux)
