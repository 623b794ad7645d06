"""Thesis section 7.6 and Table 7.2: simplifications of the library car's equations of motion
on the step steer of Fig. 7.6 — constant mass matrix, neglected ``Gr``/``Ge`` (eq. 5.45),
neglected ``S c`` (Table 7.2's "vector c" of eq. 5.58), neglected ``S b`` (eq. 5.55), the
neglected centre-of-mass shift, and projection matrices held for k steps. Each variant's
largest deviation from the complete flexible model, channel by channel (also as a share of
what the chassis's flexibility itself changes), and its cost: steps and wall time.
"""

import dataclasses
import gc
import time

import jax
import numpy as np

from .._core import ParameterError
from ..manoeuvre import PATH_CHANNELS, StepSteer, simulate, start_trim, step_steer, step_steer_metrics
from ..multibody import FlexOptions

#: The variants by name: ``FlexOptions`` flags, and ``freeze`` for held projection matrices.
SIMPLIFICATIONS = {
    "complete": {},
    "constant_mass": {"constant_mass": True},
    "neglect_gyroscopic": {"neglect_gyroscopic": True},
    "neglect_sc": {"neglect_sc": True},
    "neglect_sb": {"neglect_sb": True},
    "neglect_com_shift": {"neglect_com_shift": True},
    "frozen_projection": {"freeze": True},
}
#: Steps the projection matrices are held for in ``frozen_projection`` (default).
FREEZE_STEPS = 5
#: Fig. 7.6's step: 90 km/h, 6 deg at the steering wheel over 0.1 s from t = 0.5 s, 5 s.
STEP_SPEED, STEP_ANGLE_DEG, STEP_START, STEP_RISE, STEP_DURATION = 25.0, 6.0, 0.5, 0.1, 5.0


def table_7_2_step_steer(duration: float = STEP_DURATION):
    """The step steer the study runs (Fig. 7.6's, ``duration`` s)."""
    return step_steer(speed=STEP_SPEED, angle=float(np.deg2rad(STEP_ANGLE_DEG)), start=STEP_START, rise=STEP_RISE,
                      duration=duration)


def _check_variants(variants) -> tuple[str, ...]:
    variants = tuple(variants)
    unknown = [v for v in variants if v not in SIMPLIFICATIONS]
    if unknown or not variants:
        raise ParameterError(f"variants = {list(variants)!r} are not all known: allowed {', '.join(SIMPLIFICATIONS)}")
    return variants


def variant_car(car, variant: str):
    """``car`` with the ``FlexOptions`` of ``variant`` (held projection matrices are a
    solver setting, not an option: the car is unchanged for ``frozen_projection``)."""
    flags = {k: v for k, v in SIMPLIFICATIONS[_check_variants((variant,))[0]].items() if k != "freeze"}
    return dataclasses.replace(car, system=car.system.with_options(FlexOptions(**flags)))


def _timed_run(car, manoeuvre, freeze_steps: int, rtol: float, points: int, trim, repeats: int) -> tuple:
    """The library-form run from ``trim`` and its cost: ``wall_s`` the best of ``repeats``
    runs after the first (which compiles). The compiled programs are dropped afterwards:
    each variant is a program of its own, and their JIT code's memory mappings add up to
    the kernel's limit (``vm.max_map_count``) within one study otherwise."""
    run_once = lambda: simulate(car, manoeuvre, form="library", rtol=rtol, points=points,  # noqa: E731
                                freeze_steps=freeze_steps, trim=trim)
    start = time.perf_counter()
    run_once()
    first = time.perf_counter() - start
    runs = [run_once() for _ in range(repeats)]
    run = runs[-1]
    wall = min(r.wall_s for r in runs)
    cost = {"steps": int(run.steps), "rejected_steps": int(run.rejected_steps), "wall_s": wall,
            "compile_s": max(first - wall, 0.0)}
    run = jax.tree.map(np.asarray, run)
    jax.clear_caches()
    gc.collect()
    return run, cost


def _compared(run) -> dict:
    return {k: np.asarray(v) for k, v in run.channels.items() if k not in PATH_CHANNELS + ("steering_wheel_angle",)}


def _max_abs(x) -> float:
    return float(np.max(np.abs(x)))


