"""Objectives from the fast car's exact linearisation about straight running
(:func:`jaxveh.analysis.linearise_core`): the yaw-rate response to a small step steer, the
yaw-rate frequency response's bandwidth and peak, the RMS contact-patch load variation of
a four-post sine sweep, and the preview distance (section 7.5).

Each is a pure JAX function of the linearisation ``x_dot = A dx + B0 w + B1 w_dot + B2
w_ddot``, ``y = C dx + D0 w + D1 w_dot + D2 w_ddot`` (:class:`LinearIO`), so one
linearisation serves every objective of a study at one speed, and the derivatives with
respect to the car's parameters come by forward or reverse mode through the matrices (the
trim by the implicit function theorem, the Jacobians by nested forward mode).

Linear means small inputs: these are the car's responses in its linear range (a step steer
of a fraction of a degree, posts moving by millimetres), where the thesis's comparisons of
the chassis's flexibility are made (sections 7.3-7.5). A large step steer saturates the
tyres: :func:`jaxveh.manoeuvre.step_steer_metrics` on a time run measures that one.

- **Step steer.** The thesis's cubic step ``3 s^2 - 2 s^3`` over ``rise_s`` (the same law as
  :class:`jaxveh.manoeuvre.StepSteer`), integrated exactly: the state is augmented with the
  steering angle, its rate and its second derivative driven by the cubic's constant third
  derivative, and stepped by the matrix exponential on a grid of :data:`STEP_DT` with the
  end of the rise on the grid. Metrics as :func:`jaxveh.manoeuvre.step_steer_metrics`
  (ISO 7401 response time from 50 % of the input to 90 % of the steady yaw rate, steady
  value the mean over the last ``settle_s``), except that the peak is the vertex of the
  parabola through the largest sample and its neighbours (smooth in the parameters).
- **Frequency response.** ``H(s) = C (sI - A)^-1 (B0 + s B1 + s^2 B2) + D0 + s D1 + s^2 D2``
  of the yaw rate per steering-wheel angle, its gain relative to the gain at ``f_ref_hz``
  (the steady gain, to 0.2 % at 0.05 Hz): the bandwidth is the first frequency above which
  that ratio falls to 1/sqrt(2) (-3 dB), the gain peak the ratio's maximum up to ``f_max_hz``.
  Both are located on a log grid of :data:`N_GRID` points and refined by Newton's method;
  the derivative of the last Newton step, taken from a converged point, is the implicit
  function theorem's.
- **Four-post.** The posts move by ``amplitude_m`` in a pattern (heave or warp) while the
  frequency rises linearly from ``f0_hz`` to ``f1_hz`` (:func:`jaxveh.manoeuvre.four_post`).
  For a sweep slow beside the car's modes the response at each instant is the stationary
  one, so the mean square of a tyre's load variation over the sweep is
  ``amplitude^2 / 2`` times the mean of ``|H(f)|^2`` over the band (trapezoidal rule on
  :data:`N_SWEEP` points).
- **Preview distance.** :func:`jaxveh.analysis.preview_core` (the TI-optimal preview
  controller on the car's lateral position; the distance covering 98 % of the gains).
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp
import jax.scipy.linalg
import numpy as np

from jaxveh import ParameterError
from jaxveh.analysis import INPUTS, linearise_core, preview_core
from jaxveh.control import RESULTS
from jaxveh.manoeuvre import POST_PATTERNS
from jaxveh.vehicle import CORNERS

#: Column of the steering-wheel angle among the inputs (:data:`jaxveh.analysis.INPUTS`).
STEERING = INPUTS.index("steering")
#: Time step (s) of the linear step-steer response.
STEP_DT = 0.002
#: Points of the log frequency grid that locates the bandwidth and the gain peak.
N_GRID = 400
#: Points of the linear frequency grid of the four-post sweep's mean square.
N_SWEEP = 1000
#: The bandwidth's level: the half-power point, -3 dB of the gain at ``f_ref_hz``.
HALF_POWER = 1.0 / np.sqrt(2.0)
NEWTON_STEPS = 4


class LinearIO(NamedTuple):
    """The car linearised about straight running (:func:`jaxveh.analysis.linearise_core`):
    ``a`` (n, n), ``b`` (3, n, 5) and ``d`` (3, m, 5) per input and its first two time
    derivatives, ``c`` (m, n) for the ``m`` output rows, ``ok`` whether the trim converged."""

    a: jax.Array
    b: jax.Array
    c: jax.Array
    d: jax.Array
    ok: jax.Array


def linear_io(car, speed_kmh, channels) -> LinearIO:
    """:class:`LinearIO` of ``car`` at ``speed_kmh`` (km/h) with the output ``channels``
    (names of :data:`jaxveh.manoeuvre.UNITS`). Pure; differentiable."""
    a, b, c, d, _, _, ok = linearise_core(car, jnp.asarray(speed_kmh / 3.6, jnp.float64), tuple(channels))
    return LinearIO(a, b, c, d, ok)


def _nan_unless(ok, value):
    return jnp.where(ok, value, jnp.nan)


# ---- frequency response ----------------------------------------------------------------------


def transfer(io: LinearIO, row: int, weights, frequency_hz):
    """``H(f)`` (complex) of output ``row`` per unit of the input ``weights`` (5, in
    :data:`jaxveh.analysis.INPUTS` order) at ``frequency_hz`` (> 0, Hz; any shape)."""
    weights = jnp.asarray(weights, jnp.float64)
    bw = (io.b @ weights).astype(jnp.complex128)
    dw = (io.d[:, row, :] @ weights).astype(jnp.complex128)
    a, c = io.a.astype(jnp.complex128), io.c[row].astype(jnp.complex128)
    eye = jnp.eye(a.shape[0], dtype=jnp.complex128)

    def at(f):
        s = jax.lax.complex(jnp.zeros_like(f), 2.0 * jnp.pi * f)
        x = jnp.linalg.solve(s * eye - a, bw[0] + s * bw[1] + s * s * bw[2])
        return c @ x + dw[0] + s * dw[1] + s * s * dw[2]

    f = jnp.asarray(frequency_hz, jnp.float64)
    return jax.vmap(at)(f.ravel()).reshape(f.shape)


def _newton(residual, x0, lo, hi):
    """Root of ``residual`` from ``x0`` kept in ``[lo, hi]``: :data:`NEWTON_STEPS` steps
    without derivatives, then one whose derivative is the implicit function theorem's."""
    x = jax.lax.stop_gradient(x0)
    for _ in range(NEWTON_STEPS):
        r, dr = jax.jvp(residual, (x,), (jnp.ones_like(x),))
        x = jax.lax.stop_gradient(jnp.clip(x - r / dr, lo, hi))
    r, dr = jax.jvp(residual, (x,), (jnp.ones_like(x),))
    return x - r / jax.lax.stop_gradient(dr)


