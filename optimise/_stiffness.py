"""How stiff is stiff enough? (issue 14, study (a); the thesis's Fig. 7.2d question, solved.)

For each chassis mode i considered alone (the other modes frozen, i.e. rigid, as the
thesis's Fig. 7.2d considers "modes singly"), the smallest stiffness multiplier µ_i from
which on every quantity of the study (χ and the understeer gradient by default) stays
within ``tolerance`` (relative) of the rigid car's value at every roll stiffness
distribution λ of the study (set through the anti-roll bars,
:func:`optimise.arb_rates_for_lambda`). Then the modes together: every mode at its own
minimum, and the common factor s >= 1 on all of them that brings the car as a whole within
the tolerance.

The rigid reference is the same car with every mode frozen (stiffness multiplied by
:data:`jaxveh.analysis.FREEZE`; a frozen mode's share of χ is below 1e-7, tested in
tests/test_analysis_load_transfer.py), so the reference, the scans and the searches share
the same compiled programs: the quantities of one design at one λ, a program per shared
computation (:func:`handling_core`).

The search is on the forward model, not by gradients: each mode's deviation is scanned
over a geometric grid of µ, the last grid interval where it crosses the tolerance is
halved in log µ until its ends are within ``rtol`` of each other, and the answer is the
interval's upper (stiff-enough) end. A design whose steady state does not converge counts
as outside the tolerance (recorded per point in the scans).

A study file::

    [study]
    name = "stiff_enough"             # output names; default: the file's stem
    description = "..."               # optional
    vehicle = "my_car.toml"           # optional car file, relative to the study file
    modes = 6                         # chassis modes (>= 1)

    [[quantities]]                    # one table per quantity kept near the rigid car's
    name = "chi"                      # an objective of optimise.OBJECTIVES (skid-pad or load transfer)
    ay_g = [0.05, 0.1]                # its settings (default: the objective's)

    [[quantities]]
    name = "understeer_gradient"

    [requirement]
    tolerance = 0.02                  # relative to the rigid car's value, at every λ
    lambda = [0.3, 0.4, 0.5, 0.6, 0.7]
    mu = [0.1, 0.316, 1.0]            # the scan's multipliers (increasing, > 0), or
    # mu_range = [0.1, 1e4, 11]       # start, stop, number (geometric)
    rtol = 0.01                       # the bisection stops when the interval's ends differ by this ratio

    [run]
    out = "results/stiff_enough"      # default results/<name>
"""

import json
import math
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple, Optional

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from jaxveh import ParameterError, run_time_checks_off, vehicle
from jaxveh.analysis import FREEZE

from ._objectives import OBJECTIVES, arb_rates_for_lambda, objective_spec, objective_values, roll_rate_coefficients
from ._optimise_study import _spec, vehicle_path
from ._study import _check_keys, _err, _is_int, _is_number, read_study_file

#: The relative tolerance of the issue's question: within 2 % of the rigid car.
TOLERANCE = 0.02
#: Roll stiffness distributions of the question, λ in [0.3, 0.7].
LAMBDAS = (0.3, 0.4, 0.5, 0.6, 0.7)
#: The scan's multipliers by default: 0.1 to 1e4, two per decade.
MU_SCAN = tuple(float(m) for m in np.round(np.logspace(-1.0, 4.0, 11), 12))
#: Ratio of the bisection's interval ends at which it stops by default.
RTOL = 0.01
#: The quantities by default: χ and the understeer gradient at their default settings.
DEFAULT_QUANTITIES = ("chi", "understeer_gradient")
#: Sources of the quantities a study may use (the mode objectives need a chassis mode,
#: which the rigid reference has not).
_SOURCES = ("skid_pad", "load_transfer")
_KEYS = {
    "file": ("study", "quantities", "requirement", "run"),
    "study": ("name", "description", "vehicle", "modes", "model"),
    "requirement": ("tolerance", "lambda", "mu", "mu_range", "rtol"),
    "run": ("out",),
}


