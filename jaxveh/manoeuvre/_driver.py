"""Open-loop driver: steering-wheel angle laws (rad, positive to the left) and the
manoeuvre they (or the closed-loop driver of :mod:`._pursuit`) make with a held speed
(section 6.1.5 "driver model"; the speed is held by the powertrain's PID,
:class:`jaxveh.vehicle.SpeedPID`), or with a change of speed (straight-line acceleration and
braking, :func:`accelerate` and :func:`brake`: the PID follows a
:class:`jaxveh.vehicle.SpeedChange`).

Every law is an Equinox module with float leaves, so a manoeuvre is a pytree: its
amplitude, timing and speed can be traced, swept with ``vmap`` and differentiated.
"""

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._core import GRAVITY, ParameterError, is_concrete
from .._trig import sin
from ..params import Range, checked_field
from ..vehicle import AbstractRoad, AbstractSpeedTarget, FlatRoad, SpeedChange

_ANGLE = Range(-3.0, 3.0, what="steering-wheel angle, rad")
_TIME = Range(0.0, what="time, s")


class AbstractSteeringLaw(eqx.Module):
    """A steering-wheel angle history (rad, positive to the left)."""

    @abc.abstractmethod
    def __call__(self, t) -> Float[Array, ""]:
        """Steering-wheel angle (rad) at time ``t`` (s)."""

    def kinks(self) -> tuple:
        """Times (s) where a derivative of the angle jumps: the integrator ends its steps
        there instead of stepping across them (none by default)."""
        return ()


class Straight(AbstractSteeringLaw):
    """No steering: the steering wheel held at the straight-running angle."""

    def __call__(self, t):
        return jnp.zeros_like(jnp.asarray(t, jnp.float64))


class StepSteer(AbstractSteeringLaw):
    """The thesis's step (sections 3.3.3 and 7.4): 0 before ``start``, ``amplitude`` after
    ``start + rise``, the cubic ``3 s^2 - 2 s^3`` between (continuous first derivative)."""

    amplitude: Float[Array, ""] = checked_field("StepSteer.amplitude", _ANGLE)
    start: Float[Array, ""] = checked_field("StepSteer.start", _TIME)
    rise: Float[Array, ""] = checked_field("StepSteer.rise", Range(0.0, low_open=True, what="rise time, s"))

    def __call__(self, t):
        s = jnp.clip((t - self.start) / self.rise, 0.0, 1.0)
        return self.amplitude * s * s * (3.0 - 2.0 * s)

    def kinks(self):
        return (self.start, self.start + self.rise)


class RampSteer(AbstractSteeringLaw):
    """Ramp steer (section 6.4.3): 0 before ``start``, then ``rate`` (rad/s) times the time
    since ``start``, blended in over ``blend`` seconds (a quadratic) so that the rate is
    continuous."""

    rate: Float[Array, ""] = checked_field("RampSteer.rate", Range(-1.0, 1.0, what="steering-wheel rate, rad/s"))
    start: Float[Array, ""] = checked_field("RampSteer.start", _TIME)
    blend: Float[Array, ""] = checked_field("RampSteer.blend", Range(0.0, low_open=True, what="blend time, s"))

    def __call__(self, t):
        s = jnp.maximum(t - self.start, 0.0)
        return self.rate * jnp.where(s < self.blend, 0.5 * s * s / self.blend, s - 0.5 * self.blend)

    def kinks(self):
        return (self.start, self.start + self.blend)


class SweptSine(AbstractSteeringLaw):
    """Swept sine (Fig. 6.15): ``amplitude sin(phase)`` from ``start``, the frequency rising
    linearly from ``f0`` to ``f1`` (Hz) over ``sweep`` seconds."""

    amplitude: Float[Array, ""] = checked_field("SweptSine.amplitude", _ANGLE)
    f0: Float[Array, ""] = checked_field("SweptSine.f0", Range(0.0, what="start frequency, Hz"))
    f1: Float[Array, ""] = checked_field("SweptSine.f1", Range(0.0, what="end frequency, Hz"))
    sweep: Float[Array, ""] = checked_field("SweptSine.sweep", Range(0.0, low_open=True, what="sweep time, s"))
    start: Float[Array, ""] = checked_field("SweptSine.start", _TIME)

    def __call__(self, t):
        return self.amplitude * sin(sweep_phase(t, self.f0, self.f1, self.sweep, self.start))

    def kinks(self):
        return (self.start, self.start + self.sweep)


