"""Study files: a design grid over named variables of a car, the quantities to evaluate on it
and how to run it, as TOML (``jaxveh sweep STUDY.toml``; shared by the optimiser's study
files). Loading checks everything that can be checked without building the model and
raises :class:`~jaxveh.ParameterError` naming the file, the key and what is allowed.

A study file::

    [study]
    name = "lambda_mu_map"            # output names; default: the file's stem
    description = "..."               # optional, copied to the Dataset's attributes
    model = "car"                     # "car" (the chapter-6 car) or "analytic" (chapter 3)
    vehicle = "my_car.toml"           # optional: car file (model "car") or Appendix A file
                                      # ("analytic"), relative to the study file; default: shipped
    modes = 6                         # chassis modes of the car (0-20; model "car" only)
    quantities = ["chi"]              # see QUANTITIES; model "car": also any objective of
                                      # optimise.OBJECTIVES (understeer_gradient, bump_steer, ...)
    ay_g = [0.05, 0.1]                # model "car": lateral accelerations (g), χ between the first two
    radius = 50.0                     # model "car": skid-pad radius (m), of χ

    [settings.understeer_gradient]    # model "car": an objective quantity's settings (default:
    ay_g = 0.3                        # the objective's own, OBJECTIVES[name].settings)

    [[variables]]                     # one table per grid axis, outermost first
    path = "lambda"                   # a path into the parameter pytree, or a label (LABELS)
    start = 0.3                       # start/stop/num (optional log = true: geometric) ...
    stop = 0.7
    num = 8

    [[variables]]
    path = "chassis.stiffness_scale[0]"
    name = "mu_1"                     # coordinate name; default: the path made an identifier
    units = "1"                       # optional; default "1" for labels, "SI" for paths
    values = [0.1, 1.0, 10.0]         # ... or the values themselves (strictly increasing)

    [run]
    backend = "local"                 # "local" or "ray"
    chunk = 16                        # points per compiled call
    out = "results/lambda_mu_map"     # output folder; default results/<name>
    address = "ray://head:10001"      # backend "ray": a cluster; default: start Ray locally
    num_cpus = 2                      # backend "ray", local start: worker CPUs
"""

import math
import re
from pathlib import Path
from typing import NamedTuple, Optional

import numpy as np
import tomllib

from jaxveh import ParameterError
from jaxveh.analysis import LOW_AY_PAIR_G, SKID_PAD_RADIUS
from jaxveh.params import parse_path

from ._objectives import OBJECTIVES, allowed_corners, objective_spec

#: The models a study can run on.
MODELS = ("car", "analytic")
#: Labels that are not paths into the parameter pytree, per model: λ = kF / (kF + kR) (the
#: car: set through the anti-roll bars, ``jaxveh.analysis.arb_rates_for_distribution``; the
#: chapter-3 model: ``jaxveh.analytic.with_distribution``) and, chapter 3 only,
#: µ = kC / (kF + kR).
LABELS = {"car": ("lambda",), "analytic": ("lambda", "mu")}
#: The labels of sweep studies: those of :data:`LABELS` and, on the car, the speed
#: ``speed_kmh`` (km/h) of every objective quantity with a ``speed_kmh`` setting (a traced
#: value: one compiled program for every speed of the grid).
SWEEP_LABELS = {"car": ("lambda", "speed_kmh"), "analytic": ("lambda", "mu")}
#: The range of a swept speed (km/h).
SPEED_RANGE_KMH = (1.0, 360.0)
#: Quantities per model: name -> (units, description).
QUANTITIES = {
    "car": {
        "chi": ("1", "front share of the lateral load transfer at low ay, between the first two ay_g "
                "(jaxveh.analysis.load_transfer_batch(...).chi_low_ay)"),
        **{name: (o.units, o.description + " (optimise.OBJECTIVES)") for name, o in OBJECTIVES.items()
           if name != "chi"},
    },
    "analytic": {
        "chi": ("1", "front share of the lateral load transfer with a torsional chassis, eq. (3.6)"),
        "chi_rigid": ("1", "front share of the lateral load transfer of a rigid chassis, eq. (3.3)"),
        "chi_error": ("1", "|chi - chi_rigid| / chi_rigid"),
        "understeer_gradient": ("deg/g", "linear understeer gradient with a torsional chassis, eq. (3.16)"),
        "understeer_gradient_rigid": ("deg/g", "linear understeer gradient of a rigid chassis, eq. (3.11)"),
    },
}
#: The most grid points a study may have, per model (a car point costs four steady states).
MAX_POINTS = {"car": 4096, "analytic": 1_000_000}
#: The largest chunk (points per compiled call).
MAX_CHUNK = 65536
#: Backends that run the chunks.
BACKENDS = ("local", "ray")
#: Name of the car model's convergence flag in the Dataset (a data variable beside the quantities).
CONVERGED = "converged"
#: Default points per chunk, per model.
DEFAULT_CHUNK = {"car": 16, "analytic": 256}

