"""Quasi-static kinematic rigs on the assembled car (thesis Figs. 6.11, 6.12): bump, steer
and roll tests by root finding.

Every rig point is a configuration of the whole car: the chassis held in a pose, the wheel
centres held at heights (the rig's pads), the rack at a travel, and the remaining
coordinates found by closing the twenty links (:func:`jaxveh.multibody.solve_assembly`). With
a flexible chassis, ``flexible=True`` also finds the modal coordinates in equilibrium with
the suspension loads at that point (the chassis deforms under the rig's loads, the springs
and anti-roll bars included); ``flexible=False`` holds them where the static set-up left
them (the chassis as loaded at rest). Loads follow from virtual work along the rig's motion:
with ``x_p(s)`` the points along the rig coordinate ``s`` and ``F_p`` the suspension forces
(springs, dampers at rest, anti-roll bars),

    pad load at a wheel   F_z = m_u g - Σ_p F_p · dx_p/dz_W      (N, the vertical load the pad carries)
    roll moment           M   = -Σ_p F_p · dx_p/dφ                (N m, suspension only: no gravity, rigid tyres)

so roll stiffness per axle is ``dM/dφ`` from that axle's suspension alone.

Angles (chassis axes for the bump and steer rigs, road axes for the roll rig): camber
positive with the top of the wheel outward, toe positive toe-in, road-wheel steer angle
positive to the left; track = distance of the two wheel centres (m).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._core import GRAVITY
from ..multibody import AssemblyError, body_poses, constraints, kinematics, marker_positions
from ._car import CORNERS, Car, car_elements, design_coordinates, steering_rack, system_params
from ._corner import WHEEL_CENTRE_HEIGHT
from ._setup import StaticState

#: Newton steps allowed for each rig assembly (from the design configuration), and the
#: largest constraint residual accepted (m).
RIG_ITERATIONS, RIG_ATOL = 24, 1e-10
#: Newton steps of the modal equilibrium of a flexible chassis, and the relative
#: change of the modal coordinates accepted after them.
MODAL_ITERATIONS, MODAL_TOL = 4, 1e-9
#: Roll step (rad) of the central difference that gives the roll stiffness of a flexible
#: chassis (whose modes are re-balanced at every angle); exact derivative otherwise.
ROLL_STEP = 1e-4
#: Code of a rig point whose links closed but whose modes did not balance.
MODES_UNBALANCED = -2
AXLES = ("front", "rear")


def _corners(axle: str) -> tuple[int, int]:
    if axle not in AXLES:
        raise ValueError(f"axle = {axle!r} is not allowed: choose 'front' or 'rear'")
    return (0, 1) if axle == "front" else (2, 3)


def _fixed(car: Car) -> tuple[int, ...]:
    """Held coordinates: the chassis (pose and modes), each wheel centre's height, each spin."""
    s = car.system
    fixed = list(range(6 + car.n_modes))
    for c in CORNERS:
        fixed += [s.q_index(f"{c}.upright", "z"), s.q_offsets[s.body_names.index(f"{c}.wheel")]]
    return tuple(sorted(fixed))


def _assemble(car, sp, q_guess, rack):
    """Close the links from ``q_guess`` holding :func:`_fixed`: Newton on the twenty free
    upright coordinates (a square system), differentiable by the implicit function theorem.
    Returns ``(q, worst)``: ``worst`` is -1 when every link closed, else the constraint row
    with the largest gap."""
    free = np.setdiff1d(np.arange(car.system.n_q), np.asarray(_fixed(car)))
    u = jnp.reshape(rack, (1,))

    def residual(qf, q_held):
        return constraints(car.system, sp, q_held.at[free].set(qf), u)

    sol = optx.root_find(residual, optx.Newton(rtol=1e-12, atol=RIG_ATOL), q_guess[free], q_guess,
                         max_steps=RIG_ITERATIONS, throw=False)
    q = q_guess.at[free].set(sol.value)
    gaps = jnp.abs(residual(sol.value, q_guess))
    ok = (sol.result == optx.RESULTS.successful) & (jnp.max(gaps) <= RIG_ATOL)
    return q, jnp.where(ok, -1, jnp.argmax(jnp.where(jnp.isfinite(gaps), gaps, jnp.inf)))


def _gap(car, sp, q, rack):
    """Largest constraint residual (m) of a rig configuration."""
    return jnp.max(jnp.abs(constraints(car.system, sp, q, jnp.reshape(rack, (1,)))))


