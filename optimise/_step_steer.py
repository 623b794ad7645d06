"""Step-steer objectives from the full car's time run: the fast car integrated through the
thesis's cubic step (sections 6.4.3, 7.4) at any size, tyres saturating as they do.

The run starts from straight running at ``speed_kmh`` (the fast car's steady state by Newton's
method: its derivative by the implicit function theorem), the steering wheel turns by
``angle_deg`` along ``3 s^2 - 2 s^3`` from t = 0 over ``rise_s``
(:class:`jaxveh.manoeuvre.StepSteer`), and Tsit5 with a PID step-size controller at
``rtol`` (``atol = rtol / 100``) integrates to ``duration_s``. The yaw rate is read off
Diffrax's dense output every 2 ms (:func:`optimise._response.step_grid`; save times never
force steps) and measured as the linearised car's step response is (:func:`optimise._response.step_metrics`: ISO 7401
response time, the peak as the vertex of the parabola through the largest sample and its
neighbours, steady value the mean over the last ``settle_s``).

**Derivatives.** Diffrax differentiates the discrete solution, the steps the controller
chose held fixed, so a derivative is the exact one to the integration's tolerance (hence the
tight default ``rtol``). The adjoint sets which mode works: ``reverse=False`` (default)
integrates with ``diffrax.ForwardMode`` (values, ``jax.jvp``, ``jax.jacfwd``: what study
files use); ``reverse=True`` with the fast car's replay of the accepted steps (``jax.grad``;
the same derivative as Diffrax's recursive checkpointing, docs/manoeuvre.md).

A run that stops early (the car spins or rolls, the solver fails) or whose start is not
found gives NaN.
"""

import diffrax
import jax.numpy as jnp
import numpy as np

from jaxveh import ParameterError
from jaxveh.manoeuvre import manoeuvre_channels, step_steer, straight_trim

from ._response import StepMetrics, step_grid, step_metrics

#: The settings, with their defaults: 90 km/h as Fig. 7.6, the CLI's 6 deg steering-wheel
#: step, the steady window ``settle_s`` (s) and the integration's ``rtol``.
SETTINGS = {"speed_kmh": 90.0, "angle_deg": 6.0, "rise_s": 0.2, "duration_s": 5.0, "settle_s": 0.5, "rtol": 1e-6}
MAX_STEPS = 100_000


def _check_run(speed_kmh, angle_deg, rise_s, duration_s, rtol) -> None:
    if not 5.0 <= speed_kmh <= 250.0:
        raise ParameterError(f"speed_kmh = {speed_kmh!r} is out of range: allowed [5, 250] km/h")
    if not 0.0 < abs(angle_deg) <= 180.0:
        raise ParameterError(f"angle_deg = {angle_deg!r} is out of range: allowed 0 < |angle_deg| <= 180 deg "
                             "(steering wheel; negative: right)")
    if not 0.0 < rise_s < duration_s <= 60.0:
        raise ParameterError(f"rise_s = {rise_s!r}, duration_s = {duration_s!r}: allowed 0 < rise_s < duration_s "
                             "<= 60 s")
    if not 1e-12 <= rtol <= 1e-2:
        raise ParameterError(f"rtol = {rtol!r} is out of range: allowed [1e-12, 1e-2]")


def step_steer_run(car, speed_kmh=90.0, angle_deg=6.0, rise_s=0.2, duration_s=5.0, rtol=1e-6,
                   reverse: bool = False):
    """``(ts, yaw_rate, ok)``: the fast car's step steer (module docs), the yaw rate (deg/s)
    at the save times ``ts`` (s, NumPy) and whether the run completed from a converged
    start; pure, differentiable in forward mode (``reverse=False``) or reverse mode
    (``reverse=True``)."""
    _check_run(speed_kmh, angle_deg, rise_s, duration_s, rtol)
    dt, _, n_steps = step_grid(rise_s, duration_s)
    ts = np.arange(n_steps + 1) * dt
    speed = jnp.asarray(speed_kmh / 3.6, jnp.float64)
    manoeuvre = step_steer(speed=speed, angle=jnp.asarray(np.deg2rad(angle_deg), jnp.float64), start=0.0,
                           rise=rise_s, duration=float(ts[-1]))
    trim = straight_trim(car, speed, "fast")
    channels, _, status = manoeuvre_channels(
        car, manoeuvre, jnp.asarray(ts), form="fast", trim=trim, rtol=rtol, atol=1e-2 * rtol,
        max_steps=MAX_STEPS, adjoint=None if reverse else diffrax.ForwardMode())
    return ts, channels["yaw_rate"], trim.ok & (status == 0)


def step_steer_metrics(car, speed_kmh=90.0, angle_deg=6.0, rise_s=0.2, duration_s=5.0, settle_s=0.5, rtol=1e-6,
                       reverse: bool = False) -> StepMetrics:
    """Yaw-rate response time and peak time (s, from 50 % of the input), overshoot (%) and
    steady yaw rate (deg/s) of the fast car's step steer (:func:`step_steer_run`; metrics as
    :func:`optimise._response.step_metrics`); NaN where the run did not complete."""
    if not 0.0 < settle_s < duration_s - rise_s:
        raise ParameterError(f"settle_s = {settle_s!r} is out of range: allowed (0, duration_s - rise_s) s")
    ts, r, ok = step_steer_run(car, speed_kmh, angle_deg, rise_s, duration_s, rtol, reverse)
    metrics = step_metrics(jnp.asarray(ts), r, rise_s, settle_s)
    return StepMetrics(*(jnp.where(ok, x, jnp.nan) for x in metrics))