_KEYS = {
    "study": ("name", "description", "model", "vehicle", "modes", "quantities", "ay_g", "radius"),
    "settings": (),
    "variables": ("path", "name", "units", "values", "start", "stop", "num", "log"),
    "run": ("backend", "chunk", "out", "address", "num_cpus"),
}
_CAR_ONLY = ("modes", "ay_g", "radius")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


class SweepVariable(NamedTuple):
    """One grid axis: coordinate ``name``, ``path`` into the parameter pytree (or a label of
    :data:`LABELS`), its grid ``values`` (strictly increasing), ``units`` and whether the
    grid is geometric (``log``)."""

    name: str
    path: str
    values: tuple[float, ...]
    units: str
    log: bool = False


class Study(NamedTuple):
    """A loaded study file (module docs). ``file`` is the study file's path (``None`` when
    built in Python), used in error messages and to resolve ``vehicle``. ``settings``: the
    car's objective quantities' settings beyond their defaults, ``((name, ((key, value),
    ...)), ...)`` (:func:`quantity_specs`)."""

    name: str
    model: str
    variables: tuple[SweepVariable, ...]
    quantities: tuple[str, ...]
    vehicle: Optional[str] = None
    modes: int = 6
    ay_g: tuple[float, ...] = tuple(LOW_AY_PAIR_G)
    radius: float = SKID_PAD_RADIUS
    backend: str = "local"
    chunk: int = 16
    out: str = "results/study"
    address: Optional[str] = None
    num_cpus: Optional[int] = None
    description: str = ""
    file: Optional[str] = None
    settings: tuple = ()

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one axis per variable."""
        return tuple(len(v.values) for v in self.variables)

    @property
    def n_points(self) -> int:
        """Number of grid points."""
        return math.prod(self.shape)

    def where(self, key: str) -> str:
        """``"FILE: key"`` (or ``"study: key"`` without a file) for error messages."""
        return f"{self.file if self.file else 'study'}: {key}"


def _err(where: str, key: str, message: str) -> ParameterError:
    return ParameterError(f"{where}: {key} {message}")


def _is_int(x) -> bool:
    return isinstance(x, (int, np.integer)) and not isinstance(x, bool)


def _is_number(x) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and math.isfinite(x)


def _check_keys(where: str, section: str, table: dict, allowed) -> None:
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise _err(where, f"{section}.{unknown[0]}", f"is not a known key: allowed keys of [{section}] are "
                   f"{', '.join(allowed)}")


def _identifier(path: str) -> str:
    name = re.sub(r"[^A-Za-z0-9_]+", "_", path).strip("_")
    return name if _NAME.match(name) else f"v_{name}"


def grid_values(where: str, key: str, table: dict) -> tuple[float, ...]:
    """The grid values of one ``[[variables]]`` table: ``values = [...]`` (finite, strictly
    increasing) or ``start``, ``stop`` (> start), ``num`` (>= 2) with optional ``log``
    (geometric; start > 0). ``ParameterError`` naming ``key`` otherwise."""
    has_values = "values" in table
    has_range = any(k in table for k in ("start", "stop", "num"))
    log = table.get("log", False)
    if not isinstance(log, bool):
        raise _err(where, f"{key}.log", f"= {log!r} is not allowed: true or false")
    if has_values == has_range:
        raise _err(where, key, "needs either values = [...] or start, stop and num (not both)")
    if has_values:
        values = table["values"]
        if log:
            raise _err(where, f"{key}.log", "applies to start/stop/num only (values are given as they are)")
        if not isinstance(values, list) or not values:
            raise _err(where, f"{key}.values", f"= {values!r} is empty or not a list: allowed a non-empty "
                       "list of finite numbers")
        if not all(_is_number(x) for x in values):
            raise _err(where, f"{key}.values", f"= {values!r} is not allowed: finite numbers only")
        if any(b <= a for a, b in zip(values, values[1:])):
            raise _err(where, f"{key}.values", f"= {values!r} is not allowed: strictly increasing values")
        return tuple(float(x) for x in values)
    missing = [k for k in ("start", "stop", "num") if k not in table]
    if missing:
        raise _err(where, f"{key}.{missing[0]}", "is missing: a range needs start, stop and num")
    start, stop, num = table["start"], table["stop"], table["num"]
    for k, x in (("start", start), ("stop", stop)):
        if not _is_number(x):
            raise _err(where, f"{key}.{k}", f"= {x!r} is not allowed: a finite number")
    if not _is_int(num) or num < 2:
        raise _err(where, f"{key}.num", f"= {num!r} gives an empty or single-point range: allowed integers "
                   ">= 2 (one value: values = [x])")
    if not stop > start:
        raise _err(where, f"{key}", f"has start = {start!r}, stop = {stop!r}: reversed or empty range, "
                   "allowed stop > start")
    if log and not start > 0:
        raise _err(where, f"{key}.start", f"= {start!r} is not allowed with log = true: start > 0")
    grid = np.geomspace(start, stop, num) if log else np.linspace(start, stop, num)
    return tuple(float(x) for x in grid)


def _label_range(where: str, key: str, label: str, values) -> None:
    lo, hi = min(values), max(values)
    if label == "speed_kmh" and not (SPEED_RANGE_KMH[0] <= lo and hi <= SPEED_RANGE_KMH[1]):
        raise _err(where, key, f"has speed_kmh values {lo!r} to {hi!r}: allowed {SPEED_RANGE_KMH[0]:g} to "
                   f"{SPEED_RANGE_KMH[1]:g} km/h")
    if label == "lambda" and not (0.0 < lo and hi < 1.0):
        raise _err(where, key, f"has lambda values {lo!r} to {hi!r}: allowed 0 < lambda < 1 "
                   "(roll stiffness distribution kF / (kF + kR))")
    if label == "mu" and not lo > 0.0:
        raise _err(where, key, f"has mu values from {lo!r}: allowed mu > 0 (kC / (kF + kR))")


def _variable(where: str, i: int, table, model: str, labels=LABELS) -> SweepVariable:
    key = f"variables[{i}]"
    if not isinstance(table, dict):
        raise _err(where, key, "is not a table: write [[variables]] tables")
    _check_keys(where, "variables", table, _KEYS["variables"])
    path = table.get("path")
    if not isinstance(path, str):
        raise _err(where, f"{key}.path", f"= {path!r} is not allowed: a path into the parameter pytree "
                   f"(e.g. 'chassis.stiffness_scale[0]') or one of the labels {', '.join(labels[model])}")
    path = path.strip()
    if path in labels["car"] + labels["analytic"] and path not in labels[model]:
        raise _err(where, f"{key}.path", f"= {path!r} is a label of another model: labels of model = "
                   f"{model!r} are {', '.join(labels[model])}")
    if path not in labels[model]:
        try:
            parse_path(path)
        except ParameterError as e:
            raise _err(where, f"{key}.path", f"= {path!r}: {e}") from None
    name = table.get("name", _identifier(path))
    if not isinstance(name, str) or not _NAME.match(name):
        raise _err(where, f"{key}.name", f"= {name!r} is not allowed: an identifier (letters, digits, _)")
    units = table.get("units", ("km/h" if path == "speed_kmh" else "1") if path in labels[model] else "SI")
    if not isinstance(units, str):
        raise _err(where, f"{key}.units", f"= {units!r} is not allowed: a string")
    values = grid_values(where, key, table)
    if path in labels[model]:
        _label_range(where, key, path, values)
    return SweepVariable(name=name, path=path, values=values, units=units, log=bool(table.get("log", False)))


def objective_quantities(study: Study) -> tuple[str, ...]:
    """The study's quantities that are objectives of the car (all but ``chi``)."""
    return tuple(q for q in study.quantities if study.model == "car" and q != "chi")


