"""Static set-up of the car (section 6.1): the static equilibrium at rest by Newton root
finding in minimal coordinates, with exact gradients by the implicit function theorem.

At rest the car stands on frictionless plates (as on corner-weight scales with slip plates):
the tyres carry their normal loads only, so the equilibrium is defined by the vertical load
path alone (heave, roll, pitch, the chassis modes and the four suspension travels), and the
remaining directions (x, y, yaw, wheel spins) are in equilibrium identically. The equations
are the generalised forces ``R^T T^T (Q_int + Q_ext)`` in those directions at zero velocity
(the accelerations would couple in the free directions through the mass matrix).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .._core import check_range, is_concrete, run_time_checks_off
from ..multibody import MultibodyError, dynamics, rotation_matrix
from ._car import CORNERS, Car, car_elements, check_car, design_coordinates, static_corner_loads, system_params
from ._corner import WHEEL_CENTRE_HEIGHT
from ._powertrain import ConstantSpeed

#: Newton stops when the step (m, rad, modal units) is below ``atol + rtol |x|`` and the
#: generalised forces (N, N m) below ``atol``.
SETUP_RTOL, SETUP_ATOL = 1e-10, 1e-8


class SetupError(MultibodyError):
    """The static set-up did not converge."""


class StaticState(eqx.Module):
    """The car at rest. ``q`` coordinates; ``corner_loads`` tyre normal loads (N, FL, FR, RL,
    RR); ``travel`` wheel-centre vertical travel relative to the chassis from the design
    position (m, positive in bump); ``spring_forces`` (N, compression) and ``spring_lengths``
    (m); ``rocker_angles`` (rad); ``ride_heights`` chassis-frame origin height above the road
    under the front and rear axle (m; the design frame sits on the road, so this is the
    change from the design drawing); ``pitch``, ``roll`` (rad); ``modes`` the chassis modal
    coordinates; ``twist`` the chassis's static twist (rad: the modal rotation about x
    of the front axle's wishbone pivots A, B, E, F, mean, less the rear axle's; 0 when
    rigid); ``link_forces`` (N, tension positive, the links of Table 6.3 per corner);
    ``constraint_residual`` (m, largest link gap); ``residual`` largest generalised-force
    residual (N or N m) and ``ok``."""

    q: Float[Array, " nq"]
    corner_loads: Float[Array, "4"]
    travel: Float[Array, "4"]
    spring_forces: Float[Array, "4"]
    spring_lengths: Float[Array, "4"]
    rocker_angles: Float[Array, "4"]
    ride_heights: Float[Array, "2"]
    pitch: Float[Array, ""]
    roll: Float[Array, ""]
    modes: Float[Array, " nm"]
    twist: Float[Array, ""]
    link_forces: Float[Array, "4 5"]
    constraint_residual: Float[Array, ""]
    residual: Float[Array, ""]
    ok: Array


def vertical_directions(car: Car) -> np.ndarray:
    """Indices of the independent velocities in the vertical load path: each upright's
    vertical velocity, the chassis's heave, roll and pitch rates and its modal velocities."""
    z = [2 * k for k in range(4)]
    return np.asarray(z + [10, 11, 12] + [14 + k for k in range(car.n_modes)], dtype=int)


def _guess(car: Car) -> Float[Array, " nq"]:
    """Design position lowered by the mean static tyre deflection (the tyres touch the road)."""
    v, t = car.params.vehicle, car.params.tyres
    sink = WHEEL_CENTRE_HEIGHT - jnp.mean(t.unloaded_radius - static_corner_loads(v) / t.vertical_stiffness)
    q = design_coordinates(car)
    system = car.system
    rows = [system.q_index("chassis", "z")] + [system.q_index(f"{c}.upright", "z") for c in CORNERS]
    return q.at[np.asarray(rows)].add(-sink)


def _held(car: Car) -> np.ndarray:
    """Coordinates the set-up holds: the chassis's x, y and yaw and the wheel spin angles."""
    system = car.system
    rows = [system.q_index("chassis", n) for n in ("x", "y", "rot0_z")]
    rows += [system.q_offsets[system.body_names.index(f"{c}.wheel")] for c in CORNERS]
    return np.asarray(sorted(rows))


def _residual_fn(car: Car):
    """Residual on the free coordinates: the constraints and the generalised forces in the
    vertical directions (a square system: one free coordinate per constraint or direction)."""
    free_q = np.setdiff1d(np.arange(car.system.n_q), _held(car))
    rows = vertical_directions(car)
    rack = jnp.zeros(1)

    def residual(x, car):
        sp = system_params(car)
        q = _guess(car).at[free_q].set(x)
        elements = car_elements(car, powertrain=False, tyre_horizontal=False)
        dyn = dynamics(car.system, sp, q, jnp.zeros((car.system.n_dof,)), 0.0, lambda t: rack, elements=elements,
                       aux=jnp.zeros((8,)))
        forces = (dyn.internal_forces + dyn.external_forces)[rows]
        return jnp.concatenate([dyn.projection.phi, forces]), (q, dyn, elements)

    return residual, free_q


