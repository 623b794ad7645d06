"""The 9-body topology of the flexible-chassis vehicle (thesis section 6.1), shared by the
multibody benchmarks (``bench_multibody.py``, ``bench_engine.py``).

FE chassis as a free modal body (6 modes by default), four uprights on five links each
(Table 6.3) with the Appendix B hard points, four wheels on tree revolute joints, a rack
input moving both front L points. 9 bodies, 20 link constraints, 20 independent velocities.
Benchmark only: the vehicle itself (rockers, Pacejka tyres) is built elsewhere.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from jaxveh import multibody as mb
from jaxveh.vehicle import QUARTER_CAR_LINKS, WHEEL_CENTRE_HEIGHT

CORNERS = ("front_left", "front_right", "rear_left", "rear_right")
#: Chassis pivots whose FE mode shapes carry the (off-mesh) spring mount above each wheel.
SPRING_MOUNT_NODES = ("A", "B", "E", "F")
#: Height of the spring mount above the wheel centre (m); the spring is vertical.
SPRING_MOUNT_HEIGHT = 0.30


def sprung_rigid_part(modal, data):
    """The modal body with its rigid part (mass, centre of mass, inertia about the body
    origin) replaced by the Table B.1 sprung mass, as the thesis does for the chassis
    (section 6.1: rigid part of the sprung-mass matrix from the vehicle data, deformation
    from the FE modes). Sprung c.g. at ``(0, 0, h_cg)`` in the vehicle frame (m)."""
    m = jnp.asarray(data.sprung.mass, jnp.float64)
    c = jnp.asarray([0.0, 0.0, float(data.h_cg)])
    j_origin = jnp.asarray(data.sprung.inertia) + m * (jnp.dot(c, c) * jnp.eye(3) - jnp.outer(c, c))
    return eqx.tree_at(lambda b: (b.invariants.mass, b.invariants.c0, b.invariants.J0), modal, (m, c, j_origin))


def vehicle_topology(n_modes: int = 6, damping_ratio: float = 0.025, sprung_mass: bool = False,
                     force_points: bool = False):
    """``(system, params, q_design)`` of the 9-body vehicle topology.

    ``damping_ratio``: modal damping of every chassis mode (thesis section 7.3: 2.5 %).
    ``sprung_mass``: the chassis's rigid part is the Table B.1 sprung mass (225 kg) instead
    of the bare FE frame (23.6 kg), see :func:`sprung_rigid_part`.
    ``force_points``: also add, per corner, ``{corner}.spring_top`` on the chassis
    ``SPRING_MOUNT_HEIGHT`` above the wheel centre (translational and rotational mode
    shapes: the mean of those of the wishbone pivots ``SPRING_MOUNT_NODES``, a rigid
    bracket spread over them), and on the upright ``{corner}.W`` (wheel centre) and
    ``{corner}.contact`` (``WHEEL_CENTRE_HEIGHT`` below it), for springs and tyres.

    ``q_design``: design position (chassis frame on the vehicle-frame origin, uprights at the
    wheel centres, zero angles, modes and spin), which closes every loop at zero rack.
    """
    from jaxveh import fe
    from jaxveh.params import HARD_POINT_NAMES, hard_points_vehicle_frame, load_vehicle_data

    data = load_vehicle_data()
    hp = hard_points_vehicle_frame(data)
    modal = fe.frame_modal_body(fe.load_frame(), n_modes, damping_ratio=damping_ratio)
    if sprung_mass:
        modal = sprung_rigid_part(modal, data)
    b = mb.SystemBuilder()
    b.add_input("rack")
    b.add_flexible_body("chassis", modal)
    q = [jnp.zeros(6 + n_modes)]
    for corner in CORNERS:
        pts = np.asarray(hp[corner])
        front = corner.startswith("front")
        track = float(data.track_front if front else data.track_rear)
        x = float(data.a) if front else -float(data.b)
        w = np.array([x, track / 2 * (1 if corner.endswith("left") else -1), WHEEL_CENTRE_HEIGHT])
        ub = data.unsprung_front if front else data.unsprung_rear
        up, wh = f"{corner}.upright", f"{corner}.wheel"
        b.add_rigid_body(up, float(ub.body.mass), np.asarray(ub.body.inertia), parent="chassis", rotation="zxy")
        b.add_rigid_body(wh, 0.0, np.diag([0.0, float(ub.wheel_spin_inertia), 0.0]), parent=up,
                         revolute=((0, 0, 0), (0, 1, 0)))
        for n in ("A", "B", "E", "F", "L"):
            kw = {"input": "rack", "input_direction": (0.0, 1.0, 0.0)} if (n == "L" and front) else {}
            b.add_modal_point(f"{corner}.{n}", "chassis", f"{corner}.{n}", **kw)
        for n in ("C", "H", "M"):
            b.add_point(f"{corner}.{n}", up, pts[HARD_POINT_NAMES.index(n)] - w)
        for link, pa, pq in QUARTER_CAR_LINKS:
            length = np.linalg.norm(pts[HARD_POINT_NAMES.index(pa)] - pts[HARD_POINT_NAMES.index(pq)])
            b.add_link(f"{corner}.{link}", f"{corner}.{pa}", f"{corner}.{pq}", length)
        if force_points:
            idx = [modal.point_index(f"{corner}.{n}") for n in SPRING_MOUNT_NODES]
            shapes = np.mean(np.asarray(modal.point_phi_translation)[idx], axis=0)
            rot = np.mean(np.asarray(modal.point_phi_rotation)[idx], axis=0)
            b.add_point(f"{corner}.spring_top", "chassis", w + np.array([0.0, 0.0, SPRING_MOUNT_HEIGHT]), shapes,
                        rotation_shapes=rot)
            b.add_point(f"{corner}.W", up, np.zeros(3))
            b.add_point(f"{corner}.contact", up, np.array([0.0, 0.0, -WHEEL_CENTRE_HEIGHT]))
        b.add_independent(up, "uz")
        b.add_independent(wh, "theta_dot")
        q += [jnp.concatenate([jnp.asarray(w), jnp.zeros(3)]), jnp.zeros(1)]
    for name in ("ux", "uy", "uz", "wx", "wy", "wz") + tuple(f"p{k}_dot" for k in range(n_modes)):
        b.add_independent("chassis", name)
    system, params = b.build()
    return system, params, jnp.concatenate(q)


def assembly_fixed(system) -> tuple[int, ...]:
    """Coordinates held by :func:`jaxveh.multibody.assemble` to close the suspension loops at
    a given chassis pose and ride height: all chassis coordinates, each upright's vertical
    position and each wheel's spin angle (the links then fix the other five upright
    coordinates)."""
    n_chassis = system.q_size(system.body_names.index("chassis"))
    fixed = list(range(n_chassis))
    for corner in CORNERS:
        fixed.append(system.q_index(f"{corner}.upright", "z"))
        fixed.append(system.q_offsets[system.body_names.index(f"{corner}.wheel")])
    return tuple(sorted(fixed))


def vehicle_scale_system():
    """The topology as ``bench_multibody.py`` uses it (bare FE frame, no force points)."""
    return vehicle_topology()