def _check_band(f_ref_hz, f_max_hz):
    if not 0.0 < f_ref_hz < f_max_hz <= 200.0:
        raise ParameterError(f"f_ref_hz = {f_ref_hz!r}, f_max_hz = {f_max_hz!r}: allowed 0 < f_ref_hz < f_max_hz "
                             "<= 200 Hz")


def _gain_ratio(io: LinearIO, f_ref_hz):
    """``ratio(log f)``: the yaw-rate gain over its value at ``f_ref_hz``."""
    w = np.eye(len(INPUTS))[STEERING]
    g0 = jnp.abs(transfer(io, 0, w, f_ref_hz))
    return lambda u: jnp.abs(transfer(io, 0, w, jnp.exp(u))) / g0


def yaw_rate_bandwidth_of(io: LinearIO, f_ref_hz, f_max_hz):
    """The first frequency (Hz) above which the yaw-rate gain falls to 1/sqrt(2) of its value
    at ``f_ref_hz`` (``io``'s first output row the yaw rate); NaN when it stays above up to
    ``f_max_hz`` or without the trim."""
    _check_band(f_ref_hz, f_max_hz)
    ratio = _gain_ratio(io, f_ref_hz)
    u = jnp.linspace(np.log(f_ref_hz), np.log(f_max_hz), N_GRID)
    r = ratio(u)
    below = r < HALF_POWER
    k = jnp.maximum(jnp.argmax(below), 1)
    start = u[k - 1] + (r[k - 1] - HALF_POWER) / (r[k - 1] - r[k]) * (u[k] - u[k - 1])
    root = _newton(lambda x: ratio(x) - HALF_POWER, start, u[k - 1], u[k])
    return _nan_unless(io.ok & jnp.any(below), jnp.exp(root))


