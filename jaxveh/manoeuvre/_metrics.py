"""Handling metrics of a manoeuvre's channels (post-processing, NumPy; braking in a turn in
JAX, differentiable)."""

import jax.numpy as jnp
import numpy as np

from .._core import GRAVITY, ParameterError, is_concrete
from ..analytic._transient import _first_crossing
from ..vehicle import SpeedChange
from ._driver import StepSteer
from ._paths import Circle, DoubleLaneChange


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


def frequency_response(ts, channels: dict, outputs=("yaw_rate", "ay"), f_max: float | None = None,
                       window_sigma: float = 0.5, input: str = "steering_wheel_angle") -> dict:
    """Frequency responses of a swept-sine run by FFT (section 6.4.3, Fig. 6.15): each output
    channel and the steering-wheel angle, less their values at the start (straight running),
    times one Gaussian window centred on the record (standard deviation ``window_sigma`` of
    the half record: the thesis's 0.5), give ``H(f) = Y(f) / U(f)`` at the FFT frequencies
    ``k / T`` from the first non-zero one up to ``f_max`` (Hz; default the Nyquist frequency).

    ``input``: the channel taken as the input (default the steering-wheel angle; the
    four-post rig uses a post's height). Every channel named must hold one value per save
    time.

    Returns ``frequency_hz`` and per output ``{name}_gain`` (channel units per unit of the
    input: deg/s/deg for the yaw rate per steering-wheel degree, g/deg for ay), ``{name}_gain_db``
    (20 log10 of it) and ``{name}_phase_deg`` (unwrapped from the lowest frequency, so a
    turn in the steered direction starts near 0). ``ts`` must be evenly spaced (s)."""
    ts = np.asarray(ts, float)
    dt = np.diff(ts)
    if ts.size < 8 or not np.allclose(dt, dt[0], rtol=1e-9, atol=0.0):
        raise ParameterError("ts must hold at least 8 evenly spaced save times for an FFT")
    if not window_sigma > 0.0:
        raise ParameterError(f"window_sigma = {window_sigma!r} is out of range: allowed > 0 (of the half record)")
    nyquist = 0.5 / dt[0]
    f_max = nyquist if f_max is None else float(f_max)
    if not 0.0 < f_max <= nyquist * (1.0 + 1e-12):
        raise ParameterError(f"f_max = {f_max!r} is out of range: allowed (0, {nyquist:g}] Hz (the Nyquist frequency)")
    half = 0.5 * (ts[-1] - ts[0])
    window = np.exp(-0.5 * ((ts - ts[0] - half) / (window_sigma * half)) ** 2)
    if input not in channels or np.ndim(channels[input]) != 1:
        raise ParameterError(f"input {input!r} must be a scalar channel of the run (one value per save time)")
    u = np.asarray(channels[input], float)
    spectrum = np.fft.rfft(window * (u - u[0]))
    freq = np.fft.rfftfreq(ts.size, dt[0])
    keep = (freq > 0.0) & (freq <= f_max * (1.0 + 1e-12))
    out = {"frequency_hz": freq[keep]}
    for name in outputs:
        y = np.asarray(channels[name], float)
        if y.ndim != 1:
            raise ParameterError(f"output {name!r} must be a scalar channel (one value per save time)")
        h = (np.fft.rfft(window * (y - y[0])) / spectrum)[keep]
        out[f"{name}_gain"] = np.abs(h)
        out[f"{name}_gain_db"] = 20.0 * np.log10(np.abs(h))
        out[f"{name}_phase_deg"] = np.rad2deg(np.unwrap(np.angle(h)))
    return out


