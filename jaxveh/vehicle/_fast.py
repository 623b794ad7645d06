"""The fast car: the chapter-6 car's equations in minimal coordinates (thesis section 6.1,
the independent set of Table 6.1), the four corners vectorised.

Coordinates ``q = [chassis (x, y, z, yaw, pitch, roll, modes), travel (4), spin (4)]`` and
velocities ``u = [chassis body velocities (u, omega in chassis axes, modal rates),
travel rates (4), spin rates (4)]``: the chassis as the library's free flexible body, each
upright by its suspension travel (the wheel centre's height in the chassis frame from its
design position, m, positive in bump), each wheel by its spin angle about the upright's y
axis. The corner kinematics (:mod:`._corner_kinematics`) give every upright's pose, its
rates and its velocity-product accelerations from the travel, the rack and the chassis
deformation, exactly, for the four corners at once.

The equations are Kane's: ``sum_b J_b^T (M_b (J_b u_dot + a0_b) - Q_b) = 0`` over the
chassis (the library's modal body: mass matrix, quadratic velocity, elastic and gravity
forces), the uprights and the wheels (rotors of spin inertia about the upright's y axis;
their mass is the upright's), with ``J_b`` the partial velocities, ``a0_b`` the body
accelerations at ``u_dot = 0`` and ``Q_b`` gravity and the car's force elements
(:func:`jaxveh.vehicle.car_elements`, the same code as the library car, fed with the same
:class:`jaxveh.multibody.Kinematics`). No constraint projection and no drift: the links
close exactly at every evaluation. A corner's velocities depend on the chassis's and on its
own travel and spin rates only, so the mass matrix is an arrow: the corners' 2 x 2 blocks
are eliminated in closed form and only the chassis's Schur complement (12 x 12 with six
modes) is factorised.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.linalg import cho_factor, cho_solve
from jaxtyping import Array, Float

from .._trig import sin_cos
from ..multibody import Kinematics, SystemParams, body_forces, element_forces, input_state, rotation_matrix
from ..multibody._inputs import as_inputs
from ..multibody._rotations import elementary, skew
from ._car import CORNERS, Car, system_params, wheel_centres
from ._corner_kinematics import (
    CornerGeometry,
    CornerMotion,
    KinematicMap,
    build_map,
    corner_geometry,
    corner_motion,
    pose_residual,
)
from ._fast_suspension import split_suspensions, suspension_forces

_EY = ((0.0, 1.0, 0.0),)  # the spin axis, as a row


class PointTables(eqx.Module):
    """The points' design data, stacked once per model (the equations read them at every
    evaluation; stacked there, a gradient would gather each point's cotangent at every
    stage): chassis points' positions ``chassis`` (n, 3), translational and rotational mode
    shapes times the coupling factor (n, 3, modes), rack directions ``inputs`` (n, 3; zero
    where the rack does not move the point); upright and wheel points' positions in their
    body frames (m)."""

    chassis: Float[Array, "nc 3"]
    shapes: Float[Array, "nc 3 nm"]
    rotation_shapes: Float[Array, "nc 3 nm"]
    inputs: Float[Array, "nc 3"]
    upright: Float[Array, "nu 3"]
    wheel: Float[Array, "nw 3"]


class FastModel(eqx.Module):
    """What the fast car's equations read, rebuilt from :class:`CarParams` by JAX operations:
    the library parameters, the corners' link geometry, the kinematic map (the Newton
    guess), the points' stacked design data and the corners' upright masses (kg), inertias
    (kg m^2, upright axes) and wheel spin inertias (kg m^2)."""

    params: SystemParams
    geometry: CornerGeometry
    kmap: KinematicMap
    points: PointTables
    upright_mass: Float[Array, "4"]
    upright_inertia: Float[Array, "4 3 3"]
    spin_inertia: Float[Array, "4"]


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
    lay = _layout(car)
    return FastModel(params=params, geometry=geometry, kmap=build_map(geometry),
                     points=_point_tables(car, params, lay),
                     upright_mass=jnp.stack([params.bodies[i].mass for i in lay["uprights"]]),
                     upright_inertia=jnp.stack([params.bodies[i].inertia for i in lay["uprights"]]),
                     spin_inertia=jnp.stack([params.bodies[i].inertia[1, 1] for i in lay["wheels"]]))


def split(car: Car, x):
    """``(chassis, travel, spin)`` parts of a coordinate or velocity vector."""
    n = 6 + car.n_modes
    return x[:n], x[n : n + 4], x[n + 4 :]


# ---- static layout ---------------------------------------------------------------------------


def _layout(car: Car):
    """Static index sets: chassis points, upright points with their corner, wheel points
    with their corner, and the body index of each corner's upright and wheel."""
    sys = car.system
    chassis = sys.body_names.index("chassis")
    uprights = [sys.body_names.index(f"{c}.upright") for c in CORNERS]
    wheels = [sys.body_names.index(f"{c}.wheel") for c in CORNERS]
    on_chassis = [k for k, b in enumerate(sys.point_body) if b == chassis]
    on_upright = [(k, uprights.index(b)) for k, b in enumerate(sys.point_body) if b in uprights]
    on_wheel = [(k, wheels.index(b)) for k, b in enumerate(sys.point_body) if b in wheels]
    if len(on_chassis) + len(on_upright) + len(on_wheel) != len(sys.point_names):
        raise ValueError("the fast car expects every point on the chassis, an upright or a wheel")
    order = on_chassis + [k for k, _ in on_upright] + [k for k, _ in on_wheel]
    return {
        "chassis_points": np.asarray(on_chassis, int),
        "upright_points": np.asarray([k for k, _ in on_upright], int),
        "upright_corner": np.asarray([c for _, c in on_upright], int),
        "wheel_points": np.asarray([k for k, _ in on_wheel], int),
        "wheel_corner": np.asarray([c for _, c in on_wheel], int),
        "unstack": np.argsort(np.asarray(order, int)),
        "uprights": uprights,
        "wheels": wheels,
    }