def _suspension_forces(car, sp, q, rack, axles=AXLES):
    """Forces (np, 3; N) of the chosen axles' push-rod suspensions at rest in ``q``."""
    system = car.system
    poses = body_poses(system, sp, q)
    vs = [jnp.zeros((system.v_size(i),), q.dtype) for i in range(system.n_bodies)]
    u = jnp.reshape(rack, (1,))
    kin = kinematics(system, sp, q, vs, poses, u, jnp.zeros_like(u), jnp.zeros((), q.dtype))
    elements = car_elements(car, powertrain=False)
    total = jnp.zeros_like(kin.x)
    for axle in axles:
        total = total + elements[AXLES.index(axle)](kin, jnp.zeros((0,)), system).forces
    return total


def _configuration(car, sp, q_ref, set_held, flexible):
    """``(solve, closed)`` for the rig coordinate ``s``: ``closed(s, p)`` holds the
    coordinates ``set_held(q_ref, s)`` gives (a function returning ``(q_guess, rack)``) and
    the modes ``p`` and closes the links; ``solve(s)`` also finds the modes in equilibrium
    when ``flexible`` (else keeps those of ``q_ref``). Both return ``(q, worst, rack)``.

    Loads on a held coordinate are partial derivatives at fixed modes: where the modes are in
    equilibrium, their own virtual work vanishes (so nothing is differentiated through the
    modal solve)."""
    m = car.n_modes
    modal_rows = np.arange(6, 6 + m)

    def closed(s, p):
        q_guess, rack = set_held(q_ref, s)
        if m:
            q_guess = q_guess.at[modal_rows].set(p)
        return _assemble(car, sp, q_guess, rack) + (rack,)

    if not (flexible and m):
        return (lambda s: closed(s, q_ref[modal_rows])), closed

    chassis = sp.bodies[0]
    stiffness = chassis.modal.stiffness_matrix()

    def modal_loads(p, s):
        """Generalised forces on the modes (N per modal unit) of the suspension (virtual work
        along the modes with the links closed) and of the chassis's own weight (the uprights'
        weight does no work: their heights are held); the elastic force apart."""
        q, _, rack = closed(s, p)
        u = jnp.reshape(rack, (1,))
        forces = _suspension_forces(car, sp, q, rack)
        jac_x = jax.jacfwd(lambda pp: marker_positions(car.system, sp, closed(s, pp)[0], u))(p)
        g_body = body_poses(car.system, sp, q)[0][1].T @ sp.gravity
        return jnp.einsum("pi,pij->j", forces, jac_x) + chassis.gravity(g_body, p, car.system.options)[6:]

    def solve(s):
        # K p = f(p) by Newton's method (the loads' dependence on p through the geometry is
        # not negligible against the softest modes: fixed-point iteration does not converge)
        def residual(p):
            return stiffness @ p - modal_loads(p, s)

        def sweep(_, p):
            r, jac = residual(p), jax.jacfwd(residual)(p)
            return p - jnp.linalg.solve(jac, r)

        p = jax.lax.fori_loop(0, MODAL_ITERATIONS, sweep, q_ref[modal_rows])
        change = jnp.max(jnp.abs(sweep(0, p) - p))
        q, worst, rack = closed(s, p)
        balanced = change <= MODAL_TOL * (1.0 + jnp.max(jnp.abs(p)))
        return q, jnp.where((worst < 0) & ~balanced, MODES_UNBALANCED, worst), rack

    return solve, closed




# ---- wheel measures -------------------------------------------------------------------------


def _wheel_measures(car, sp, q, road_axes: bool):
    """Per corner (rows as CORNERS): camber, toe-in, steer angle (rad), wheel centre (m) and
    spin axis, in the chassis axes (or the road's with ``road_axes``)."""
    system = car.system
    poses = body_poses(system, sp, q)
    frame = jnp.eye(3) if road_axes else poses[0][1]
    rows = []
    for k, c in enumerate(CORNERS):
        r, a = poses[system.body_names.index(f"{c}.upright")][:2]
        axis = frame.T @ a[:, 1]
        centre = frame.T @ (r - (jnp.zeros(3) if road_axes else poses[0][0]))
        side = 1.0 if k % 2 == 0 else -1.0  # left, right
        camber = jnp.arctan2(-side * axis[2], axis[1])
        steer = jnp.arctan2(-axis[0], axis[1])
        rows.append((camber, -side * steer, steer, centre, axis))
    camber, toe, steer, centre, axis = (jnp.stack([row[i] for row in rows]) for i in range(5))
    return {"camber": camber, "toe": toe, "steer": steer, "centre": centre, "axis": axis}


def _reference(car: Car, state: StaticState | None):
    """Rig reference configuration: the chassis level at its design pose, the modes where the
    static set-up left them (zero without a state), the suspensions at design."""
    q = design_coordinates(car)
    if state is not None and car.n_modes:
        q = q.at[6:6 + car.n_modes].set(state.modes)
    return q


