"""Integrate the car through a manoeuvre from straight running, in either form, and return
named channels (:mod:`._channels`) at the save times.

The start is straight running at the manoeuvre's speed, each form's own (the fast car's
steady state by :mod:`._steady`, the library car's :func:`jaxveh.vehicle.straight_running`:
the two agree to their Newton tolerances); the rack follows the
steering law on top of the trim rack; the powertrain holds the speed. Both forms save on
Diffrax's dense output (save times never force steps). :func:`manoeuvre_channels` is the
pure, differentiable core; :func:`simulate` adds the checks, the wall time and the stop
reason.
"""

import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import multibody as mb
from .._core import ParameterError, is_concrete, run_time_checks_off
from .._trig import arctan2
from ..multibody._simulate import _hold_after_stop
from ..vehicle import (
    ConstantSpeed,
    FastState,
    SetupError,
    car_elements,
    check_car,
    check_form,
    fast_dynamics,
    fast_model,
    steering_rack,
    straight_running,
    system_params,
)
from ..vehicle._setup import CHASSIS_FORWARD, CHASSIS_LATERAL
from ._channels import UNITS, car_channels
from ._driver import AbstractSteeringLaw, Manoeuvre, kink_times
from ._imex import IMEX_METHODS, imex_solver, relinearised_solve
from ._pursuit import DRIVER_STATES, DriverElement, PurePursuit, driver_inputs
from ._steady import straight_trim_core

#: Solvers by name (docs/manoeuvre.md compares them): explicit Tsit5; the IMEX KenCarp5 and
#: KenCarp4 (the fast car: its linearisation implicit, taken again in each of
#: :data:`LINEARISATIONS` time segments, :mod:`._imex`; the library car: its chassis modes'
#: forces implicit); the fully implicit Kvaerno5.
SOLVERS = ("tsit5", "kencarp5", "kencarp4", "kvaerno5")
#: The additive Runge-Kutta (IMEX) solvers of :data:`SOLVERS`.
IMEX_SOLVERS = tuple(IMEX_METHODS)
#: ``solver="auto"`` (the default of :func:`simulate`) takes KenCarp5 on the fast car from this
#: rtol up (2-3 times faster than Tsit5 at 1e-4 and 1e-3) and Tsit5 below it and on the
#: library car (docs/manoeuvre.md, "Solvers").
AUTO_IMEX_RTOL = 1e-5
#: Linearisations of the fast car's IMEX split per run: the run is cut into this many equal
#: time segments, each linearised at its start (:func:`._imex.relinearised_solve`). On the
#: benchmark step steer (5 s, rtol 1e-4) KenCarp5 with 3 / 4 / 5 of them takes 155 / 141 / 146
#: steps; each costs a Jacobian (about 2-4 ms) and a restart (docs/manoeuvre.md, "Speed").
LINEARISATIONS = 4
#: First step (s): given rather than estimated, which would compile two more copies of the
#: vector field; the controller adapts it from the first step on.
FIRST_STEP = 1e-3
#: The fast car's position and heading on the ground (x, y, yaw: ``q[0]``, ``q[1]``,
#: ``q[3]``, first in its flat state) stay out of the IMEX split's implicit part
#: (:mod:`._imex`): only a closed-loop driver's path or a road reads them, neither stiffly.
GROUND_POSE = (0, 1, 3)
#: Events that stop a run, by code (0: none): the chassis rolls or pitches beyond
#: ``ROLLOVER_ANGLE``, or its velocity turns beyond ``SPIN_ANGLE`` from its x axis.
EVENTS = ("rollover", "spin")
ROLLOVER_ANGLE, SPIN_ANGLE = 1.0, 1.2  # rad (57 deg, 69 deg)