# ---- motion ----------------------------------------------------------------------------------


class CarMotion(eqx.Module):
    """Poses and velocities of the chassis, uprights and wheels at one state (see
    :func:`car_motion`)."""

    r_c: Float[Array, "3"]
    a_c: Float[Array, "3 3"]
    r_rel: Float[Array, "4 3"]
    a_rel: Float[Array, "4 3 3"]
    spin_rot: Float[Array, "4 3 3"]
    e_rel: Float[Array, "4 3 3"]
    corners: CornerMotion
    velocity: object


def _mv(a, v):
    """``a @ v`` of 3 x 3 matrices and 3-vectors over leading axes, as elementwise sums (XLA
    fuses them; a batched dot is one operation of its own)."""
    return a[..., 0] * v[..., None, 0] + a[..., 1] * v[..., None, 1] + a[..., 2] * v[..., None, 2]


def _mm(a, b):
    """``a @ b`` of 3 x 3 matrices over leading axes, as elementwise sums."""
    return a[..., :, 0, None] * b[..., None, 0, :] + a[..., :, 1, None] * b[..., None, 1, :] + (
        a[..., :, 2, None] * b[..., None, 2, :])


def _rotation_zxy(angles):
    """``rotation_matrix("zxy", angles)`` by elementwise products."""
    return _mm(_mm(elementary(2, angles[0]), elementary(0, angles[1])), elementary(1, angles[2]))


def _rate_matrix_zxy(angles):
    """``angular_velocity_matrix("zxy", angles)`` by elementwise products."""
    r2t, r3t = elementary(0, angles[1]).T, elementary(1, angles[2]).T
    return jnp.stack([_mv(r3t, r2t[:, 2]), r3t[:, 0], jnp.asarray([0.0, 1.0, 0.0])], axis=1)