class StiffnessStudy(NamedTuple):
    """A "how stiff is stiff enough" study (module docs): the car (``vehicle`` file or None
    for the shipped one, ``modes``), the ``quantities`` (:class:`~optimise.ObjectiveSpec`),
    the relative ``tolerance``, the ``lambdas``, the scan's multipliers ``mu``, the
    bisection's ``rtol``, the output folder ``out``."""

    name: str
    quantities: tuple
    tolerance: float = TOLERANCE
    lambdas: tuple = LAMBDAS
    mu: tuple = MU_SCAN
    rtol: float = RTOL
    vehicle: Optional[str] = None
    modes: int = 6
    out: str = "results/stiff_enough"
    description: str = ""
    file: Optional[str] = None


def _increasing(where: str, key: str, values, low: float, high: float) -> tuple:
    if not isinstance(values, list) or not values or not all(_is_number(v) for v in values):
        raise _err(where, key, f"= {values!r} is not allowed: a non-empty list of numbers")
    if not all(low < v < high for v in values) or not all(b > a for a, b in zip(values, values[1:])):
        raise _err(where, key, f"= {values!r} is not allowed: strictly increasing numbers in ({low:g}, {high:g})")
    return tuple(float(v) for v in values)


def _mu_scan(where: str, table: dict) -> tuple:
    if "mu" in table and "mu_range" in table:
        raise _err(where, "requirement.mu", "and requirement.mu_range are both given: write one")
    if "mu_range" in table:
        r = table["mu_range"]
        if not (isinstance(r, list) and len(r) == 3 and all(_is_number(v) for v in r[:2]) and _is_int(r[2])):
            raise _err(where, "requirement.mu_range", f"= {r!r} is not allowed: [start, stop, number]")
        start, stop, num = float(r[0]), float(r[1]), r[2]
        if not (0 < start < stop < FREEZE and 2 <= num <= 101):
            raise _err(where, "requirement.mu_range", f"= {r!r} is not allowed: 0 < start < stop < {FREEZE:g} and "
                       "2 to 101 points")
        return tuple(float(m) for m in np.geomspace(start, stop, num))
    mu = _increasing(where, "requirement.mu", table.get("mu", list(MU_SCAN)), 0.0, FREEZE)
    if len(mu) < 2:
        raise _err(where, "requirement.mu", f"= {list(mu)!r} is not allowed: at least 2 multipliers")
    return mu


def _quantities(where: str, tables) -> tuple:
    if tables is None:
        return tuple(objective_spec(n) for n in DEFAULT_QUANTITIES)
    if not isinstance(tables, list) or not tables:
        raise _err(where, "quantities", "is not a non-empty array of tables: write [[quantities]] tables")
    specs = []
    for i, table in enumerate(tables):
        key = f"quantities[{i}]"
        if not isinstance(table, dict):
            raise _err(where, key, "is not a table")
        spec = _spec(where, key, table, ("name",))
        source = OBJECTIVES[spec.name].source
        if source not in _SOURCES:
            allowed = [n for n, o in OBJECTIVES.items() if o.source in _SOURCES]
            raise _err(where, f"{key}.name", f"= {spec.name!r} is not allowed: the rigid reference has no chassis "
                       f"mode; allowed {', '.join(allowed)}")
        if spec in specs:
            raise _err(where, key, f"repeats quantity {spec.name!r} with the same settings")
        specs.append(spec)
    return tuple(specs)


def is_stiffness_study(path) -> bool:
    """Whether the TOML file ``path`` is a stiffness-requirement study (it has a
    ``[requirement]`` table); False for anything else, unreadable files included (their
    loaders report those)."""
    try:
        return isinstance(read_study_file(path)[1].get("requirement"), dict)
    except ParameterError:
        return False