def ramp_steer_metrics(channels: dict, wheelbase: float, ay_range_g=(0.1, 0.3)) -> dict:
    """Constant-speed gradients of a slow ramp steer (ISO 4138, continuous-steer method),
    each the least-squares slope against ay (g) of the samples with ``|ay|`` in
    ``ay_range_g``: ``understeer_gradient_deg_per_g`` of the dynamic steer angle
    ``delta - l r / V`` (delta the mean front road-wheel angle, l ``wheelbase`` (m), r the
    yaw rate, V the speed: the Ackermann part removed), ``steering_wheel_gradient_deg_per_g``,
    ``roll_gradient_deg_per_g`` and ``sideslip_gradient_deg_per_g``; ``gradient_points`` used. Signs
    as for a left turn (a right ramp gives the same gradients)."""
    lo, hi = (float(x) for x in ay_range_g)
    if not 0.0 <= lo < hi:
        raise ParameterError(f"ay_range_g = {ay_range_g!r} is out of range: allowed 0 <= low < high (g)")
    if not wheelbase > 0.0:
        raise ParameterError(f"wheelbase = {wheelbase!r} is out of range: allowed > 0 (m)")
    ay = np.asarray(channels["ay"], float)
    side = 1.0 if ay[np.argmax(np.abs(ay))] >= 0.0 else -1.0
    use = (side * ay >= lo) & (side * ay <= hi)
    if use.sum() < 3:
        raise ParameterError(f"the run has {int(use.sum())} samples with |ay| in [{lo:g}, {hi:g}] g: steer further "
                             "or save more points (at least 3 needed)")
    speed = np.asarray(channels["speed"], float)
    kinematic = np.rad2deg(wheelbase * np.deg2rad(np.asarray(channels["yaw_rate"], float)) / speed)
    delta = np.asarray(channels["road_wheel_angle"], float)[:, :2].mean(axis=1)
    series = {
        "understeer_gradient_deg_per_g": delta - kinematic,
        "steering_wheel_gradient_deg_per_g": np.asarray(channels["steering_wheel_angle"], float),
        "roll_gradient_deg_per_g": np.asarray(channels["roll"], float),
        "sideslip_gradient_deg_per_g": np.asarray(channels["sideslip"], float),
    }
    out = {key: float(np.polyfit(side * ay[use], side * y[use], 1)[0]) for key, y in series.items()}
    return out | {"gradient_points": int(use.sum())}


def lane_change_metrics(channels: dict, path: DoubleLaneChange, car_width: float) -> dict:
    """ISO 3888-1 lane change: the c.g.'s largest distance from the reference path, the
    smallest margin (m) between the car and a marked lane's edge over the three lanes
    (negative: a cone is hit; the car is its c.g.'s lateral place plus and minus half of
    ``car_width``, its yaw ignored), whether every lane is cleared, and the largest
    steering-wheel angle, lateral acceleration and yaw rate. Save times must be dense
    enough to sample each lane (its 15-25 m)."""
    if not car_width > 0.0:
        raise ParameterError(f"car_width = {car_width!r} is out of range: allowed > 0 m")
    x, y = np.asarray(channels["x"]), np.asarray(channels["y"])
    error = np.asarray(path.lateral_error(np.stack([x, y], axis=-1)))
    margins = []
    for x0, x1, centre, width in path.lanes(car_width):
        inside = (x >= x0) & (x <= x1)
        if not inside.any():
            raise ParameterError(f"the run does not reach the lane from x = {x0:g} to {x1:g} m "
                                 "(too short a duration, or too few save points)")
        margins.append(float(np.min(0.5 * (width - car_width) - np.abs(y[inside] - centre))))
    return {
        "max_path_error_m": float(np.max(np.abs(error))),
        "lane_margin_m": min(margins),
        "lanes_cleared": bool(min(margins) >= 0.0),
        "lane_margins_m": margins,
        "max_steering_wheel_angle_deg": float(np.max(np.abs(channels["steering_wheel_angle"]))),
        "max_ay_g": float(np.max(np.abs(channels["ay"]))),
        "max_yaw_rate_deg_s": float(np.max(np.abs(channels["yaw_rate"]))),
    }


def constant_radius_metrics(ts, channels: dict, path: Circle, settle_window: float = 2.0) -> dict:
    """Closed-loop skid-pad: over the last ``settle_window`` seconds, the mean path radius of
    the c.g. (its speed over the yaw rate), steering-wheel angle, lateral acceleration,
    sideslip and roll, the c.g.'s mean distance from the circle (m, positive inside) and how
    much the steering still moves (its range, deg: a settled run has next to none)."""
    ts = np.asarray(ts)
    if not 0.0 < settle_window < ts[-1] - ts[0]:
        raise ParameterError(f"settle_window = {settle_window!r} is out of range: allowed (0, {ts[-1] - ts[0]:g}) s")
    tail = ts >= ts[-1] - settle_window
    ch = {k: np.asarray(channels[k])[tail] for k in ("speed", "yaw_rate", "steering_wheel_angle", "ay", "sideslip",
                                                      "roll", "x", "y")}
    error = np.asarray(path.lateral_error(np.stack([ch["x"], ch["y"]], axis=-1)))
    return {
        "path_radius_m": float(np.mean(ch["speed"] / np.radians(np.abs(ch["yaw_rate"])))),
        "path_offset_m": float(np.mean(error)),
        "steering_wheel_angle_deg": float(np.mean(ch["steering_wheel_angle"])),
        "steering_wheel_range_deg": float(np.ptp(ch["steering_wheel_angle"])),
        "ay_g": float(np.mean(ch["ay"])),
        "sideslip_deg": float(np.mean(ch["sideslip"])),
        "roll_deg": float(np.mean(ch["roll"])),
    }