def _pad_loads(car, sp, q, closed, pads, s):
    """Vertical pad loads (N) at the wheels whose heights the rig coordinates ``s`` set, in
    the configuration ``q`` (its modes held: see :func:`_configuration`)."""
    v = car.params.vehicle
    mu = jnp.stack([v.unsprung_front.body.mass] * 2 + [v.unsprung_rear.body.mass] * 2)
    p = q[6:6 + car.n_modes]
    rack = jnp.zeros(())
    forces = _suspension_forces(car, sp, q, rack)
    u = jnp.reshape(rack, (1,))
    jac = jax.jacfwd(lambda ss: marker_positions(car.system, sp, closed(ss, p)[0], u))(s)
    return mu[np.asarray(pads)] * GRAVITY - jnp.einsum("pi,pij->j", forces, jac)


@eqx.filter_jit
def _bump(car: Car, travel, axle: str, state, flexible: bool):
    sp = system_params(car)
    pads = _corners(axle)
    rows = np.asarray([car.system.q_index(f"{CORNERS[k]}.upright", "z") for k in pads])

    def held(q_ref, s):
        return q_ref.at[rows].add(s), jnp.zeros(())

    config, closed = _configuration(car, sp, _reference(car, state), held, flexible)

    def point(h):
        s = jnp.stack([h, h])
        q, worst, rack = config(s)
        m = _wheel_measures(car, sp, q, road_axes=False)
        w0 = design_coordinates(car)
        left, right = pads
        return {
            "travel": jnp.stack([m["centre"][k, 2] - w0[rows[i]] for i, k in enumerate(pads)]),
            "camber": m["camber"][np.asarray(pads)],
            "toe": m["toe"][np.asarray(pads)],
            "track": m["centre"][left, 1] - m["centre"][right, 1],
            "wheel_centre_x": m["centre"][np.asarray(pads), 0],
            "wheel_centre_y": m["centre"][np.asarray(pads), 1],
            "fz": _pad_loads(car, sp, q, closed, pads, s),
            "worst": worst,
            "gap": _gap(car, sp, q, rack),
        }

    return jax.vmap(point)(travel)


def bump_rig(car: Car, travel, axle: str = "front", state: StaticState | None = None, flexible: bool = True) -> dict:
    """Bump test of one axle (Fig. 6.11): both wheel centres moved by ``travel`` (m, array,
    positive up) relative to the level chassis. Returns arrays over the travel with a
    trailing axis (left, right) where per wheel: ``travel`` (m, wheel centre relative to the
    chassis from the design position), ``camber``, ``toe`` (rad), ``wheel_centre_x``,
    ``wheel_centre_y`` (m, chassis axes), ``fz`` (N, pad load); ``track`` (m), ``gap`` (m, the largest link
    residual) and ``worst``
    (-1 where every link closed and the modes balanced; else the constraint row with the
    largest gap, or ``MODES_UNBALANCED``; :func:`check_rig` raises on them)."""
    return _bump(car, jnp.asarray(travel, jnp.float64), axle, state, flexible)


def _scrub_radius(car, sp, q, corner: int):
    """Scrub radius (m): from the contact point to where the steering axis (through the
    ball joints C and H) meets the ground, along the wheel's lateral ground line; positive
    when the axis meets the ground inboard of the contact point."""
    x = marker_positions(car.system, sp, q, jnp.zeros(1))
    c = CORNERS[corner]
    xc, xh = x[car.system.point_index(f"{c}.C")], x[car.system.point_index(f"{c}.H")]
    ground = xc + (xh - xc) * (-xc[2] / (xh[2] - xc[2]))
    m = _wheel_measures(car, sp, q, road_axes=True)
    centre, axis = m["centre"][corner], m["axis"][corner]
    lateral = jnp.stack([axis[0], axis[1], jnp.zeros_like(axis[2])])
    lateral = lateral / jnp.linalg.norm(lateral)
    contact = centre - jnp.asarray([0.0, 0.0, 1.0]) * centre[2]
    side = 1.0 if corner % 2 == 0 else -1.0
    return -side * jnp.dot(ground - contact, lateral)


@eqx.filter_jit
def _steer(car: Car, angles, state, flexible: bool):
    sp = system_params(car)

    def held(q_ref, s):
        return q_ref, steering_rack(car, s)

    config, _ = _configuration(car, sp, _reference(car, state), held, flexible)
    v = car.params.vehicle

    def point(angle):
        q, worst, rack = config(angle)
        m = _wheel_measures(car, sp, q, road_axes=False)
        left, right = m["steer"][0], m["steer"][1]
        inner, outer = jnp.where(angle >= 0, left, -right), jnp.where(angle >= 0, right, -left)
        track = m["centre"][0, 1] - m["centre"][1, 1]
        ideal_inner = jnp.arctan(v.wheelbase / (v.wheelbase / jnp.tan(outer) - track))
        ackermann = 100.0 * (inner - outer) / (ideal_inner - outer)
        return {
            "steer": m["steer"][:2],
            "camber": m["camber"][:2],
            "track": track,
            "scrub_radius": jnp.stack([_scrub_radius(car, sp, q, 0), _scrub_radius(car, sp, q, 1)]),
            "ackermann": jnp.where(jnp.abs(angle) < 1e-6, jnp.nan, ackermann),
            "worst": worst,
            "gap": _gap(car, sp, q, rack),
        }

    return jax.vmap(point)(angles)