def quantity_specs(study: Study) -> tuple:
    """The :class:`optimise.ObjectiveSpec` of each objective quantity (its settings over
    the objective's defaults)."""
    given = dict(study.settings)
    return tuple(objective_spec(q, dict(given.get(q, ()))) for q in objective_quantities(study))


def _check_speed(where: str, study: Study) -> None:
    """A swept ``speed_kmh`` needs a quantity with that setting, and no fixed one."""
    if "speed_kmh" not in [v.path for v in study.variables]:
        return
    with_speed = [q for q in objective_quantities(study) if "speed_kmh" in OBJECTIVES[q].settings]
    if not with_speed:
        raise _err(where, "variables", "sweep speed_kmh, which no quantity of study.quantities has: allowed with "
                   "the objectives with a speed_kmh setting (" + ", ".join(
                       n for n, o in OBJECTIVES.items() if "speed_kmh" in o.settings) + ")")
    for name, settings in study.settings:
        if "speed_kmh" in dict(settings):
            raise _err(where, f"settings.{name}.speed_kmh", "is not allowed: the study sweeps speed_kmh")


def check_setting(where: str, key: str, name: str, setting: str, value) -> None:
    """``value`` of the objective ``name``'s ``setting`` (a key it has) is allowed: its
    ``corner`` one of :func:`optimise.allowed_corners`, a string where the default is one,
    increasing numbers > 0 where the default is a tuple, a number > 0 otherwise;
    ``ParameterError`` naming ``key.setting`` otherwise."""
    default = OBJECTIVES[name].settings[setting]
    if setting == "corner":
        if value not in allowed_corners(name):
            raise _err(where, f"{key}.corner", f"= {value!r} is not allowed: one of {', '.join(allowed_corners(name))}")
        return
    if isinstance(default, str):
        ok, what = isinstance(value, str), "a string"
    elif isinstance(default, tuple):
        ok = isinstance(value, (list, tuple)) and len(value) == len(default) and all(
            _is_number(x) and x > 0 for x in value) and all(b > a for a, b in zip(value, value[1:]))
        what = f"{len(default)} increasing numbers > 0"
    else:
        ok, what = _is_number(value) and value > 0, "a number > 0"
    if not ok:
        raise _err(where, f"{key}.{setting}", f"= {value!r} is not allowed: {what} (default {default!r})")