def four_post_metrics(ts, channels: dict, f_range=(0.5, 30.0), window_sigma: float = 0.5) -> dict:
    """Metrics of a four-post sweep (:func:`jaxveh.manoeuvre.four_post`, Fig. 7.9): the RMS
    contact-patch load variation of each tyre about its value at the start (N and % of it;
    FL, FR, RL, RR), the smallest load (N; ``wheel_lift`` when a tyre leaves the post), and
    the frequency responses per front-left post displacement (:func:`frequency_response`,
    input the front-left ``road_height``) of the front-left load (N/mm), the chassis twist
    (deg/mm) and each modal coordinate (1/mm), with the frequency and value of each peak in
    ``f_range`` (Hz; twist and modes only on a flexible chassis: None and empty lists on a
    rigid one). The responses' ``frequency_hz`` and gains are returned under
    ``frequency_response`` (gains per mm)."""
    fz = np.asarray(channels["fz"], float)
    static = fz[0]
    rms = np.sqrt(np.mean((fz - static) ** 2, axis=0))
    scalar = {"road": np.asarray(channels["road_height"], float)[:, 0] * 1e3, "fz_front_left": fz[:, 0]}
    modes = np.asarray(channels["modes"], float)
    flexible = modes.shape[1] > 0
    if flexible:  # a rigid chassis has no twist and no modal coordinates
        scalar["twist"] = np.asarray(channels["twist"], float)
        scalar |= {f"mode_{k + 1}": modes[:, k] for k in range(modes.shape[1])}
    outputs = tuple(k for k in scalar if k != "road")
    frf = frequency_response(ts, scalar, outputs=outputs, f_max=f_range[1], window_sigma=window_sigma, input="road")
    f = frf["frequency_hz"]
    band = f >= f_range[0]
    if not np.any(band):
        raise ParameterError(f"f_range = {f_range!r} holds no frequency of the run's FFT (resolution {f[0]:g} Hz)")

    def peak(name):
        g = np.where(band, frf[f"{name}_gain"], -np.inf)
        k = int(np.argmax(g))
        return float(f[k]), float(g[k])

    out = {
        "rms_fz_variation_n": rms.tolist(),
        "rms_fz_variation_pct": (100.0 * rms / static).tolist(),
        "min_fz_n": fz.min(axis=0).tolist(),
        "wheel_lift": bool(np.any(fz <= 0.0)),
    }
    out["fz_front_left_peak_hz"], out["fz_front_left_peak_n_per_mm"] = peak("fz_front_left")
    out["twist_peak_hz"], out["twist_peak_deg_per_mm"] = peak("twist") if flexible else (None, None)
    peaks = [peak(f"mode_{k + 1}") for k in range(modes.shape[1])]
    out["modes_peak_hz"] = [p[0] for p in peaks]
    out["modes_peak_per_mm"] = [p[1] for p in peaks]
    out["frequency_response"] = {"frequency_hz": f.tolist()} | {
        f"{name}_gain": frf[f"{name}_gain"].tolist() for name in outputs}
    return out


#: ``straight_line_metrics``' ``target_followed``: the hold's mean ax within this share of the target.
FOLLOWED = 0.05


