"""Steady states of the fast car by root finding (beyond the thesis, which ran long time
integrations): straight running and steady cornering on a flat road.

In a steady turn the chassis yaws at a constant rate ``omega`` about the vertical axis and
everything else is constant in the chassis frame: its body velocities, roll, pitch, heave,
the modal coordinates, the suspension travels, the wheel spin rates, the rack, the tyres'
relaxation states and the powertrain's states. At heading 0 the chassis's global velocity
is horizontal, ``(vx, vy, 0)``, and its angular velocity ``(0, 0, omega)``. Unknowns: heave,
pitch, roll, modal coordinates, travels, ``vx``, ``vy``, spin rates, rack, auxiliary
states, the powertrain's speed set-point and ``omega``. Equations: every velocity rate and
every auxiliary-state rate zero (the coordinate rates of heave, pitch, roll, modes and
travels vanish by construction), plus two conditions chosen from

- ``speed``: the powertrain's set-point, the c.g.'s forward velocity along the chassis x
  axis (m/s; what a manoeuvre holds);
- ``radius``: the c.g.'s path radius, its horizontal speed over ``omega`` (m);
- ``ay``: the c.g.'s centripetal acceleration, horizontal speed times ``omega`` (m/s^2);
- ``yaw_rate``: ``omega`` itself (rad/s; 0 for straight running);
- ``steer``: the steering-wheel angle (rad, positive left; the rack at
  :func:`jaxveh.vehicle.steering_rack` of it): what an open-loop run holds.

Newton's method (Optimistix) with gradients by the implicit function theorem; the skid-pad
curve is one call that continues from each steady state to the next.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .._core import GRAVITY, ParameterError, run_time_checks_off
from .._differences import DifferenceNewton
from ..multibody import TimeInputs, rotation_matrix
from ..vehicle import (
    ConstantSpeed,
    FastState,
    SetupError,
    car_elements,
    check_car,
    fast_dynamics,
    fast_model,
    static_corner_loads,
    steering_rack,
)
from ..vehicle._corner import WHEEL_CENTRE_HEIGHT
from ._channels import PATH_CHANNELS, car_channels

#: The conditions a steady state can be asked for (two of them, see the module docs).
CONDITIONS = ("speed", "radius", "ay", "yaw_rate", "steer")
#: Newton stops when its step is below ``atol + rtol |x|`` (SI units of each unknown).
STEADY_RTOL, STEADY_ATOL = 1e-11, 1e-10


class SteadyCornering(eqx.Module):
    """A steady state of the fast car: its ``state`` (heading, position and spin angles 0),
    the ``rack`` travel (m), the powertrain's ``speed_target`` (m/s), ``yaw_rate`` (rad/s),
    the c.g.'s path ``radius`` (m, inf when straight) and centripetal acceleration ``ay``
    (m/s^2), the :data:`jaxveh.manoeuvre.UNITS` ``channels`` there, the largest
    ``residual`` (SI units of the rates) and ``ok`` (Newton converged)."""

    state: FastState
    rack: Float[Array, ""]
    speed_target: Float[Array, ""]
    yaw_rate: Float[Array, ""]
    radius: Float[Array, ""]
    ay: Float[Array, ""]
    channels: dict
    residual: Float[Array, ""]
    ok: Array


def check_conditions(conditions: dict) -> tuple[str, str]:
    """The two condition names of ``conditions`` in :data:`CONDITIONS` order (a clear error
    otherwise)."""
    names = tuple(conditions)
    unknown = [n for n in names if n not in CONDITIONS]
    if unknown or len(names) != 2:
        raise ParameterError(
            f"a steady state needs exactly two of {', '.join(CONDITIONS)}; got {', '.join(names) or 'none'}")
    if len(set(names)) != 2:
        raise ParameterError(f"the two conditions must differ; got {', '.join(names)}")
    if "yaw_rate" in names and "radius" in names:
        raise ParameterError("radius and yaw_rate do not fix the speed: give speed or ay with one of them")
    return tuple(n for n in CONDITIONS if n in names)


def _n_aux(car) -> int:
    """Number of the car's auxiliary states (tyres, powertrain)."""
    return sum(len(e.aux_names) for e in car_elements(car))


