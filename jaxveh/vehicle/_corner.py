"""One corner of the chapter-6 car from its hard points (section 6.1, Tables 6.2-6.3,
Appendix B): the double-wishbone quarter car on a fixed chassis, its kinematics sweep and
its wheel angles. Built with :mod:`jaxveh.multibody` as any user of the library would.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._core import GRAVITY, float_field, is_concrete
from .._trig import arctan2
from ..multibody import (
    AssemblyError,
    System,
    SystemBuilder,
    SystemParams,
    assembly_message,
    body_poses,
    point_force,
    rotation_matrix,
    solve_assembly,
)
from ..params import HARD_POINT_NAMES, load_vehicle_data

#: Wheel-centre height (m) of the quarter car: the thesis's unsprung c.g. height. The
#: wheel centre sits at x = 0 (axle centre) and y = track / 2 in the corner frame.
WHEEL_CENTRE_HEIGHT = 0.255
#: Links of the double wishbone (Table 6.3): (name, chassis point, upright point).
QUARTER_CAR_LINKS = (
    ("lower_rear", "A", "C"),
    ("lower_front", "B", "C"),
    ("upper_rear", "E", "H"),
    ("upper_front", "F", "H"),
    ("track_rod", "L", "M"),
)
#: Chassis-side points of the corner: the link pivots and the push-rod path's rocker axis
#: (P, Q) and spring mount (T).
_CHASSIS_POINTS = ("A", "B", "E", "F", "L", "P", "Q", "T")
_UPRIGHT_POINTS = ("C", "H", "M")


def _hard_point(points, name):
    return points[HARD_POINT_NAMES.index(name)]


def quarter_car(data=None, axle: str = "front") -> tuple[System, SystemParams]:
    """Front-left (or rear-left) quarter car from the Appendix B hard points.

    Chassis fixed (ground, corner frame of ``jaxveh.params``: origin on the ground below the
    axle centre in the vehicle centre plane, x forward, y left, z up). The upright (unsprung
    mass, toe-camber-spin sequence ``"zxy"``, reference point and c.g. at the wheel centre
    ``W = (0, track/2, WHEEL_CENTRE_HEIGHT)``) is held by the five links of Table 6.3; the
    wheel spins on it (tree revolute joint about the upright y axis; its mass is lumped in
    the upright, it carries the spin inertia). The steering input ``rack`` (m) moves the
    inner track-rod joint L along the chassis y axis: the rack carries L (Table 6.2 puts L on
    the sprung side); the thesis's wording "moves points M" describes the same rack.
    Independent velocities: ``upright.uz`` (bump) and ``wheel.theta_dot`` (spin).
    """
    data = load_vehicle_data() if data is None else data
    hp = (data.hard_points_front if axle == "front" else data.hard_points_rear).points
    unsprung = data.unsprung_front if axle == "front" else data.unsprung_rear
    w = np.asarray(quarter_car_wheel_centre(data, axle))
    b = SystemBuilder(gravity=(0.0, 0.0, -GRAVITY))
    b.add_input("rack")
    b.add_rigid_body("upright", float(unsprung.body.mass), np.asarray(unsprung.body.inertia), rotation="zxy")
    spin = float(unsprung.wheel_spin_inertia)
    b.add_rigid_body("wheel", 0.0, np.diag([0.0, spin, 0.0]), parent="upright", revolute=((0, 0, 0), (0, 1, 0)))
    for name in _CHASSIS_POINTS:
        kwargs = {"input": "rack", "input_direction": (0.0, 1.0, 0.0)} if name == "L" else {}
        b.add_point(name, "ground", np.asarray(_hard_point(hp, name)), **kwargs)
    for name in _UPRIGHT_POINTS:
        b.add_point(name, "upright", np.asarray(_hard_point(hp, name)) - w)
    b.add_point("W", "upright", (0.0, 0.0, 0.0))  # wheel centre, where road loads are applied
    for link, p, q in QUARTER_CAR_LINKS:
        length = np.linalg.norm(np.asarray(_hard_point(hp, p)) - np.asarray(_hard_point(hp, q)))
        b.add_link(link, p, q, length)
    b.add_independent("upright", "uz")
    b.add_independent("wheel", "theta_dot")
    return b.build()


def quarter_car_wheel_centre(data=None, axle: str = "front"):
    """Wheel centre (m, corner frame) of :func:`quarter_car`: ``(0, track / 2, 0.255)``."""
    data = load_vehicle_data() if data is None else data
    track = data.track_front if axle == "front" else data.track_rear
    return jnp.stack([jnp.zeros_like(track), track / 2.0, jnp.full_like(track, WHEEL_CENTRE_HEIGHT)])


def quarter_car_design_q(system: System, wheel_centre=None):
    """Design-position coordinates: upright at the wheel centre (default: front axle of the
    shipped Appendix B data), zero angles, zero spin."""
    w = quarter_car_wheel_centre() if wheel_centre is None else jnp.asarray(wheel_centre)
    return jnp.concatenate([w, jnp.zeros((system.n_q - 3,))])


def quarter_car_with_hard_points(system: System, params: SystemParams, hard_points, wheel_centre) -> SystemParams:
    """Parameters for new hard points (14 x 3, m, corner frame) and wheel centre (m): point
    positions and link lengths recomputed with JAX, so gradients flow to the hard points."""

    hard_points, w = jnp.asarray(hard_points), jnp.asarray(wheel_centre)
    points = list(params.points)
    for name in _CHASSIS_POINTS:
        k = system.point_index(name)
        points[k] = eqx.tree_at(lambda p: p.position, points[k], _hard_point(hard_points, name))
    for name in _UPRIGHT_POINTS:
        k = system.point_index(name)
        points[k] = eqx.tree_at(lambda p: p.position, points[k], _hard_point(hard_points, name) - w)
    joints = list(params.joints)
    for link, p, q in QUARTER_CAR_LINKS:
        k = system.joint_names.index(link)
        length = jnp.linalg.norm(_hard_point(hard_points, p) - _hard_point(hard_points, q))
        joints[k] = eqx.tree_at(lambda j: j.length, joints[k], length)
    return eqx.tree_at(lambda s: (s.points, s.joints), params, (tuple(points), tuple(joints)))


class WheelRate(eqx.Module):
    """Vertical spring-damper between the chassis and the wheel centre ``W`` (the quarter car's
    suspension reduced to a wheel rate): stiffness ``k`` (N/m), damping ``c`` (Ns/m), force
    free at wheel-centre height ``z0`` (m); plus a constant vertical load ``fz`` (N)."""

    k: jnp.ndarray = float_field()
    c: jnp.ndarray = float_field()
    z0: jnp.ndarray = float_field()
    fz: jnp.ndarray = float_field(default=0.0)

    def force(self, system: System, params: SystemParams, q, v):
        """Generalised force (``v`` coordinates) on the upright."""

        a = rotation_matrix(system.sequence[0], q[3:6])
        z_dot = (a @ v[:3])[2]
        fz = self.fz - self.k * (q[2] - self.z0) - self.c * z_dot
        zero = jnp.zeros_like(fz)
        return point_force(system, params, q, "W", jnp.stack([zero, zero, fz]))

    def energy(self, q):
        """Spring energy (J) plus the potential of the constant load."""
        return 0.5 * self.k * (q[2] - self.z0) ** 2 - self.fz * q[2]


def wheel_angles(system: System, params: SystemParams, q):
    """Camber and toe-in (rad) of the left wheel from its spin axis ``a`` (global):
    camber = atan2(-a_z, a_y) (positive top outwards), toe-in = atan2(a_x, a_y)."""

    a = body_poses(system, params, q)[system.body_names.index("upright")][1][:, 1]
    return arctan2(-a[2], a[1]), arctan2(a[0], a[1])


def quarter_car_kinematics(
    system: System, params: SystemParams, bump, rack, wheel_centre=None, iterations=25, throw: bool = True
):
    """Assemble the quarter car at wheel-centre vertical travel ``bump`` (m) and rack travel
    ``rack`` (m); returns ``(q, outputs)`` with camber and toe-in (rad), wheel-centre
    position (m), track (m, twice the wheel-centre y), the max constraint residual and
    ``ok`` (the travel was reached on the design branch).

    A travel that cannot be reached (or a solve that leaves the design branch) raises
    :class:`AssemblyError` for concrete values with ``throw``; under ``jit`` / ``vmap``
    (sweeps) nothing raises: the outputs stay finite and ``ok`` is False at that point, so
    callers must honour the flag.
    """

    q0 = quarter_car_design_q(system, wheel_centre)
    iz = system.q_index("upright", "z")
    q_guess = q0.at[iz].add(bump)
    fixed = (iz, system.q_index("wheel", "theta"))
    rack = jnp.asarray(rack, jnp.float64)
    inputs = lambda t: jnp.reshape(rack, (1,))  # noqa: E731
    result = solve_assembly(system, params, q_guess, fixed, 0.0, inputs, iterations)
    if throw and is_concrete(result.ok) and not bool(result.ok):
        raise AssemblyError(
            f"quarter car at bump {float(bump) * 1e3:g} mm, rack {float(rack) * 1e3:g} mm: "
            + assembly_message(system, result)
        )
    q = result.q
    camber, toe = wheel_angles(system, params, q)
    wc = q[:3]
    return q, {
        "camber": camber,
        "toe": toe,
        "wheel_centre": wc,
        "track": 2.0 * wc[1],
        "residual": result.residual,
        "ok": result.ok,
    }