def straight_line_metrics(ts, channels: dict, target: SpeedChange, settle_time: float = 0.5) -> dict:
    """Metrics of straight-line acceleration or braking toward ``target`` (the manoeuvre's
    :class:`jaxveh.vehicle.SpeedChange`; the run must end settled at the final speed). The
    hold window runs from ``settle_time`` (s) after the target reaches its full rate to the
    end of the hold; over it: the mean longitudinal acceleration ``ax_mean_g`` (negative
    braking) against the target's ``ax_target_g`` (``target_followed``: within
    :data:`FOLLOWED` of it; false when the tyres' grip or the torque limits cannot give
    the rate, and the other metrics are then those of the car braking or accelerating as
    hard as it can), the mean pitch (``pitch_mean_deg``;
    positive nose down) and the pitch per g of ax (``pitch_gradient_deg_per_g``: the pitch
    less straight running's at the same speed, interpolated linearly in the speed squared
    between the run's first and last samples as the aero loads grow, over the mean ax;
    negative: the nose dives when braking and rises when accelerating), the front axle's mean share of the tyre loads
    (``front_load_share``) and of the wheel torques (``front_torque_share``: the brake
    balance when braking, 0 for the rear-wheel drive). ``time_to_final_speed_s``: from the
    target's start until the speed first comes within 1 % of the change from its final
    value; ``distance_m``: travelled over that time; ``peak_ax_g``: the largest ax in the
    direction of the change."""
    ts = np.asarray(ts, float)
    start, rise, rate = float(target.start), float(target.rise), float(target.rate)
    v0, v1 = float(target.speed), float(target.final_speed)
    sign = 1.0 if v1 > v0 else -1.0
    hold = straight_line_hold(ts, start, rise, abs(v1 - v0) / rate, settle_time)
    speed, ax = np.asarray(channels["speed"]), np.asarray(channels["ax"])
    reached = sign * (speed - v1) >= -0.01 * abs(v1 - v0)
    after = ts >= start
    if not np.any(reached & after):
        raise ParameterError(f"the speed never came within 1 % of the change from {v1:g} m/s: a longer duration, "
                             "or the car cannot follow the target (tyre grip, torque limits)")
    end = int(np.argmax(reached & after))
    window = (ts >= start) & (ts <= ts[end])
    distance = float(np.sum(0.5 * (speed[window][1:] + speed[window][:-1]) * np.diff(ts[window])))
    means = {k: float(v) for k, v in straight_line_means(channels, hold).items()}
    return {
        "ax_target_g": sign * rate / GRAVITY,
        "ax_mean_g": means["ax_mean_g"],
        "target_followed": bool(abs(means["ax_mean_g"] - sign * rate / GRAVITY) <= FOLLOWED * rate / GRAVITY),
        "peak_ax_g": float(sign * np.max(sign * ax)),
        "time_to_final_speed_s": float(ts[end] - start),
        "distance_m": distance,
    } | {k: means[k] for k in ("pitch_mean_deg", "pitch_gradient_deg_per_g", "front_load_share",
                               "front_torque_share")}


def straight_line_hold(ts, start: float, rise: float, change_time: float, settle_time: float):
    """The hold window of :func:`straight_line_metrics` (a NumPy mask of the save times ``ts``,
    s): from ``settle_time`` after the target's rate is reached (``start + rise``) to the end
    of the hold (``start + change_time``); a clear error when it holds fewer than 3."""
    ts = np.asarray(ts, float)
    hold = (ts >= start + rise + settle_time) & (ts <= start + change_time)
    if hold.sum() < 3:
        raise ParameterError(f"the hold at the full rate is too short for the metrics: fewer than 3 save times "
                             f"between {start + rise + settle_time:g} s and {start + change_time:g} s "
                             "(a larger speed change, a lower rate, more points or a shorter settle_time)")
    return hold


def straight_line_means(channels: dict, hold) -> dict:
    """The hold window's means of :func:`straight_line_metrics` (``hold``: a NumPy mask of the
    save times): ``ax_mean_g``, ``pitch_mean_deg``, ``pitch_gradient_deg_per_g``,
    ``front_load_share``, ``front_torque_share``. Pure JAX: differentiable (the optimiser's
    braking objectives)."""
    hold = np.asarray(hold, bool)
    speed, ax, pitch = (jnp.asarray(channels[k]) for k in ("speed", "ax", "pitch"))
    fz, torque = jnp.asarray(channels["fz"]), jnp.asarray(channels["wheel_torque"])
    # straight running's own pitch at each speed (aero loads grow with v^2): linear in v^2
    # between the start and the settled end of the run
    pitch_straight = pitch[0] + (pitch[-1] - pitch[0]) * (speed ** 2 - speed[0] ** 2) / (speed[-1] ** 2 - speed[0] ** 2)
    ax_mean = jnp.mean(ax[hold])
    return {
        "ax_mean_g": ax_mean,
        "pitch_mean_deg": jnp.mean(pitch[hold]),
        "pitch_gradient_deg_per_g": jnp.mean((pitch - pitch_straight)[hold]) / ax_mean,
        "front_load_share": jnp.mean(fz[hold, :2].sum(axis=1) / fz[hold].sum(axis=1)),
        "front_torque_share": jnp.mean(torque[hold, :2].sum(axis=1) / torque[hold].sum(axis=1)),
    }