class CarRun(eqx.Module):
    """A manoeuvre's result: save times ``ts`` (s), ``channels`` (name -> array with a
    leading time axis, units in ``units``), the ``form`` and ``solver`` that ran, the Diffrax
    step counts, ``status`` (0 completed, 1 stopped by an event, 2 solver failure), ``stop_reason``
    ("completed", the event or the failure and its time, or "traced" under ``jit``),
    ``wall_s`` (s: the compiled programs' runs, trim included, after their compilation; NaN
    under ``jit``) and
    ``valid`` (per save time: reached before the stop; later values hold the last reached
    one, never inf or NaN)."""

    ts: Float[Array, " nt"]
    channels: dict
    steps: Array
    rejected_steps: Array
    status: Array
    form: str = eqx.field(static=True)
    stop_reason: str = eqx.field(static=True, default="traced")
    wall_s: float = eqx.field(static=True, default=float("nan"))
    valid: Array | None = None
    solver: str = eqx.field(static=True, default="")

    @property
    def units(self) -> dict:
        return {k: UNITS.get(k, "m") for k in self.channels}


def _solver(name: str, form: str = "library"):
    if name == "tsit5":
        return diffrax.Tsit5()
    if name in IMEX_SOLVERS and form == "fast":
        return imex_solver(method=name)
    if name in IMEX_SOLVERS or name == "kvaerno5":
        import optimistix as optx

        # Newton, not Diffrax's default chord iteration (far more steps on this problem)
        newton = optx.Newton(rtol=1e-8, atol=1e-10)
        library_solvers = {name: cls for name, (cls, _) in IMEX_METHODS.items()} | {"kvaerno5": diffrax.Kvaerno5}
        return library_solvers[name](root_finder=newton)
    raise ParameterError(f"solver = {name!r} is not available: allowed 'auto', {', '.join(map(repr, SOLVERS))}")


def pick_solver(solver: str, form: str, rtol: float) -> str:
    """The solver of :data:`SOLVERS` that ``solver`` ("auto" or one of them) names for a run in
    ``form`` at ``rtol``."""
    if solver != "auto":
        _solver(solver)
        return solver
    return "kencarp5" if form == "fast" and rtol >= AUTO_IMEX_RTOL else "tsit5"


class _Driving(eqx.Module):
    """How a manoeuvre steers: the rack ``law``, the force ``elements`` (the car's, plus the
    closed-loop driver's), the driver's initial states ``aux0`` and the steering-wheel
    ``angle(t, aux)`` (rad)."""

    law: mb.AbstractInputs
    elements: tuple
    aux0: Array
    angle: Callable


def _check_steering(manoeuvre: Manoeuvre):
    steering = manoeuvre.steering
    if not isinstance(steering, (AbstractSteeringLaw, PurePursuit)):
        raise ParameterError(f"manoeuvre.steering is a {type(steering).__name__}: allowed a steering law "
                             "(StepSteer, RampSteer, SweptSine) or a PurePursuit driver")
    return steering


def _driving(car, manoeuvre: Manoeuvre, trim_rack, pose: int) -> _Driving:
    """Open-loop laws steer as functions of time; a :class:`PurePursuit` driver steers
    from its own state (the chassis's x coordinate at ``q[pose]``)."""
    target = ConstantSpeed(manoeuvre.speed) if manoeuvre.speed_target is None else manoeuvre.speed_target
    elements = car_elements(car, target, road=manoeuvre.road)
    steering = _check_steering(manoeuvre)
    if isinstance(steering, AbstractSteeringLaw):
        law = mb.TimeInputs(lambda t: trim_rack + steering_rack(car, steering(t)))
        return _Driving(law, elements, jnp.zeros(0), lambda t, aux: steering(t))
    k = sum(len(e.aux_names) for e in elements)
    law = driver_inputs(car, steering, pose, k, trim_rack)
    return _Driving(law, elements + (DriverElement(steering, pose),), jnp.zeros(len(DRIVER_STATES)),
                    lambda t, aux: aux[k])


def _explicit_states(car) -> tuple[int, ...]:
    """The flat indices the fast car's split keeps explicit: :data:`GROUND_POSE` and the four
    wheel spin angles (``q[10 + modes:]``), on which no equation depends (their columns of the
    split's matrix are zero either way; left out, the matrix's forward difference evaluates
    the field four times fewer per linearisation)."""
    spins = 10 + car.n_modes
    return GROUND_POSE + tuple(range(spins, spins + 4))