def yaw_rate_gain_peak_of(io: LinearIO, f_ref_hz, f_max_hz):
    """The largest yaw-rate gain up to ``f_max_hz`` over the gain at ``f_ref_hz`` (1; 1 when
    the gain only falls); NaN when it still rises at ``f_max_hz`` or without the trim."""
    _check_band(f_ref_hz, f_max_hz)
    ratio = _gain_ratio(io, f_ref_hz)
    u = jnp.linspace(np.log(f_ref_hz), np.log(f_max_hz), N_GRID)
    r = ratio(u)
    k = jnp.argmax(r)
    kk = jnp.clip(k, 1, N_GRID - 2)
    slope = lambda x: jax.jvp(ratio, (x,), (jnp.ones_like(x),))[1]  # noqa: E731
    top = jax.lax.stop_gradient(_newton(slope, u[kk], u[kk - 1], u[kk + 1]))
    peak = jnp.where(k == 0, 1.0, ratio(top))  # at the maximum the peak's derivative is the ratio's own
    return _nan_unless(io.ok & (k < N_GRID - 1), peak)


# ---- step steer ------------------------------------------------------------------------------------


def _check_step(rise_s, duration_s, settle_s):
    if not (0.0 < rise_s and 0.0 < settle_s and rise_s + settle_s < duration_s <= 60.0):
        raise ParameterError(f"rise_s = {rise_s!r}, settle_s = {settle_s!r}, duration_s = {duration_s!r}: allowed "
                             "rise_s > 0, settle_s > 0 and rise_s + settle_s < duration_s <= 60 s")


def step_grid(rise_s, duration_s) -> tuple[float, int, int]:
    """``(dt, rise steps, all steps)`` of the step response: about :data:`STEP_DT`, the end
    of the rise on the grid."""
    n_rise = max(1, round(rise_s / STEP_DT))
    dt = rise_s / n_rise
    return dt, n_rise, round(duration_s / dt)


def step_response(io: LinearIO, row: int, rise_s, duration_s):
    """``(ts, y)``: output ``row`` (its units per rad) after the steering wheel turns by 1 rad
    along the cubic ``3 s^2 - 2 s^3`` from t = 0 over ``rise_s`` (s), to ``duration_s``;
    exact on the grid of :func:`step_grid`."""
    dt, n_rise, n_steps = step_grid(rise_s, duration_s)
    a, b = io.a, io.b[:, :, STEERING]
    n = a.shape[0]
    # the state x, then the angle, its rate and its second derivative, then 1 (the jerk's source)
    m = jnp.zeros((n + 4, n + 4)).at[:n, :n].set(a).at[:n, n:n + 3].set(b.T)
    m = m.at[n, n + 1].set(1.0).at[n + 1, n + 2].set(1.0)
    rising = jax.scipy.linalg.expm(m.at[n + 2, n + 3].set(-12.0 / rise_s**3) * dt)
    holding = jax.scipy.linalg.expm(m * dt)
    out = jnp.concatenate([io.c[row], io.d[:, row, STEERING], jnp.zeros(1)])

    def advance(phi):
        def step(z, _):
            z = phi @ z
            return z, out @ z
        return step

    z0 = jnp.zeros(n + 4).at[n + 2].set(6.0 / rise_s**2).at[n + 3].set(1.0)
    z, y_rise = jax.lax.scan(advance(rising), z0, None, length=n_rise)
    z = z.at[n + 1 : n + 3].set(0.0)  # the angle held: no rate, no acceleration
    _, y_hold = jax.lax.scan(advance(holding), z, None, length=n_steps - n_rise)
    # at both ends of the rise the samples take the input's derivatives outside it (zero)
    y_rise = y_rise.at[-1].set(out @ z)
    ts = jnp.arange(n_steps + 1, dtype=jnp.float64) * dt
    return ts, jnp.concatenate([jnp.zeros(1), y_rise, y_hold])


class StepMetrics(NamedTuple):
    """Yaw-rate response time and peak time (s, from 50 % of the input), overshoot (%) and
    the steady yaw rate (the output's units per rad of steering-wheel angle)."""

    response_time: jax.Array
    peak_time: jax.Array
    overshoot: jax.Array
    steady: jax.Array