#: Time (s) after the brake onset at which braking in a turn is measured (ISO 7975's t_n).
BRAKE_IN_TURN_AFTER = 1.0


def brake_in_turn_metrics(ts, channels: dict, target: SpeedChange, after: float = BRAKE_IN_TURN_AFTER) -> dict:
    """How braking changes a steady circle (:func:`jaxveh.manoeuvre.brake_in_turn`), measured
    ``after`` seconds past the brake onset ``t0 = target.start`` against the circle the car
    was on at ``t0`` (radius ``R0`` = speed over yaw rate, centre beside the c.g. across its
    velocity). Pure JAX (channels interpolated linearly between save times): differentiable
    and vmappable; dict of scalars:

    - ``initial_speed_kmh``, ``initial_radius_m`` (``|R0|``), ``initial_ay_g``,
      ``initial_yaw_rate_deg_s`` (at ``t0``);
    - ``yaw_rate_ratio``: yaw rate at ``t0 + after`` over its value at ``t0``;
    - ``yaw_rate_ratio_to_reference``: yaw rate at ``t0 + after`` over the reference's, the
      initial circle driven at the car's current speed (``v / R0``): above 1 the car turns
      into the circle, below 1 it runs wide;
    - ``heading_deviation_deg``: heading change since ``t0`` less the reference's (the
      integral of ``v / R0``), positive into the turn;
    - ``path_deviation_m``: the c.g.'s distance from the initial circle's centre less
      ``|R0|`` (positive: outside the circle);
    - ``sideslip_change_deg`` (into the turn positive), ``ay_g`` at ``t0 + after``;
    - ``deceleration_g``: the mean deceleration over the interval (speed change over time).
    """
    if not after > 0.0:
        raise ParameterError(f"after = {after!r} is out of range: allowed > 0 s")
    if is_concrete(ts) and is_concrete(target.start):  # checked in NumPy (also inside a trace)
        saved, onset = np.asarray(ts, float), float(target.start)
        if not (saved[0] <= onset and onset + after <= saved[-1]):
            raise ParameterError(f"the run must cover the brake onset and {after:g} s after it: saved over "
                                 f"[{saved[0]:g}, {saved[-1]:g}] s, brake onset at {onset:g} s")
    ts = jnp.asarray(ts, jnp.float64)
    t0 = jnp.asarray(target.start, jnp.float64)
    t1 = t0 + after

    def at(name, t):
        return jnp.interp(t, ts, jnp.asarray(channels[name]))

    heading = jnp.unwrap(jnp.radians(jnp.asarray(channels["heading"])))
    yaw0, yaw1 = jnp.radians(at("yaw_rate", t0)), jnp.radians(at("yaw_rate", t1))
    v0, v1 = at("speed", t0), at("speed", t1)
    radius = v0 / yaw0  # signed: positive turning left
    turn = jnp.sign(yaw0)
    grid = jnp.linspace(t0, t1, 201)
    speed_on_grid = at("speed", grid)
    travelled = jnp.sum(0.5 * (speed_on_grid[1:] + speed_on_grid[:-1]) * jnp.diff(grid))
    course = jnp.interp(t0, ts, heading) + jnp.radians(at("sideslip", t0))
    centre = jnp.stack([at("x", t0) - radius * jnp.sin(course), at("y", t0) + radius * jnp.cos(course)])
    position = jnp.stack([at("x", t1), at("y", t1)])
    turned = jnp.interp(t1, ts, heading) - jnp.interp(t0, ts, heading)
    return {
        "initial_speed_kmh": 3.6 * v0,
        "initial_radius_m": jnp.abs(radius),
        "initial_ay_g": at("ay", t0),
        "initial_yaw_rate_deg_s": jnp.degrees(yaw0),
        "yaw_rate_ratio": yaw1 / yaw0,
        "yaw_rate_ratio_to_reference": yaw1 / (v1 / radius),
        "heading_deviation_deg": turn * jnp.degrees(turned - travelled / radius),
        "path_deviation_m": jnp.linalg.norm(position - centre) - jnp.abs(radius),
        "sideslip_change_deg": turn * (at("sideslip", t1) - at("sideslip", t0)),
        "ay_g": at("ay", t1),
        "deceleration_g": (v0 - v1) / after / GRAVITY,
    }