def steer_rig(car: Car, steering_wheel_angle, state: StaticState | None = None, flexible: bool = True) -> dict:
    """Steering test (Fig. 6.12): the steering wheel turned by ``steering_wheel_angle`` (rad,
    array, positive left) with the chassis level and the wheel centres at design height.
    Per front wheel (left, right): ``steer`` (road-wheel angle, rad, positive left),
    ``camber`` (rad), ``scrub_radius`` (m); ``track`` (m); ``ackermann`` (%: the inner-outer
    angle difference over the ideal one for the wheelbase and track;
    NaN at zero steer, where it is undefined); ``worst`` (see :func:`bump_rig`)."""
    return _steer(car, jnp.asarray(steering_wheel_angle, jnp.float64), state, flexible)


@eqx.filter_jit
def _roll(car: Car, angles, state, flexible: bool, axis_height):
    sp = system_params(car)
    roll_row = car.system.q_index("chassis", "rot2_x")

    def held(q_ref, s):  # rotation by s about the x axis at axis_height
        origin = jnp.stack([jnp.zeros_like(s), axis_height * jnp.sin(s), axis_height * (1.0 - jnp.cos(s))])
        return q_ref.at[roll_row].add(s).at[:3].add(origin), jnp.zeros(())

    config, closed = _configuration(car, sp, _reference(car, state), held, flexible)

    def moments(phi):
        q, _, rack = config(phi)
        u = jnp.reshape(rack, (1,))
        p = q[6:6 + car.n_modes]
        dx = jax.jacfwd(lambda s: marker_positions(car.system, sp, closed(s, p)[0], u))(phi)
        return jnp.stack([-jnp.sum(_suspension_forces(car, sp, q, rack, (axle,)) * dx) for axle in AXLES])

    def point(phi):
        q, worst, rack = config(phi)
        m = _wheel_measures(car, sp, q, road_axes=True)
        if flexible and car.n_modes:  # central difference: no derivative through the modal solve
            moment = moments(phi)
            stiffness = (moments(phi + ROLL_STEP) - moments(phi - ROLL_STEP)) / (2.0 * ROLL_STEP)
        else:
            moment, stiffness = jax.jvp(moments, (phi,), (jnp.ones_like(phi),))
        return {"camber": m["camber"], "toe": m["toe"], "moment": moment, "stiffness": stiffness, "worst": worst,
                "gap": _gap(car, sp, q, rack)}

    return jax.vmap(point)(angles)


def roll_rig(car: Car, roll, state: StaticState | None = None, flexible: bool = True,
             axis_height=WHEEL_CENTRE_HEIGHT) -> dict:
    """Roll test: the chassis rolled by ``roll`` (rad, array, positive right side down) about
    the x axis at ``axis_height`` (m; default the wheel-centre height, where the static wheel
    loads do no work in roll, so the moment is the suspension's own) with every wheel centre
    held at its design height. Per corner (FL, FR, RL, RR): ``camber`` and ``toe`` (rad, road
    axes: roll camber, roll steer); per axle (front, rear): ``moment`` (N m, the
    suspension's restoring roll moment) and ``stiffness`` (N m/rad, its derivative);
    ``worst`` (see :func:`bump_rig`)."""
    return _roll(car, jnp.asarray(roll, jnp.float64), state, flexible, jnp.asarray(axis_height, jnp.float64))


def check_rig(car: Car, name: str, result: dict) -> dict:
    """Raise :class:`jaxveh.multibody.AssemblyError` naming the first failed point of a rig
    sweep and why (the link and its gap, or unbalanced modes); return ``result``."""
    worst = np.asarray(result["worst"]).ravel()
    bad = np.flatnonzero(worst != -1)
    if bad.size:
        code = int(worst[bad[0]])
        gap = float(np.asarray(result["gap"]).ravel()[bad[0]])
        why = ("the chassis modes did not balance" if code == MODES_UNBALANCED else
               f"link {car.system.constraint_names[code]} does not close (largest gap {gap:.3e} m, tolerance "
               f"{RIG_ATOL:g} m)")
        raise AssemblyError(f"{name}: cannot assemble the car at sweep point {int(bad[0])} of {worst.size}: {why}; "
                            "reduce the range or check the hard points")
    return result
