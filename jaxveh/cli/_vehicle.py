"""``jaxveh vehicle`` and ``jaxveh rig``: the 14-DOF car's summary and its kinematic rigs."""

import time
from pathlib import Path

import numpy as np
import typer

from .._core import ParameterError
from ._common import emit_json, fail, new_app, write_json

vehicle_app = new_app("The 14-DOF car with its flexible chassis: summary.")
rig_app = new_app("Quasi-static kinematic rigs of the car (Figs. 6.11, 6.12).")

VehicleOpt = typer.Option(None, "--vehicle", help="car TOML file (default: the shipped car.toml)")
ModesOpt = typer.Option(6, "--modes", help="chassis modes, 0 (rigid) to 20")
JsonOpt = typer.Option(False, "--json", help="print only JSON on stdout")
OutOpt = typer.Option(None, "--out", help="write JSON, CSV and a PNG into this folder")
PointsOpt = typer.Option(21, "--points", help="points of the sweep (>= 3)")
LoadedOpt = typer.Option(
    False, "--loaded", help="hold the chassis modes as loaded at rest instead of balancing them at every point"
)


def _car(vehicle: Path | None, modes: int):
    from .. import vehicle as veh

    return veh.load_car(vehicle, modes=modes)


def _errors():
    from ..multibody import MultibodyError

    return (ParameterError, MultibodyError)


@vehicle_app.command()
def info(vehicle: Path = VehicleOpt, modes: int = ModesOpt, as_json: bool = JsonOpt) -> None:
    """Masses, static corner loads, wheel rates, ride frequencies, roll stiffness and λ,
    chassis modes and model sizes."""
    from .. import vehicle as veh

    try:
        out = veh.vehicle_info(_car(vehicle, modes))
    except _errors() as e:
        fail(str(e))
    if as_json:
        emit_json(out)
        return
    c = out["corner_loads_n"]
    typer.echo(f"mass {out['total_mass_kg']:.1f} kg; corner loads FL {c['fl']:.1f} FR {c['fr']:.1f} "
               f"RL {c['rl']:.1f} RR {c['rr']:.1f} N (front share {100 * out['front_load_share']:.2f} %)")
    for axle in ("front", "rear"):
        typer.echo(f"{axle}: wheel rate {out['wheel_rate_n_per_m'][axle] / 1e3:.2f} N/mm, ride "
                   f"{out['ride_frequency_hz'][axle]:.2f} Hz, roll stiffness "
                   f"{out['roll_stiffness_nm_per_deg'][axle]:.1f} Nm/deg")
    typer.echo(f"roll stiffness distribution λ = {out['roll_stiffness_distribution']:.3f}")
    modes_hz = ", ".join(f"{f:.1f}" for f in out["chassis_modes_hz"]) or "rigid chassis"
    typer.echo(f"chassis modes (Hz): {modes_hz}")
    m = out["model"]
    typer.echo(f"{m['bodies']} bodies, {m['coordinates']} coordinates, {m['constraints']} constraints, "
               f"{m['independent_velocities']} independent velocities, {m['auxiliary_states']} auxiliary states")


def _sweep(points: int, limit: float) -> np.ndarray:
    if points < 3:
        fail(f"--points must be >= 3, got {points}")
    return np.linspace(-limit, limit, points)


def _write(out_dir: Path | None, name: str, report: dict, x_key: str, plot) -> None:
    """JSON, one CSV per axle block and the figure into ``out_dir``."""
    if out_dir is None:
        return
    from .. import plots

    out_dir = Path(out_dir)
    write_json(report, out_dir / f"{name}.json")
    for block, values in report.items():
        if not isinstance(values, dict) or not all(isinstance(v, list) for v in values.values()):
            continue
        keys = list(values)
        x = report[x_key] if x_key in report else values[keys[0]]
        rows = np.column_stack([x] + [[np.nan if v is None else v for v in values[k]] for k in keys])
        header = ",".join([x_key] + keys) if x_key in report else ",".join(keys)
        data = rows if x_key in report else rows[:, 1:]
        np.savetxt(out_dir / f"{name}_{block}.csv", data, delimiter=",", header=header, comments="")
    plots.save(plot(report, title=f"{name} rig"), out_dir / f"{name}.png")