class _FastSolve(eqx.Module):
    """The fast car's solve of a manoeuvre: the ``states`` at the save times (held at the last
    reached one after a stop), the ``model`` it ran (:func:`fast_model`), Diffrax's ``stats``
    (with ``event`` and ``valid``) and the ``status``."""

    states: FastState
    model: object
    stats: dict
    status: Array


def _fast_setup(car, manoeuvre, trim, model):
    """The manoeuvre's :class:`_Driving` on the fast car and its equations
    ``dynamics(t, state)``, jitted so that one trace serves the stage loop, the split's
    Jacobian and the channels of one program (JAX's trace cache: the car's equations were
    traced seven times, half the tracing time)."""
    driving = _driving(car, manoeuvre, trim.rack, 0)
    return driving, jax.jit(lambda t, s: fast_dynamics(car, model, s.q, s.u, s.aux, t, driving.law,
                                                       driving.elements))


def _fast_solve(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, adjoint, linearisations, model,
                driving, dynamics) -> _FastSolve:
    s0 = FastState(trim.state.q, trim.state.u, jnp.concatenate([trim.state.aux, driving.aux0]))

    def field(t, s, args):
        d = dynamics(t, s)
        return FastState(d.q_dot, d.u_dot, d.aux_dot)

    conditions = tuple(lambda t, s, args, fn=fn, **kw: fn(s.q, s.u) for fn in (_rolled_over, _spun))
    # the states at the save times (dense output); the channels follow in one vectorised
    # pass (_fast_channels): a save function would be traced five times by Diffrax and sit
    # inside the step loop
    sol = relinearised_solve(
        field, s0, manoeuvre.duration, ts, segments=linearisations if solver in IMEX_SOLVERS else 1,
        controller=diffrax.PIDController(rtol=rtol, atol=atol, jump_ts=kink_times(manoeuvre)),
        event=diffrax.Event(conditions), dt0=FIRST_STEP, max_steps=max_steps, adjoint=adjoint,
        solver=_solver(solver, "fast"), split=solver in IMEX_SOLVERS, explicit=_explicit_states(car))
    rolled, spun = sol.event_mask
    valid = jnp.isfinite(sol.ys.q[:, 0])  # Diffrax fills the save times after a stop with inf
    states = jax.tree.map(lambda x: _hold_after_stop(x, valid), sol.ys)
    stats = dict(sol.stats) | {"event": _event_code(rolled, spun), "valid": valid}
    return _FastSolve(states=states, model=model, stats=stats, status=sol.status)


def _fast_channels(car, ts, states, driving, dynamics) -> dict:
    """The channels at the save times ``ts`` from the ``states`` there, in one vectorised
    pass."""

    def channels(t, s):
        d = dynamics(t, s)
        out = car_channels(car, driving.elements, d.kinematics, s.aux, s.u[:6], d.u_dot[:6], driving.angle(t, s.aux))
        return out | {"constraint_residual": d.link_residual}

    return jax.vmap(channels)(ts, states)


def _fast(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, freeze_steps, adjoint, linearisations):
    del freeze_steps  # refused for the fast car, which has no projection
    model = fast_model(car)
    driving, dynamics = _fast_setup(car, manoeuvre, trim, model)
    sol = _fast_solve(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, adjoint, linearisations, model,
                      driving, dynamics)
    return _fast_channels(car, ts, sol.states, driving, dynamics), sol.stats, sol.status


def _fast_solve_program(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, linearisations) -> _FastSolve:
    """:func:`simulate`'s first program on the fast car: the solve (the channels are a second
    program, compiled beside it, :func:`_compile_programs`)."""
    model = fast_model(car)
    driving, dynamics = _fast_setup(car, manoeuvre, trim, model)
    return _fast_solve(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, None, linearisations, model,
                       driving, dynamics)


def _fast_channels_program(car, manoeuvre, trim, ts, states, model) -> dict:
    """:func:`simulate`'s second program on the fast car: the channels of a solve's states."""
    driving, dynamics = _fast_setup(car, manoeuvre, trim, model)
    return _fast_channels(car, ts, states, driving, dynamics)