def _rel_pose(corners: CornerMotion, travel, centre):
    r = centre + jnp.concatenate([corners.w[:, :2], travel[:, None]], axis=1)
    a = jax.vmap(_rotation_zxy)(corners.w[:, 2:])
    e = jax.vmap(_rate_matrix_zxy)(corners.w[:, 2:])
    return r, a, e


def _velocities(m, corners: CornerMotion, vc, travel_rate, spin_rate, rack_rate):
    """Body velocities (body axes; affine in the velocities): chassis ``vc``, uprights
    ``(v, omega)``, wheels' angular velocity in upright axes."""
    n_modes = vc.shape[0] - 6
    xi = jnp.concatenate([travel_rate[:, None], jnp.broadcast_to(rack_rate, (4, 1)),
                          jnp.broadcast_to(vc[6:], (4, n_modes))], axis=1)
    w_dot = jnp.einsum("kwm,km->kw", corners.sens, xi)
    r_dot = jnp.concatenate([w_dot[:, :2], travel_rate[:, None]], axis=1)
    omega_rel = _mv(m.e_rel, w_dot[:, 2:])
    u_c, w_c = vc[:3], vc[3:6]
    a_relt = jnp.swapaxes(m.a_rel, 1, 2)
    v_up = _mv(a_relt, u_c[None, :] + jnp.cross(w_c[None, :], m.r_rel) + r_dot)
    w_up = _mv(a_relt, w_c[None, :]) + omega_rel
    w_wheel = w_up + spin_rate[:, None] * jnp.asarray(_EY)
    return vc, v_up, w_up, w_wheel


def car_motion(car: Car, model: FastModel, q, u, rack, rack_rate, rack_acc) -> CarMotion:
    """Corner motion and every body's pose and velocity at ``(q, u)``, rack travel, rate and
    acceleration (m, m/s, m/s^2)."""
    qc, travel, spin = split(car, q)
    vc, travel_rate, spin_rate = split(car, u)
    corners = corner_motion(model.geometry, model.kmap, travel, rack, qc[6:], travel_rate, rack_rate, vc[6:],
                            rack_acc)
    r_rel, a_rel, e_rel = _rel_pose(corners, travel, model.geometry.centre)
    m = CarMotion(r_c=qc[:3], a_c=rotation_matrix("zyx", qc[3:6]), r_rel=r_rel, a_rel=a_rel,
                  spin_rot=jax.vmap(lambda a: elementary(1, a))(spin), e_rel=e_rel, corners=corners, velocity=None)
    return eqx.tree_at(lambda x: x.velocity, m, _velocities(m, corners, vc, travel_rate, spin_rate, rack_rate),
                       is_leaf=lambda x: x is None)


def _bias(m: CarMotion, vc, travel_rate):
    """Body accelerations at ``u_dot = 0`` (body axes): uprights ``(v_dot, omega_dot)``; the
    chassis's are zero and the wheels' angular one is the upright's."""
    c = m.corners
    r_dot = jnp.concatenate([c.w_dot[:, :2], travel_rate[:, None]], axis=1)
    r_acc = jnp.concatenate([c.w_acc0[:, :2], jnp.zeros((4, 1))], axis=1)
    omega_rel = _mv(m.e_rel, c.w_dot[:, 2:])
    e_dot = jax.vmap(lambda a, da: jax.jvp(_rate_matrix_zxy, (a,), (da,))[1])(
        c.w[:, 2:], c.w_dot[:, 2:])
    omega_rel_acc = _mv(m.e_rel, c.w_acc0[:, 2:]) + _mv(e_dot, c.w_dot[:, 2:])
    u_c, w_c = vc[:3], vc[3:6]
    a_relt = jnp.swapaxes(m.a_rel, 1, 2)
    x = u_c[None, :] + jnp.cross(w_c[None, :], m.r_rel) + r_dot
    v_acc = _mv(a_relt, jnp.cross(w_c[None, :], r_dot) + r_acc) - jnp.cross(omega_rel, _mv(a_relt, x))
    w_acc = -jnp.cross(omega_rel, _mv(a_relt, w_c[None, :])) + omega_rel_acc
    return v_acc, w_acc


