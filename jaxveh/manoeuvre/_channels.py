"""Named output channels of a manoeuvre, computed from what both forms of the car share: the
force elements' :class:`jaxveh.multibody.Kinematics`, their auxiliary states and the
chassis frame's body velocities and accelerations. One function for both forms, so the
fast car and the library car are compared channel by channel on the same definitions."""

import jax.numpy as jnp
import numpy as np

from .._core import GRAVITY
from .._trig import arcsin, arctan2
from ..vehicle import CORNERS, Car, Powertrain, PushrodSuspension, TyreContact, chassis_twist, wheel_centres

#: Channel name -> unit (per corner channels hold FL, FR, RL, RR on their last axis).
UNITS = {
    "steering_wheel_angle": "deg",
    "speed": "m/s",
    "x": "m",
    "y": "m",
    "heading": "deg",
    "ax": "g",
    "ay": "g",
    "yaw_rate": "deg/s",
    "sideslip": "deg",
    "roll": "deg",
    "pitch": "deg",
    "twist": "deg",
    "modes": "1",
    "fz": "N",
    "fx": "N",
    "fy": "N",
    "slip_angle": "deg",
    "slip_ratio": "1",
    "camber": "deg",
    "road_height": "m",
    "travel": "m",
    "road_wheel_angle": "deg",
    "spring_length": "m",
    "spring_force": "N",
    "wheel_torque": "Nm",
}
#: The channels of the car's place and heading on the ground (not states of a steady turn).
PATH_CHANNELS = ("x", "y", "heading")


def _aux_slices(elements):
    out, k = [], 0
    for e in elements:
        out.append(slice(k, k + len(e.aux_names)))
        k += len(e.aux_names)
    return out


def _element(elements, kind):
    return [(e, s) for e, s in zip(elements, _aux_slices(elements)) if isinstance(e, kind)]


def _wheel_torques(car: Car, elements: tuple, kin, aux):
    """Drive (positive) and brake (negative) torque on each wheel (N m, FL, FR, RL, RR) from
    the powertrain, zeros without one."""
    out = jnp.zeros(4)
    hubs = [car.system.point_index(f"{c}.hub") for c in CORNERS]
    for e, s in _element(elements, Powertrain):
        drive, brake = e.split(e.control(kin, aux[s])[0])
        for points, torques in ((e.wheels, drive), (e.brake_wheels, brake)):
            for k, point in enumerate(points):
                out = out.at[hubs.index(point)].add(torques[k])
    return out


def car_channels(car: Car, elements: tuple, kin, aux, chassis_velocity, chassis_acceleration, steering_angle):
    """The channels of :data:`UNITS` at one state. ``chassis_velocity``: the chassis frame's
    body velocities ``(u, omega)`` (m/s, rad/s, chassis axes) and ``chassis_acceleration``
    their time derivatives; ``steering_angle`` in rad. Accelerations and sideslip are those
    of the sprung mass's c.g. on the undeformed chassis frame; ``x``, ``y`` its position on
    the ground (m, from the start) and ``heading`` the chassis x axis's direction (deg)."""
    sys = car.system
    c = sys.body_names.index("chassis")
    r_c, a_c = kin.origins[c], kin.rotations[c]
    v, w = chassis_velocity[:3], chassis_velocity[3:6]
    v_dot, w_dot = chassis_acceleration[:3], chassis_acceleration[3:6]
    cg_global = kin.x[sys.point_index("chassis.cg")]
    cg = a_c.T @ (cg_global - r_c)
    v_cg = v + jnp.cross(w, cg)
    a_cg = v_dot + jnp.cross(w, v) + jnp.cross(w_dot, cg) + jnp.cross(w, jnp.cross(w, cg))
    modes = kin.modal[c]
    uprights = np.asarray([sys.body_names.index(f"{k}.upright") for k in CORNERS])
    rel = jnp.einsum("ji,kjl->kil", a_c, kin.rotations[uprights])
    centre = jnp.einsum("ji,kj->ki", a_c, kin.origins[uprights] - r_c[None, :])
    (tyres, tyre_aux), = _element(elements, TyreContact)
    _, _, _, tyre = tyres.evaluate(kin, aux[tyre_aux])
    lengths, forces = [], []
    for e, _ in _element(elements, PushrodSuspension):
        (length, _), (rate, _) = e.states(kin)
        lengths.append(length)
        forces.append(e.spring_forces(length, rate))
    deg = 180.0 / jnp.pi
    return {
        "steering_wheel_angle": steering_angle * deg,
        "speed": jnp.hypot(v_cg[0], v_cg[1]),
        "x": cg_global[0],
        "y": cg_global[1],
        "heading": arctan2(a_c[1, 0], a_c[0, 0]) * deg,
        "ax": a_cg[0] / GRAVITY,
        "ay": a_cg[1] / GRAVITY,
        "yaw_rate": w[2] * deg,
        "sideslip": arctan2(v_cg[1], v_cg[0]) * deg,
        "roll": arctan2(a_c[2, 1], a_c[2, 2]) * deg,
        "pitch": -arcsin(a_c[2, 0]) * deg,
        "twist": chassis_twist(car, modes) * deg,
        "modes": modes,
        "fz": tyre["fz"],
        "fx": tyre["fx"],
        "fy": tyre["fy"],
        "slip_angle": tyre["alpha"] * deg,
        "slip_ratio": tyre["kappa"],
        "camber": tyre["gamma"] * deg,
        "road_height": tyre["road_height"],
        "travel": centre[:, 2] - wheel_centres(car.params.vehicle)[:, 2],
        "road_wheel_angle": arctan2(-rel[:, 0, 1], rel[:, 1, 1]) * deg,
        "spring_length": jnp.concatenate(lengths),
        "spring_force": jnp.concatenate(forces),
        "wheel_torque": _wheel_torques(car, elements, kin, aux),
    }