def _rolled_over(q, u):
    """Roll or pitch beyond :data:`ROLLOVER_ANGLE` (chassis coordinates: yaw, pitch, roll)."""
    return jnp.max(jnp.abs(q[4:6])) > ROLLOVER_ANGLE


def _spun(q, u):
    """The chassis velocity (body axes ``u[:2]``) beyond :data:`SPIN_ANGLE` from its x axis."""
    return jnp.abs(arctan2(u[1], u[0])) > SPIN_ANGLE


def _event_code(rolled, spun):
    return jnp.where(rolled, 1, jnp.where(spun, 2, 0))


def _library(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, freeze_steps, adjoint, linearisations):
    del adjoint, linearisations  # refused for the library car (manoeuvre_channels); its IMEX split is fixed
    c = car.system.body_names.index("chassis")
    q_c = car.system.q_offsets[c]  # the chassis's x, y, z, yaw, pitch, roll
    chassis = slice(q_c, q_c + 6)
    driving = _driving(car, manoeuvre, trim.rack, q_c)
    law, elements = driving.law, driving.elements

    def outputs(t, state, dyn):
        out = car_channels(car, elements, dyn.kinematics, state.aux, dyn.y[chassis], dyn.y_dot[chassis],
                           driving.angle(t, state.aux))
        return out | {"constraint_residual": jnp.max(jnp.abs(dyn.projection.phi))}

    def rolled(state):
        return _rolled_over(state.q[q_c:q_c + 6], None)

    def spun(state):  # the independent velocities hold the chassis's body-axis u, v
        return _spun(None, state.z[np.asarray([CHASSIS_FORWARD, CHASSIS_LATERAL])])

    aux0 = jnp.concatenate([trim.aux, driving.aux0])
    sim = mb.simulate(car.system, system_params(car), trim.static.q, trim.z, 0.0, manoeuvre.duration, ts,
                      inputs=law, elements=elements, aux0=aux0, outputs=outputs, solver=_solver(solver),
                      rtol=rtol, atol=atol, dt0=FIRST_STEP, max_steps=max_steps, jump_ts=kink_times(manoeuvre),
                      implicit_modes=solver in IMEX_SOLVERS, freeze_steps=freeze_steps, throw=False,
                      events={"rollover": lambda t, st: rolled(st), "spin": lambda t, st: spun(st)})
    event = jnp.where(sim.status == 1, _event_code(rolled(sim.final), spun(sim.final)), 0)
    return sim.outputs, dict(sim.stats) | {"event": event, "valid": sim.valid}, sim.status


def manoeuvre_channels(car, manoeuvre: Manoeuvre, ts, *, form: str, trim=None, solver: str = "tsit5", rtol=1e-4,
                       atol=1e-6, max_steps: int = 100_000, freeze_steps: int = 0, adjoint=None,
                       linearisations: int = LINEARISATIONS):
    """``(channels, stats, status)`` of ``manoeuvre`` on ``car`` at the save times ``ts`` (s)
    in ``form`` ("fast" or "library"), from ``trim`` (default: :func:`straight_trim`): a
    pure function of the car and the manoeuvre (jit, vmap and grad through it; reverse
    mode replays the accepted steps in the fast form (:func:`._replay.replayed_solve`; a
    Diffrax ``adjoint`` instead when given) and uses Diffrax's recursive checkpointing in
    the library form; forward mode, ``jax.jvp`` and ``jax.jacfwd``, needs
    ``adjoint=diffrax.ForwardMode()``, fast form only). ``stats``: Diffrax's counts, ``event``
    (0 or the 1-based index into :data:`EVENTS`) and ``valid`` (save times reached);
    ``status``: 0 completed, 1 stopped by an event, 2 solver failure. ``freeze_steps``
    (library form): hold the projection matrices for that many steps
    (:class:`jaxveh.multibody.ProjectedSolver`; 0: exact). ``linearisations`` (fast form,
    IMEX solvers): time segments of the run, each with the IMEX split linearised at its start
    (:data:`LINEARISATIONS`; 1: once, at the start); ``max_steps`` holds per segment.
    ``solver``: one of :data:`SOLVERS`, or "auto" (:func:`pick_solver`, which needs a
    concrete ``rtol``)."""
    run = _fast if check_form(form) == "fast" else _library
    solver = _resolved_solver(solver, form, rtol)
    _check_freeze_steps(freeze_steps, form)
    _check_linearisations(linearisations)
    if adjoint is not None and form != "fast":
        raise ParameterError(f"adjoint = {type(adjoint).__name__}() needs form = 'fast' (the library car integrates "
                             "with Diffrax's default adjoint)")
    trim = straight_trim(car, manoeuvre.speed, form) if trim is None else trim
    return run(car, manoeuvre, trim, ts, solver, rtol, atol, max_steps, freeze_steps, adjoint, linearisations)