# ---- kinematics for the force elements --------------------------------------------------------


def _point_tables(car: Car, params: SystemParams, lay) -> PointTables:
    pts = params.points
    ch = lay["chassis_points"]
    local = jnp.stack([pts[k].position for k in ch])
    n = car.n_modes
    shapes = jnp.stack([pts[k].shapes for k in ch]) if n else jnp.zeros((len(ch), 3, 0))
    rshapes = jnp.stack([pts[k].rotation_shapes for k in ch]) if n else jnp.zeros((len(ch), 3, 0))
    coupling = params.bodies[car.system.body_names.index("chassis")].coupling if n else jnp.zeros(())
    inputs = jnp.stack([pts[k].input_direction * float(car.system.point_input[k] >= 0) for k in ch])
    up = jnp.stack([pts[k].position for k in lay["upright_points"]])
    wh = jnp.stack([pts[k].position for k in lay["wheel_points"]])
    return PointTables(chassis=local, shapes=coupling * shapes, rotation_shapes=coupling * rshapes, inputs=inputs,
                       upright=up, wheel=wh)


def _chassis_points(car, model, q, rack):
    """Positions (m, chassis axes) of the chassis's points: design, modal deflection and the
    rack's travel (at the rack's points)."""
    pt = model.points
    return pt.chassis + pt.shapes @ split(car, q)[0][6:] + rack * pt.inputs


def _point_kinematics(car, model, lay, m: CarMotion, q, rack):
    """Positions and material orientations of every point (library order)."""
    pt = model.points
    rshapes, up, wh = pt.rotation_shapes, pt.upright, pt.wheel
    modes = split(car, q)[0][6:]
    x_ch = _chassis_points(car, model, q, rack)
    a_up = _mm(m.a_c[None], m.a_rel)
    r_up = m.r_c[None, :] + _mv(m.a_c[None], m.r_rel)
    a_wh = _mm(a_up, m.spin_rot)
    uc, wc = lay["upright_corner"], lay["wheel_corner"]
    x = jnp.concatenate([
        m.r_c[None, :] + _mv(m.a_c[None], x_ch),
        r_up[uc] + _mv(a_up[uc], up),
        r_up[wc] + _mv(a_wh[wc], wh),
    ])[lay["unstack"]]
    theta = rshapes @ modes
    rot_ch = m.a_c[None] + _mm(m.a_c[None], jax.vmap(skew)(theta))
    rots = jnp.concatenate([rot_ch, a_up[uc], a_wh[wc]])[lay["unstack"]]
    return x, rots, r_up, a_up, a_wh


def _point_rates(car, model, lay, m: CarMotion, velocity, a_up, q, rack, rack_rate):
    """Velocities and angular velocities (global axes) of every point, linear in the body
    velocities ``velocity`` and the rack rate (m/s; it moves the rack's points on the
    chassis)."""
    pt = model.points
    shapes, rshapes, inputs, up, wh = pt.shapes, pt.rotation_shapes, pt.inputs, pt.upright, pt.wheel
    vc, v_up, w_up, w_wheel = velocity
    x_ch = _chassis_points(car, model, q, rack)
    uc, wc = lay["upright_corner"], lay["wheel_corner"]
    xd_ch = _mv(m.a_c[None], vc[None, :3] + jnp.cross(vc[None, 3:6], x_ch) + shapes @ vc[6:] + rack_rate * inputs)
    xd_up = _mv(a_up[uc], v_up[uc] + jnp.cross(w_up[uc], up))
    # wheel points (the hubs) sit on the spin axis: their velocity is the upright's there
    xd_wh = _mv(a_up[wc], v_up[wc] + jnp.cross(w_wheel[wc], _mv(m.spin_rot[wc], wh)))
    om_ch = _mv(m.a_c[None], vc[None, 3:6] + rshapes @ vc[6:])
    om_up = _mv(a_up[uc], w_up[uc])
    om_wh = _mv(a_up[wc], w_wheel[wc])
    xd = jnp.concatenate([xd_ch, xd_up, xd_wh])[lay["unstack"]]
    om = jnp.concatenate([om_ch, om_up, om_wh])[lay["unstack"]]
    return xd, om