def _unpack(car, x, n_aux):
    """``(q, u, rack, aux, speed_target, omega)`` from the unknowns ``x`` (module docs)."""
    nm = car.n_modes
    heave, pitch, roll = x[0], x[1], x[2]
    modes, travel = x[3:3 + nm], x[3 + nm:7 + nm]
    k = 7 + nm
    vx, vy, spin_rate, rack = x[k], x[k + 1], x[k + 2:k + 6], x[k + 6]
    aux, speed_target, omega = x[k + 7:k + 7 + n_aux], x[k + 7 + n_aux], x[k + 8 + n_aux]
    zero = jnp.zeros_like(heave)
    angles = jnp.stack([zero, pitch, roll])
    a = rotation_matrix("zyx", angles)
    q = jnp.concatenate([jnp.stack([zero, zero, heave]), angles, modes, travel, jnp.zeros(4, x.dtype)])
    body = jnp.concatenate([a.T @ jnp.stack([vx, vy, zero]), a.T @ jnp.stack([zero, zero, omega])])
    u = jnp.concatenate([body, jnp.zeros(nm + 4, x.dtype), spin_rate])
    return q, u, rack, aux, speed_target, omega


def _evaluate(car, model, x, n_aux):
    """The fast car's equations and channels at the unknowns ``x``."""
    q, u, rack, aux, speed_target, omega = _unpack(car, x, n_aux)
    elements = car_elements(car, ConstantSpeed(speed_target))
    d = fast_dynamics(car, model, q, u, aux, 0.0, TimeInputs(lambda t: rack + jnp.zeros_like(t)), elements)
    steer = -rack / car.params.rack_ratio
    ch = car_channels(car, elements, d.kinematics, aux, u[:6], jnp.zeros(6, x.dtype), steer)
    ch = {k: v for k, v in ch.items() if k not in PATH_CHANNELS}  # a steady turn has no place or heading
    cg = car.system.point_index("chassis.cg")
    v_cg = d.kinematics.xd[cg]
    speed_h = jnp.hypot(v_cg[0], v_cg[1])
    return d, ch, speed_h, (q, u, rack, aux, speed_target, omega)


def _candidates(car, value, rack, speed_target, omega, speed_h):
    """Every condition's residual at one given value, in :data:`CONDITIONS` order."""
    return jnp.stack([speed_target - value, speed_h - omega * value, speed_h * omega - value, omega - value,
                      rack - steering_rack(car, value)])


def _conditions(car, kinds, values, rack, speed_target, omega, speed_h):
    """The residuals of the conditions ``kinds`` (indices into :data:`CONDITIONS`, data, so
    one compiled program serves every pair) at their ``values``."""
    return jax.vmap(lambda k, v: _candidates(car, v, rack, speed_target, omega, speed_h)[k])(kinds, values)


def _residual(x, args):
    car, model, kinds, values, n_aux = args
    d, _, speed_h, (_, _, rack, _, speed_target, omega) = _evaluate(car, model, x, n_aux)
    return jnp.concatenate([d.u_dot, d.aux_dot, _conditions(car, kinds, values, rack, speed_target, omega, speed_h)])


def initial_guess(car, kinds, values) -> Float[Array, " nx"]:
    """A start for Newton: the design position lowered onto the tyres, rolling at the
    requested speed (or ``sqrt(ay R)``, ``ay / yaw_rate``, else 20 m/s) and yaw rate, with the
    requested steering (else none)."""

    def has(name):
        return jnp.any(kinds == CONDITIONS.index(name))

    def given(name):
        return jnp.sum(jnp.where(kinds == CONDITIONS.index(name), values, 0.0))

    ay, radius, yaw = given("ay"), given("radius"), given("yaw_rate")
    speed = jnp.where(has("speed"), given("speed"), jnp.where(
        has("radius") & has("ay"), jnp.sqrt(jnp.abs(ay) * radius),
        jnp.where(has("yaw_rate") & has("ay") & (yaw != 0.0), ay / jnp.where(yaw == 0.0, 1.0, yaw), 20.0)))
    omega = jnp.where(has("yaw_rate"), yaw, jnp.where(has("radius"), speed / jnp.where(has("radius"), radius, 1.0),
                                                      jnp.where(has("ay"), ay / speed, 0.0)))
    v, t = car.params.vehicle, car.params.tyres
    sink = WHEEL_CENTRE_HEIGHT - jnp.mean(t.unloaded_radius - static_corner_loads(v) / t.vertical_stiffness)
    nm = car.n_modes
    n_aux = _n_aux(car)
    aux = jnp.zeros(n_aux).at[-1].set(speed)  # the powertrain's speed filter holds the speed
    rack = jnp.where(has("steer"), steering_rack(car, given("steer")), 0.0)
    zero = jnp.zeros_like(speed)
    return jnp.concatenate([jnp.stack([-sink, zero, zero]), jnp.zeros(nm + 4), jnp.stack([speed, zero]),
                            jnp.broadcast_to(speed / t.unloaded_radius, (4,)), jnp.reshape(rack, (1,)), aux,
                            jnp.stack([speed, omega])])