def _resolved_solver(solver: str, form: str, rtol) -> str:
    if solver != "auto":
        return solver
    if not is_concrete(rtol):
        raise ParameterError("solver = 'auto' picks by rtol, which is traced here: pass a concrete rtol or name one "
                             f"of {', '.join(map(repr, SOLVERS))}")
    return pick_solver(solver, form, float(rtol))


def _check_linearisations(linearisations) -> None:
    if not (isinstance(linearisations, int) and not isinstance(linearisations, bool) and linearisations >= 1):
        raise ParameterError(f"linearisations = {linearisations!r} is out of range: allowed integers >= 1 (time "
                             "segments of the fast car's IMEX run, each linearised at its start)")


def _check_freeze_steps(freeze_steps, form: str) -> None:
    if not (isinstance(freeze_steps, int) and freeze_steps >= 0):
        raise ParameterError(f"freeze_steps = {freeze_steps!r} is out of range: allowed integers >= 0 (0: exact)")
    if freeze_steps and form != "library":
        raise ParameterError(f"freeze_steps = {freeze_steps} needs form = 'library' (the fast car has no projection)")


def straight_trim(car, speed, form: str):
    """Straight running at ``speed`` (m/s) in ``form``: the fast car's own steady state
    (:class:`jaxveh.manoeuvre.StraightTrim`: :func:`jaxveh.manoeuvre.steady_state` with zero
    yaw rate, without its channels) or the library car's
    :func:`jaxveh.vehicle.straight_running`; both have a ``rack``."""
    if check_form(form) == "fast":
        return straight_trim_core(car, speed)
    return straight_running(car, speed)


# the trim and the run compile separately (one large program compiles far slower than two)
_compiled_library_trim = eqx.filter_jit(straight_running)
_compiled_fast_trim = eqx.filter_jit(straight_trim_core)
_compiled = eqx.filter_jit(manoeuvre_channels)


def _trim_program(form: str):
    return _compiled_fast_trim if form == "fast" else _compiled_library_trim


def _trim_ok(trim, form: str):
    return trim.ok if form == "fast" else trim.static.ok


def _compiled_trim(car, speed, form):
    """``(trim, ok)``: :func:`straight_trim` compiled and whether its Newton solve
    converged."""
    trim = _trim_program(form)(car, jnp.asarray(speed, jnp.float64))
    return trim, _trim_ok(trim, form)


_compiled_fast_solve = eqx.filter_jit(_fast_solve_program)
_compiled_fast_channels = eqx.filter_jit(_fast_channels_program)
#: Signatures of the program sets :func:`_compile_programs` has compiled.
_compiled_sets: set = set()


def _signature(*trees):
    """A hashable key of what a compiled program depends on in ``trees``: their structure,
    the shapes and dtypes of their arrays and their other leaves (None if one is
    unhashable)."""
    leaves, treedef = jax.tree.flatten(trees)
    key = (treedef, tuple((x.shape, x.dtype) if eqx.is_array(x) else x for x in leaves))
    try:
        hash(key)
    except TypeError:
        return None
    return key


def _placeholder(shapes):
    """Zeros of the shapes and dtypes of ``eqx.filter_eval_shape``'s output (other leaves as they
    are): what a program is compiled for before the values exist."""
    return jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype) if isinstance(s, jax.ShapeDtypeStruct) else s, shapes)


