"""Objectives from the linearised car (optimise._response) on small systems with closed
forms and independent references: the transfer function against
``jaxveh.analysis.transfer_function``; the yaw-rate bandwidth and gain peak of a
second-order system against their closed forms, with derivatives; the step response against
SciPy's ``lsim`` and its metrics against ``jaxveh.manoeuvre.step_steer_metrics``; the
four-post mean square against a slow chirp through ``lsim``; bad settings refused by name.
The same functions on the car's own linearisation: tests/test_manoeuvre_fourpost.py
(derivatives, the four-post time run) and tests/test_manoeuvre.py (the time run's step
steer)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.signal

import optimise
from jaxveh import ParameterError
from jaxveh.analysis import CarLinearisation, transfer_function
from jaxveh.manoeuvre import StepSteer, step_steer_metrics
from optimise import _response as R

OMEGA = 2.0 * np.pi * 3.0  # rad/s
ZETA = 0.2


def second_order(zeta, omega=OMEGA, column=R.STEERING, rows=1):
    """``y = omega^2 / (s^2 + 2 zeta omega s + omega^2)`` per unit of input ``column``, as
    :class:`optimise._response.LinearIO` (the output in row 0 of ``rows``)."""
    a = jnp.asarray([[0.0, 1.0], [-omega**2, -2.0 * zeta * omega]])
    b = jnp.zeros((3, 2, 5)).at[0, 1, column].set(omega**2)
    c = jnp.zeros((rows, 2)).at[0, 0].set(1.0)
    return R.LinearIO(a, b, c, jnp.zeros((3, rows, 5)), jnp.asarray(True))


def gain(zeta, f, omega=OMEGA):
    w = 2.0 * np.pi * f
    return omega**2 / np.sqrt((omega**2 - w**2) ** 2 + (2.0 * zeta * omega * w) ** 2)


def random_io(seed, n=5, rows=2):
    """A stable random system with every input-derivative and feed-through term."""
    rng = np.random.default_rng(seed)
    m = rng.normal(size=(n, n))
    a = m - (np.max(np.linalg.eigvals(m).real) + 1.0) * np.eye(n)
    return R.LinearIO(jnp.asarray(a), jnp.asarray(rng.normal(size=(3, n, 5))), jnp.asarray(rng.normal(size=(rows, n))),
                      jnp.asarray(rng.normal(size=(3, rows, 5))), jnp.asarray(True))


def test_transfer_equals_the_analysis_transfer_function():
    io = random_io(0)
    lin = CarLinearisation(a=np.asarray(io.a), b=np.asarray(io.b), c=np.asarray(io.c), d=np.asarray(io.d),
                           x0=np.zeros(5), x_dot0=np.zeros(5), speed=np.asarray(10.0), outputs=("p", "q"), n_q=2,
                           n_modes=0)
    f = np.asarray([0.1, 1.0, 7.0])
    weights = np.asarray([0.3, -1.0, 0.0, 2.0, 0.5])
    expected = transfer_function(lin, f, weights)
    for row in (0, 1):
        np.testing.assert_allclose(np.asarray(R.transfer(io, row, weights, f)), expected[:, row], rtol=1e-12)


def test_bandwidth_and_peak_of_a_second_order_system():
    """Closed forms: the peak ``1 / (2 zeta sqrt(1 - zeta^2))`` and the half-power frequency,
    both over the gain at ``f_ref_hz``; their derivatives with respect to zeta (reverse
    mode through the matrices) against central differences of the closed forms."""
    f_ref, f_max = 0.05, 20.0

    def closed_form(zeta):
        g0 = gain(zeta, f_ref)
        peak = 1.0 / (2.0 * zeta * np.sqrt(1.0 - zeta**2)) / g0
        p = 1.0 - 2.0 * zeta**2
        x = OMEGA**2 * (p + np.sqrt(p * p - 1.0 + 2.0 / g0**2))
        return np.sqrt(x) / (2.0 * np.pi), peak

    bandwidth = lambda z: R.yaw_rate_bandwidth_of(second_order(z), f_ref, f_max)  # noqa: E731
    peak = lambda z: R.yaw_rate_gain_peak_of(second_order(z), f_ref, f_max)  # noqa: E731
    bw_exact, peak_exact = closed_form(ZETA)
    np.testing.assert_allclose(float(bandwidth(ZETA)), bw_exact, rtol=1e-10)
    np.testing.assert_allclose(float(peak(ZETA)), peak_exact, rtol=1e-10)
    h = 1e-6
    for fn, k in ((bandwidth, 0), (peak, 1)):
        fd = (closed_form(ZETA + h)[k] - closed_form(ZETA - h)[k]) / (2 * h)
        np.testing.assert_allclose(float(jax.grad(fn)(ZETA)), fd, rtol=1e-6)
        np.testing.assert_allclose(float(jax.jacfwd(fn)(ZETA)), fd, rtol=1e-6)
    # an over-damped system's gain only falls: peak 1 (at f_ref), derivative 0
    assert float(peak(1.5)) == 1.0 and float(jax.grad(peak)(1.5)) == 0.0
    # still above -3 dB at f_max, or still rising there: NaN, not a number off the grid
    assert np.isnan(float(R.yaw_rate_bandwidth_of(second_order(ZETA), f_ref, 2.0)))
    assert np.isnan(float(R.yaw_rate_gain_peak_of(second_order(ZETA), f_ref, 2.0)))


def test_step_response_equals_lsim():
    """The exact discretisation against SciPy's ``lsim`` (first-order hold on a 20 times
    finer grid; the rise and the hold as two runs, so that the input's second derivative
    jumps only between them) of the same system driven by the angle, its rate and its
    acceleration: 1e-7 of the largest output."""
    io, rise, duration = random_io(1), 0.2, 3.0
    ts, y = R.step_response(io, 1, rise, duration)
    a, b = np.asarray(io.a), np.asarray(io.b)[:, :, R.STEERING].T
    c, d = np.asarray(io.c)[1:2], np.asarray(io.d)[:, 1, R.STEERING][None, :]
    n_rise = round(rise / R.STEP_DT)
    t1 = np.linspace(0.0, rise, 20 * n_rise + 1)
    s = t1 / rise
    cubic = np.stack([s * s * (3 - 2 * s), 6 * s * (1 - s) / rise, (6 - 12 * s) / rise**2], axis=1)
    _, y1, x1 = scipy.signal.lsim((a, b, c, d), cubic, t1)
    t2 = np.linspace(rise, duration, 20 * (len(ts) - 1 - n_rise) + 1)
    held = np.tile([1.0, 0.0, 0.0], (len(t2), 1))
    _, y2, _ = scipy.signal.lsim((a, b, c, d), held, t2 - rise, X0=x1[-1])
    ref = np.concatenate([[0.0], y1[20:-1:20], y2[::20]])  # t = 0 before the step, t = rise after it
    np.testing.assert_allclose(np.asarray(ts), np.concatenate([t1[:-1:20], t2[::20]]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(y), ref, rtol=0, atol=1e-7 * np.max(np.abs(ref)))


def test_step_metrics_match_the_time_run_definitions():
    """On a second-order response: the response time equals
    ``jaxveh.manoeuvre.step_steer_metrics``'s (both interpolate the 90 % crossing); the
    parabola's peak lies within one step of the largest sample and its overshoot within
    0.05 % of the closed form ``100 exp(-pi zeta / sqrt(1 - zeta^2))`` (a near-instant
    rise); derivatives against central differences of the function itself."""
    rise, duration, settle = 0.01, 4.0, 0.5
    io = second_order(ZETA)
    ts, r = R.step_response(io, 0, rise, duration)
    m = R.step_metrics(ts, r, rise, settle)
    shifted = np.asarray(ts) + 1.0
    ref = step_steer_metrics(shifted, {"yaw_rate": np.asarray(r), **{k: np.zeros(len(ts)) for k in
                                                                    ("ay", "roll", "sideslip")}},
                             StepSteer(amplitude=1.0, start=1.0, rise=rise), settle_window=settle)
    np.testing.assert_allclose(float(m.response_time), ref["yaw_rate_response_time_s"], rtol=1e-10)
    dt = float(ts[1] - ts[0])
    assert abs(float(m.peak_time) - ref["yaw_rate_peak_time_s"]) <= dt
    assert float(m.overshoot) >= ref["yaw_rate_overshoot_pct"]
    overshoot = 100.0 * np.exp(-np.pi * ZETA / np.sqrt(1.0 - ZETA**2))
    np.testing.assert_allclose(float(m.overshoot), overshoot, atol=0.05)
    np.testing.assert_allclose(float(m.steady), 1.0, rtol=1e-5)  # decayed to 2e-6 by 3.5 s

    def metrics(zeta):
        return jnp.stack(R.step_metrics_of(second_order(zeta), rise, duration, settle)[:3])

    h = 1e-6
    fd = (np.asarray(metrics(ZETA + h)) - np.asarray(metrics(ZETA - h))) / (2 * h)
    np.testing.assert_allclose(np.asarray(jax.jacfwd(metrics)(ZETA)), fd, rtol=1e-6)
    np.testing.assert_allclose(np.asarray(jax.jacrev(metrics)(ZETA)), fd, rtol=1e-6)
    # an over-damped system has no peak before the settling window
    assert np.isnan(float(R.step_metrics_of(second_order(1.5), rise, duration, settle).peak_time))


def test_sweep_rms_equals_a_slow_chirp():
    """The quasi-stationary mean square against ``lsim`` of the front-left post following a
    linear chirp (1 -> 9 Hz over 200 s, 2 mm) through a second-order resonance at 3 Hz: the
    RMS over the sweep within 0.5 % (a slow sweep; the start-up transient included)."""
    io = second_order(ZETA, column=0, rows=4)
    f0, f1, sweep, amplitude = 1.0, 9.0, 200.0, 0.002
    ts = np.linspace(0.0, sweep, 400_001)
    u = amplitude * np.sin(2 * np.pi * (f0 * ts + 0.5 * (f1 - f0) / sweep * ts**2))
    _, y, _ = scipy.signal.lsim((np.asarray(io.a), np.asarray(io.b)[0, :, :1], np.asarray(io.c)[:1],
                                 np.zeros((1, 1))), u, ts)
    rms = float(R.sweep_rms_of(io, "front_left", "warp", amplitude, f0, f1))
    np.testing.assert_allclose(rms, np.sqrt(np.mean(y**2)), rtol=5e-3)
    # the other corners' rows are zero here
    assert float(R.sweep_rms_of(io, "rear_left", "warp", amplitude, f0, f1)) == 0.0


def test_registry_settings_and_failed_trim():
    assert optimise.OBJECTIVES["yaw_rate_response_time"].settings == {"speed_kmh": 90.0, "rise_s": 0.2,
                                                                      "duration_s": 5.0, "settle_s": 0.5}
    assert optimise.OBJECTIVES["rms_fz_variation"].units == "N"
    assert optimise.OBJECTIVES["preview_length"].settings == {"speed_kmh": 100.0, "n_preview": 250}
    spec = optimise.objective_spec("yaw_rate_bandwidth", {"speed_kmh": 60.0})
    assert spec.source_key == ("steering_response", (("speed_kmh", 60.0),))
    assert spec.options == {"f_max_hz": 20.0, "f_ref_hz": 0.05}
    # objectives of one source and speed share one linearisation
    other = optimise.objective_spec("yaw_rate_overshoot", {"speed_kmh": 60.0})
    assert other.source_key == spec.source_key
    failed = second_order(ZETA)._replace(ok=jnp.asarray(False))
    assert np.isnan(float(R.yaw_rate_bandwidth_of(failed, 0.05, 20.0)))
    assert np.all(np.isnan(np.asarray(R.step_metrics_of(failed, 0.2, 5.0, 0.5))))


@pytest.mark.parametrize("call, match", [
    (lambda io: R.yaw_rate_bandwidth_of(io, 1.0, 0.5), "f_ref_hz"),
    (lambda io: R.yaw_rate_gain_peak_of(io, 0.0, 10.0), "f_ref_hz"),
    (lambda io: R.step_metrics_of(io, 0.0, 5.0, 0.5), "rise_s"),
    (lambda io: R.step_metrics_of(io, 0.2, 0.6, 0.5), "duration_s"),
    (lambda io: R.sweep_rms_of(io, "front", "warp", 0.002, 0.5, 30.0), "corner"),
    (lambda io: R.sweep_rms_of(io, "front_left", "twist", 0.002, 0.5, 30.0), "pattern"),
    (lambda io: R.sweep_rms_of(io, "front_left", "warp", -0.002, 0.5, 30.0), "amplitude_m"),
    (lambda io: R.sweep_rms_of(io, "front_left", "warp", 0.002, 0.0, 30.0), "f0_hz"),
])
def test_bad_settings_are_refused_by_name(call, match):
    with pytest.raises(ParameterError, match=match):
        call(second_order(ZETA, rows=4))


def test_bad_preview_points_are_refused():
    with pytest.raises(ParameterError, match="n_preview"):
        R.preview_distance_of(None, 100.0, 1)