def _solve(car, model, kinds, values, x0, max_steps):
    n_aux = _n_aux(car)
    args = (car, model, kinds, values, n_aux)
    solver = DifferenceNewton(rtol=STEADY_RTOL, atol=STEADY_ATOL)
    sol = optx.root_find(_residual, solver, x0, args, max_steps=max_steps, throw=False)
    return sol.value, sol.result == optx.RESULTS.successful


def _result(car, model, kinds, values, x, converged) -> SteadyCornering:
    n_aux = _n_aux(car)
    d, ch, speed_h, (q, u, rack, aux, speed_target, omega) = _evaluate(car, model, x, n_aux)
    residual = jnp.max(jnp.abs(jnp.concatenate([d.u_dot, d.aux_dot,
                                                _conditions(car, kinds, values, rack, speed_target, omega,
                                                            speed_h)])))
    ok = converged & jnp.isfinite(residual)
    radius = jnp.where(omega == 0.0, jnp.inf, speed_h / jnp.where(omega == 0.0, 1.0, omega))
    return SteadyCornering(state=FastState(q, u, aux), rack=rack, speed_target=speed_target, yaw_rate=omega,
                       radius=radius, ay=speed_h * omega, channels=ch | {"constraint_residual": d.link_residual},
                       residual=residual, ok=ok)


#: Newton steps allowed to the straight-running trim (as :func:`steady_state`'s default).
TRIM_MAX_STEPS = 64


class StraightTrim(eqx.Module):
    """Straight running of the fast car, where a manoeuvre starts: its ``state`` (heading,
    position and spin angles 0), the ``rack`` travel (m), the powertrain's ``speed_target``
    (m/s) and ``ok`` (Newton converged to a finite state). The same state as
    :func:`steady_state` at zero yaw rate, without the channels and the residual there, so
    that its program holds the car's equations once, in Newton's loop (docs/manoeuvre.md,
    "Compilation")."""

    state: FastState
    rack: Float[Array, ""]
    speed_target: Float[Array, ""]
    ok: Array


def straight_trim_core(car, speed) -> StraightTrim:
    """The fast car's :class:`StraightTrim` at ``speed`` (m/s); pure (jit, vmap, grad: the
    state's derivatives come from Optimistix's implicit function theorem)."""
    model = fast_model(car)
    n_aux = _n_aux(car)
    speed = jnp.asarray(speed, jnp.float64)
    kinds, values = condition_kinds(("speed", "yaw_rate")), jnp.stack([speed, jnp.zeros_like(speed)])
    x, converged = _solve(car, model, kinds, values, initial_guess(car, kinds, values), TRIM_MAX_STEPS)
    q, u, rack, aux, speed_target, _ = _unpack(car, x, n_aux)
    return StraightTrim(state=FastState(q, u, aux), rack=rack, speed_target=speed_target,
                        ok=converged & jnp.all(jnp.isfinite(x)))


def condition_kinds(names) -> Array:
    """Indices into :data:`CONDITIONS` of the condition ``names``."""
    return jnp.asarray([CONDITIONS.index(n) for n in names])