def _check_settings(where: str, study: Study) -> None:
    for name, settings in study.settings:
        key = f"settings.{name}"
        if name not in objective_quantities(study):
            raise _err(where, key, f"is not allowed: settings of the car's objective quantities of "
                       f"study.quantities only ({', '.join(objective_quantities(study)) or 'none'})")
        allowed = OBJECTIVES[name].settings
        for k, v in settings:
            if k not in allowed:
                raise _err(where, f"{key}.{k}", f"is not a key of objective {name!r}: allowed "
                           f"{', '.join(allowed) or 'none'}")
            check_setting(where, key, name, k, v)


def _settings_tables(where: str, table) -> tuple:
    if not isinstance(table, dict) or not all(isinstance(t, dict) for t in table.values()):
        raise _err(where, "settings", "is not allowed: [settings.NAME] tables, one per objective quantity")
    return tuple(sorted((name, tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in t.items())))
                        for name, t in table.items()))


def _positive_int(where: str, key: str, value, low: int, high: int) -> int:
    if not _is_int(value) or not low <= value <= high:
        raise _err(where, key, f"= {value!r} is not allowed: an integer from {low} to {high}")
    return int(value)


def check_study(study: Study) -> Study:
    """Check a :class:`Study` built in Python or loaded from a file (its backend, chunk,
    quantities, point count, ...); returns it. ``ParameterError`` naming the key."""
    where = study.file if study.file else "study"
    if study.model not in MODELS:
        raise _err(where, "study.model", f"= {study.model!r} is not allowed: one of {', '.join(MODELS)}")
    if not study.variables:
        raise _err(where, "variables", "is empty: a study needs at least one [[variables]] table")
    names = [v.name for v in study.variables]
    paths = [v.path for v in study.variables]
    for what, items in (("path", paths), ("name", names)):
        dup = sorted({x for x in items if items.count(x) > 1})
        if dup:
            raise _err(where, "variables", f"repeat the {what} {dup[0]!r}: each variable once")
    known = QUANTITIES[study.model]
    if not study.quantities:
        raise _err(where, "study.quantities", f"is empty: allowed one or more of {', '.join(known)}")
    for q in study.quantities:
        if q not in known:
            raise _err(where, "study.quantities", f"has the unknown quantity {q!r}: allowed for model = "
                       f"{study.model!r}: {', '.join(known)}")
    if len(set(study.quantities)) != len(study.quantities) or set(study.quantities) & set(names):
        raise _err(where, "study.quantities", "repeat a quantity or a variable name: each name once")
    if study.model == "car" and CONVERGED in names:
        raise _err(where, "variables", f"use the name {CONVERGED!r}, which the car's convergence flag has: "
                   "choose another name")
    if study.n_points > MAX_POINTS[study.model]:
        raise _err(where, "variables", f"give {study.n_points} grid points ({' x '.join(map(str, study.shape))}): "
                   f"more than the maximum of {MAX_POINTS[study.model]} for model = {study.model!r}")
    if study.backend not in BACKENDS:
        raise _err(where, "run.backend", f"= {study.backend!r} is not allowed: one of {', '.join(BACKENDS)}")
    _positive_int(where, "run.chunk", study.chunk, 1, MAX_CHUNK)
    if study.num_cpus is not None:
        _positive_int(where, "run.num_cpus", study.num_cpus, 1, 4096)
    if study.address is not None and (not isinstance(study.address, str) or not study.address.strip()):
        raise _err(where, "run.address", f"= {study.address!r} is not allowed: a Ray address such as "
                   "'auto' or 'ray://HOST:10001'")
    if study.model == "car":
        _positive_int(where, "study.modes", study.modes, 0, 20)
        ay = study.ay_g
        if len(ay) < 2 or not all(_is_number(a) and a > 0 for a in ay):
            raise _err(where, "study.ay_g", f"= {list(ay)!r} is not allowed: at least two lateral accelerations "
                       "> 0 (g), the first two giving chi at low ay")
        if not (_is_number(study.radius) and study.radius > 0):
            raise _err(where, "study.radius", f"= {study.radius!r} is not allowed: a radius > 0 (m)")
    if not isinstance(study.name, str) or not re.match(r"^[A-Za-z0-9_.-]+$", study.name):
        raise _err(where, "study.name", f"= {study.name!r} is not allowed: letters, digits, '_', '.', '-'")
    _check_settings(where, study)
    _check_speed(where, study)
    return study


