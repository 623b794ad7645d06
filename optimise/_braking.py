"""Braking objectives from the full car's time runs: straight-line braking and braking in a
turn (open loop, after ISO 7975), the fast car integrated as ``jaxveh simulate brake`` and
``jaxveh simulate brake-in-turn`` run it, measured by the same JAX metrics
(:func:`jaxveh.manoeuvre.straight_line_means`, :func:`jaxveh.manoeuvre.brake_in_turn_metrics`).

- *Straight-line braking* from ``speed_kmh`` to ``final_speed_kmh`` at ``decel_g``
  (:func:`jaxveh.manoeuvre.brake`): over the hold window (from ``settle_s`` after the rate is
  reached to the end of the ramp) the mean deceleration (g; below the target when the tyres
  or the brake torque limit cannot give it: with a target beyond the car, the largest
  deceleration its brake balance allows), the dive per g and the front axle's share of the
  tyre loads.
- *Braking in a turn*: the car held on a ``radius_m`` circle at ``speed_kmh`` (the steering
  for it from the design's own steady state, so a design change does not move the circle;
  the straight-running trim and the circle's steady state by Newton, derivatives by the
  implicit function theorem), then braking at ``decel_g`` from 3 s; ``after_s`` seconds into
  the braking the yaw rate over the initial circle's at the current speed, the heading and
  path deviations from that circle and the sideslip change.

Derivatives as :mod:`optimise._step_steer`: the discrete solution with the controller's
steps held (hence the tight default ``rtol``); forward mode by default (study files),
reverse mode with ``reverse=True``. A run that stops early or whose start (trim, circle) is
not found gives NaN.
"""

from typing import NamedTuple

import diffrax
import jax.numpy as jnp
import numpy as np

from jaxveh import GRAVITY, ParameterError
from jaxveh.manoeuvre import (
    brake,
    brake_in_turn,
    brake_in_turn_metrics,
    circle_steer_core,
    manoeuvre_channels,
    straight_line_hold,
    straight_line_means,
    straight_trim,
)

#: Straight-line braking's settings: ``jaxveh simulate brake``'s defaults, the hold's
#: ``settle_s`` (s) and the integration's ``rtol``.
BRAKING_SETTINGS = {"speed_kmh": 100.0, "final_speed_kmh": 20.0, "decel_g": 1.0, "settle_s": 0.5, "rtol": 1e-6}
#: Braking in a turn's settings: ``jaxveh simulate brake-in-turn``'s defaults and ``rtol``.
BRAKE_IN_TURN_SETTINGS = {"speed_kmh": 80.0, "radius_m": 100.0, "decel_g": 0.5, "after_s": 1.0, "rtol": 1e-6}
#: Brake onset of the turn (s): the steering turns in from 0.5 to 0.7 s, the car settles.
BRAKE_START = 3.0
#: Save times per second (the metrics read the channels between them linearly).
SAVES_PER_S = 200
MAX_STEPS = 100_000


class BrakingMetrics(NamedTuple):
    """Straight-line braking over the hold: ``deceleration`` (g, positive), ``pitch_gradient``
    (deg/g; negative: the nose dives), ``front_load_share`` (1)."""

    deceleration: jnp.ndarray
    pitch_gradient: jnp.ndarray
    front_load_share: jnp.ndarray


def _check(speed_kmh, decel_g, rtol) -> None:
    if not 5.0 <= speed_kmh <= 250.0:
        raise ParameterError(f"speed_kmh = {speed_kmh!r} is out of range: allowed [5, 250] km/h")
    if not 0.0 < decel_g <= 3.0:
        raise ParameterError(f"decel_g = {decel_g!r} is out of range: allowed (0, 3] g")
    if not 1e-12 <= rtol <= 1e-2:
        raise ParameterError(f"rtol = {rtol!r} is out of range: allowed [1e-12, 1e-2]")


def _channels(car, manoeuvre, ts, trim, rtol, reverse):
    channels, _, status = manoeuvre_channels(
        car, manoeuvre, jnp.asarray(ts), form="fast", trim=trim, rtol=rtol, atol=1e-2 * rtol, max_steps=MAX_STEPS,
        adjoint=None if reverse else diffrax.ForwardMode())
    return channels, status == 0


def braking_metrics(car, speed_kmh=100.0, final_speed_kmh=20.0, decel_g=1.0, settle_s=0.5, rtol=1e-6,
                    reverse: bool = False) -> BrakingMetrics:
    """Straight-line braking's :class:`BrakingMetrics` (module docs); NaN where the run did not
    complete from a converged trim."""
    _check(speed_kmh, decel_g, rtol)
    if not 0.0 < final_speed_kmh < speed_kmh:
        raise ParameterError(f"final_speed_kmh = {final_speed_kmh!r} is out of range: allowed (0, speed_kmh) km/h")
    change_time = (speed_kmh - final_speed_kmh) / 3.6 / (decel_g * GRAVITY)
    duration = 0.5 + change_time + 0.2 + 1.0  # as brake()'s default: start, ramp, its fall, a second after
    m = brake(speed_kmh / 3.6, final_speed_kmh / 3.6, decel_g, duration=duration)
    ts = np.linspace(0.0, duration, int(round(SAVES_PER_S * duration)) + 1)
    hold = straight_line_hold(ts, 0.5, 0.2, change_time, settle_s)
    speed = jnp.asarray(speed_kmh / 3.6, jnp.float64)
    trim = straight_trim(car, speed, "fast")
    channels, completed = _channels(car, m, ts, trim, rtol, reverse)
    means = straight_line_means(channels, hold)
    ok = trim.ok & completed
    return BrakingMetrics(*(jnp.where(ok, x, jnp.nan) for x in (
        -means["ax_mean_g"], means["pitch_gradient_deg_per_g"], means["front_load_share"])))


def brake_in_turn_objectives(car, speed_kmh=80.0, radius_m=100.0, decel_g=0.5, after_s=1.0, rtol=1e-6,
                             reverse: bool = False) -> dict:
    """Braking in a turn's metrics (module docs; the keys of
    :func:`jaxveh.manoeuvre.brake_in_turn_metrics`); NaN where the trim, the circle's steady
    state or the run failed."""
    _check(speed_kmh, decel_g, rtol)
    if not 5.0 <= radius_m <= 10_000.0:
        raise ParameterError(f"radius_m = {radius_m!r} is out of range: allowed [5, 10000] m")
    if not 0.0 < after_s <= 5.0:
        raise ParameterError(f"after_s = {after_s!r} is out of range: allowed (0, 5] s")
    speed = jnp.asarray(speed_kmh / 3.6, jnp.float64)
    trim = straight_trim(car, speed, "fast")
    steer, circle_ok = circle_steer_core(car, speed, speed / radius_m, trim.rack)
    duration = BRAKE_START + after_s + 0.1
    m = brake_in_turn(speed, steer, decel_g, brake_start=BRAKE_START, duration=duration)
    ts = np.linspace(0.0, duration, int(round(SAVES_PER_S * duration)) + 1)
    channels, completed = _channels(car, m, ts, trim, rtol, reverse)
    out = brake_in_turn_metrics(ts, channels, m.speed_target, after=after_s)
    ok = trim.ok & circle_ok & completed
    return {k: jnp.where(ok, v, jnp.nan) for k, v in out.items()}