def steady_state_core(car, kinds, values, x0=None, max_steps: int = 64):
    """``(SteadyCornering, x)``: the pure core of :func:`steady_state` (jit, vmap, grad);
    ``kinds`` from :func:`condition_kinds`, ``values`` their values (SI units)."""
    model = fast_model(car)
    kinds = jnp.asarray(kinds)
    values = jnp.stack([jnp.asarray(v, jnp.float64) for v in values]) if isinstance(values, tuple) else values
    x0 = initial_guess(car, kinds, values) if x0 is None else x0
    x, ok = _solve(car, model, kinds, values, x0, max_steps)
    return _result(car, model, kinds, values, x, ok), x


def _sensitivities(car, model, kinds, values, x):
    """``(dx, d channels)``: derivatives of the unknowns and of every channel with respect to
    the last condition's value at the steady state ``x`` (implicit function theorem:
    ``J dx = e``, ``e`` that condition's row)."""
    n_aux = _n_aux(car)
    args = (car, model, kinds, values, n_aux)
    jac = jax.jacfwd(_residual)(x, args)
    dx = jnp.linalg.solve(jac, jnp.zeros_like(x).at[-1].set(1.0))
    return dx, jax.jvp(lambda xx: _evaluate(car, model, xx, n_aux)[1], (x,), (dx,))[1]


#: :func:`steady_state_core` compiled (one program per car structure serves every condition pair).
compiled_core = eqx.filter_jit(steady_state_core)


def steady_state(car, *, speed=None, radius=None, ay=None, yaw_rate=None, steer=None, max_steps: int = 64,
                 throw: bool = True) -> SteadyCornering:
    """The fast car's steady state for two of ``speed`` (m/s, the powertrain's set-point),
    ``radius`` (m), ``ay`` (m/s^2), ``yaw_rate`` (rad/s) and ``steer`` (steering-wheel angle,
    rad) (module docs): straight running is ``speed=V, yaw_rate=0``; a skid-pad point
    ``radius=R, ay=a``; where an open-loop run settles ``speed=V, steer=d``. Positive ay, yaw
    rate and steer turn left (``radius`` is a magnitude: with it, ay must be positive).
    Differentiable in the
    car's parameters and the conditions (implicit function theorem). ``throw``: a failed
    solve raises :class:`jaxveh.vehicle.SetupError` naming the residual."""
    given = {k: v for k, v in (("speed", speed), ("radius", radius), ("ay", ay), ("yaw_rate", yaw_rate),
                               ("steer", steer)) if v is not None}
    names = check_conditions(given)
    for name in ("speed", "radius"):
        if name in given and not float(given[name]) > 0.0:
            raise ParameterError(f"{name} = {given[name]!r} is out of range: allowed > 0 "
                                 f"({'m/s' if name == 'speed' else 'm'})")
    values = jnp.asarray([float(given[n]) for n in names])  # an array: new values never recompile
    with run_time_checks_off():  # the car checked here: a program the disk cache keeps
        result, _ = compiled_core(check_car(car), condition_kinds(names), values, max_steps=max_steps)
    if throw and not bool(result.ok):
        raise SetupError(f"no steady state at {', '.join(f'{n} = {float(given[n]):g}' for n in names)}: largest "
                         f"residual {float(result.residual):.3e} after {max_steps} Newton steps (beyond the tyres' "
                         "grip, or no equilibrium)")
    return result


def circle_steer_core(car, speed, yaw_rate, straight_rack, max_steps: int = 64):
    """``(steer, ok)``: the pure core of :func:`circle_steer` (jit, vmap, grad): the
    steering-wheel angle (rad) from straight running's (its ``straight_rack``, m) to the
    steady state at ``speed`` (m/s) and ``yaw_rate`` (rad/s), and whether Newton converged."""
    circle, _ = steady_state_core(car, condition_kinds(("speed", "yaw_rate")), (speed, yaw_rate),
                                  max_steps=max_steps)
    return (straight_rack - circle.rack) / car.params.rack_ratio, circle.ok