def _solve_kwargs(run_kwargs: dict) -> dict:
    """The options of :func:`_fast_solve_program` among :func:`simulate`'s run options."""
    return {k: run_kwargs[k] for k in ("solver", "rtol", "atol", "max_steps", "linearisations")}


def _run_programs(car, manoeuvre, ts, trim, run_kwargs: dict):
    """``(channels, stats, status)`` of :func:`simulate`'s compiled programs from ``trim``: on
    the fast car the solve and then the channels of its states (two programs, so that they
    compile at once), on the library car one program."""
    if run_kwargs["form"] == "library":
        return _compiled(car, manoeuvre, ts, trim=trim, **run_kwargs)
    sol = _compiled_fast_solve(car, manoeuvre, trim, ts, **_solve_kwargs(run_kwargs))
    return _compiled_fast_channels(car, manoeuvre, trim, ts, sol.states, sol.model), sol.stats, sol.status


def _compile_programs(car, speed, manoeuvre, ts, run_kwargs: dict, trim=None) -> None:
    """Compile :func:`simulate`'s programs (the trim's, unless ``trim`` is given, and the
    run's: on the fast car the solve's and the channels') at once, once per signature: this
    thread traces each in turn for placeholders of its inputs' shapes
    (``eqx.filter_eval_shape`` of the program before it) and two more compile them as they
    come (XLA releases the Python lock while it compiles, so they use two cores). JAX's cache
    then serves the calls (docs/manoeuvre.md, "Compilation")."""
    key = _signature(car, manoeuvre, ts, run_kwargs, trim)
    if key is None or key in _compiled_sets:
        return
    form = run_kwargs["form"]
    trim_program, speed = _trim_program(form), jnp.asarray(speed, jnp.float64)
    with ThreadPoolExecutor(2) as pool:
        jobs = []
        if trim is None:
            trim = _placeholder(eqx.filter_eval_shape(trim_program, car, speed))
            jobs.append(pool.submit(trim_program.lower(car, speed).compile))
        if form == "library":
            jobs.append(pool.submit(_compiled.lower(car, manoeuvre, ts, trim=trim, **run_kwargs).compile))
        else:
            kwargs = _solve_kwargs(run_kwargs)
            sol = _placeholder(eqx.filter_eval_shape(_compiled_fast_solve, car, manoeuvre, trim, ts, **kwargs))
            jobs.append(pool.submit(_compiled_fast_solve.lower(car, manoeuvre, trim, ts, **kwargs).compile))
            jobs.append(pool.submit(_compiled_fast_channels.lower(car, manoeuvre, trim, ts, sol.states,
                                                                  sol.model).compile))
        for job in jobs:
            job.result()
    _compiled_sets.add(key)


def start_trim(car, speed, form: str | None = None):
    """The straight-running state at ``speed`` (m/s) that :func:`simulate` starts ``car``
    from in ``form`` (default the car's own): compiled (disk-cached) and checked; raises
    :class:`jaxveh.vehicle.SetupError` when its Newton solve does not converge."""
    form = check_form(car.form if form is None else form)
    check_car(car)
    with run_time_checks_off():
        trim, ok = _compiled_trim(car, speed, form)
    if not bool(ok):
        raise SetupError(f"the {form} car's straight running at {float(speed):g} m/s was not found "
                         "(the powertrain's torque against drag and rolling resistance?)")
    return trim


def _check_trim(trim, form: str):
    """Whether a given trim (of ``form``) converged; a trim of the other form is refused."""
    library = hasattr(trim, "static")
    if library != (form == "library"):
        raise ParameterError(f"trim is a {'library' if library else 'fast'} car's straight running: pass one of "
                             f"the {form} form (straight_trim(car, speed, {form!r}))")
    return trim.static.ok if library else trim.ok


def save_times(manoeuvre: Manoeuvre, points: int):
    """``points`` evenly spaced save times over the manoeuvre (s)."""
    return jnp.linspace(0.0, manoeuvre.duration, points)