def simplification_study(car, rigid=None, variants=tuple(SIMPLIFICATIONS), freeze_steps: int = FREEZE_STEPS,
                         manoeuvre=None, rtol: float = 1e-4, points: int = 501, repeats: int = 3,
                         on_variant=None) -> dict:
    """Table 7.2 on the library form of ``car`` (flexible): every variant of
    :data:`SIMPLIFICATIONS` runs ``manoeuvre`` (default :func:`table_7_2_step_steer`) at
    ``rtol``; ``rigid`` (the same car without modes, optional) adds the rigid-chassis row and
    the scale of the flexibility's own effect. Per variant: ``steps``, ``rejected_steps``,
    ``wall_s`` (s, the best of ``repeats`` runs after compilation, trim excluded),
    ``compile_s``, the yaw-rate step metrics, and per channel ``max_deviation`` (largest |variant - complete| over time
    and corners/modes, in the channel's unit), ``relative_deviation`` (that over the
    complete run's largest |value|) and ``share_of_flexibility_effect`` (that over the
    largest |complete - rigid|; with ``rigid`` only). Every variant starts from the complete
    model's straight running (the simplifications concern the integration; one trim program
    instead of one per variant). ``on_variant(name, row)`` is called as each row is done."""
    variants = _check_variants(variants)
    if car.n_modes == 0:
        raise ParameterError("car has no chassis modes: the study needs the flexible car (modes >= 1)")
    if rigid is not None and rigid.n_modes != 0:
        raise ParameterError(f"rigid has {rigid.n_modes} modes: pass the car loaded with modes = 0")
    if not (isinstance(repeats, int) and repeats >= 1):
        raise ParameterError(f"repeats = {repeats!r} is out of range: allowed integers >= 1 (timed runs)")
    if not (isinstance(freeze_steps, int) and freeze_steps >= 1):
        raise ParameterError(f"freeze_steps = {freeze_steps!r} is out of range: allowed integers >= 1")
    manoeuvre = table_7_2_step_steer() if manoeuvre is None else manoeuvre
    if not isinstance(manoeuvre.steering, StepSteer):
        raise ParameterError(f"manoeuvre steers by {type(manoeuvre.steering).__name__}: the study needs a step steer")
    complete = variant_car(car, "complete")
    trim = start_trim(complete, manoeuvre.speed, "library")
    base_run, base_cost = _timed_run(complete, manoeuvre, 0, rtol, points, trim, repeats)
    base = _compared(base_run)
    report = on_variant or (lambda name, row: None)
    rows, effect = {}, None
    if rigid is not None:
        rigid_run, rigid_cost = _timed_run(rigid, manoeuvre, 0, rtol, points,
                                           start_trim(rigid, manoeuvre.speed, "library"), repeats)
        rigid_ch = _compared(rigid_run)
        effect = {k: _max_abs(base[k] - rigid_ch[k]) for k in base if k != "modes"}
        rows["rigid"] = rigid_cost | step_steer_metrics(rigid_run.ts, rigid_ch, manoeuvre.steering)
        report("rigid", rows["rigid"])
    for name in variants:
        if name == "complete":
            run, cost = base_run, base_cost
        else:
            freeze = freeze_steps if SIMPLIFICATIONS[name].get("freeze") else 0
            run, cost = _timed_run(variant_car(car, name), manoeuvre, freeze, rtol, points, trim, repeats)
        ch = _compared(run)
        dev = {k: _max_abs(ch[k] - base[k]) for k in base}
        row = cost | step_steer_metrics(run.ts, ch, manoeuvre.steering) | {
            "max_deviation": dev,
            "relative_deviation": {k: dev[k] / max(_max_abs(base[k]), 1e-300) for k in base}}
        if effect is not None:
            row["share_of_flexibility_effect"] = {k: dev[k] / max(effect[k], 1e-300) for k in effect}
        rows[name] = row
        report(name, row)
    return {"variants": rows, "flexibility_effect": effect, "freeze_steps": freeze_steps, "rtol": rtol,
            "modes": car.n_modes, "units": {k: run.units[k] for k in base},
            "manoeuvre": {"speed_kmh": float(manoeuvre.speed) * 3.6,
                          "steering_wheel_deg": float(np.rad2deg(manoeuvre.steering.amplitude)),
                          "duration_s": float(manoeuvre.duration)}}
