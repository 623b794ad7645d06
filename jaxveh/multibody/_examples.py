"""Built-in example systems: the compound planar double pendulum of thesis section 5.7, a
planar four-bar linkage and a flexible pendulum made of a free-free FE beam (section
5.4.2). Each builder returns ``(system, params)``. The vehicle corner (quarter car) lives in
:mod:`jaxveh.vehicle`: nothing here knows about vehicles.
"""

import jax.numpy as jnp
import numpy as np

from .._core import GRAVITY
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
            [
                J1 + a1**2 * m1 + J2 + a2**2 * m2 + l1**2 * m2 + 2 * a2 * l1 * m2 * c2,
                J2 + a2**2 * m2 + a2 * l1 * m2 * c2,
            ],
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