def _run_rig(name, make, vehicle, modes, points, limit, loaded, out_dir, as_json, x_key, plot):
    from .. import vehicle as veh

    try:
        car = _car(vehicle, modes)
        state = veh.static_equilibrium(car) if (loaded and modes) else None
        start = time.perf_counter()
        report = make(car, _sweep(points, limit), not loaded, state)
        report["elapsed_s"] = time.perf_counter() - start
        report["modes"] = modes
        report["chassis"] = "rigid" if modes == 0 else ("loaded at rest" if loaded else "flexible")
    except _errors() as e:
        fail(str(e))
    _write(out_dir, name, report, x_key, plot)
    if as_json:
        emit_json(report)
    else:
        typer.echo(f"{name} rig: {points} points in {report['elapsed_s']:.1f} s (compilation included)"
                   + (f"; wrote {out_dir}" if out_dir else ""))


@rig_app.command()
def bump(vehicle: Path = VehicleOpt, modes: int = ModesOpt, points: int = PointsOpt,
         travel: float = typer.Option(50.0, "--travel", help="largest wheel travel (mm), swept +-"),
         loaded: bool = LoadedOpt, out: Path = OutOpt, as_json: bool = JsonOpt) -> None:
    """Bump test: both wheels of each axle moved vertically (Fig. 6.11)."""
    from .. import plots, vehicle as veh

    _run_rig("bump", veh.bump_report, vehicle, modes, points, travel, loaded, out, as_json, "travel_mm",
             plots.plot_bump)


@rig_app.command()
def steer(vehicle: Path = VehicleOpt, modes: int = ModesOpt, points: int = PointsOpt,
          angle: float = typer.Option(120.0, "--angle", help="largest steering-wheel angle (deg), swept +-"),
          loaded: bool = LoadedOpt, out: Path = OutOpt, as_json: bool = JsonOpt) -> None:
    """Steering test: the steering wheel turned (Fig. 6.12)."""
    from .. import plots, vehicle as veh

    _run_rig("steer", veh.steer_report, vehicle, modes, points, angle, loaded, out, as_json,
             "steering_wheel_deg", plots.plot_steer)


@rig_app.command()
def roll(vehicle: Path = VehicleOpt, modes: int = ModesOpt, points: int = PointsOpt,
         angle: float = typer.Option(2.0, "--angle", help="largest chassis roll (deg), swept +-"),
         loaded: bool = LoadedOpt, out: Path = OutOpt, as_json: bool = JsonOpt) -> None:
    """Roll test: the chassis rolled with the wheels on the ground (roll camber, roll steer,
    roll stiffness per axle)."""
    from .. import plots, vehicle as veh

    _run_rig("roll", veh.roll_report, vehicle, modes, points, angle, loaded, out, as_json, "roll_deg",
             plots.plot_roll)


RigidOpt = typer.Option(False, "--rigid", help="rigid chassis (same as --modes 0)")


