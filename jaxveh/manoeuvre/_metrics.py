"""Handling metrics of a manoeuvre's channels (post-processing, NumPy)."""

import numpy as np

from .._core import ParameterError
from ..analytic._transient import _first_crossing
from ._driver import StepSteer


def step_steer_metrics(ts, channels: dict, steer: StepSteer, settle_window: float = 0.5) -> dict:
    """Yaw-rate response time, peak time and overshoot, steady yaw rate and ay of a step
    steer (definitions as :func:`jaxveh.analytic.step_steer_metrics`: ISO 7401 response
    time from 50 % of the input to 90 % of the steady yaw rate; steady values are means
    over the last ``settle_window`` seconds; overshoot relative to the steady value, in the
    direction of the turn)."""
    ts = np.asarray(ts)
    if not 0.0 < settle_window < ts[-1] - ts[0]:
        raise ParameterError(f"settle_window = {settle_window!r} is out of range: allowed (0, {ts[-1] - ts[0]:g}) s")
    tail = ts >= ts[-1] - settle_window
    r = np.asarray(channels["yaw_rate"])
    r_ss = float(r[tail].mean())
    t_half = float(steer.start) + 0.5 * float(steer.rise)
    peak = int(np.argmax(np.sign(r_ss) * r))
    return {
        "yaw_rate_response_time_s": _first_crossing(ts, np.sign(r_ss) * r, 0.9 * abs(r_ss)) - t_half,
        "yaw_rate_peak_time_s": float(ts[peak]) - t_half,
        "yaw_rate_overshoot_pct": 100.0 * (r[peak] - r_ss) / r_ss,
        "yaw_rate_steady_deg_s": r_ss,
        "ay_steady_g": float(np.asarray(channels["ay"])[tail].mean()),
        "roll_steady_deg": float(np.asarray(channels["roll"])[tail].mean()),
        "sideslip_steady_deg": float(np.asarray(channels["sideslip"])[tail].mean()),
    }