@eqx.filter_jit
def _solve(car: Car, max_steps: int):
    residual, free_q = _residual_fn(car)
    solver = optx.Newton(rtol=SETUP_RTOL, atol=SETUP_ATOL)
    sol = optx.root_find(lambda x, c: residual(x, c)[0], solver, _guess(car)[free_q], car, max_steps=max_steps,
                         throw=False)
    f, (q, dyn, elements) = residual(sol.value, car)
    return _state(car, q, dyn, elements, jnp.max(jnp.abs(f)), sol.result == optx.RESULTS.successful)


def _state(car, q, dyn, elements, res, converged, aux=None) -> StaticState:
    system, kin = car.system, dyn.kinematics
    front, rear, tyres = elements[0], elements[1], elements[2]
    _, _, _, outs = tyres.evaluate(kin, jnp.zeros((8,)) if aux is None else aux[:8])
    (lf, tf), (rf, _) = front.states(kin)
    (lr, tr), (rr, _) = rear.states(kin)
    lengths, thetas = jnp.concatenate([lf, lr]), jnp.concatenate([tf, tr])
    forces = jnp.concatenate([front.spring_forces(lf, rf), rear.spring_forces(lr, rr)])
    origin = q[:3]
    a = rotation_matrix("zyx", q[3:6])
    w_design = design_coordinates(car)
    travel, heights = [], []
    for c in CORNERS:
        i = system.q_index(f"{c}.upright", "x")
        local = a.T @ (q[i:i + 3] - origin)
        local0 = w_design[i:i + 3]
        travel.append(local[2] - local0[2])
    v = car.params.vehicle
    for x in (v.a, -v.b):
        point = origin + a @ jnp.stack([x, jnp.zeros_like(x), jnp.zeros_like(x)])
        heights.append(point[2])
    links = []
    for c in CORNERS:
        rows = [system.constraint_names.index(n) for n in system.constraint_names if n.startswith(f"{c}.")]
        links.append(dyn.multipliers[np.asarray(rows)])
    return StaticState(
        q=q,
        corner_loads=outs["fz"],
        travel=jnp.stack(travel),
        spring_forces=forces,
        spring_lengths=lengths,
        rocker_angles=thetas,
        ride_heights=jnp.stack(heights),
        pitch=q[4],
        roll=q[5],
        modes=q[6:6 + car.n_modes],
        twist=chassis_twist(car, q[6:6 + car.n_modes]),
        link_forces=jnp.stack(links),
        constraint_residual=jnp.max(jnp.abs(dyn.projection.phi)),
        residual=res,
        ok=converged & jnp.isfinite(res),
    )


def chassis_twist(car: Car, modes) -> Float[Array, ""]:
    """Twist (rad) of the chassis at modal coordinates ``modes``: mean roll rotation of the
    front wishbone pivots less that of the rear ones (see :class:`StaticState`)."""
    chassis = car.params.chassis
    if chassis is None:
        return jnp.zeros(())

    def roll(corners):
        idx = np.asarray([chassis.point_index(f"{c}.{n}") for c in corners for n in "ABEF"])
        return jnp.mean(chassis.point_phi_rotation[idx, 0, :] @ modes)

    return car.params.coupling * (roll(CORNERS[:2]) - roll(CORNERS[2:]))


def static_equilibrium(car: Car, max_steps: int = 32, throw: bool = True) -> StaticState:
    """The car at rest on a flat road (see module). With ``throw`` a failed solve raises
    :class:`SetupError` (a run-time error under ``jit``). Differentiable in ``car.params``.
    A concrete car is checked here (:func:`check_car`) and solved by a program without
    run-time checks, which JAX's disk cache keeps."""
    if all(is_concrete(x) for x in jax.tree.leaves(eqx.filter(car, eqx.is_array))):
        check_car(car)
        with run_time_checks_off():
            state = _solve(car, max_steps)
    else:
        state = _solve(car, max_steps)
    if not throw:
        return state
    if is_concrete(state.ok):
        if not bool(state.ok):
            raise SetupError(
                f"static set-up failed: largest generalised-force residual {float(state.residual):.3e} after "
                f"{max_steps} Newton steps; check that the springs can carry the car (free lengths, rates) and the "
                "hard points assemble"
            )
        return state
    return eqx.tree_at(lambda s: s.q, state, eqx.error_if(state.q, ~state.ok, "static set-up failed"))


# ---- straight running at speed ------------------------------------------------------------

#: Independent velocities of the straight-running trim: the wheel spins and the chassis's
#: body-axis lateral velocity (unknown), its forward velocity (held), its vertical velocity
#: (whatever keeps the motion horizontal); the yaw rate is held at zero.
_SPINS, _FORWARD, _LATERAL, _VERTICAL = (1, 3, 5, 7), 8, 9, 10
#: Rows of the chassis's body-axis forward and lateral velocities among the independent ones.
CHASSIS_FORWARD, CHASSIS_LATERAL = _FORWARD, _LATERAL
#: Auxiliary-state row of the powertrain's error integral: its equation (speed error = 0)
#: holds identically at the held speed; the forward force balance sets the integral instead.
_INTEGRAL_ROW = 8