@vehicle_app.command()
def lltd(vehicle: Path = VehicleOpt, modes: int = ModesOpt, rigid: bool = RigidOpt,
         radius: float = typer.Option(50.0, "--radius", help="skid-pad radius (m)"),
         as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """Lateral load transfer distribution χ (front share) of the car on the skid-pad at low
    ay (steady states by root finding) beside the chapter-3 model's χ (eqs. 3.4-3.6) for the
    car's own roll stiffnesses and geometry, and the load transfer against ay (Fig. 7.2a)."""
    from ..analysis import lltd_report

    try:
        report = lltd_report(_car(vehicle, 0 if rigid else modes), radius)
    except _errors() as e:
        fail(str(e))
    if out is not None:
        out = Path(out)
        write_json(report, out / "lltd.json")
        c = report["curve"]
        keys = [k for k in c if k != "ay_g"]
        rows = np.column_stack([c["ay_g"]] + [np.asarray(c[k], float) for k in keys])
        np.savetxt(out / "lltd.csv", rows, delimiter=",", header=",".join(["ay_g"] + keys), comments="")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"{report['chassis']}: chi {report['chi_low_ay']:.4f} at low ay "
               f"({report['low_ay_g'][0]:g}-{report['low_ay_g'][1]:g} g) on R = "
               f"{report['radius_m']:g} m (lambda {report['lam']:.3f}, mu {report['mu']:.3f})")
    typer.echo(f"chapter 3: eq. 3.4 rigid {report['chi_eq_3_4_rigid']:.4f}, eq. 3.5 flexible "
               f"{report['chi_eq_3_5_flexible']:.4f}; eq. 3.6 (mean track) rigid "
               f"{report['chi_eq_3_6_rigid_mean_track']:.4f}, flexible {report['chi_eq_3_6_flexible_mean_track']:.4f}"
               + (f"; wrote {out}" if out else ""))


@vehicle_app.command("root-locus")
def root_locus(vehicle: Path = VehicleOpt, modes: int = ModesOpt,
               sweep: str = typer.Option("coupling", "--sweep", help="coupling (0 to 1), speed (5 to 120 km/h) or "
                                         "first-mode (first chassis mode's free-free frequency, 12 to 120 Hz)"),
               speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="speed of the straight running linearised "
                                               "about, km/h (not for --sweep speed)"),
               as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """Root locus of the linearised car (Fig. 7.7): eigenvalues along a sweep, each mode
    tracked by MAC and labelled by where its kinetic energy sits; for the coupling sweep the
    first chassis mode's uncoupled and coupled frequencies."""
    from ..analysis import root_locus_report
    from ._simulate import _compilation_cache

    _compilation_cache()
    if not speed_kmh > 0.0:
        fail(f"--speed-kmh must be > 0, got {speed_kmh:g}")
    try:
        report = root_locus_report(_car(vehicle, modes), sweep, speed=speed_kmh / 3.6)
    except (*_errors(), RuntimeError) as e:
        fail(str(e))
    if out is not None:
        from .. import plots

        out = Path(out)
        write_json(report, out / "root_locus.json")
        loci = {f"{k + 1}: {m['label']}": (np.asarray(m["real_per_s"]) + 2j * np.pi * np.asarray(m["frequency_hz"]))
                [:, None] for k, m in enumerate(report["modes"])}
        fig = plots.plot_root_locus(loci, title=f"root locus, {sweep} sweep (Fig. 7.7; square: start, circle: end)")
        fig.set_size_inches(9.5, 5.5)
        fig.axes[0].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside the loci, not on them
        plots.save(fig, out / "root_locus.png")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"root locus, {sweep} sweep over {report['values'][0]:g}-{report['values'][-1]:g} {report['unit']} "
               f"({len(report['values'])} points)" + (f"; wrote {out}" if out else ""))
    for m in report["modes"]:
        f, z = m["frequency_hz"], m["damping_ratio"]
        typer.echo(f"  {m['label']:>22}: {f[0]:7.2f} -> {f[-1]:7.2f} Hz, damping {z[0]:.3f} -> {z[-1]:.3f}")
    if "first_chassis_mode_hz" in report:
        c = report["first_chassis_mode_hz"]
        typer.echo(f"first chassis mode: {c['uncoupled']:.2f} Hz uncoupled -> {c['coupled']:.2f} Hz coupled "
                   f"({c['label']})")


