"""Time integration of the 4-DOF model with Diffrax, and step-steer metrics (section 3.3.3)."""

import diffrax
import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import GRAVITY
from ..params import POSITIVE, AnalyticVehicle, ParameterError, Range, check, check_int, check_static
from ._checks import check_speed
from ._inputs import AbstractSteer, SmoothStep
from ._model import N_STATES, PHIF, PHIR, R, Variant, lateral_acceleration, vector_field

#: Default integration tolerances: relative 1e-8, absolute 1e-10 (states are O(1e-3..10)).
RTOL = 1e-8
ATOL = 1e-10


class Trajectory(eqx.Module):
    """Time histories: times (s), states (n_t, 9), road-wheel steer (rad), ay (m/s^2)."""

    ts: Float[Array, " n"]
    states: Float[Array, "n 9"]
    steer: Float[Array, " n"]
    ay: Float[Array, " n"]


def simulate(
    vehicle: AnalyticVehicle,
    steer: AbstractSteer,
    variant: Variant,
    speed,
    t_end: float,
    n_save: int = 401,
    y0=None,
    solver=None,
    rtol: float = RTOL,
    atol: float = ATOL,
    max_steps: int = 100_000,
) -> Trajectory:
    """Integrate eqs. (3.25)-(3.26) at constant ``speed`` (m/s) from ``y0`` (default: rest on
    a straight line) over [0, ``t_end``] s; ``n_save`` evenly spaced outputs.

    A failed solve raises Diffrax's error (max steps reached, step size too small, NaN).
    Inputs are checked (``ParameterError``; traced values: ``eqx.error_if``): ``speed`` > 0,
    ``t_end`` > 0, ``n_save`` >= 2, ``rtol``, ``atol`` > 0, ``max_steps`` >= 1, ``y0`` not NaN
    with 9 entries.
    """
    speed = check_speed(speed)
    t_end = check("t_end", t_end, Range(0.0, low_open=True, what="end time, s"))
    n_save = check_int("n_save", n_save, 2, "number of saved times")
    max_steps = check_int("max_steps", max_steps, 1)
    for name, tol in (("rtol", rtol), ("atol", atol)):
        check_static(name, tol, POSITIVE)
    if y0 is None:
        y0 = jnp.zeros(N_STATES)
    else:
        y0 = jnp.asarray(y0, dtype=jnp.float64)
        if y0.shape != (N_STATES,):
            raise ParameterError(f"y0 must have shape ({N_STATES},) (the state of STATE_NAMES); got {y0.shape}")
        y0 = check("y0", y0, Range(what="initial state, SI units"))
    ts = jnp.linspace(0.0, t_end, n_save)

    def rhs(t, y, args):
        return vector_field(vehicle, y, speed, steer(t), variant)

    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        diffrax.Tsit5() if solver is None else solver,
        t0=0.0,
        t1=t_end,
        dt0=1e-3,
        y0=y0,
        saveat=diffrax.SaveAt(ts=ts),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        max_steps=max_steps,
    )
    steer_values = eqx.filter_vmap(steer)(ts)
    ay = eqx.filter_vmap(lambda y, d: lateral_acceleration(vehicle, y, speed, d, variant))(sol.ys, steer_values)
    return Trajectory(ts=ts, states=sol.ys, steer=steer_values, ay=ay)


def _first_crossing(ts: np.ndarray, values: np.ndarray, level: float) -> float:
    """First time (s) where ``values`` reaches ``level`` (linear interpolation)."""
    above = np.nonzero(values >= level)[0]
    if above.size == 0:
        return float("nan")
    i = int(above[0])
    if i == 0:
        return float(ts[0])
    frac = (level - values[i - 1]) / (values[i] - values[i - 1])
    return float(ts[i - 1] + frac * (ts[i] - ts[i - 1]))


def settling_time(ts: np.ndarray, values: np.ndarray, final: float, band: float = 0.02, t0: float = 0.0) -> float:
    """Time (s) from ``t0`` after which ``values`` stays within ``band`` x |final| of ``final``."""
    outside = np.nonzero(np.abs(values - final) > band * abs(final))[0]
    if outside.size == 0:
        return 0.0
    i = int(outside[-1])
    return float(ts[min(i + 1, len(ts) - 1)] - t0)


def step_steer_metrics(traj: Trajectory, steer: SmoothStep, settle_window: float = 0.5) -> dict[str, float]:
    """Yaw-rate response time, overshoot, steady ay and twist settling time of a step steer.

    Steady values are the means over the last ``settle_window`` seconds. Response time is
    ISO 7401's: from 50 % of the steer input to 90 % of the steady yaw rate. Overshoot is
    (peak - steady)/steady of the yaw rate. Twist settling time is measured from the start
    of the steer input until φC = φF - φR stays within 2 % of its steady value (None when
    the chassis does not twist). ``settle_window`` must lie in (0, duration of ``traj``) s.
    """
    ts = np.asarray(traj.ts)
    check("settle_window", settle_window, Range(0.0, float(ts[-1] - ts[0]), low_open=True, high_open=True,
                                                 what="averaging window at the end of the trajectory, s"))
    tail = ts >= ts[-1] - settle_window
    r = np.asarray(traj.states[:, R])
    twist = np.asarray(traj.states[:, PHIF] - traj.states[:, PHIR])
    r_ss, ay_ss, twist_ss = r[tail].mean(), np.asarray(traj.ay)[tail].mean(), twist[tail].mean()
    t_half_input = float(steer.start) + 0.5 * float(steer.rise)
    twist_settling = (
        settling_time(ts, twist, twist_ss, t0=float(steer.start)) if abs(twist_ss) > 1e-12 else None
    )
    return {
        "yaw_rate_response_time_s": _first_crossing(ts, r, 0.9 * r_ss) - t_half_input,
        "yaw_rate_peak_time_s": float(ts[np.argmax(r)]) - t_half_input,
        "yaw_rate_overshoot_pct": 100.0 * (r.max() - r_ss) / r_ss,
        "yaw_rate_steady_deg_s": float(np.degrees(r_ss)),
        "ay_steady_g": ay_ss / GRAVITY,
        "twist_steady_deg": float(np.degrees(twist_ss)),
        "twist_settling_time_s": twist_settling,
    }