def load_stiffness_study(path, *, out=None) -> StiffnessStudy:
    """The study of the TOML file ``path`` (module docs), with the output folder ``out``
    overridden. ``ParameterError`` naming the file and key for anything not allowed."""
    path = Path(path)
    where, data = read_study_file(path)
    _check_keys(where, "file", data, _KEYS["file"])
    for section in ("study", "requirement", "run"):
        if not isinstance(data.get(section, {}), dict):
            raise _err(where, section, f"is not a table: write a [{section}] section")
        _check_keys(where, section, data.get(section, {}), _KEYS[section])
    study_t, req, run_t = data.get("study", {}), data.get("requirement", {}), data.get("run", {})
    if study_t.get("model", "car") != "car":
        raise _err(where, "study.model", f"= {study_t['model']!r} is not allowed: 'car' (the chapter-6 car)")
    lambdas = _increasing(where, "requirement.lambda", req.get("lambda", list(LAMBDAS)), 0.0, 1.0)
    mu = _mu_scan(where, req)
    quantities = _quantities(where, data.get("quantities"))
    name = study_t.get("name", path.stem)
    if not isinstance(name, str) or not re.match(r"^[A-Za-z0-9_.-]+$", name):
        raise _err(where, "study.name", f"= {name!r} is not allowed: letters, digits, '_', '.', '-'")
    description = study_t.get("description", "")
    if not isinstance(description, str):
        raise _err(where, "study.description", "is not a string")
    out = str(out) if out is not None else run_t.get("out", f"results/{name}")
    if not isinstance(out, str) or not out:
        raise _err(where, "run.out", f"= {out!r} is not allowed: a folder path")
    study = StiffnessStudy(name=name, quantities=quantities, tolerance=req.get("tolerance", TOLERANCE),
                           lambdas=lambdas, mu=mu, rtol=req.get("rtol", RTOL), modes=study_t.get("modes", 6), out=out,
                           description=description, file=where)
    check_stiffness_study(study)  # tolerance, rtol, modes: the checks a study built in Python gets
    return study._replace(tolerance=float(study.tolerance), rtol=float(study.rtol),
                          vehicle=vehicle_path(where, path, study_t.get("vehicle")))


# ---- the model --------------------------------------------------------------------------------


def handling_core(car, coefficients, lam, scale, specs):
    """The quantities ``specs`` (one array, :func:`optimise.objective_values`) of ``car``
    with the modal stiffness multipliers ``scale`` (``chassis.stiffness_scale``) at the
    roll stiffness distribution ``lam`` (set through the bars by
    :func:`optimise.arb_rates_for_lambda` with ``coefficients``); NaN where a steady state
    failed. Pure."""
    params = eqx.tree_at(lambda p: p.chassis.stiffness_scale, car.params, scale)
    params = eqx.tree_at(lambda p: p.arb_rates, params, arb_rates_for_lambda(coefficients, lam))
    return objective_values(eqx.tree_at(lambda c: c.params, car, params), specs)


_compiled_handling = eqx.filter_jit(handling_core)


class Handling(NamedTuple):
    """The study's model: ``evaluate(scale) -> (n_lambda, n_quantities)`` NumPy values
    (NaN where a steady state failed), the ``car``, its free-free natural frequencies
    ``frequencies_hz`` at its own multipliers and the ``base_scale`` (the car's own
    multipliers)."""

    car: object
    evaluate: Callable
    frequencies_hz: np.ndarray
    base_scale: np.ndarray