@vehicle_app.command("lltd-modes")
def lltd_modes(vehicle: Path = VehicleOpt,
               max_modes: int = typer.Option(10, "--max-modes", help="largest number of chassis modes, 1 to 20"),
               radius: float = typer.Option(50.0, "--radius", help="skid-pad radius (m)"),
               as_json: bool = JsonOpt) -> None:
    """χ (front share of the lateral load transfer at low ay on the skid-pad) against the
    number of chassis modes 0 ... --max-modes (Fig. 7.2c; thesis: χ = 0.441 with six modes
    against eq. 3.6's 0.445), beside eq. 3.6 with the car's own stiffnesses and geometry."""
    from .. import analytic
    from ..analysis import analytic_vehicle, chapter3_parameters, chi_by_modes
    from ._simulate import _compilation_cache

    _compilation_cache()
    start = time.perf_counter()
    try:
        chi = chi_by_modes(max_modes, vehicle, radius)
        p = chapter3_parameters(_car(vehicle, 6))
    except _errors() as e:
        fail(str(e))
    report = {"modes": list(range(max_modes + 1)), "chi_by_modes": [float(x) for x in np.asarray(chi)],
              "chi_eq36": float(analytic.chi(analytic_vehicle(p))), "lam": float(p.lam), "radius_m": radius,
              "wall_time_s": time.perf_counter() - start}
    if as_json:
        emit_json(report)
        return
    typer.echo(f"chi vs number of chassis modes (lambda {report['lam']:.3f}, R = {radius:g} m; eq. 3.6: "
               f"{report['chi_eq36']:.4f}):")
    for n, c in zip(report["modes"], report["chi_by_modes"], strict=True):
        typer.echo(f"  {n:2d} modes: {c:.4f}")


@vehicle_app.command("kinematic-gradients")
def kinematic_gradients(vehicle: Path = VehicleOpt, modes: int = ModesOpt,
                        radius: float = typer.Option(50.0, "--radius", help="skid-pad radius (m)"),
                        ay_ref_g: float = typer.Option(0.3, "--ay-ref-g", help="lateral acceleration the gradients "
                                                       "are taken at (g; a multiple of 0.05 g)"),
                        as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """Table 7.1: camber and toe-in change per g of lateral acceleration due to the chassis
    deformation (deformation gradients of the projection matrix R times the modal
    coordinates' exact gradients on the skid-pad, turning left), front and rear left wheels,
    beside the thesis's; with --out also Fig. 7.4 (full model vs linear approximation)."""
    from ..analysis import kinematic_gradients_report
    from ._simulate import _compilation_cache

    _compilation_cache()
    if not radius > 0.0:
        fail(f"--radius must be > 0 (m), got {radius:g}")
    try:
        report = kinematic_gradients_report(_car(vehicle, modes), radius, ay_ref_g)
    except (*_errors(), RuntimeError) as e:
        fail(str(e))
    if out is not None:
        from .. import plots

        out = Path(out)
        write_json(report, out / "kinematic_gradients.json")
        plots.save(plots.plot_kinematic_gradients(report, title=f"effect of the chassis on the kinematics, "
                                                  f"R = {radius:g} m (Fig. 7.4)"), out / "kinematic_gradients.png")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"kinematic gradients due to the chassis ({modes} modes, R = {radius:g} m, at "
               f"{report['reference_ay_g']:.2f} g, left wheels; thesis Table 7.1 in brackets):")
    for axle in ("front", "rear"):
        r, t = report[axle], report["thesis_table_7_1"][axle]
        typer.echo(f"  {axle:>5}: camber {r['camber_deg_per_g']:+.4f} ({t['camber_deg_per_g']:+.3f}) deg/g, "
                   f"toe-in {r['toe_deg_per_g']:+.4f} ({t['toe_deg_per_g']:+.3f}) deg/g")
    if out is not None:
        typer.echo(f"wrote {out}")