class SteadyState(eqx.Module):
    """Straight running at a constant speed: the :class:`StaticState` of that condition
    (corner loads now include downforce), the independent velocities ``z`` (wheel spins
    rad/s, forward speed m/s, the small lateral velocity that comes with the tyres'
    asymmetric offsets), the ``rack`` travel (m) that holds the car straight against them,
    auxiliary states ``aux`` (tyre deflections, powertrain), ``drive_torque`` (N m at the
    rear wheels) and the aero loads ``drag``, ``downforce`` (N)."""

    static: StaticState
    z: Float[Array, " ndof"]
    rack: Float[Array, ""]
    aux: Float[Array, " na"]
    drive_torque: Float[Array, ""]
    drag: Float[Array, ""]
    downforce: Float[Array, ""]


def _steady_residual_fn(car: Car):
    free_q = np.setdiff1d(np.arange(car.system.n_q), _held(car))
    n = car.system.n_dof
    free_z = np.asarray(_SPINS + (_LATERAL,))
    aux_rows = np.setdiff1d(np.arange(10), [_INTEGRAL_ROW])

    def unpack(x, speed, car):
        nq, nz = free_q.size, free_z.size
        q = _guess(car).at[free_q].set(x[:nq])
        z = jnp.zeros((n,), x.dtype).at[free_z].set(x[nq:nq + nz]).at[_FORWARD].set(speed)
        # the chassis moves horizontally: its body-axis vertical velocity cancels the
        # forward and lateral ones' vertical share on the pitched and rolled chassis
        a = rotation_matrix("zyx", q[3:6])
        z = z.at[_VERTICAL].set(-(a[2, 0] * z[_FORWARD] + a[2, 1] * z[_LATERAL]) / a[2, 2])
        return q, z, x[nq + nz], x[nq + nz + 1:]

    def residual(x, args):
        car, speed = args
        q, z, rack, aux = unpack(x, speed, car)
        elements = car_elements(car, ConstantSpeed(speed))
        dyn = dynamics(car.system, system_params(car), q, z, 0.0, lambda t: jnp.reshape(rack, (1,)),
                       elements=elements, aux=aux)
        out = jnp.concatenate([dyn.projection.phi, dyn.internal_forces + dyn.external_forces, dyn.aux_dot[aux_rows]])
        return out, (q, z, rack, aux, dyn, elements)

    def guess(car, speed):
        spins = speed / car.params.tyres.unloaded_radius
        aux = jnp.zeros((10,)).at[9].set(speed)
        return jnp.concatenate([_guess(car)[free_q], spins, jnp.zeros(2), aux])

    return residual, guess


@eqx.filter_jit
def _solve_steady(car: Car, speed, max_steps: int):
    residual, guess = _steady_residual_fn(car)
    solver = optx.Newton(rtol=SETUP_RTOL, atol=SETUP_ATOL)
    sol = optx.root_find(lambda x, a: residual(x, a)[0], solver, guess(car, speed), (car, speed),
                         max_steps=max_steps, throw=False)
    f, (q, z, rack, aux, dyn, elements) = residual(sol.value, (car, speed))
    state = _state(car, q, dyn, elements, jnp.max(jnp.abs(f)), sol.result == optx.RESULTS.successful, aux)
    torque = elements[4].control(dyn.kinematics, aux[8:])[0]
    drag, front, rear = car.params.aero.loads(speed)
    return SteadyState(static=state, z=z, rack=rack, aux=aux, drive_torque=torque, drag=drag, downforce=front + rear)


def straight_running(car: Car, speed, max_steps: int = 48, throw: bool = True) -> SteadyState:
    """The car running straight ahead at ``speed`` (m/s, > 0) on a flat road: every
    acceleration and state rate zero with the aero loads, rolling tyres (their deflection
    states), the PID-controlled drive torque that balances drag and rolling resistance, and
    the small rack travel and lateral velocity with which the driver holds the car straight
    against the tyres' asymmetric offsets (ply steer, conicity): zero yaw rate. Newton's
    method on the free coordinates, wheel spins, lateral velocity, rack and auxiliary
    states. Differentiable in ``car.params`` and ``speed``."""
    speed = check_range("speed", speed, low=0.0, low_open=True, what="m/s, straight running needs motion")
    result = _solve_steady(car, speed, max_steps)
    ok = result.static.ok
    if throw and is_concrete(ok) and not bool(ok):
        raise SetupError(
            f"straight running at {float(speed):g} m/s not found: largest residual {float(result.static.residual):.3e} "
            f"after {max_steps} Newton steps; check the powertrain's torque limits against drag and rolling resistance"
        )
    return result