def simulate(car, manoeuvre: Manoeuvre, *, form: str | None = None, points: int = 501, solver: str = "auto",
             rtol: float = 1e-4, atol: float | None = None, max_steps: int = 100_000, throw: bool = True,
             freeze_steps: int = 0, trim=None, linearisations: int = LINEARISATIONS) -> CarRun:
    """Run ``manoeuvre`` on ``car`` (compiled once per car structure and solver) and return a
    :class:`CarRun` with ``points`` save times. ``form``: "fast" or "library" (default: the
    car's own, ``car.form``). ``rtol``/``atol``: the PID step-size controller's tolerances
    (default ``atol = rtol / 100`` on every state: metres, radians, modal coordinates).
    ``solver``: one of :data:`SOLVERS`, or "auto" (:func:`pick_solver`: KenCarp5 IMEX on the
    fast car from rtol :data:`AUTO_IMEX_RTOL` up, else Tsit5); the run's is ``CarRun.solver``.
    A run stops early when the car rolls over or spins (:data:`EVENTS`; ``status`` 1,
    ``stop_reason`` names the event and its time). A failed solve raises ``RuntimeError``
    naming the last time reached (``throw=False``: the run is returned with ``status`` 2).
    ``freeze_steps`` (library form, Table 7.2 studies): see :func:`manoeuvre_channels`.
    ``trim``: start from this straight-running state (:func:`straight_trim` of a car with the
    same coordinates in the same form at the manoeuvre's speed, e.g. the complete model's
    for a simplified one) instead of the car's own. After a stop the channels hold their last
    reached values (``valid`` marks the save times reached). ``linearisations``: see
    :func:`manoeuvre_channels`."""
    form = check_form(car.form if form is None else form)
    if not (isinstance(points, int) and points >= 2):
        raise ParameterError(f"points = {points!r} is out of range: allowed integers >= 2 (save times)")
    if not 0.0 < rtol < 1.0:
        raise ParameterError(f"rtol = {rtol!r} is out of range: allowed (0, 1)")
    atol = rtol * 1e-2 if atol is None else atol
    if not atol > 0.0:
        raise ParameterError(f"atol = {atol!r} is out of range: allowed > 0")
    solver = pick_solver(solver, form, rtol)
    _check_steering(manoeuvre)
    _check_freeze_steps(freeze_steps, form)
    _check_linearisations(linearisations)
    ts = save_times(manoeuvre, points)
    check_car(car)  # here, so that the programs need no run-time checks (the disk cache keeps them)
    run_kwargs = dict(form=form, solver=solver, rtol=jnp.asarray(rtol, jnp.float64),
                      atol=jnp.asarray(atol, jnp.float64), max_steps=max_steps, freeze_steps=freeze_steps,
                      linearisations=linearisations)  # tolerances as arrays: one compilation serves all
    with run_time_checks_off():
        trim_ok = None if trim is None else _check_trim(trim, form)  # a given trim checked before compiling
        _compile_programs(car, manoeuvre.speed, manoeuvre, ts, run_kwargs, trim)
        start = time.perf_counter()  # the wall time: the programs' runs, after their compilation
        if trim is None:
            trim, trim_ok = _compiled_trim(car, manoeuvre.speed, form)
        if not bool(trim_ok):
            raise SetupError(f"the {form} car's straight running at {float(manoeuvre.speed):g} m/s was not found "
                             "(the powertrain's torque against drag and rolling resistance?)")
        channels, stats, status = _run_programs(car, manoeuvre, ts, trim, run_kwargs)
        channels = jax.block_until_ready(channels)
    wall = time.perf_counter() - start
    status, valid = int(status), np.asarray(stats["valid"])
    reached = np.asarray(ts)[valid]
    after = f"after t = {reached[-1] if reached.size else 0.0:.4g} s"
    reason = "completed"
    if status == 1:
        reason = f"{EVENTS[int(stats['event']) - 1]} {after}"
    elif status == 2:
        reason = f"solver failure {after}"
        if throw:
            raise RuntimeError(f"the {form} car's integration failed: {reason}")
    return CarRun(ts=ts, channels=channels, steps=stats["num_steps"], rejected_steps=stats["num_rejected_steps"],
                  status=jnp.asarray(status), form=form, stop_reason=reason, wall_s=wall, valid=jnp.asarray(valid),
                  solver=solver)