def _corner_sum(corner, x):
    """Sums of the rows of ``x`` (n, 3) by their corner (static, n): (4, 3), as one product."""
    return jnp.asarray(np.eye(4)[corner].T, x.dtype) @ x


def _applied_wrenches(car, model, lay, m: CarMotion, a_up, q, rack, forces, torques):
    """The point forces and torques (global axes, library order) as generalised forces:
    the chassis's ``(n_c,)`` (force, moment in chassis axes and the modal forces of the
    translational and rotational mode shapes) and, per corner, the upright's force and
    moment about its centre and the wheel's moment about its hub (upright axes; the wheel's
    force is the upright's). The point-velocity Jacobian transposed, body by body."""
    pt = model.points
    shapes, rshapes, up, wh = pt.shapes, pt.rotation_shapes, pt.upright, pt.wheel
    ch = lay["chassis_points"]
    x_ch = _chassis_points(car, model, q, rack)
    f_ch, t_ch = _mv(m.a_c.T[None], forces[ch]), _mv(m.a_c.T[None], torques[ch])
    modal = jnp.einsum("pim,pi->m", shapes, f_ch) + jnp.einsum("pim,pi->m", rshapes, t_ch)
    q_chassis = jnp.concatenate([f_ch.sum(0), (jnp.cross(x_ch, f_ch) + t_ch).sum(0), modal])
    uc, wc = lay["upright_corner"], lay["wheel_corner"]
    a_upt = jnp.swapaxes(a_up, 1, 2)
    up_ix, wh_ix = lay["upright_points"], lay["wheel_points"]
    f_up, t_up = _mv(a_upt[uc], forces[up_ix]), _mv(a_upt[uc], torques[up_ix])
    f_wh, t_wh = _mv(a_upt[wc], forces[wh_ix]), _mv(a_upt[wc], torques[wh_ix])
    force = _corner_sum(uc, f_up) + _corner_sum(wc, f_wh)
    moment = _corner_sum(uc, jnp.cross(up, f_up) + t_up)
    wheel_moment = _corner_sum(wc, jnp.cross(_mv(m.spin_rot[wc], wh), f_wh) + t_wh)
    return q_chassis, (force, moment, wheel_moment)


def _corner_partials(m: CarMotion):
    """Partial velocities of each corner's upright, without their structural zeros: ``P_v``
    (4, 3, n_c + 1), the wheel centre's velocity in chassis axes with respect to the
    chassis velocities ``[u, omega, modal rates]`` and the corner's travel rate, and ``P_w``
    (4, 3, n_c - 2), the upright's angular velocity in upright axes with respect to
    ``[omega, modal rates]`` and the travel rate (the chassis's ``u`` does not turn it, and a
    wheel's spin rate moves the wheel only). Each corner's velocities depend on no other
    corner's rates, which :func:`_kane_solve` exploits."""
    sens = m.corners.sens  # d w / d [travel, rack, modes]
    # the wheel centre's velocity in chassis axes: u + omega x r + (dx, dy, travel) rates
    eye = jnp.broadcast_to(jnp.eye(3), (4, 3, 3))
    lever = -jax.vmap(skew)(m.r_rel)
    modal_v = jnp.concatenate([sens[:, :2, 2:], jnp.zeros((4, 1, sens.shape[2] - 2))], axis=1)
    travel_v = jnp.concatenate([sens[:, :2, 0], jnp.ones((4, 1))], axis=1)[:, :, None]
    p_v = jnp.concatenate([eye, lever, modal_v, travel_v], axis=2)
    # the angular velocity: the chassis's plus the angle rates through the rate matrix
    angle_rates = jnp.einsum("kij,kjl->kil", m.e_rel, sens[:, 2:, :])  # (4, 3, 2 + n)
    p_w = jnp.concatenate([jnp.swapaxes(m.a_rel, 1, 2), angle_rates[:, :, 2:], angle_rates[:, :, :1]], axis=2)
    return p_v, p_w