def sweep_phase(t, f0, f1, sweep, start):
    """Phase (rad) at ``t`` (s) of a linear sweep from ``f0`` to ``f1`` (Hz) over ``sweep``
    seconds after ``start``: zero before ``start``, constant after the sweep."""
    s = jnp.clip(t - start, 0.0, sweep)
    return 2.0 * jnp.pi * (f0 * s + 0.5 * (f1 - f0) * s * s / sweep)


class Manoeuvre(eqx.Module):
    """A manoeuvre from straight running: the ``steering`` (an open-loop law of time, or a
    closed-loop driver such as :class:`jaxveh.manoeuvre.PurePursuit`), the ``speed`` held
    (m/s), the ``duration`` (s), the ``road`` (flat by default; a
    :class:`jaxveh.manoeuvre.PostSweep` for the four-post rig; its height at the start must
    be zero: the run starts from straight running on a flat road) and the ``speed_target``
    the powertrain and brakes follow (default: hold ``speed``; a
    :class:`jaxveh.vehicle.SpeedChange` from ``speed`` for acceleration and braking)."""

    steering: eqx.Module
    speed: Float[Array, ""] = checked_field("Manoeuvre.speed", Range(0.0, 100.0, low_open=True, what="speed, m/s"))
    duration: Float[Array, ""] = checked_field("Manoeuvre.duration",
                                               Range(0.0, 600.0, low_open=True, what="duration, s"))
    road: AbstractRoad = FlatRoad()
    speed_target: AbstractSpeedTarget | None = None

    def __check_init__(self):
        target = self.speed_target
        if target is not None and not isinstance(target, AbstractSpeedTarget):
            raise ParameterError(f"Manoeuvre.speed_target is a {type(target).__name__}: allowed None (hold the "
                                 "speed) or a jaxveh.vehicle speed target such as SpeedChange")
        if isinstance(target, SpeedChange) and is_concrete(target.speed) and is_concrete(self.speed):
            if abs(float(target.speed) - float(self.speed)) > 1e-9 * float(self.speed):
                raise ParameterError(f"Manoeuvre.speed_target starts at {float(target.speed):g} m/s where the "
                                     f"manoeuvre starts at {float(self.speed):g} m/s: they must be equal (the run "
                                     "starts from straight running at Manoeuvre.speed)")


def step_steer(speed: float = 25.0, angle: float = 0.1, start: float = 0.5, rise: float = 0.2,
               duration: float = 5.0) -> Manoeuvre:
    """Step steer at ``speed`` (m/s; default 90 km/h as Fig. 7.6) to a steering-wheel
    ``angle`` (rad, positive left), rising from ``start`` over ``rise`` seconds."""
    return Manoeuvre(steering=StepSteer(amplitude=angle, start=start, rise=rise), speed=speed, duration=duration)


def _straight_line(speed, final_speed, acceleration, start, rise, duration, settle) -> Manoeuvre:
    change = SpeedChange(speed=speed, final_speed=final_speed, rate=acceleration * GRAVITY, start=start, rise=rise)
    if duration is None:
        duration = float(start + change.change_time() + rise + settle)
    return Manoeuvre(steering=Straight(), speed=speed, duration=duration, speed_target=change)


def accelerate(speed: float = 30 / 3.6, final_speed: float = 90 / 3.6, acceleration: float = 0.6,
               start: float = 0.5, rise: float = 0.2, duration: float | None = None,
               settle: float = 1.0) -> Manoeuvre:
    """Straight-line acceleration from ``speed`` to ``final_speed`` (m/s) at ``acceleration``
    (g) from ``start`` (s), the target's acceleration rising and falling over ``rise`` (s)
    (:class:`jaxveh.vehicle.SpeedChange`), steering wheel held straight; ``duration``
    (default: the change and ``settle`` seconds after)."""
    if not float(final_speed) > float(speed):
        raise ParameterError(f"final_speed = {float(final_speed):g} m/s must exceed speed = {float(speed):g} m/s "
                             "(accelerate; brake for a lower speed)")
    return _straight_line(speed, final_speed, acceleration, start, rise, duration, settle)