def read_study_file(path) -> tuple[str, dict]:
    """``(where, table)``: the study file ``path`` read as TOML, ``where`` its name for
    messages; ``ParameterError`` when it is missing or not valid TOML."""
    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"study file {str(path)!r} not found")
    try:
        return str(path), tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise ParameterError(f"{path}: not valid TOML: {e}") from None


def load_study(path, *, backend=None, address=None, out=None, chunk=None, num_cpus=None) -> Study:
    """The study of the TOML file ``path`` (module docs), with any of the run settings
    overridden (the CLI's options). ``ParameterError`` naming the file and key for anything
    not allowed; paths into the pytree are checked when the model is built
    (:func:`optimise.build_model`)."""
    path = Path(path)
    where, data = read_study_file(path)
    _check_keys(where, "file", data, tuple(_KEYS))
    sections = {}
    for section in ("study", "run"):
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise _err(where, section, "is not a table: write [study] and [run] sections")
        _check_keys(where, section, table, _KEYS[section])
        sections[section] = table
    study_t, run_t = sections["study"], sections["run"]
    model = study_t.get("model", "car")
    if model not in MODELS:
        raise _err(where, "study.model", f"= {model!r} is not allowed: one of {', '.join(MODELS)}")
    if model != "car":
        for key in _CAR_ONLY:
            if key in study_t:
                raise _err(where, f"study.{key}", "applies to model = 'car' only")
    tables = data.get("variables", [])
    if not isinstance(tables, list):
        raise _err(where, "variables", "is not an array of tables: write [[variables]] tables")
    variables = tuple(_variable(where, i, t, model, SWEEP_LABELS) for i, t in enumerate(tables))
    quantities = study_t.get("quantities", ["chi"])
    if isinstance(quantities, str):
        quantities = [quantities]
    if not isinstance(quantities, list) or not all(isinstance(q, str) for q in quantities):
        raise _err(where, "study.quantities", f"= {quantities!r} is not allowed: a list of names of "
                   f"{', '.join(QUANTITIES[model])}")
    vehicle = study_t.get("vehicle")
    if vehicle is not None:
        if not isinstance(vehicle, str):
            raise _err(where, "study.vehicle", f"= {vehicle!r} is not allowed: a file path")
        resolved = Path(vehicle) if Path(vehicle).is_absolute() else path.parent / vehicle
        if not resolved.is_file():
            raise _err(where, "study.vehicle", f"= {vehicle!r}: file {str(resolved)!r} not found")
        vehicle = str(resolved.resolve())
    ay_g = study_t.get("ay_g", list(LOW_AY_PAIR_G))
    if not isinstance(ay_g, list):
        raise _err(where, "study.ay_g", f"= {ay_g!r} is not allowed: a list of lateral accelerations (g)")
    name = study_t.get("name", path.stem)
    description = study_t.get("description", "")
    if not isinstance(description, str):
        raise _err(where, "study.description", "is not a string")
    study = Study(
        name=name,
        model=model,
        variables=variables,
        quantities=tuple(quantities),
        vehicle=vehicle,
        modes=study_t.get("modes", 6),
        ay_g=tuple(ay_g),
        radius=study_t.get("radius", SKID_PAD_RADIUS),
        backend=backend if backend is not None else run_t.get("backend", "local"),
        chunk=chunk if chunk is not None else run_t.get("chunk", DEFAULT_CHUNK[model]),
        out=str(out) if out is not None else run_t.get("out", f"results/{name}"),
        address=address if address is not None else run_t.get("address"),
        num_cpus=num_cpus if num_cpus is not None else run_t.get("num_cpus"),
        description=description,
        file=where,
        settings=_settings_tables(where, data.get("settings", {})),
    )
    if not isinstance(study.out, str) or not study.out:
        raise _err(where, "run.out", f"= {study.out!r} is not allowed: a folder path")
    return check_study(study)