def build_handling(study: StiffnessStudy) -> Handling:
    """Load the study's car and prepare its compiled model (:class:`Handling`).

    One compiled call per λ and per shared computation (skid-pad point, load transfer),
    not one vmapped call: batched over λ, XLA's CPU runtime ran the designs' LAPACK
    triangular solves concurrently, each splitting its batch over the same 2-thread pool
    and waiting for it, and the 6-mode car's program hung (jaxlib 0.10.2, ``lapack_dtrsm_ffi``
    in ``ParallelBatchMap``; single-threaded Eigen did not help). Unbatched, every solve
    runs in place."""
    car = vehicle.load_car(study.vehicle, modes=study.modes)
    vehicle.check_car(car)
    coefficients = roll_rate_coefficients(car)
    base = np.asarray(car.params.chassis.stiffness_scale, float)
    groups = {}
    for q, spec in enumerate(study.quantities):
        groups.setdefault(spec.source_key, []).append(q)

    def evaluate(scale):
        scale = np.asarray(scale, float)
        if scale.shape != base.shape or not np.all(np.isfinite(scale)) or not np.all(scale > 0):
            raise ParameterError(f"scale = {scale.tolist()!r} is not allowed: {base.size} finite multipliers > 0")
        out = np.empty((len(study.lambdas), len(study.quantities)))
        for j, lam in enumerate(study.lambdas):
            for columns in groups.values():
                specs = tuple(study.quantities[q] for q in columns)
                with run_time_checks_off():
                    out[j, columns] = np.asarray(_compiled_handling(car, coefficients, jnp.asarray(lam),
                                                                    jnp.asarray(scale), specs))
        return out

    return Handling(car=car, evaluate=evaluate, frequencies_hz=np.asarray(car.params.chassis.frequencies_hz, float),
                    base_scale=base)


# ---- the search -------------------------------------------------------------------------------