def brake(speed: float = 100 / 3.6, final_speed: float = 20 / 3.6, deceleration: float = 1.0, start: float = 0.5,
          rise: float = 0.2, duration: float | None = None, settle: float = 1.0) -> Manoeuvre:
    """Straight-line braking from ``speed`` to ``final_speed`` (m/s, > 0: the tyre model needs
    rolling wheels) at ``deceleration`` (g, > 0) from ``start`` (s), as :func:`accelerate`;
    the brake torque is split between the axles by ``SpeedPID.brake_front_share``."""
    if not float(final_speed) < float(speed):
        raise ParameterError(f"final_speed = {float(final_speed):g} m/s must be below speed = {float(speed):g} m/s "
                             "(brake; accelerate for a higher speed)")
    return _straight_line(speed, final_speed, deceleration, start, rise, duration, settle)


def brake_in_turn(speed: float = 80 / 3.6, angle: float = 0.0618, deceleration: float = 0.5,
                  final_speed: float | None = None, steer_start: float = 0.5, rise: float = 0.2,
                  brake_start: float = 3.0, brake_rise: float = 0.2, duration: float | None = None,
                  settle: float = 0.5) -> Manoeuvre:
    """Braking in a turn, open loop (after ISO 7975): from straight running at ``speed`` (m/s)
    the steering wheel turns by ``angle`` (rad from straight running's, positive left; the
    default 3.54 deg puts the shipped 6-mode car on a 100 m circle at 80 km/h, 0.5 g:
    :func:`jaxveh.manoeuvre.circle_steer` gives it for any car and circle) from
    ``steer_start`` over ``rise`` (s) and is then held; the car
    settles on its circle and from ``brake_start`` (s) brakes at ``deceleration`` (g, > 0)
    toward ``final_speed`` (m/s; default half of ``speed``), the rate rising over
    ``brake_rise`` (s). ``duration`` (default: the speed change and ``settle`` s after).
    :func:`jaxveh.manoeuvre.brake_in_turn_metrics` measures how the braking changes the
    circle."""
    final_speed = 0.5 * speed if final_speed is None else final_speed
    if all(map(is_concrete, (speed, final_speed))) and not 0.0 < float(final_speed) < float(speed):
        raise ParameterError(f"final_speed = {float(final_speed):g} m/s must lie in (0, speed = {float(speed):g}) "
                             "m/s (brake_in_turn; the tyre model needs rolling wheels)")
    if (all(map(is_concrete, (brake_start, steer_start, rise)))
            and not float(brake_start) >= float(steer_start) + float(rise)):
        raise ParameterError(f"brake_start = {float(brake_start):g} s must not come before the steering reaches "
                             f"its angle at steer_start + rise = {float(steer_start) + float(rise):g} s")
    change = SpeedChange(speed=speed, final_speed=final_speed, rate=deceleration * GRAVITY, start=brake_start,
                         rise=brake_rise)
    if duration is None:
        duration = float(brake_start + change.change_time() + brake_rise + settle)
    return Manoeuvre(steering=StepSteer(amplitude=angle, start=steer_start, rise=rise), speed=speed,
                     duration=duration, speed_target=change)


def kink_times(manoeuvre: Manoeuvre):
    """The times (s) where the manoeuvre's steering, road or speed target has a derivative
    jump (``kinks()`` of each; closed-loop drivers have none), as an array for Diffrax's
    ``PIDController(jump_ts=...)``, or None. Steps that end there are not rejected for the
    jump: 302 -> 274 steps and 30 -> 10 rejections on the benchmark step steer. They are held
    out of differentiation, so a law's timing (a step's ``rise``, a speed change's ``rate``)
    can be differentiated through the run."""
    steering = manoeuvre.steering.kinks() if isinstance(manoeuvre.steering, AbstractSteeringLaw) else ()
    speed = manoeuvre.speed_target.kinks() if manoeuvre.speed_target is not None else ()
    times = [*steering, *manoeuvre.road.kinks(), *speed]
    # step boundaries only: held out of differentiation (the solution does not depend on them)
    return jax.lax.stop_gradient(jnp.stack([jnp.asarray(t, jnp.float64) for t in times])) if times else None