@vehicle_app.command("preview")
def preview(vehicle: Path = VehicleOpt, modes: int = ModesOpt,
            speed_kmh: float = typer.Option(100.0, "--speed-kmh", help="speed of the straight running, km/h"),
            points: int = typer.Option(250, "--points", help="preview points (>= 2; the thesis's 250)"),
            as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """TI-optimal preview control of the linearised car (Fig. 7.10): preview gains and
    preview distance with all chassis modes, with the first k (k = 0: rigid), beside the
    chapter-3 model's."""
    from ..analysis import preview_report
    from ._simulate import _compilation_cache

    _compilation_cache()
    if not 0.0 < speed_kmh <= 360.0:
        fail(f"--speed-kmh must be in (0, 360], got {speed_kmh:g}")
    if points < 2:
        fail(f"--points must be >= 2, got {points}")
    try:
        report = preview_report(_car(vehicle, modes), speed_kmh, points)
    except (*_errors(), RuntimeError) as e:
        fail(str(e))
    if out is not None:
        from .. import plots

        out = Path(out)
        write_json(report, out / "preview.json")
        plots.save(plots.plot_car_preview(report), out / "preview.png")
    if as_json:
        emit_json(report)
        return
    lp = {k: report[k]["preview_distance_m"] for k in ("flexible", "rigid")}
    lp3 = {k: report["chapter_3"][k]["preview_distance_m"] for k in ("flexible", "rigid")}
    typer.echo(f"preview distance at {speed_kmh:g} km/h ({points} points): flexible {lp['flexible']:.2f} m, rigid "
               f"{lp['rigid']:.2f} m; chapter-3 model {lp3['flexible']:.2f} / {lp3['rigid']:.2f} m")
    typer.echo("  by number of modes: " + ", ".join(f"{k}: {lp:.2f}" for k, lp in
                                                    enumerate(report["preview_distance_by_modes_m"])))


@vehicle_app.command("frequency-response")
def frequency_response(vehicle: Path = VehicleOpt, modes: int = ModesOpt,
                       input: str = typer.Option("steering", "--input", help="steering, heave or warp (the posts)"),
                       speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="speed of the straight running, km/h"),
                       f_max: float = typer.Option(20.0, "--f-max", help="highest frequency, Hz"),
                       points: int = typer.Option(200, "--points", help="log-spaced frequencies from 0.1 Hz"),
                       as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """Exact frequency responses of the linearised car (Figs 7.8, 7.9): yaw rate, ay,
    sideslip, roll and twist per degree of steering-wheel angle, or the front-left tyre load,
    twist, roll, travel and modal coordinates per mm of post motion (heave: the four posts
    together, warp: diagonals in anti-phase)."""
    from ..analysis import linear_frequency_response, linearise
    from ._simulate import _compilation_cache

    _compilation_cache()
    if input not in ("steering", "heave", "warp"):
        fail(f"--input must be steering, heave or warp, got {input!r}")
    if not 0.0 < speed_kmh <= 360.0:
        fail(f"--speed-kmh must be in (0, 360], got {speed_kmh:g}")
    if not 0.1 < f_max <= 200.0:
        fail(f"--f-max must be in (0.1, 200] Hz, got {f_max:g}")
    if points < 2:
        fail(f"--points must be >= 2, got {points}")
    start = time.perf_counter()
    try:
        lin = linearise(_car(vehicle, modes), speed_kmh / 3.6)
    except (*_errors(), RuntimeError) as e:
        fail(str(e))
    f = np.logspace(-1.0, np.log10(f_max), points)
    report = {"input": input, "speed_kmh": speed_kmh, "modes": modes,
              "per": "deg of steering-wheel angle" if input == "steering" else "mm at the front-left post",
              **linear_frequency_response(lin, f, input), "wall_time_s": time.perf_counter() - start}
    if out is not None:
        from .. import plots

        out = Path(out)
        write_json(report, out / "frequency_response.json")
        title = f"linearised car at {speed_kmh:g} km/h, {input} input"
        fig = (plots.plot_frequency_response({f"{modes} modes": report}, title=title) if input == "steering"
               else plots.plot_four_post({f"{modes} modes": report}, title=title))
        plots.save(fig, out / "frequency_response.png")
    if as_json:
        emit_json(report)
        return
    names = [k.removesuffix("_gain") for k in report if k.endswith("_gain")]
    typer.echo(f"frequency responses per {report['per']} at {speed_kmh:g} km/h ({modes} modes), peak gains:")
    for name in names:
        gain = np.asarray(report[f"{name}_gain"])
        typer.echo(f"  {name:>18}: {gain.max():.4g} at {f[gain.argmax()]:.2f} Hz")


@vehicle_app.command("simplifications")
def simplifications(vehicle: Path = VehicleOpt, modes: int = ModesOpt,
                    variants: str = typer.Option(None, "--variants",
                                                 help="comma-separated variants (default: all of Table 7.2's)"),
                    freeze_steps: int = typer.Option(5, "--freeze-steps",
                                                     help="steps the projection matrices are held (>= 1)"),
                    duration: float = typer.Option(5.0, "--duration", help="length of the step steer, s (> 0.6)"),
                    rtol: float = typer.Option(1e-4, "--rtol", help="relative tolerance of the integration"),
                    rigid: bool = typer.Option(True, "--rigid/--no-rigid", help="add the rigid-chassis car's row"),
                    as_json: bool = JsonOpt, out: Path = OutOpt) -> None:
    """Table 7.2 and section 7.6 on the library car: the step steer of Fig. 7.6 with the
    complete flexible model and each simplification (constant mass matrix, neglected Gr/Ge,
    S c, S b, centre-of-mass shift, projection matrices held for k steps): steps, wall time
    and each channel's largest deviation from the complete model."""
    from ..analysis import SIMPLIFICATIONS, simplification_study, table_7_2_step_steer
    from ._simulate import _compilation_cache

    _compilation_cache()
    chosen = tuple(SIMPLIFICATIONS) if variants is None else tuple(v.strip() for v in variants.split(","))
    unknown = [v for v in chosen if v not in SIMPLIFICATIONS]
    if unknown or not chosen:
        fail(f"--variants must name some of {', '.join(SIMPLIFICATIONS)}; unknown: {', '.join(unknown) or '(none)'}")
    if modes < 1:
        fail(f"--modes must be >= 1 (the simplifications concern the flexible chassis), got {modes}")
    if freeze_steps < 1:
        fail(f"--freeze-steps must be >= 1, got {freeze_steps}")
    if not duration > 0.6:
        fail(f"--duration must be > 0.6 s (the step rises at 0.5-0.6 s), got {duration:g}")
    if not 0.0 < rtol < 1.0:
        fail(f"--rtol must be in (0, 1), got {rtol:g}")
    try:
        report = simplification_study(_car(vehicle, modes), _car(vehicle, 0) if rigid else None, chosen,
                                      freeze_steps, table_7_2_step_steer(duration), rtol)
    except (*_errors(), RuntimeError) as e:
        fail(str(e))
    if out is not None:
        from .. import plots

        out = Path(out)
        write_json(report, out / "simplifications.json")
        plots.save(plots.plot_simplifications(report), out / "simplifications.png")
    if as_json:
        emit_json(report)
        return
    typer.echo(f"{'variant':<20}{'steps':>7}{'wall s':>9}{'yaw rate dev.':>15}{'ay dev.':>10}{'modes dev.':>12}")
    for name, row in report["variants"].items():
        dev = row.get("relative_deviation", {})
        cols = "".join(f"{dev[k]:>{w}.1e}" if k in dev else f"{'-':>{w}}"
                       for k, w in (("yaw_rate", 15), ("ay", 10), ("modes", 12)))
        typer.echo(f"{name:<20}{row['steps']:>7}{row['wall_s']:>9.2f}{cols}")