def _inverse_2x2(a):
    """Inverses of 2 x 2 matrices over the leading axis, in closed form."""
    det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
    adj = jnp.stack([jnp.stack([a[:, 1, 1], -a[:, 0, 1]], -1), jnp.stack([-a[:, 1, 0], a[:, 0, 0]], -1)], -2)
    return adj / det[:, None, None]


def _kane_solve(m: CarMotion, m_c, f_c, mass, inertia, spin, f_up, t_up, t_wh):
    """``u_dot`` from Kane's equations with their structure: the chassis block (``m_c``,
    generalised force ``f_c``) coupled to each corner's travel and spin and to nothing else,
    so the four corners' 2 x 2 blocks are eliminated in closed form and the chassis's Schur
    complement (n_c x n_c, symmetric positive definite) is solved by Cholesky. The corner
    terms: upright mass and inertia (4,) (4, 3, 3), wheel spin inertia (4,), the upright's
    force and moment and the wheel's moment (4, 3, upright axes; inertial, gravity and
    applied)."""
    n_c = m_c.shape[0]
    p_v, p_w = _corner_partials(m)
    # the wheel's angular velocity about the upright's y: the upright's (these columns) + its spin rate
    spin_partial = p_w[:, 1, :]
    mass_w = jnp.einsum("kia,kib->kab", p_w, jnp.einsum("kij,kjl->kil", inertia, p_w)) + (
        spin[:, None, None] * spin_partial[:, :, None] * spin_partial[:, None, :])
    # columns [u, omega, modal rates, travel rate, spin rate]: P_v covers the first n_c + 1,
    # P_w and the wheel's spin rate columns 3 to n_c, the spin rate its own
    turned = slice(3, n_c + 1)
    mass_l = (jnp.zeros((4, n_c + 2, n_c + 2), m_c.dtype)
              .at[:, : n_c + 1, : n_c + 1].add(mass[:, None, None] * jnp.einsum("kia,kib->kab", p_v, p_v))
              .at[:, turned, turned].add(mass_w)
              .at[:, turned, n_c + 1].set(spin[:, None] * spin_partial)
              .at[:, n_c + 1, turned].set(spin[:, None] * spin_partial)
              .at[:, n_c + 1, n_c + 1].set(spin))
    force_l = (jnp.zeros((4, n_c + 2), m_c.dtype)
               .at[:, : n_c + 1].add(jnp.einsum("kia,ki->ka", p_v, _mv(m.a_rel, f_up)))
               .at[:, turned].add(jnp.einsum("kia,ki->ka", p_w, t_up + t_wh))
               .at[:, n_c + 1].set(t_wh[:, 1]))
    m_cb, inv_bb = mass_l[:, :n_c, n_c:], _inverse_2x2(mass_l[:, n_c:, n_c:])
    x = jnp.einsum("kab,kbc->kac", m_cb, inv_bb)  # (4, n_c, 2)
    schur = m_c + mass_l[:, :n_c, :n_c].sum(0) - jnp.einsum("kac,kbc->ab", x, m_cb)
    a_c = cho_solve(cho_factor(schur), f_c + force_l[:, :n_c].sum(0) - jnp.einsum("kac,kc->a", x, force_l[:, n_c:]))
    a_b = jnp.einsum("kcd,kd->kc", inv_bb, force_l[:, n_c:] - jnp.einsum("kac,a->kc", m_cb, a_c))
    return jnp.concatenate([a_c, a_b[:, 0], a_b[:, 1]])