def circle_steer(car, speed, radius, right: bool = False, max_steps: int = 64):
    """The steering-wheel angle (rad, from straight running's, negative right) an open-loop
    run of the fast car holds to settle on a circle of ``radius`` (m, the c.g.'s path) at
    ``speed`` (m/s): the steady states at yaw rate ``+-speed / radius`` and 0
    (:func:`steady_state`; a manoeuvre's steering law is measured from straight running's
    rack, which the tyres' asymmetry moves off centre)."""
    if not float(radius) > 0.0:
        raise ParameterError(f"radius = {radius!r} is out of range: allowed > 0 m")
    yaw_rate = (-1.0 if right else 1.0) * float(speed) / float(radius)
    straight = steady_state(car, speed=speed, yaw_rate=0.0, max_steps=max_steps)
    circle = steady_state(car, speed=speed, yaw_rate=yaw_rate, max_steps=max_steps)
    return (straight.rack - circle.rack) / car.params.rack_ratio


class SkidPad(eqx.Module):
    """Steady states on a circle of ``radius`` (m) at the lateral accelerations ``ay``
    (m/s^2, the targets): ``states`` (a :class:`SteadyCornering` with a leading axis),
    ``gradients`` (each channel's derivative with respect to ay, channel units per m/s^2,
    exact by the implicit function theorem) and ``ok`` (converged, and so was every point
    before it: the curve ends at the first ay without a steady state)."""

    radius: Float[Array, ""]
    ay: Float[Array, " n"]
    states: SteadyCornering
    gradients: dict
    ok: Array

    @property
    def understeer_gradient(self) -> Float[Array, " n"]:
        """``d delta / d ay`` (deg/g): delta the mean front road-wheel angle (at a constant
        radius the kinematic part ``l / R`` is constant, so this is the dynamic steer
        angle's gradient, the thesis's ku)."""
        return jnp.mean(self.gradients["road_wheel_angle"][:, :2], axis=1) * GRAVITY


def skid_pad_core(car, radius, ay, max_steps: int = 64) -> SkidPad:
    """The pure core of :func:`skid_pad`: Newton continued along ``ay`` (each solve starts
    from the previous steady state moved along its exact tangent)."""
    model = fast_model(car)
    kinds = condition_kinds(("radius", "ay"))
    radius = jnp.asarray(radius, jnp.float64)
    ay = jnp.asarray(ay, jnp.float64)
    # the first point from the rough guess (no tangent yet), the rest by continuation
    x_first = initial_guess(car, kinds, jnp.stack([radius, ay[0]]))

    def step(carry, target):
        x_prev, ay_prev, tangent, alive = carry
        values = jnp.stack([radius, target])
        x, converged = _solve(car, model, kinds, values, x_prev + tangent * (target - ay_prev), max_steps)
        state = _result(car, model, kinds, values, x, converged)
        ok = state.ok & alive
        dx, grads = _sensitivities(car, model, kinds, values, x)
        carry = (jnp.where(ok, x, x_prev), jnp.where(ok, target, ay_prev), jnp.where(ok, dx, tangent), ok)
        return carry, (state, grads, ok)

    start = (x_first, ay[0], jnp.zeros_like(x_first), jnp.asarray(True))
    _, (states, grads, ok) = jax.lax.scan(step, start, ay)
    return SkidPad(radius=radius, ay=ay, states=states, gradients=grads, ok=ok)


_compiled_skid_pad = eqx.filter_jit(skid_pad_core)


def skid_pad(car, radius=50.0, ay=None, max_steps: int = 64) -> SkidPad:
    """The skid-pad curve on a circle of ``radius`` m (default 50, the thesis's) turning left:
    steady states at the lateral accelerations ``ay`` (m/s^2, increasing, > 0; default 0.05 g
    to 2.5 g in steps of 0.05 g) as one compiled call (one compilation per car structure and
    number of points). Points beyond the car's limit come back with ``ok`` False."""
    if not float(radius) > 0.0:
        raise ParameterError(f"radius = {radius!r} is out of range: allowed > 0 (m)")
    ay = np.arange(1, 51) * 0.05 * GRAVITY if ay is None else np.asarray(ay, float)
    if ay.ndim != 1 or ay.size < 1 or not np.all(ay > 0.0) or not np.all(np.diff(ay) > 0.0):
        raise ParameterError("ay must be a non-empty, increasing sequence of positive lateral accelerations (m/s^2)")
    with run_time_checks_off():
        return _compiled_skid_pad(check_car(car), jnp.asarray(float(radius)), jnp.asarray(ay), max_steps=max_steps)