def relative_deviation(values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """|values - reference| / |reference| per λ and quantity; infinite where a value is NaN
    (its steady state failed)."""
    dev = np.abs(values - reference) / np.abs(reference)
    return np.where(np.isfinite(dev), dev, np.inf)


class ModeRequirement(NamedTuple):
    """One mode's answer: ``mu_min`` (the smallest multiplier from which on the car stays
    within the tolerance; None when even the scan's largest does not), ``status``
    (``"found"``, ``"below_range"``: within the tolerance over the whole scan, ``mu_min``
    its smallest multiplier; ``"above_range"``), ``frequency_hz`` (the mode's free-free
    frequency at ``mu_min``), the binding ``quantity`` and ``lambda`` at ``mu_min``'s lower
    neighbour, the scan's deviations ``scan`` ((n_mu, n_lambda, n_quantities)), the
    bisection's evaluations ``bisection`` [(mu, max deviation)]."""

    mode: int
    mu_min: Optional[float]
    status: str
    frequency_hz: Optional[float]
    quantity: Optional[str]
    lam: Optional[float]
    scan: np.ndarray
    bisection: list


class StiffnessResult(NamedTuple):
    """The study's answer (module docs): ``reference`` (the rigid car's quantities per λ),
    ``nominal`` (the car as loaded) and its deviations, each mode's
    :class:`ModeRequirement`, the ``joint`` check (all modes at their minima), the common
    ``factor`` and the multipliers ``joint_mu`` (relative to the car's own) that bring the
    car as a whole within the tolerance (None when a mode has no minimum), the count of
    evaluations and the wall time."""

    study: StiffnessStudy
    frequencies_hz: np.ndarray
    reference: np.ndarray
    nominal: np.ndarray
    modes: tuple
    joint_at_minima: Optional[np.ndarray]
    factor: Optional[float]
    joint_mu: Optional[np.ndarray]
    joint_deviation: Optional[np.ndarray]
    evaluations: int
    wall_s: float


def _isolated(base: np.ndarray, mode: int, mu: float) -> np.ndarray:
    scale = base * FREEZE
    scale[mode] = base[mode] * mu
    return scale


def _worst(dev: np.ndarray) -> float:
    return float(np.max(dev))


def _bisect(measure, lo: float, hi: float, dev_hi: np.ndarray, rtol: float, within) -> tuple:
    """Shrink ``(lo, hi)`` (``lo`` outside the tolerance, ``hi`` within it, its deviations
    ``dev_hi``) in log until ``hi / lo <= 1 + rtol``: ``(hi, dev_hi, [(x, deviations)])``."""
    trail = []
    while hi / lo > 1.0 + rtol:
        mid = math.sqrt(lo * hi)
        dev = measure(mid)
        trail.append((mid, dev))
        if within(dev):
            hi, dev_hi = mid, dev
        else:
            lo = mid
    return hi, dev_hi, trail


def _binding(study: StiffnessStudy, dev: Optional[np.ndarray]) -> tuple:
    """The quantity and λ of the largest deviation in ``dev`` (None, None without one)."""
    if dev is None:
        return None, None
    j, q = np.unravel_index(np.argmax(np.where(np.isfinite(dev), dev, 1e300)), dev.shape)
    return study.quantities[q].name, study.lambdas[j]


def check_stiffness_study(study: StiffnessStudy) -> StiffnessStudy:
    """Check a :class:`StiffnessStudy` built in Python as its file would be checked;
    returns it. ``ParameterError`` naming the field and what is allowed."""
    where = study.file or "study"
    if not (_is_number(study.tolerance) and 0 < study.tolerance < 1):
        raise _err(where, "requirement.tolerance", f"= {study.tolerance!r} is not allowed: a number in (0, 1) "
                   "(relative to the rigid car's value)")
    if not (_is_number(study.rtol) and 1e-6 <= study.rtol <= 1):
        raise _err(where, "requirement.rtol", f"= {study.rtol!r} is not allowed: a number in [1e-6, 1]")
    _increasing(where, "requirement.lambda", list(study.lambdas), 0.0, 1.0)
    if len(_increasing(where, "requirement.mu", list(study.mu), 0.0, FREEZE)) < 2:
        raise _err(where, "requirement.mu", f"= {list(study.mu)!r} is not allowed: at least 2 multipliers")
    if not (_is_int(study.modes) and 1 <= study.modes <= 20):
        raise _err(where, "study.modes", f"= {study.modes!r} is not allowed: an integer 1 to 20 (the modes whose "
                   "stiffness is asked for; a rigid car has none)")
    if not study.quantities:
        raise _err(where, "quantities", "is empty: at least one quantity")
    for i, spec in enumerate(study.quantities):
        if spec.name not in OBJECTIVES or OBJECTIVES[spec.name].source not in _SOURCES:
            allowed = [n for n, o in OBJECTIVES.items() if o.source in _SOURCES]
            raise _err(where, f"quantities[{i}].name", f"= {spec.name!r} is not allowed: one of {', '.join(allowed)}")
    return study


def stiffness_requirement(study: StiffnessStudy, handling: Optional[Handling] = None,
                          progress: Optional[Callable[[str], None]] = None) -> StiffnessResult:
    """Run the study (module docs; checked first, :func:`check_stiffness_study`);
    ``progress`` receives a line per stage."""
    check_stiffness_study(study)
    start = time.perf_counter()
    say = progress or (lambda _: None)
    h = handling if handling is not None else build_handling(study)
    base, tol = h.base_scale, study.tolerance
    count = [0]

    def values(scale):
        count[0] += 1
        return h.evaluate(scale)

    say("rigid reference (every mode frozen) and the car as loaded")
    reference, nominal = values(base * FREEZE), values(base)
    if not np.all(np.isfinite(reference)):
        bad = [study.lambdas[i] for i in np.nonzero(~np.all(np.isfinite(reference), axis=1))[0]]
        raise RuntimeError(f"the rigid reference's steady state failed at lambda = {bad}: no requirement can be "
                           "measured against it")

    def deviation(scale):
        return relative_deviation(values(scale), reference)

    def within(dev):
        return _worst(dev) <= tol

    modes = []
    for i in range(base.size):
        say(f"mode {i + 1}: scan of {len(study.mu)} multipliers")
        scan = np.stack([deviation(_isolated(base, i, m)) for m in study.mu])
        outside = np.nonzero([not within(d) for d in scan])[0]
        trail, last_outside = [], scan[outside[-1]] if outside.size else None
        if outside.size == 0:
            mu_min, status = study.mu[0], "below_range"
        elif outside[-1] == len(study.mu) - 1:
            mu_min, status = None, "above_range"
        else:
            k = outside[-1]
            say(f"mode {i + 1}: bisection between mu = {study.mu[k]:.4g} and {study.mu[k + 1]:.4g}")
            mu_min, _, trail = _bisect(lambda m, i=i: deviation(_isolated(base, i, m)), study.mu[k], study.mu[k + 1],
                                       scan[k + 1], study.rtol, within)
            status = "found"
            # the binding deviations: the last point outside the tolerance, just below the answer
            last_outside = next((d for m, d in reversed(trail) if not within(d)), last_outside)
        quantity, lam = _binding(study, last_outside)
        freq = None if mu_min is None else float(h.frequencies_hz[i] * math.sqrt(mu_min))
        modes.append(ModeRequirement(mode=i + 1, mu_min=mu_min, status=status, frequency_hz=freq, quantity=quantity,
                                     lam=lam, scan=scan, bisection=[(m, _worst(d)) for m, d in trail]))

    joint_at_minima = factor = joint_mu = joint_dev = None
    if all(m.mu_min is not None for m in modes):
        mu_min = np.array([m.mu_min for m in modes])
        minima = base * mu_min
        joint_at_minima = deviation(minima)
        factor, joint_dev = 1.0, joint_at_minima
        if not within(joint_at_minima):
            say("all modes together: search of the common factor")
            lo, hi = 1.0, 2.0
            dev_hi = deviation(minima * hi)
            while not within(dev_hi) and hi < 2.0**20:
                lo, hi = hi, 2.0 * hi
                dev_hi = deviation(minima * hi)
            if within(dev_hi):
                factor, joint_dev, _ = _bisect(lambda f: deviation(minima * f), lo, hi, dev_hi, study.rtol, within)
            else:
                factor, joint_dev = None, None
        joint_mu = None if factor is None else mu_min * factor
    return StiffnessResult(study=study, frequencies_hz=h.frequencies_hz, reference=reference, nominal=nominal,
                           modes=tuple(modes), joint_at_minima=joint_at_minima, factor=factor,
                           joint_mu=joint_mu, joint_deviation=joint_dev, evaluations=count[0],
                           wall_s=time.perf_counter() - start)


# ---- outputs ----------------------------------------------------------------------------------


def _number(x) -> Optional[float]:
    """A float for JSON; None for NaN and infinity (a failed steady state)."""
    return float(x) if np.isfinite(x) else None


def _floats(a) -> Optional[list]:
    return None if a is None else [_number(x) for x in np.ravel(a)]


def _per_quantity(study: StiffnessStudy, values: np.ndarray) -> dict:
    """``{quantity: [value per λ]}`` of an ``(n_lambda, n_quantities)`` array."""
    return {s.name: _floats(values[:, q]) for q, s in enumerate(study.quantities)}


def _worst_per_quantity(study: StiffnessStudy, dev: Optional[np.ndarray]) -> Optional[dict]:
    return None if dev is None else {s.name: _number(np.max(dev[:, q])) for q, s in enumerate(study.quantities)}


def stiffness_report(result: StiffnessResult) -> dict:
    """The result as JSON-ready data: settings, the rigid and nominal cars' quantities per λ,
    per mode ``mu_min``, ``status``, ``frequency_hz`` (free-free, at ``mu_min``), the binding
    quantity and λ, the scan's worst deviation per quantity and µ, the bisection; the joint
    check and the common factor."""
    st = result.study
    units = {s.name: OBJECTIVES[s.name].units for s in st.quantities}
    nominal_dev = relative_deviation(result.nominal, result.reference)
    modes = []
    for m in result.modes:
        modes.append({
            "mode": m.mode, "mu_min": m.mu_min, "status": m.status, "frequency_hz": m.frequency_hz,
            "nominal_frequency_hz": float(result.frequencies_hz[m.mode - 1]), "binding_quantity": m.quantity,
            "binding_lambda": m.lam,
            "scan_worst_deviation": {s.name: _floats(np.max(m.scan[:, :, q], axis=1))
                                     for q, s in enumerate(st.quantities)},
            "bisection": [{"mu": mu, "worst_deviation": _number(d)} for mu, d in m.bisection],
        })
    joint = None
    if result.joint_at_minima is not None:
        joint = {"worst_deviation_at_minima": _worst_per_quantity(st, result.joint_at_minima),
                 "factor": result.factor, "mu": _floats(result.joint_mu),
                 "frequency_hz": None if result.joint_mu is None else
                 _floats(result.frequencies_hz * np.sqrt(result.joint_mu)),
                 "worst_deviation": _worst_per_quantity(st, result.joint_deviation)}
    return {
        "study": st.name, "file": st.file, "description": st.description, "modes": st.modes,
        "tolerance": st.tolerance, "lambda": list(st.lambdas), "mu_scan": list(st.mu), "rtol": st.rtol,
        "quantities": [{"name": s.name, "units": units[s.name], **dict(s.settings)} for s in st.quantities],
        "rigid": _per_quantity(st, result.reference), "nominal": _per_quantity(st, result.nominal),
        "nominal_worst_deviation": _worst_per_quantity(st, nominal_dev),
        "nominal_frequency_hz": _floats(result.frequencies_hz),
        "per_mode": modes, "joint": joint, "evaluations": result.evaluations, "wall_s": result.wall_s,
    }


def plot_stiffness_requirement(report: dict, path) -> Path:
    """Worst relative deviation from the rigid car over λ against each mode's multiplier,
    one panel per quantity, with the tolerance and each mode's answer marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [q["name"] for q in report["quantities"]]
    fig, axes = plt.subplots(1, len(names), figsize=(5.6 * len(names), 4.6), squeeze=False)
    mu = np.asarray(report["mu_scan"])
    for ax, name in zip(axes[0], names):
        for m in report["per_mode"]:
            dev = np.asarray([np.nan if d is None else d for d in m["scan_worst_deviation"][name]], float)
            if m["status"] == "above_range":
                answer = ": none in the scan"
            else:
                answer = f": µ ≥ {m['mu_min']:.3g}" + (" (the scan's lowest)" if m["status"] == "below_range" else "")
            line, = ax.loglog(mu, np.where(np.isfinite(dev), dev * 100.0, np.nan), "-o", ms=3,
                              label=f"mode {m['mode']}{answer}")
            if m["mu_min"] is not None and m["status"] == "found":
                ax.axvline(m["mu_min"], color=line.get_color(), lw=0.7, ls=":")
        ax.axhline(report["tolerance"] * 100.0, color="k", lw=0.9, ls="--", label="tolerance")
        ax.set_xlabel("stiffness multiplier µ of the mode (the others rigid)")
        ax.set_ylabel("worst relative deviation over λ (%)")
        ax.set_title(name)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    fig.suptitle(f"How stiff is stiff enough: |value - rigid| / |rigid|\nat λ = {report['lambda'][0]:g}-"
                 f"{report['lambda'][-1]:g}, tolerance {report['tolerance'] * 100:g} %")
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.93))
    path = Path(path)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def write_stiffness_outputs(result: StiffnessResult, out_dir=None) -> dict:
    """Write ``OUT/NAME.json`` (:func:`stiffness_report`) and ``OUT/NAME.png``
    (:func:`plot_stiffness_requirement`); returns ``{"json": path, "png": path}``."""
    out = Path(out_dir if out_dir is not None else result.study.out)
    out.mkdir(parents=True, exist_ok=True)
    report = stiffness_report(result)
    files = {"json": str(out / f"{result.study.name}.json"), "png": str(out / f"{result.study.name}.png")}
    report["files"] = files
    Path(files["json"]).write_text(json.dumps(report, indent=2))
    plot_stiffness_requirement(report, files["png"])
    return files