# ---- equations -------------------------------------------------------------------------------


class FastDynamics(eqx.Module):
    """The fast car's equations at one state: ``q_dot``, ``u_dot``, ``aux_dot``, the rack
    travel and rate, the force elements' :class:`Kinematics` and ``link_residual`` (m, what
    the corner solve left)."""

    q_dot: Float[Array, " n"]
    u_dot: Float[Array, " n"]
    aux_dot: Float[Array, " na"]
    rack: Float[Array, ""]
    rack_rate: Float[Array, ""]
    kinematics: Kinematics
    link_residual: Float[Array, ""]


def coordinate_rates(car: Car, q, u):
    """``q_dot`` from ``(q, u)``: chassis position rate in global axes, angle rates from the
    body angular velocity (``"zyx"``, the inverse of its rate matrix in closed form), modal,
    travel and spin rates."""
    angles = q[3:6]
    r_dot = rotation_matrix("zyx", angles) @ u[:3]
    pitch, roll = angles[1], angles[2]
    wx, wy, wz = u[3], u[4], u[5]
    sin_roll, cos_roll = sin_cos(roll)
    sin_pitch, cos_pitch = sin_cos(pitch)
    lateral = wy * sin_roll + wz * cos_roll
    angle_rates = jnp.stack([lateral / cos_pitch, wy * cos_roll - wz * sin_roll,
                             wx + lateral * sin_pitch / cos_pitch])
    return jnp.concatenate([r_dot, angle_rates, u[6:]])


def _rack(system, law, t, q, aux, q_dot=None, aux_dot=None):
    value, rate = input_state(system, law, t, q, aux)
    if q_dot is None:
        return value, rate
    return jax.jvp(lambda tt, qq, aa: law.rate(tt, qq, aa), (t, q, aux), (jnp.ones_like(t), q_dot, aux_dot))[1]


def _check_state(car: Car, q, u, aux, elements):
    n = 14 + car.n_modes
    n_aux = sum(len(e.aux_names) for e in elements)
    layout = f"chassis 6 + {car.n_modes} modes, 4 travels, 4 spins"
    for name, x, size, what in (("q", q, n, layout), ("u", u, n, layout), ("aux", aux, n_aux, "the elements' states")):
        if jnp.shape(x) != (size,):
            raise ValueError(f"{name} must hold {size} values ({what}), got shape {jnp.shape(x)}")


