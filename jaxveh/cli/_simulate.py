"""``jaxveh simulate``: manoeuvres of the 14-DOF car (fast or library form), open-loop and
with the closed-loop driver."""

import math
import os
import sys
from pathlib import Path

import numpy as np
import typer

from .._core import ParameterError
from ._common import emit_json, fail, new_app, write_curve_csv, write_json

app = new_app("Manoeuvres of the 14-DOF car with its flexible chassis.")

VehicleOpt = typer.Option(None, "--vehicle", help="car TOML file (default: the shipped car.toml)")
ModesOpt = typer.Option(6, "--modes", help="chassis modes, 0 (rigid) to 20")
RigidOpt = typer.Option(False, "--rigid", help="rigid chassis (same as --modes 0)")
FormOpt = typer.Option("fast", "--form", help="fast (minimal coordinates) or library (the multibody reference)")
SpeedOpt = typer.Option(90.0, "--speed-kmh", help="speed held by the powertrain, km/h")
RtolOpt = typer.Option(1e-4, "--rtol", help="relative tolerance of the step-size controller")
JsonOpt = typer.Option(False, "--json", help="print only JSON on stdout")
OutOpt = typer.Option(None, "--out", help="write JSON, CSV, netCDF (manoeuvres) and a PNG into this folder")
QuietOpt = typer.Option(False, "--quiet", help="no progress messages on stderr")
ParamOpt = typer.Option(None, "--param", help="set a car parameter, PATH=VALUE (repeatable): arb_rates[0]=30000, "
                        "chassis.stiffness_scale[0]=2, coupling=0.5 (paths into CarParams, SI units)")


def _params(settings) -> dict:
    """``{path: value}`` from ``--param PATH=VALUE`` options."""
    out = {}
    for item in settings or ():
        path, sep, value = item.rpartition("=")
        try:
            if not sep or not path.strip():
                raise ValueError
            out[path.strip()] = float(value)
        except ValueError:
            fail(f"--param {item!r}: expected PATH=VALUE with a number, e.g. arb_rates[0]=30000")
    return out


def _load(vehicle, modes, form, settings):
    """The car with ``--param`` settings applied (checked)."""
    from ..vehicle import load_car, with_params

    return with_params(load_car(vehicle, modes=modes, form=form), _params(settings))


def _compilation_cache() -> None:
    """Keep compiled programs between runs (the car's first compilation takes minutes),
    unless the caller already chose a cache folder."""
    import jax

    if jax.config.jax_compilation_cache_dir:
        return
    folder = Path(os.environ.get("JAXVEH_CACHE", Path.home() / ".cache" / "jaxveh" / "jax"))
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)


def _say(quiet: bool, message: str) -> None:
    if not quiet and sys.stderr.isatty():
        typer.echo(message, err=True)


def _write(out_dir: Path, name: str, run, report: dict, panels=None) -> None:
    from .. import plots
    from ..manoeuvre import UNITS, write_netcdf

    out_dir = Path(out_dir)
    write_json(report, out_dir / f"{name}.json")
    columns, header = [np.asarray(run.ts)], ["t_s"]
    order = list(UNITS)  # the channels in their documented order (jit returns them sorted by name)
    for key in sorted(run.channels, key=lambda k: order.index(k) if k in order else len(order)):
        v = np.asarray(run.channels[key])
        unit = run.units[key]
        if v.ndim == 1:
            columns.append(v)
            header.append(f"{key}_{unit}")
        else:
            labels = ("fl", "fr", "rl", "rr") if v.shape[1] == 4 and key != "modes" else range(1, v.shape[1] + 1)
            for k, label in enumerate(labels):
                columns.append(v[:, k])
                header.append(f"{key}_{label}_{unit}")
    np.savetxt(out_dir / f"{name}.csv", np.column_stack(columns), delimiter=",", header=",".join(header),
               comments="")
    attrs = {k: v for k, v in report.items() if isinstance(v, (str, int, float)) and not isinstance(v, bool)}
    write_netcdf(run, out_dir / f"{name}.nc", attrs)
    history = {"t_s": np.asarray(run.ts)} | {k: np.asarray(v) for k, v in run.channels.items()}
    panels = {} if panels is None else {"panels": panels}
    plots.save(plots.plot_manoeuvre({report["chassis"]: history}, title=report["title"], **panels),
               out_dir / f"{name}.png")