def step_metrics(ts, r, rise_s, settle_s) -> StepMetrics:
    """:class:`StepMetrics` of the response ``r`` at the uniform times ``ts`` (s; the step
    starts at 0 and rises over ``rise_s``), steady value the mean over the last
    ``settle_s`` (s). NaN: the response never reaches 90 % (response time) or peaks only in
    the settling window (peak time; the overshoot is then that of the samples)."""
    dt = ts[1] - ts[0]
    n = r.shape[0]
    tail = ts >= ts[-1] - settle_s
    steady = jnp.sum(jnp.where(tail, r, 0.0)) / jnp.sum(tail.astype(jnp.float64))
    s, level = jnp.sign(steady) * r, jnp.abs(steady)
    t_half = 0.5 * rise_s
    above = s >= 0.9 * level
    i = jnp.maximum(jnp.argmax(above), 1)
    crossing = ts[i - 1] + (0.9 * level - s[i - 1]) / (s[i] - s[i - 1]) * dt
    k = jnp.argmax(s)
    kk = jnp.clip(k, 1, n - 2)
    y0, y1, y2 = s[kk - 1], s[kk], s[kk + 1]
    offset = jnp.clip(0.5 * (y0 - y2) / (y0 - 2.0 * y1 + y2), -1.0, 1.0)
    peaked = ~tail[k]
    peak = jnp.where(peaked, y1 - 0.25 * (y0 - y2) * offset, s[k])
    return StepMetrics(
        response_time=jnp.where(jnp.any(above), crossing - t_half, jnp.nan),
        peak_time=jnp.where(peaked, ts[kk] + offset * dt - t_half, jnp.nan),
        overshoot=100.0 * (peak - level) / level,
        steady=steady,
    )


def step_metrics_of(io: LinearIO, rise_s, duration_s, settle_s) -> StepMetrics:
    """:class:`StepMetrics` of the yaw rate (``io``'s first output row) after a small step
    steer (module docs); NaN without the trim."""
    _check_step(rise_s, duration_s, settle_s)
    ts, r = step_response(io, 0, rise_s, duration_s)
    return StepMetrics(*(_nan_unless(io.ok, x) for x in step_metrics(ts, r, rise_s, settle_s)))


# ---- four-post -----------------------------------------------------------------------------------


def _check_sweep(corner, pattern, amplitude_m, f0_hz, f1_hz):
    if corner not in CORNERS:
        raise ParameterError(f"corner = {corner!r} is not allowed: one of {', '.join(CORNERS)}")
    if pattern not in POST_PATTERNS:
        raise ParameterError(f"pattern = {pattern!r} is not allowed: one of {', '.join(POST_PATTERNS)}")
    if not 0.0 < amplitude_m <= 0.1:
        raise ParameterError(f"amplitude_m = {amplitude_m!r} is out of range: allowed (0, 0.1] m")
    if not 0.0 < f0_hz < f1_hz <= 200.0:
        raise ParameterError(f"f0_hz = {f0_hz!r}, f1_hz = {f1_hz!r}: allowed 0 < f0_hz < f1_hz <= 200 Hz (the "
                             "car's neutral coordinates make the response at 0 Hz undefined)")


def sweep_rms_of(io: LinearIO, corner, pattern, amplitude_m, f0_hz, f1_hz):
    """RMS variation (N) of ``corner``'s contact-patch load (``io``'s output rows the four
    loads, :data:`jaxveh.vehicle.CORNERS` order) over a four-post sine sweep of
    ``amplitude_m`` (m) in ``pattern`` from ``f0_hz`` to ``f1_hz`` (Hz), quasi-stationary
    (module docs); NaN without the trim."""
    _check_sweep(corner, pattern, amplitude_m, f0_hz, f1_hz)
    weights = jnp.concatenate([jnp.asarray(POST_PATTERNS[pattern], jnp.float64), jnp.zeros(1)])
    f = jnp.linspace(f0_hz, f1_hz, N_SWEEP)
    power = jnp.abs(transfer(io, CORNERS.index(corner), weights, f)) ** 2
    mean_square = jnp.trapezoid(power, f) / (f1_hz - f0_hz)
    return _nan_unless(io.ok, amplitude_m * jnp.sqrt(0.5 * mean_square))


# ---- preview -----------------------------------------------------------------------------------


def preview_distance_of(car, speed_kmh, n_preview):
    """Preview distance Lp (m) of the TI-optimal preview controller on the linearised car at
    ``speed_kmh`` (km/h) with ``n_preview`` points (:func:`jaxveh.analysis.car_preview`'s
    settings); NaN without the trim or the Riccati solution."""
    if not (isinstance(n_preview, int) and 2 <= n_preview <= 2000):
        raise ParameterError(f"n_preview = {n_preview!r} is out of range: allowed integers 2 to 2000")
    io = linear_io(car, speed_kmh, ("y",))
    _, lp, _, result = preview_core(io.a, io.b, io.c, jnp.asarray(speed_kmh / 3.6, jnp.float64), 14 + car.n_modes,
                                    n_preview)
    return _nan_unless(io.ok & (result == RESULTS.successful), lp)