def fast_dynamics(car: Car, model: FastModel, q, u, aux, t, inputs, elements) -> FastDynamics:
    """Kane's equations of the fast car at ``(t, q, u, aux)`` (see the module docs).
    ``inputs``: the rack law (a function of time or a :class:`jaxveh.multibody.AbstractInputs`;
    closed-loop laws read the fast car's ``q``)."""
    _check_state(car, q, u, aux, elements)
    system, params, lay = car.system, model.params, _layout(car)
    t = jnp.asarray(t, q.dtype)
    law = as_inputs(inputs)
    rack_v, rack_dot_v = _rack(system, law, t, q, aux)
    rack, rack_rate = rack_v[0], rack_dot_v[0]
    q_dot = coordinate_rates(car, q, u)
    vc, travel_rate, _ = split(car, u)
    # the rack acceleration needs aux_dot, which needs the kinematics: motion at zero first
    m = car_motion(car, model, q, u, rack, rack_rate, jnp.zeros_like(rack))
    x, rots, r_up, a_up, a_wh = _point_kinematics(car, model, lay, m, q, rack)
    xd, om = _point_rates(car, model, lay, m, m.velocity, a_up, q, rack, rack_rate)
    origins, rotations = _body_frames(car, lay, m, r_up, a_up, a_wh)
    kin = Kinematics(t=t, q=q, v=u, u=rack_v, u_dot=rack_dot_v, origins=origins, rotations=rotations, x=x, xd=xd,
                     point_rotations=rots, point_omega=om, modal=_modal_values(car, q))
    # the push-rod suspensions (no auxiliary states) as one four-corner computation
    suspensions, others = split_suspensions(elements)
    forces, torques, aux_dot = element_forces(system, params, others, kin, aux)
    if suspensions is not None:
        forces = forces + suspension_forces(suspensions, kin)
    rack_acc = _rack(system, law, t, q, aux, q_dot, aux_dot)[0] if system.n_inputs else jnp.zeros_like(rack)
    # the rack acceleration enters the corners' velocity-product terms linearly
    m = eqx.tree_at(lambda x: x.corners.w_acc0, m, m.corners.w_acc0 + m.corners.sens[:, :, 1] * rack_acc)

    v_acc, w_acc = _bias(m, vc, travel_rate)
    chassis = params.bodies[0]
    m_c = chassis.mass_matrix(q[6:6 + car.n_modes], system.options)
    quad_el, grav = body_forces(system, params, 0, (m.r_c, m.a_c, q[6:6 + car.n_modes]), vc)
    q_chassis, (f_ap, t_ap, t_ap_wh) = _applied_wrenches(car, model, lay, m, a_up, q, rack, forces, torques)
    _, v_up, w_up, w_wheel = m.velocity
    mass, inertia, spin = model.upright_mass, model.upright_inertia, model.spin_inertia
    g_up = _mv(jnp.swapaxes(_mm(m.a_c[None], m.a_rel), 1, 2), params.gravity[None, :])
    # uprights: m (v_dot + w x v) = F, J w_dot + w x J w = T (c.g. at the wheel centre)
    f_up = mass[:, None] * (g_up - v_acc - jnp.cross(w_up, v_up))
    t_up = -_mv(inertia, w_acc) - jnp.cross(w_up, _mv(inertia, w_up))
    # wheels: rotors about the upright's y axis (angular velocity w_wheel in upright axes)
    h_wh = spin[:, None] * w_wheel * jnp.asarray(_EY)
    t_wh = -spin[:, None] * w_acc * jnp.asarray(_EY) - jnp.cross(w_wheel, h_wh)
    u_dot = _kane_solve(m, m_c, quad_el + grav + q_chassis, mass, inertia, spin, f_up + f_ap, t_up + t_ap,
                        t_wh + t_ap_wh)
    residual = pose_residual(model.geometry, split(car, q)[1], rack, q[6:6 + car.n_modes], m.corners.w)
    return FastDynamics(q_dot=q_dot, u_dot=u_dot, aux_dot=aux_dot, rack=rack, rack_rate=rack_rate, kinematics=kin,
                        link_residual=residual)


def _modal_values(car, q):
    """Modal coordinates of every body (library order): the chassis's, none for the rest."""
    return tuple(q[6:6 + car.n_modes] if name == "chassis" else jnp.zeros((0,)) for name in car.system.body_names)


def _body_frames(car, lay, m: CarMotion, r_up, a_up, a_wh):
    names = car.system.body_names
    origins, rotations = [None] * len(names), [None] * len(names)
    origins[names.index("chassis")], rotations[names.index("chassis")] = m.r_c, m.a_c
    for k in range(4):
        origins[lay["uprights"][k]], rotations[lay["uprights"][k]] = r_up[k], a_up[k]
        origins[lay["wheels"][k]], rotations[lay["wheels"][k]] = r_up[k], a_wh[k]
    return jnp.stack(origins), jnp.stack(rotations)


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


def fast_state_from_library(car: Car, q_lib, y_lib, aux) -> FastState:
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

