"""Built-in example systems: the compound planar double pendulum of thesis section 5.7, a
planar four-bar linkage, a quarter car from the Appendix B hard points (section 6.1) and a
flexible pendulum made of a free-free FE beam (section 5.4.2).

These are examples *of* the library; the library itself (``jaxveh.multibody``) knows
nothing about vehicles. Each builder returns ``(system, params)``.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._core import GRAVITY, is_concrete
from ._errors import AssemblyError
from ..params import HARD_POINT_NAMES, ParameterError, float_field, load_vehicle_data

from ._rotations import rotation_matrix
from ._system import System, SystemBuilder, SystemParams

# ---------------------------------------------------------------------------------------
# Double pendulum (section 5.7, Figure 5.2)
# ---------------------------------------------------------------------------------------

#: Default parameters of the double pendulum (SI): masses (kg), inertias about the c.g.
#: (kg m^2), first link length ``l1`` (m), pivot-to-c.g. distances ``a1``, ``a2`` (m),
#: gravity ``g`` (m/s^2). Uniform slender bars of 1.0 m and 0.8 m.
DOUBLE_PENDULUM_DEFAULTS = {
    "m1": 2.0,
    "m2": 1.5,
    "J1": 2.0 * 1.0**2 / 12.0,
    "J2": 1.5 * 0.8**2 / 12.0,
    "l1": 1.0,
    "a1": 0.5,
    "a2": 0.4,
    "g": GRAVITY,
}


def double_pendulum(values: dict | None = None, tree: bool = False) -> tuple[System, SystemParams]:
    """The compound planar double pendulum of section 5.7 in the y-z plane.

    As in the thesis's listing: two free rigid bodies B1, B2 (six coordinates each), points
    P1 = (0, 0, a1) and P2 = (0, 0, -(l1 - a1)) on B1, P3 = (0, 0, a2) on B2, revolute joints
    C1 (ground pivot, P1) and C2 (P2, P3) about x, B2 recursive on B1, and the independent
    velocities ``B1.wx`` (theta1_dot, absolute) and ``B2.wx`` (theta2_dot, relative).
    ``tree=True`` builds the same pendulum with tree revolute joints and no constraints.
    """
    v = {**DOUBLE_PENDULUM_DEFAULTS, **(values or {})}
    b = SystemBuilder(gravity=(0.0, 0.0, -v["g"]))
    j1, j2 = np.eye(3) * v["J1"], np.eye(3) * v["J2"]
    if tree:
        b.add_rigid_body("B1", v["m1"], j1, cg=(0.0, 0.0, -v["a1"]), parent="ground", revolute=((0, 0, 0), (1, 0, 0)))
        b.add_rigid_body(
            "B2", v["m2"], j2, cg=(0.0, 0.0, -v["a2"]), parent="B1", revolute=((0, 0, -v["l1"]), (1, 0, 0))
        )
        b.add_independent("B1", "theta_dot")
        b.add_independent("B2", "theta_dot")
        return b.build()
    b.add_rigid_body("B1", v["m1"], j1)
    b.add_rigid_body("B2", v["m2"], j2, parent="B1")
    b.add_point("P0", "ground", (0.0, 0.0, 0.0))
    b.add_point("P1", "B1", (0.0, 0.0, v["a1"]))
    b.add_point("P2", "B1", (0.0, 0.0, -(v["l1"] - v["a1"])))
    b.add_point("P3", "B2", (0.0, 0.0, v["a2"]))
    b.add_revolute("C1", "P0", "P1", axis_i=(1.0, 0.0, 0.0))
    b.add_revolute("C2", "P2", "P3", axis_i=(1.0, 0.0, 0.0))
    b.add_independent("B1", "wx")
    b.add_independent("B2", "wx")
    return b.build()


def double_pendulum_state(system: System, params: SystemParams, theta, theta_dot):
    """``(q, z)`` of :func:`double_pendulum` at angles ``theta = (theta1, theta2)`` (rad;
    theta1 absolute from the downward vertical, theta2 relative) and their rates (rad/s)."""
    theta = jnp.asarray(theta, jnp.float64)
    z = jnp.asarray(theta_dot, jnp.float64)
    if system.tree_kind[0] != "free":
        return theta, z
    p1 = params.points[system.point_index("P1")].position
    p2 = params.points[system.point_index("P2")].position
    p3 = params.points[system.point_index("P3")].position
    zero = jnp.zeros((), jnp.float64)
    ang1 = jnp.stack([zero, zero, theta[0]])
    ang2 = jnp.stack([zero, zero, theta[0] + theta[1]])
    a1, a2 = rotation_matrix("zyx", ang1), rotation_matrix("zyx", ang2)
    r1 = -a1 @ p1
    r2 = r1 + a1 @ p2 - a2 @ p3
    return jnp.concatenate([r1, ang1, r2, ang2]), z


def double_pendulum_closed_form(theta, theta_dot, values: dict | None = None):
    """Thesis section 5.7: ``(M, Qi, Qe)`` in (theta1 absolute, theta2 relative)."""
    v = {**DOUBLE_PENDULUM_DEFAULTS, **(values or {})}
    m1, m2, J1, J2, l1, a1, a2, g = (v[k] for k in ("m1", "m2", "J1", "J2", "l1", "a1", "a2", "g"))
    t1, t2 = theta
    w1, w2 = theta_dot
    c2, s2 = np.cos(t2), np.sin(t2)
    m = np.array(
        [
            [J1 + a1**2 * m1 + J2 + a2**2 * m2 + l1**2 * m2 + 2 * a2 * l1 * m2 * c2, J2 + a2**2 * m2 + a2 * l1 * m2 * c2],
            [J2 + a2**2 * m2 + a2 * l1 * m2 * c2, J2 + a2**2 * m2],
        ]
    )
    qi = np.array([a2 * l1 * m2 * w2**2 * s2 + 2 * a2 * l1 * m2 * w1 * w2 * s2, -a2 * l1 * m2 * w1**2 * s2])
    qe = np.array(
        [-(a1 * m1 + l1 * m2) * g * np.sin(t1) - a2 * m2 * g * np.sin(t1 + t2), -a2 * m2 * g * np.sin(t1 + t2)]
    )
    return m, qi, qe


# ---------------------------------------------------------------------------------------
# Four-bar linkage
# ---------------------------------------------------------------------------------------

#: Four-bar linkage in the y-z plane (SI): ground pivots at y = 0 and y = ``ground``, bar
#: lengths ``crank``, ``coupler``, ``rocker`` (m), uniform bars of mass ``m_*`` (kg).
FOUR_BAR_DEFAULTS = {
    "ground": 0.4,
    "crank": 0.1,
    "coupler": 0.35,
    "rocker": 0.25,
    "m_crank": 0.5,
    "m_coupler": 1.0,
    "m_rocker": 0.8,
    "g": GRAVITY,
}


def _bar_inertia(m, length):
    """Inertia (kg m^2) of a slender bar along body y about its c.g.; thin in x and z."""
    j = m * length**2 / 12.0
    return np.diag([j, 1e-6 * j, j])


def four_bar(values: dict | None = None) -> tuple[System, SystemParams]:
    """A planar four-bar linkage (closed loop) in the y-z plane under gravity -z.

    Crank and rocker turn on tree revolute joints (about x) at the ground pivots, the coupler
    on a tree revolute joint at the crank tip; the loop is closed by a pin between the coupler
    end and the rocker tip (``spherical`` joint on the in-plane y, z components only; the x
    component is identically satisfied by the planar tree). One degree of freedom: the crank
    rate ``crank.theta_dot``. Body axes: bar along body y, angles from the +y axis.
    """
    v = {**FOUR_BAR_DEFAULTS, **(values or {})}
    x_axis = (1.0, 0.0, 0.0)
    b = SystemBuilder(gravity=(0.0, 0.0, -v["g"]))
    for name, parent, offset, length, mass in (
        ("crank", "ground", (0.0, 0.0, 0.0), v["crank"], v["m_crank"]),
        ("coupler", "crank", (0.0, v["crank"], 0.0), v["coupler"], v["m_coupler"]),
        ("rocker", "ground", (0.0, v["ground"], 0.0), v["rocker"], v["m_rocker"]),
    ):
        b.add_rigid_body(
            name, mass, _bar_inertia(mass, length), cg=(0.0, length / 2, 0.0), parent=parent, revolute=(offset, x_axis)
        )
    b.add_point("coupler_end", "coupler", (0.0, v["coupler"], 0.0))
    b.add_point("rocker_tip", "rocker", (0.0, v["rocker"], 0.0))
    b.add_spherical("pin", "coupler_end", "rocker_tip", components="yz")
    b.add_independent("crank", "theta_dot")
    return b.build()


def four_bar_angles(crank_angle, values: dict | None = None):
    """Closed-form loop closure: absolute (coupler, rocker) angles (rad) for a crank angle
    (rad), open assembly branch (rocker tip above the ground line)."""
    v = {**FOUR_BAR_DEFAULTS, **(values or {})}
    a = v["crank"] * np.array([np.cos(crank_angle), np.sin(crank_angle)])
    o_b = np.array([v["ground"], 0.0])
    d = o_b - a
    dist = np.linalg.norm(d)
    # circle intersection: point E with |E - A| = coupler, |E - O_B| = rocker
    l2, l3 = v["coupler"], v["rocker"]
    along = (l2**2 - l3**2 + dist**2) / (2 * dist)
    h = np.sqrt(l2**2 - along**2)
    e = a + along * d / dist + h * np.array([-d[1], d[0]]) / dist
    coupler = np.arctan2(e[1] - a[1], e[0] - a[0])
    rocker = np.arctan2(e[1] - o_b[1], e[0] - o_b[0])
    return coupler, rocker


# ---------------------------------------------------------------------------------------
# Quarter car (section 6.1, Tables 6.2-6.3, Appendix B hard points)
# ---------------------------------------------------------------------------------------

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
_CHASSIS_POINTS = ("A", "B", "E", "F", "L")
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
        from ._dynamics import point_force

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
    from ._kinematics import body_poses

    a = body_poses(system, params, q)[system.body_names.index("upright")][1][:, 1]
    return jnp.arctan2(-a[2], a[1]), jnp.arctan2(a[0], a[1])


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
    from ._simulate import assembly_message, solve_assembly

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


# ---------------------------------------------------------------------------------------
# Flexible pendulum (section 5.4.2)
# ---------------------------------------------------------------------------------------


def flexible_beam(length=1.0, n_modes=2, diameter=0.012, thickness=0.001, beta=0.0, n_elements=10):
    """A free-free straight steel tube from the FE module (:func:`jaxveh.fe.straight_beam_body`),
    origin at its ``start`` end, x along the tube; beta is stiffness-proportional damping (s)."""
    from ..fe import straight_beam_body

    return straight_beam_body(length, n_modes, n_elements, diameter, thickness, beta)


def flexible_pendulum(modal=None, coupling=1.0, pinned: bool = True, gravity=GRAVITY) -> tuple[System, SystemParams]:
    """A flexible beam (modal body, floating frame) swinging in the x-z plane.

    ``pinned``: the beam's ``start`` point is held on the ground origin by a revolute joint
    about y (independent velocities ``beam.wy`` and every modal velocity); otherwise the beam
    floats freely (all six rigid and the modal velocities independent). Rotation sequence
    ``"zxy"`` so that the swing angle (about y) is the innermost, unbounded angle.
    """
    modal = flexible_beam() if modal is None else modal
    b = SystemBuilder(gravity=(0.0, 0.0, -gravity))
    b.add_flexible_body("beam", modal, coupling=coupling, rotation="zxy")
    b.add_modal_point("start", "beam", "start")
    b.add_modal_point("end", "beam", "end")
    if pinned:
        b.add_point("pivot", "ground", (0.0, 0.0, 0.0))
        b.add_revolute("pin", "pivot", "start", axis_i=(0.0, 1.0, 0.0))
        b.add_independent("beam", "wy")
    else:
        for name in ("ux", "uy", "uz", "wx", "wy", "wz"):
            b.add_independent("beam", name)
    for k in range(modal.n_modes):
        b.add_independent("beam", f"p{k}_dot")
    return b.build()


def flexible_pendulum_state(system: System, angle=0.0, p0=None):
    """``(q, z)``: beam start at the origin, swing angle ``angle`` (rad, about y, 0 =
    horizontal along +x), modal coordinates ``p0``, at rest."""
    nm = system.n_modes[0]
    p = jnp.zeros((nm,)) if p0 is None else jnp.asarray(p0, jnp.float64)
    q = jnp.concatenate([jnp.zeros((5,)), jnp.reshape(jnp.asarray(angle, jnp.float64), (1,)), p])
    return q, jnp.zeros((system.n_dof,))


# ---------------------------------------------------------------------------------------
# Inspection (the thesis's "symbolic inspection" of M, Qi, R, done numerically)
# ---------------------------------------------------------------------------------------

#: Examples known to :func:`inspect_example`, with the meaning of their ``q`` / ``qdot``.
EXAMPLES = {
    "double-pendulum": ("theta1 (rad, absolute), theta2 (rad, relative)", "theta1_dot, theta2_dot (rad/s)"),
    "four-bar": ("crank angle (rad, from +y)", "crank rate (rad/s)"),
    "quarter-car": ("bump travel (m), rack travel (m)", "bump rate (m/s), wheel spin rate (rad/s)"),
    "flexible-pendulum": ("swing angle (rad), modal coordinates p0, p1", "swing rate (rad/s), modal rates"),
}
_DEFAULT_Q = {
    "double-pendulum": ((0.0, 0.0), (0.0, 0.0)),
    "four-bar": ((0.7,), (0.0,)),
    "quarter-car": ((0.0, 0.0), (0.0, 0.0)),
    "flexible-pendulum": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
}


def _example_state(name, q, qdot, values):
    """``(system, params, q_full, z, inputs, param_values)`` for an example at (q, qdot)."""
    if name == "double-pendulum":
        unknown = sorted(set(values) - set(DOUBLE_PENDULUM_DEFAULTS))
        if unknown:
            raise ParameterError(f"unknown --param {unknown}; allowed {sorted(DOUBLE_PENDULUM_DEFAULTS)}")
        v = {**DOUBLE_PENDULUM_DEFAULTS, **values}
        for k in ("m1", "m2", "l1"):
            if not v[k] > 0.0:
                raise ParameterError(f"--param {k}={v[k]:g} must be > 0")
        for k in ("J1", "J2"):
            if not v[k] >= 0.0:
                raise ParameterError(f"--param {k}={v[k]:g} must be >= 0")
        system, params = double_pendulum(v)
        qf, z = double_pendulum_state(system, params, q, qdot)
        return system, params, qf, z, None, v
    if name == "four-bar":
        unknown = sorted(set(values) - set(FOUR_BAR_DEFAULTS))
        if unknown:
            raise ParameterError(f"unknown --param {unknown}; allowed {sorted(FOUR_BAR_DEFAULTS)}")
        v = {**FOUR_BAR_DEFAULTS, **values}
        system, params = four_bar(v)
        coupler, rocker = four_bar_angles(q[0], v)
        qf = jnp.asarray([q[0], coupler - q[0], rocker])
        return system, params, qf, jnp.asarray(qdot, jnp.float64), None, v
    if values:
        raise ParameterError(f"example {name!r} takes no --param")
    if name == "quarter-car":
        system, params = quarter_car()
        qf, _ = quarter_car_kinematics(system, params, q[0], q[1])
        rack = jnp.asarray(q[1], jnp.float64)
        inputs = lambda t: jnp.reshape(rack, (1,))  # noqa: E731
        return system, params, qf, jnp.asarray(qdot, jnp.float64), inputs, {}
    system, params = flexible_pendulum()
    qf, _ = flexible_pendulum_state(system, q[0], q[1:])
    return system, params, qf, jnp.asarray(qdot, jnp.float64), None, {}


def inspect_example(name: str, q=None, qdot=None, values: dict | None = None) -> dict:
    """Reduced mass matrix, reduced internal and external forces and ``R`` of a built-in
    example at independent positions ``q`` and velocities ``qdot`` (see :data:`EXAMPLES`).

    ``internal_forces``: gyroscopic / Coriolis / centrifugal / elastic / damping forces
    reduced to the independent velocities, ``R^T T^T (Q_v + Q_e - M (T_dot y + T S c))``;
    ``external_forces``: gravity (and applied loads) reduced, ``R^T T^T Q_ext``. For the
    double pendulum these are the ``M``, ``Qi``, ``Qe`` printed in thesis section 5.7.
    """
    from ._projection import dynamics

    if name not in EXAMPLES:
        raise ParameterError(f"unknown example {name!r}; choose one of {sorted(EXAMPLES)}")
    dq, dqd = _DEFAULT_Q[name]
    q = tuple(dq) if q is None else tuple(float(x) for x in q)
    qdot = tuple(dqd) if qdot is None else tuple(float(x) for x in qdot)
    if len(q) != len(dq):
        raise ParameterError(f"--q for {name} takes {len(dq)} values: {EXAMPLES[name][0]}; got {len(q)}")
    if len(qdot) != len(dqd):
        raise ParameterError(f"--qdot for {name} takes {len(dqd)} values: {EXAMPLES[name][1]}; got {len(qdot)}")
    system, params, qf, z, inputs, used = _example_state(name, q, qdot, dict(values or {}))
    dyn = dynamics(system, params, qf, z, 0.0, inputs)
    return {
        "example": name,
        "q": list(q),
        "qdot": list(qdot),
        "independent_velocities": [system.y_names[k] for k in system.independent],
        "mass_matrix": np.asarray(dyn.mass_matrix).tolist(),
        "internal_forces": np.asarray(dyn.internal_forces).tolist(),
        "external_forces": np.asarray(dyn.external_forces).tolist(),
        "R": np.asarray(dyn.projection.R).tolist(),
        "joint_velocity_names": list(system.y_names),
        "constraint_residual": float(np.max(np.abs(np.asarray(dyn.projection.phi)), initial=0.0)),
        "params": {k: float(v) for k, v in used.items()},
    }
