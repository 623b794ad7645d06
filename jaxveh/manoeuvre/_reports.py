"""Reports of the car's steady states for the CLI and the experiments: plain dictionaries of
floats and lists (JSON-ready), units in the key names."""

import time

import numpy as np

from .._core import GRAVITY, ParameterError
from ._steady import skid_pad


def skid_pad_grid(ay_max_g: float = 2.5, step_g: float = 0.05) -> np.ndarray:
    """Lateral accelerations (m/s^2) from ``step_g`` to ``ay_max_g`` in steps of ``step_g``."""
    if not 0.0 < step_g <= ay_max_g:
        raise ParameterError(f"ay step = {step_g!r} g and ay max = {ay_max_g!r} g: allowed 0 < step <= max")
    n = int(np.floor(ay_max_g / step_g + 1e-9))
    return np.arange(1, n + 1) * step_g * GRAVITY


def skid_pad_report(car, radius: float = 50.0, ay_max_g: float = 2.5, step_g: float = 0.05) -> dict:
    """The skid-pad curve (Fig. 7.5) of the fast car on a circle of ``radius`` m by root
    finding: the steady states from ``step_g`` to the limit (or ``ay_max_g``), and the
    understeer gradient ``d delta / d ay`` (delta the mean front road-wheel angle; exact, by
    the implicit function theorem) at the first point, the linear range's value. Per point:
    ay (horizontal, at the c.g.), speed, steering-wheel and road-wheel angle, dynamic steer
    angle ``delta - l / R``, understeer gradient, steering sensitivity ``1 / ku``, sideslip,
    roll, yaw rate, twist, the front axle's share of the lateral load transfer (chi: right
    less left tyre load, front over front plus rear; it includes the small static
    differences the tyres' asymmetric offsets leave at ay = 0), modal coordinates and tyre
    loads."""
    ay = skid_pad_grid(ay_max_g, step_g)
    start = time.perf_counter()
    pad = skid_pad(car, radius, ay)
    ok = np.asarray(pad.ok)
    wall = time.perf_counter() - start
    if not ok[0]:
        raise RuntimeError(f"no steady state at the first point, ay = {step_g:g} g on R = {radius:g} m")
    ch = {k: np.asarray(v)[ok] for k, v in pad.states.channels.items()}
    ku = np.asarray(pad.understeer_gradient)[ok]
    delta = ch["road_wheel_angle"][:, :2].mean(axis=1)
    fz = ch["fz"]
    transfer_front, transfer_rear = fz[:, 1] - fz[:, 0], fz[:, 3] - fz[:, 2]
    kinematic = np.degrees(float(car.params.vehicle.wheelbase) / radius)
    curve = {
        "ay_g": np.asarray(pad.states.ay)[ok] / GRAVITY,
        "speed_kmh": np.asarray(pad.states.speed_target)[ok] * 3.6,
        "steering_wheel_angle_deg": ch["steering_wheel_angle"],
        "road_wheel_angle_deg": delta,
        "delta_dynamic_deg": delta - kinematic,
        "understeer_gradient_deg_per_g": ku,
        "steering_sensitivity_g_per_deg": 1.0 / ku,
        "sideslip_deg": ch["sideslip"],
        "roll_deg": ch["roll"],
        "yaw_rate_deg_s": ch["yaw_rate"],
        "twist_deg": ch["twist"],
        "lltd_front_share": transfer_front / (transfer_front + transfer_rear),
        "modes": ch["modes"],
        "fz_n": ch["fz"],
    }
    return {
        "radius_m": float(radius),
        "understeer_gradient_deg_per_g": float(ku[0]),
        "understeer_gradient_at_g": float(curve["ay_g"][0]),
        "kinematic_steer_deg": kinematic,
        "ay_limit_g": float(curve["ay_g"][-1]),
        "limit_reached": bool(not ok[-1]),
        "points": int(ok.sum()),
        "max_residual": float(np.max(np.asarray(pad.states.residual)[ok])),
        "max_constraint_residual_m": float(np.max(ch["constraint_residual"])),
        "wall_time_s": wall,
        "curve": {k: v.tolist() for k, v in curve.items()},
    }