def _run(name: str, manoeuvre, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics=None,
         points: int = 501, figures=None, settings=None, panels=None):
    """Simulate, report (plus ``metrics(run)``), write the files (plus ``figures(report)``:
    name -> figure; ``panels``: the time plot's, :func:`jaxveh.plots.plot_manoeuvre`) and
    print."""
    from ..manoeuvre import simulate

    _compilation_cache()
    modes = 0 if rigid else modes
    try:
        car = _load(vehicle, modes, form, settings)
        _say(quiet, f"jaxveh: {name}, {modes} chassis modes, {form} form (the first run compiles for minutes)")
        run = simulate(car, manoeuvre, rtol=rtol, points=points)
    except (ParameterError, RuntimeError) as e:
        fail(str(e))
    report = {
        "manoeuvre": name,
        "form": form,
        "modes": modes,
        "chassis": "rigid" if modes == 0 else f"flexible, {modes} modes",
        "speed_kmh": float(manoeuvre.speed) * 3.6,
        "duration_s": float(manoeuvre.duration),
        "rtol": rtol,
        "solver": run.solver,
        "wall_time_s": run.wall_s,
        "steps": int(run.steps),
        "rejected_steps": int(run.rejected_steps),
        "max_constraint_residual_m": float(np.max(np.asarray(run.channels["constraint_residual"]))),
        "stop_reason": run.stop_reason,
        "params": _params(settings),
    }
    if metrics is not None:
        report |= metrics(run, car)
    report["title"] = f"{name} at {report['speed_kmh']:g} km/h, {report['chassis']} ({form} form)"
    if out_dir is not None:
        _write(out_dir, name.replace("-", "_"), run, report, panels)
        if figures is not None:
            from .. import plots

            for suffix, fig in figures(report).items():
                plots.save(fig, Path(out_dir) / f"{name.replace('-', '_')}_{suffix}.png")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"{report['title']}: {report['wall_time_s']:.2f} s (after compilation), "
               f"{report['steps']} steps" + (f"; wrote {out_dir}" if out_dir else ""))
    for key, value in report.items():
        if isinstance(value, bool):
            typer.echo(f"  {key} = {str(value).lower()}")
        elif (isinstance(value, float) and key not in ("wall_time_s", "duration_s", "amplitude_mm")
              and key.endswith(("_s", "_pct", "_deg_s", "_g", "_deg", "_per_g", "_m", "_hz", "_per_mm"))
              and key not in ("wall_time_s", "duration_s")):
            typer.echo(f"  {key} = {value:.4g}")


def _speed(speed_kmh: float) -> float:
    if not speed_kmh > 0.0:
        fail(f"--speed-kmh must be > 0 (the manoeuvre holds a speed), got {speed_kmh:g}")
    return speed_kmh / 3.6


@app.command("step-steer")
def step_steer(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = SpeedOpt,
    steer_deg: float = typer.Option(6.0, "--steer-deg", help="final steering-wheel angle, deg (negative: right)"),
    duration: float = typer.Option(5.0, "--duration", help="s"),
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Step steer (Fig. 7.6): the steering wheel turns to --steer-deg between 0.5 and 0.7 s
    (a cubic with continuous rate) at a held speed; yaw-rate response time, overshoot and
    steady values."""
    from ..manoeuvre import step_steer as make, step_steer_metrics

    try:
        m = make(speed=_speed(speed_kmh), angle=math.radians(steer_deg), duration=duration)
    except ParameterError as e:
        fail(str(e))
    _run("step-steer", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet,
         lambda run, car: step_steer_metrics(run.ts, run.channels, m.steering), settings=param)


@app.command("ramp-steer")
def ramp_steer(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(40.0, "--speed-kmh", help="speed held, km/h (Fig. 6.13: 40)"),
    rate_deg_s: float = typer.Option(4.0, "--rate-deg-s", help="steering-wheel rate, deg/s (negative: right)"),
    duration: float = typer.Option(10.0, "--duration", help="s"),
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Ramp steer (Fig. 6.13): the steering wheel turns at a constant rate from 0.5 s;
    constant-speed understeer, steering-wheel, roll and sideslip gradients (ISO 4138) from
    the samples between 0.1 and 0.3 g."""
    from ..manoeuvre import Manoeuvre, RampSteer, ramp_steer_metrics

    try:
        law = RampSteer(rate=math.radians(rate_deg_s), start=0.5, blend=0.1)
        m = Manoeuvre(steering=law, speed=_speed(speed_kmh), duration=duration)
    except ParameterError as e:
        fail(str(e))
    def metrics(run, car):
        wheelbase = float(car.params.vehicle.a + car.params.vehicle.b)
        try:
            return ramp_steer_metrics(run.channels, wheelbase)
        except ParameterError as e:  # a ramp too short or too gentle to reach 0.3 g
            return {"metrics_error": str(e)}

    _run("ramp-steer", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, points=2001,
         settings=param)


@app.command("sine-sweep")
def sine_sweep(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="speed held, km/h (Fig. 6.15: 50)"),
    steer_deg: float = typer.Option(5.0, "--steer-deg", help="steering-wheel amplitude, deg (Fig. 6.15: 5)"),
    f_max: float = typer.Option(15.0, "--f-max", help="end frequency, Hz (Fig. 6.15: 15)"),
    duration: float = typer.Option(120.0, "--duration", help="sweep time, s (Table 6.6: 120)"),
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Swept sine (Fig. 6.15): frequency rising linearly from 0 to --f-max over --duration;
    yaw-rate and ay frequency responses per steering-wheel angle by FFT with a Gaussian
    window (section 6.4.3), saved at 10 points per period of --f-max."""
    from .. import plots
    from ..manoeuvre import Manoeuvre, SweptSine, frequency_response

    if not f_max > 0.0:
        fail(f"--f-max must be > 0 Hz, got {f_max:g}")
    try:
        law = SweptSine(amplitude=math.radians(steer_deg), f0=0.0, f1=f_max, sweep=duration, start=0.0)
        m = Manoeuvre(steering=law, speed=_speed(speed_kmh), duration=duration)
    except ParameterError as e:
        fail(str(e))

    def metrics(run, car):
        r = frequency_response(run.ts, run.channels, f_max=f_max)
        return {"frequency_response": {k: np.asarray(v).tolist() for k, v in r.items()}}

    def figures(report):
        r = {k: np.asarray(v) for k, v in report["frequency_response"].items()}
        return {"frf": plots.plot_frequency_response({report["chassis"]: r}, title=report["title"])}

    points = max(501, math.ceil(10.0 * f_max * duration) + 1)
    _run("sine-sweep", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, points, figures, param)


@app.command("four-post")
def four_post(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    pattern: str = typer.Option("warp", "--pattern", help="warp (each axle's wheels in anti-phase, diagonals "
                                "together) or heave (all posts in phase)"),
    speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="rolling speed on the posts, km/h"),
    amplitude_mm: float = typer.Option(0.2, "--amplitude-mm", help="post displacement amplitude, mm (small enough "
                                       "to keep the tyres on the posts at the warp resonance)"),
    f_max: float = typer.Option(30.0, "--f-max", help="end frequency of the sweep from 0, Hz (Fig. 7.9: 30)"),
    duration: float = typer.Option(40.0, "--duration", help="sweep time, s"),
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Four-post rig (Fig. 7.9): the car rolls straight on four posts sweeping in sine from 0
    to --f-max Hz after 0.5 s; RMS contact-patch load variation per tyre, the smallest load,
    and frequency responses per front-left post displacement of the front-left load, the
    chassis twist and the modal coordinates (peaks between 0.5 Hz and --f-max), saved at 10
    points per period of --f-max."""
    from .. import plots
    from ..manoeuvre import four_post as make, four_post_metrics

    if not f_max > 0.0:
        fail(f"--f-max must be > 0 Hz, got {f_max:g}")
    try:
        m = make(speed=_speed(speed_kmh), pattern=pattern, amplitude=amplitude_mm * 1e-3, f1=f_max, sweep=duration)
    except ParameterError as e:
        fail(str(e))

    def metrics(run, car):
        return {"pattern": pattern, "amplitude_mm": amplitude_mm} | four_post_metrics(run.ts, run.channels,
                                                                                     f_range=(0.5, f_max))

    def figures(report):
        return {"frf": plots.plot_four_post({report["chassis"]: report["frequency_response"]}, title=report["title"])}

    points = max(501, math.ceil(10.0 * f_max * float(m.duration)) + 1)
    _run("four-post", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, points, figures, param)


def _straight_line(name: str, speed_kmh, final_speed_kmh, rate_g, duration, vehicle, modes, rigid, form, rtol,
                   out_dir, as_json, quiet, param):
    """Acceleration or braking from --speed-kmh to --final-speed-kmh at ``rate_g``."""
    from ..manoeuvre import accelerate, brake, straight_line_metrics

    flag = "--accel-g" if name == "accelerate" else "--decel-g"
    if not rate_g > 0.0:
        fail(f"{flag} must be > 0 g, got {rate_g:g}")
    if not final_speed_kmh > 0.0:
        fail(f"--final-speed-kmh must be > 0 (the tyre model needs rolling wheels), got {final_speed_kmh:g}")
    try:
        make = accelerate if name == "accelerate" else brake
        m = make(_speed(speed_kmh), final_speed_kmh / 3.6, rate_g, duration=duration)
    except ParameterError as e:
        fail(str(e))

    def metrics(run, car):
        out = {"final_speed_kmh": final_speed_kmh}
        try:
            return out | straight_line_metrics(run.ts, run.channels, m.speed_target)
        except ParameterError as e:
            return out | {"metrics_error": str(e)}

    from ..plots import STRAIGHT_LINE_PANELS

    _run(name, m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, settings=param,
         panels=STRAIGHT_LINE_PANELS)


DurationAutoOpt = typer.Option(None, "--duration", help="s (default: the speed change and 1 s after)")


@app.command("accelerate")
def accelerate(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(30.0, "--speed-kmh", help="start speed, km/h"),
    final_speed_kmh: float = typer.Option(90.0, "--final-speed-kmh", help="final speed, km/h"),
    accel_g: float = typer.Option(0.6, "--accel-g", help="target acceleration, g"),
    duration: float = DurationAutoOpt,
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Straight-line acceleration: from 0.5 s the powertrain follows a speed ramp at --accel-g
    (rising over 0.2 s) to --final-speed-kmh through the rear wheels; mean and peak ax, time
    and distance to the final speed, squat (pitch per g) and the axle loads."""
    _straight_line("accelerate", speed_kmh, final_speed_kmh, accel_g, duration, vehicle, modes, rigid, form, rtol,
                   out_dir, as_json, quiet, param)


@app.command("brake")
def brake(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(100.0, "--speed-kmh", help="start speed, km/h"),
    final_speed_kmh: float = typer.Option(20.0, "--final-speed-kmh", help="final speed, km/h (> 0)"),
    decel_g: float = typer.Option(1.0, "--decel-g", help="target deceleration, g (> 0)"),
    duration: float = DurationAutoOpt,
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Straight-line braking: from 0.5 s the brakes follow a speed ramp at --decel-g (rising
    over 0.2 s) to --final-speed-kmh, the torque split between the axles by the car's
    brake_front_share; mean and peak deceleration, time and distance to the final speed,
    dive (pitch per g) and the axle load and torque shares."""
    _straight_line("brake", speed_kmh, final_speed_kmh, decel_g, duration, vehicle, modes, rigid, form, rtol,
                   out_dir, as_json, quiet, param)


@app.command("brake-in-turn")
def brake_in_turn(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(80.0, "--speed-kmh", help="start speed, km/h"),
    radius_m: float = typer.Option(100.0, "--radius-m", help="radius of the circle before braking, m (the steering "
                                   "for it from the car's steady state; ignored with --steer-deg)"),
    steer_deg: float = typer.Option(None, "--steer-deg", help="steering-wheel angle held, deg from straight "
                                    "running's (negative: right; default: the angle for --radius-m)"),
    right: bool = typer.Option(False, "--right", help="turn right on the --radius-m circle (default left)"),
    decel_g: float = typer.Option(0.5, "--decel-g", help="target deceleration, g (> 0)"),
    final_speed_kmh: float = typer.Option(None, "--final-speed-kmh", help="final speed, km/h (default: half the "
                                          "start speed)"),
    brake_start_s: float = typer.Option(3.0, "--brake-start-s", help="brake onset, s (the steering turns in from "
                                        "0.5 to 0.7 s)"),
    duration: float = DurationAutoOpt,
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """Braking in a turn, open loop (after ISO 7975): the steering wheel turns in and is held,
    the car settles on its circle, then brakes at --decel-g; 1 s after the onset the yaw rate
    against the initial circle's at the current speed, the heading and path deviations from
    that circle, the sideslip change and ay."""
    import jax.numpy as jnp

    from ..manoeuvre import BRAKE_IN_TURN_AFTER, brake_in_turn as make, brake_in_turn_metrics, circle_steer

    if not decel_g > 0.0:
        fail(f"--decel-g must be > 0 g, got {decel_g:g}")
    speed = _speed(speed_kmh)
    final_speed = 0.5 * speed if final_speed_kmh is None else final_speed_kmh / 3.6
    if not 0.0 < final_speed < speed:
        fail(f"--final-speed-kmh must lie in (0, --speed-kmh = {speed_kmh:g}) km/h, got {final_speed * 3.6:g}")
    if steer_deg is None:
        if not radius_m > 0.0:
            fail(f"--radius-m must be > 0 m, got {radius_m:g}")
        _compilation_cache()
        try:
            car = _load(vehicle, 0 if rigid else modes, form, param)
            steer_deg = math.degrees(float(circle_steer(car, speed, radius_m, right=right)))
        except (ParameterError, RuntimeError) as e:
            fail(f"no steady state on the --radius-m {radius_m:g} m circle at {speed_kmh:g} km/h: {e}")
    try:
        m = make(speed, math.radians(steer_deg), decel_g, final_speed=final_speed, brake_start=brake_start_s,
                 duration=duration)
    except ParameterError as e:
        fail(str(e))

    def metrics(run, car):
        out = {"steer_deg": steer_deg, "decel_target_g": decel_g, "final_speed_kmh": final_speed * 3.6}
        reached = np.asarray(run.ts)[np.asarray(run.valid)]
        if not reached.size or reached[-1] < brake_start_s + BRAKE_IN_TURN_AFTER:
            return out | {"metrics_error": f"the run stopped ({run.stop_reason}) before {BRAKE_IN_TURN_AFTER:g} s "
                                           "into the braking: no metrics"}
        try:
            values = brake_in_turn_metrics(run.ts, run.channels, m.speed_target)
        except ParameterError as e:
            return out | {"metrics_error": str(e)}
        before = np.interp([brake_start_s - 0.5, brake_start_s], np.asarray(run.ts),
                           np.asarray(run.channels["yaw_rate"]))
        steady = bool(abs(before[1] - before[0]) <= 0.01 * abs(before[1]))
        return out | {k: float(jnp.asarray(v)) for k, v in values.items()} | {
            "after_s": BRAKE_IN_TURN_AFTER, "steady_before_brake": steady}

    from ..plots import BRAKE_IN_TURN_PANELS

    _run("brake-in-turn", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, settings=param,
         panels=BRAKE_IN_TURN_PANELS)


PreviewOpt = typer.Option(0.8, "--preview-s", help="driver's preview time, s (preview distance = speed x time)")
LagOpt = typer.Option(0.1, "--lag-s", help="driver's steering lag, s")


@app.command("lane-change")
def lane_change(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    speed_kmh: float = typer.Option(80.0, "--speed-kmh", help="speed held, km/h (ISO 3888-1: 80)"),
    offset: float = typer.Option(3.5, "--offset", help="lateral offset of the second lane, m (negative: right)"),
    entry: float = typer.Option(10.0, "--entry", help="run-up before the track, m"),
    preview_s: float = PreviewOpt, lag_s: float = LagOpt,
    duration: float = typer.Option(None, "--duration", help="s (default: until 10 m past the track)"),
    rtol: float = RtolOpt, out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt,
    param: list[str] = ParamOpt,
) -> None:
    """ISO 3888-1 double lane change with the closed-loop pure-pursuit driver: the car's
    largest distance from the reference path, its margin to the lanes' cones (lanes_cleared),
    peak steering, ay and yaw rate; saved at 100 points per second."""
    from ..manoeuvre import car_width, lane_change as make, lane_change_metrics

    _compilation_cache()
    try:
        car = _load(vehicle, 0 if rigid else modes, form, param)
        m = make(car, speed=_speed(speed_kmh), entry=entry, offset=offset, duration=duration,
                 preview_time=preview_s, lag=lag_s)
    except ParameterError as e:
        fail(str(e))
    width = car_width(car)

    def metrics(run, car):
        return {"car_width_m": width} | lane_change_metrics(run.channels, m.steering.path, width)

    points = max(501, math.ceil(100.0 * float(m.duration)) + 1)
    _run("lane-change", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics, points,
         settings=param)


def _skid_pad_time_run(vehicle, modes, rigid, form, radius, speed_kmh, duration, turn, preview_s, lag_s, rtol,
                       out_dir, as_json, quiet, param):
    """The closed-loop skid-pad: the pure-pursuit driver on the circle for ``duration``."""
    from ..manoeuvre import constant_radius, constant_radius_metrics

    _compilation_cache()
    try:
        car = _load(vehicle, 0 if rigid else modes, form, param)
        m = constant_radius(car, radius=radius, speed=_speed(speed_kmh), duration=duration, turn=turn,
                            preview_time=preview_s, lag=lag_s)
    except ParameterError as e:
        fail(str(e))

    def metrics(run, car):
        try:
            return constant_radius_metrics(run.ts, run.channels, m.steering.path)
        except ParameterError as e:
            return {"metrics_error": str(e)}

    _run("skid-pad-time-run", m, vehicle, modes, rigid, form, rtol, out_dir, as_json, quiet, metrics,
         settings=param)


@app.command("skid-pad")
def skid_pad(
    vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt, form: str = FormOpt,
    radius: float = typer.Option(50.0, "--radius", help="circle radius, m (Fig. 7.5: 50)"),
    ay_max_g: float = typer.Option(2.5, "--ay-max-g", help="highest lateral acceleration tried, g"),
    step_g: float = typer.Option(0.05, "--ay-step-g", help="lateral acceleration step, g (also the first point)"),
    time_run: bool = typer.Option(False, "--time-run", help="closed-loop time run at --speed-kmh instead"),
    speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="time run: speed held, km/h"),
    duration: float = typer.Option(30.0, "--duration", help="time run: s"),
    right: bool = typer.Option(False, "--right", help="time run: turn right"),
    preview_s: float = PreviewOpt, lag_s: float = LagOpt, rtol: float = RtolOpt,
    out_dir: Path = OutOpt, as_json: bool = JsonOpt, quiet: bool = QuietOpt, param: list[str] = ParamOpt,
) -> None:
    """Skid-pad (Fig. 7.5): the car's steady states on a circle by root finding, from
    --ay-step-g to the grip limit; understeer gradient (deg/g, at the first point), dynamic
    steer angle, steering sensitivity, sideslip and roll against ay. With --time-run: the
    pure-pursuit driver follows the circle from straight running at --speed-kmh for
    --duration; the settled path radius, steering, ay, sideslip and roll."""
    from .. import plots
    from ..manoeuvre import skid_pad_report

    if time_run:
        _skid_pad_time_run(vehicle, modes, rigid, form, radius, speed_kmh, duration, -1.0 if right else 1.0,
                           preview_s, lag_s, rtol, out_dir, as_json, quiet, param)
        return
    _compilation_cache()
    modes = 0 if rigid else modes
    if form != "fast":
        fail(f"--form {form!r}: the skid-pad's steady states are found on the fast car only (allowed: fast)")
    if not radius > 0.0:
        fail(f"--radius must be > 0 m, got {radius:g}")
    try:
        car = _load(vehicle, modes, form, param)
        _say(quiet, f"jaxveh: skid-pad R = {radius:g} m, {modes} chassis modes (the first run compiles for minutes)")
        report = skid_pad_report(car, radius, ay_max_g, step_g)
    except (ParameterError, RuntimeError) as e:
        fail(str(e))
    chassis = "rigid" if modes == 0 else f"flexible, {modes} modes"
    report = {"manoeuvre": "skid-pad", "method": "steady states by root finding", "form": form, "modes": modes,
              "chassis": chassis, "params": _params(param)} | report
    report["title"] = f"skid-pad R = {radius:g} m, {chassis}"
    if out_dir is not None:
        out_dir = Path(out_dir)
        write_json(report, out_dir / "skid_pad.json")
        curve = report["curve"]
        write_curve_csv(out_dir / "skid_pad.csv", curve)
        plots.save(plots.plot_skid_pad({chassis: curve}, title=report["title"]), out_dir / "skid_pad.png")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"{report['title']}: {report['points']} steady states up to {report['ay_limit_g']:.2f} g in "
               f"{report['wall_time_s']:.2f} s (compilation included on a first run)"
               + (f"; wrote {out_dir}" if out_dir else ""))
    typer.echo(f"  understeer gradient at {report['understeer_gradient_at_g']:.2f} g = "
               f"{report['understeer_gradient_deg_per_g']:.4g} deg/g")
