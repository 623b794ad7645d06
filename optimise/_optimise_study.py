"""Optimisation study files: bounded design variables of the car, an objective from the
library (:data:`optimise.OBJECTIVES`) driven to a target or minimised/maximised, optional
constraints, and the optimiser, as TOML (``jaxveh optimise STUDY.toml``). Loading checks
everything it can before the car is built and raises :class:`~jaxveh.ParameterError` naming
the file, the key and what is allowed; the car, the model settings, the variable paths and
the ``lambda`` label are the sweep studies' (:mod:`optimise._study`).

A study file::

    [study]
    name = "roll_balance"             # output names; default: the file's stem
    description = "..."               # optional
    model = "car"                     # the chapter-6 car (the only model optimised so far)
    vehicle = "my_car.toml"           # optional car file, relative to the study file
    modes = 6                         # chassis modes (0: rigid)

    [[variables]]                     # one table per design variable
    path = "lambda"                   # a path into CarParams or the label lambda
    lower = 0.3                       # bounds (the optimiser stays strictly inside)
    upper = 0.7
    initial = 0.5                     # optional; default the middle (geometric with log)
    log = false                       # optional: optimise log(value)
    name = "lam"                      # optional coordinate name; units optional

    [objective]                       # one objective ...
    name = "understeer_gradient"      # a name of OBJECTIVES
    target = 0.1                      # ((f - target) / scale)^2 ... or minimise = true / maximise = true
    scale = 0.1                       # in the objective's units (default 1)
    ay_g = 0.05                       # the objective's settings (OBJECTIVES[name].settings)
    radius = 50.0

    # [[objectives]]                  # ... or a weighted sum: the same keys plus weight = w

    [[constraints]]                   # optional: f <= bound and/or f >= bound, or f == value
    name = "roll_gradient"
    "<=" = 1.2                        # or ">=" = ..., or "==" = ... (an equality, alone in its table)
    scale = 0.1                       # the violation's scale (default 1)

    [pareto]                          # optional: an ε-constraint front (optimise.pareto_front)
    constraint = "roll_gradient"      # the name of one bound of [[constraints]] ...
    values = [1.4, 1.2, 1.0]          # ... which takes each of these in turn (monotonic)

    [optimiser]
    method = "lbfgs"                  # "lbfgs" (Optax's L-BFGS direction, Armijo backtracking), "adam",
                                      # or "slsqp" (SciPy's SQP: constraints handled directly)
    steps = 30                        # iterations per outer (augmented-Lagrangian) iteration
    learning_rate = 0.05              # adam only
    tolerance = 1e-8                  # converged when the gradient norm (unconstrained variables) is below
    outer_steps = 8                   # with constraints: multiplier updates

    [run]
    out = "results/roll_balance"      # default results/<name>

The optimiser works on unconstrained variables ``z`` (``optimise.Problem``'s logistic map
into the bounds); every iteration evaluates the objectives and constraints and their exact
Jacobian with respect to ``z`` in one compiled forward-mode program (``jax.jacfwd``: a few
design variables, a steady state with the implicit function theorem inside). Constraints
``g <= 0`` and equalities ``h = 0`` (normalised by their scale) enter by the
Powell-Hestenes-Rockafellar augmented Lagrangian as in :func:`optimise.solve` (``lbfgs``,
``adam``), or directly as the linearised constraints of SciPy's sequential quadratic
programming (``slsqp``: a BFGS
model of the Lagrangian's Hessian, a quadratic subproblem per iteration, converged when
the KKT conditions hold to ``tolerance``; it works on the variables' places in their
bounds with SciPy's bounds, so that a variable can end on its bound): for a few variables
with active constraints it needs far fewer evaluations.
"""

import csv
import dataclasses
import json
import math
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
import scipy.optimize
import scipy.special

from jaxveh import ParameterError, run_time_checks_off, vehicle

from ._car_file import changed_car_values, optimum_car_file
from ._frame_design import (
    car_with_frame,
    check_frame_variables,
    frame_text,
    is_frame_path,
    load_car_frame,
    optimum_frame_text,
    parse_frame_path,
    set_frame_sizes,
)
from ._objectives import (
    FRAME_OBJECTIVES,
    FRAME_SOURCE,
    OBJECTIVES,
    ObjectiveSpec,
    arb_rates_for_lambda,
    follow_mode,
    objective_spec,
    objective_units,
    objective_values,
    prepare,
    roll_rate_coefficients,
    state_matrix,
)
from ._problem import Problem, Variable
from ._study import (
    LABELS,
    Study,
    SweepVariable,
    _check_keys,
    _err,
    _is_number,
    _positive_int,
    _variable,
    check_setting,
    check_study,
    read_study_file,
)
from ._sweep import _check_path

#: Optimisation methods.
METHODS = ("lbfgs", "adam", "slsqp")
#: How an objective term is driven.
SENSES = ("target", "minimise", "maximise")
#: Default optimiser settings.
DEFAULT_OPTIMISER = {"method": "lbfgs", "steps": 30, "learning_rate": 0.05, "tolerance": 1e-8, "memory": 10,
                     "outer_steps": 8, "rho": 10.0, "rho_growth": 4.0, "constraint_tol": 1e-6}
#: Armijo sufficient-decrease constant and the most halvings of the L-BFGS line search.
ARMIJO_C1, MAX_HALVINGS = 1e-4, 30
#: The parts of CarParams the λ label's rate coefficients depend on: a study may not vary
#: them together with λ (:func:`optimise.arb_rates_for_lambda`).
LAMBDA_EXCLUDES = ("vehicle", "springs", "arb_rates")
_KEYS = {
    "arb_rates[0]": ("suspension_front", "arb_rate", "Nm/rad"),
    "arb_rates[1]": ("suspension_rear", "arb_rate", "Nm/rad"),
    "coupling": ("chassis", "coupling", "-"),
    "rack_ratio": ("steering", "rack_ratio", "mm/deg"),
}

_KEYS = {
    "file": ("study", "variables", "objective", "objectives", "constraints", "optimiser", "pareto", "run"),
    "study": ("name", "description", "model", "vehicle", "modes"),
    "variables": ("path", "name", "units", "lower", "upper", "initial", "log"),
    "term": ("name", "target", "minimise", "maximise", "scale", "weight"),
    "constraint": ("name", "<=", ">=", "==", "scale", "reference", "relative"),
    "optimiser": tuple(DEFAULT_OPTIMISER),
    "pareto": ("constraint", "values"),
    "run": ("out",),
}


class DesignVariable(NamedTuple):
    """A design variable: coordinate ``name``, ``path`` (into CarParams, or ``"lambda"``),
    bounds, ``initial`` value, ``log`` scale and ``units``."""

    name: str
    path: str
    lower: float
    upper: float
    initial: float
    log: bool = False
    units: str = "SI"


class Term(NamedTuple):
    """One objective term: ``spec`` (objective and settings), ``sense`` (:data:`SENSES`),
    ``target`` (for "target"), ``scale`` and ``weight``."""

    spec: ObjectiveSpec
    sense: str
    target: Optional[float]
    scale: float = 1.0
    weight: float = 1.0

    def value(self, f):
        """The term's contribution at objective value ``f`` (NumPy or JAX)."""
        if self.sense == "target":
            return self.weight * ((f - self.target) / self.scale) ** 2
        return self.weight * (f if self.sense == "minimise" else -f) / self.scale

    def slope(self, f):
        """d value / d f."""
        if self.sense == "target":
            return self.weight * 2.0 * (f - self.target) / self.scale**2
        return self.weight * (1.0 if self.sense == "minimise" else -1.0) / self.scale


class Bound(NamedTuple):
    """A constraint ``spec <= upper`` (``kind`` "<="), ``spec >= lower`` (">=") or
    ``spec == value`` ("=="), its violation ``(f - bound) / scale`` (``(bound - f) / scale``
    for ">=") feasible when <= 0, for an equality when it is 0.

    With ``reference = "rigid"`` the bound is on the difference from the same objective of
    the rigid car, ``f - f_rigid`` (``relative``: ``(f - f_rigid) / |f_rigid|``, and the
    scale is relative too); ``rigid_value`` is ``f_rigid``, set when the study's design is
    built (:func:`build_design`)."""

    spec: ObjectiveSpec
    kind: str
    bound: float
    scale: float = 1.0
    reference: Optional[str] = None
    relative: bool = False
    rigid_value: Optional[float] = None

    @property
    def _unit(self) -> float:
        if self.reference is None:
            return 1.0
        if self.rigid_value is None:
            raise RuntimeError(f"the bound on {self.spec.name} relative to the rigid car has no rigid value yet: "
                               "build the study's design first (build_design)")
        return abs(self.rigid_value) if self.relative else 1.0

    @property
    def limit(self) -> float:
        """The bound on the objective itself (its units)."""
        return self.bound * self._unit + (self.rigid_value if self.reference is not None else 0.0)

    @property
    def limit_scale(self) -> float:
        """The violation's scale in the objective's units."""
        return self.scale * self._unit

    @property
    def is_equality(self) -> bool:
        return self.kind == "=="

    def violation(self, f):
        """Signed and scaled: feasible when <= 0 (an inequality) or == 0 (an equality)."""
        return self.sign * (f - self.limit) / self.limit_scale

    @property
    def sign(self) -> float:
        return -1.0 if self.kind == ">=" else 1.0


class ParetoSweep(NamedTuple):
    """An ε-constraint sweep: the bound ``constraint`` (index into the study's
    constraints) takes each of ``values`` in turn (the constraint's units), one optimisation
    each (:func:`optimise.pareto_front`)."""

    constraint: int
    values: tuple


class OptimisationStudy(NamedTuple):
    """A loaded optimisation study file (module docs); ``file`` for messages; ``pareto``:
    an optional :class:`ParetoSweep`."""

    name: str
    variables: tuple[DesignVariable, ...]
    terms: tuple[Term, ...]
    constraints: tuple[Bound, ...] = ()
    optimiser: dict = DEFAULT_OPTIMISER
    vehicle: Optional[str] = None
    modes: int = 6
    model: str = "car"
    out: str = "results/study"
    description: str = ""
    file: Optional[str] = None
    pareto: Optional[ParetoSweep] = None

    @property
    def specs(self) -> tuple[ObjectiveSpec, ...]:
        """Every objective evaluated: the terms' then the constraints', each once."""
        return tuple(dict.fromkeys([t.spec for t in self.terms] + [c.spec for c in self.constraints]))

    def where(self, key: str) -> str:
        return f"{self.file if self.file else 'study'}: {key}"


# ---- loading ----------------------------------------------------------------------------------


def _number(where, key, value, low=None, *, positive=False) -> float:
    if not _is_number(value):
        raise _err(where, key, f"= {value!r} is not allowed: a finite number")
    if positive and not value > 0:
        raise _err(where, key, f"= {value!r} is not allowed: a number > 0")
    return float(value)


def _design_variable(where: str, i: int, table, model: str) -> DesignVariable:
    key = f"variables[{i}]"
    if not isinstance(table, dict):
        raise _err(where, key, "is not a table: write [[variables]] tables")
    _check_keys(where, "variables", table, _KEYS["variables"])
    for k in ("lower", "upper"):
        if k not in table:
            raise _err(where, f"{key}.{k}", "is missing: a design variable needs lower and upper bounds")
        _number(where, f"{key}.{k}", table[k])
    lower, upper = float(table["lower"]), float(table["upper"])
    if not lower < upper:
        raise _err(where, key, f"has lower = {lower!r}, upper = {upper!r}: reversed or empty bounds, allowed "
                   "lower < upper")
    log = table.get("log", False)
    if not isinstance(log, bool):
        raise _err(where, f"{key}.log", f"= {log!r} is not allowed: true or false")
    if log and not lower > 0:
        raise _err(where, f"{key}.lower", f"= {lower!r} is not allowed with log = true: lower > 0")
    initial = table.get("initial", math.sqrt(lower * upper) if log else 0.5 * (lower + upper))
    initial = _number(where, f"{key}.initial", initial)
    if not lower < initial < upper:
        raise _err(where, f"{key}.initial", f"= {initial!r} is not allowed: strictly between lower = {lower!r} "
                   f"and upper = {upper!r}")
    if is_frame_path(table.get("path")):
        return _frame_design_variable(where, key, table, lower, upper, initial, log)
    # the sweep's checks of the path (or label), the name, the units and the label's range
    sweep_table = {k: table[k] for k in ("path", "name", "units") if k in table} | {"values": [lower, upper]}
    var = _variable(where, i, sweep_table, model)
    return DesignVariable(name=var.name, path=var.path, lower=lower, upper=upper, initial=initial, log=log,
                          units=var.units)


def _frame_design_variable(where, key, table, lower, upper, initial, log) -> DesignVariable:
    """A variable of the frame's tube sizes (:mod:`optimise._frame_design`; m)."""
    path = table["path"].strip()
    try:
        parse_frame_path(path)
    except ParameterError as e:
        raise _err(where, f"{key}.path", f"= {path!r} {e}") from None
    if not lower > 0.0:
        raise _err(where, f"{key}.lower", f"= {lower!r} is not allowed: a tube size (m) or factor > 0")
    name = table.get("name", "_".join(re.findall(r"[A-Za-z0-9]+", path[len("frame.sections."):])))
    if not isinstance(name, str) or not re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", name):
        raise _err(where, f"{key}.name", f"= {name!r} is not allowed: an identifier (letters, digits, _)")
    units = "1" if parse_frame_path(path).is_scale else "m"
    if table.get("units", units) != units:
        raise _err(where, f"{key}.units", f"= {table['units']!r} is not allowed: {units!r} (sizes are in metres, "
                   "factors have no unit)")
    return DesignVariable(name=name, path=path, lower=lower, upper=upper, initial=initial, log=log, units=units)


def _settings(table: dict, reserved) -> dict:
    return {k: v for k, v in table.items() if k not in reserved}


def _spec(where: str, key: str, table: dict, reserved, frame: bool = False) -> ObjectiveSpec:
    name = table.get("name")
    if not isinstance(name, str):
        raise _err(where, f"{key}.name", f"= {name!r} is not allowed: one of {', '.join(OBJECTIVES)}")
    if name in FRAME_OBJECTIVES:
        if not frame:
            raise _err(where, f"{key}.name", f"= {name!r} is an objective of the chassis frame (a function of "
                       "jaxveh.fe.Frame): allowed in a study with frame variables (frame.sections... paths); "
                       f"the car's objectives are {', '.join(OBJECTIVES)}")
        extra = sorted(_settings(table, reserved))
        if extra:
            raise _err(where, f"{key}.{extra[0]}", f"is not a key of objective {name!r}: allowed "
                       f"{', '.join(reserved)}")
        return objective_spec(name, frame=True)
    if name not in OBJECTIVES:
        raise _err(where, f"{key}.name", f"= {name!r} is not a known objective: allowed {', '.join(OBJECTIVES)}")
    settings = _settings(table, reserved)
    allowed = OBJECTIVES[name].settings
    for k, v in settings.items():
        if k not in allowed:
            raise _err(where, f"{key}.{k}", f"is not a key of objective {name!r}: allowed "
                       f"{', '.join(reserved + tuple(allowed))}")
        check_setting(where, key, name, k, v)
    spec = objective_spec(name, {k: float(v) if _is_number(v) else v for k, v in settings.items()})
    return spec


def _term(where: str, key: str, table, weighted: bool, frame: bool = False) -> Term:
    if not isinstance(table, dict):
        raise _err(where, key, "is not a table")
    reserved = _KEYS["term"]
    spec = _spec(where, key, table, reserved, frame)
    senses = [s for s in ("target", "minimise", "maximise") if s in table]
    if len(senses) != 1:
        raise _err(where, key, f"needs exactly one of target = VALUE, minimise = true, maximise = true; got "
                   f"{', '.join(senses) or 'none'}")
    sense = senses[0]
    target = None
    if sense == "target":
        target = _number(where, f"{key}.target", table["target"])
    elif table[sense] is not True:
        raise _err(where, f"{key}.{sense}", f"= {table[sense]!r} is not allowed: true")
    scale = _number(where, f"{key}.scale", table.get("scale", 1.0), positive=True)
    if "weight" in table and not weighted:
        raise _err(where, f"{key}.weight", "applies to [[objectives]] (a weighted sum) only")
    weight = _number(where, f"{key}.weight", table.get("weight", 1.0), positive=True)
    return Term(spec=spec, sense=sense, target=target, scale=scale, weight=weight)


def _constraints(where: str, tables, frame: bool = False) -> tuple[Bound, ...]:
    if not isinstance(tables, list):
        raise _err(where, "constraints", "is not an array of tables: write [[constraints]] tables")
    out, bounds = [], {}
    for i, table in enumerate(tables):
        key = f"constraints[{i}]"
        if not isinstance(table, dict):
            raise _err(where, key, "is not a table: write [[constraints]] tables")
        spec = _spec(where, key, table, _KEYS["constraint"], frame)
        kinds = [k for k in ("<=", ">=", "==") if k in table]
        if not kinds:
            raise _err(where, key, 'needs a bound: "<=" = VALUE and/or ">=" = VALUE, or "==" = VALUE')
        if "==" in kinds and len(kinds) > 1:
            raise _err(where, f'{key}."=="', 'is not allowed beside "<=" or ">=" in one table: an equality stands '
                       "alone (write the bounds in their own [[constraints]] table)")
        scale = _number(where, f"{key}.scale", table.get("scale", 1.0), positive=True)
        reference, relative = table.get("reference"), table.get("relative", False)
        if reference not in (None, "rigid"):
            raise _err(where, f"{key}.reference", f"= {reference!r} is not allowed: 'rigid' (bounds on the "
                       "difference from the rigid car's value)")
        if reference is not None and spec.source_key[0] == FRAME_SOURCE:
            raise _err(where, f"{key}.reference", f"is not allowed on {spec.name!r}: the rigid car has no frame")
        if not isinstance(relative, bool) or (relative and reference is None):
            raise _err(where, f"{key}.relative", f"= {relative!r} is not allowed: true or false, and true only with "
                       'reference = "rigid"')
        for kind in kinds:
            bound = _number(where, f'{key}."{kind}"', table[kind])
            out.append(Bound(spec=spec, kind=kind, bound=bound, scale=scale, reference=reference, relative=relative))
            bounds.setdefault((spec, reference, relative), []).append((kind, bound, key))
    for (spec, _, _), items in bounds.items():  # the bounds on one quantity must leave a value
        _check_feasible(where, spec.name, items)
    return tuple(out)


def _check_feasible(where: str, name: str, items) -> None:
    """The bounds ``(kind, bound, key)`` on one quantity leave at least one value."""
    lows = [(b, k) for kind, b, k in items if kind in (">=", "==")]
    highs = [(b, k) for kind, b, k in items if kind in ("<=", "==")]
    if lows and highs:
        (low, k_low), (high, k_high) = max(lows), min(highs)
        if low > high:
            raise _err(where, k_low, f"is infeasible: {name} >= {low!r} ({k_low}) and <= {high!r} ({k_high}) leave "
                       'no value; allowed ">=" bound <= "<=" bound, and one "==" value inside them')


def _optimiser(where: str, table) -> dict:
    if not isinstance(table, dict):
        raise _err(where, "optimiser", "is not a table: write an [optimiser] section")
    _check_keys(where, "optimiser", table, _KEYS["optimiser"])
    out = {**DEFAULT_OPTIMISER, **table}
    if out["method"] not in METHODS:
        raise _err(where, "optimiser.method", f"= {out['method']!r} is not allowed: one of {', '.join(METHODS)}")
    for k, high in (("steps", 100_000), ("memory", 100), ("outer_steps", 1000)):
        out[k] = _positive_int(where, f"optimiser.{k}", out[k], 1, high)
    for k in ("learning_rate", "tolerance", "rho", "constraint_tol"):
        out[k] = _number(where, f"optimiser.{k}", out[k], positive=True)
    out["rho_growth"] = _number(where, "optimiser.rho_growth", out["rho_growth"])
    if out["rho_growth"] < 1.0:
        raise _err(where, "optimiser.rho_growth", f"= {out['rho_growth']!r} is not allowed: a number >= 1")
    return out


def _pareto(where: str, table, constraints) -> Optional[ParetoSweep]:
    if table is None:
        return None
    if not isinstance(table, dict):
        raise _err(where, "pareto", "is not a table: write a [pareto] section")
    _check_keys(where, "pareto", table, _KEYS["pareto"])
    name = table.get("constraint")
    matches = [j for j, c in enumerate(constraints) if c.spec.name == name]
    if len(matches) != 1:
        names = ", ".join(c.spec.name for c in constraints) or "none"
        raise _err(where, "pareto.constraint", f"= {name!r} is not allowed: the name of exactly one bound of "
                   f"[[constraints]] (its bound takes each of pareto.values); the bounds: {names}")
    values = table.get("values")
    if not isinstance(values, list) or len(values) < 2 or not all(_is_number(v) for v in values):
        raise _err(where, "pareto.values", f"= {values!r} is not allowed: a list of at least 2 numbers (the "
                   "constraint's bounds, in its units)")
    if not (all(b > a for a, b in zip(values, values[1:])) or all(b < a for a, b in zip(values, values[1:]))):
        raise _err(where, "pareto.values", f"= {values!r} is not allowed: strictly monotonic (each optimisation "
                   "starts from the previous optimum)")
    return ParetoSweep(constraint=matches[0], values=tuple(float(v) for v in values))


#: The shared computations a bound relative to the rigid car may use (a rigid car has them).
RIGID_SOURCES = ("skid_pad", "load_transfer")


def _check_rigid_references(where: str, constraints, variables) -> None:
    """Bounds relative to the rigid car: on its steady-state objectives, and only with frame
    variables (the rigid car is then the same at every design: its values are computed once)."""
    for j, c in enumerate(constraints):
        if c.reference is None:
            continue
        if c.spec.source_key[0] not in RIGID_SOURCES:
            allowed = [n for n, o in OBJECTIVES.items() if o.source in RIGID_SOURCES]
            raise _err(where, "constraints", f"bound {j} on {c.spec.name!r} has reference = 'rigid': allowed on "
                       f"{', '.join(allowed)} (the rigid car has no chassis mode)")
        moving = [v.path for v in variables if not is_frame_path(v.path)]
        if moving:
            raise _err(where, "constraints", f"bound {j} on {c.spec.name!r} has reference = 'rigid' with the "
                       f"variable {moving[0]!r}, which changes the rigid car too: allowed with frame variables "
                       "only (frame.sections... paths)")


def _check_lambda(where: str, variables) -> None:
    if "lambda" not in [v.path for v in variables]:
        return
    for i, v in enumerate(variables):
        root = re.split(r"[.\[]", v.path)[0]
        if root in LAMBDA_EXCLUDES:
            raise _err(where, f"variables[{i}].path", f"= {v.path!r} cannot be varied together with lambda (set "
                       "through the anti-roll bars with the base car's roll-rate coefficients): allowed with "
                       f"lambda are paths outside {', '.join(LAMBDA_EXCLUDES)}")


def load_optimisation_study(path, *, out=None) -> OptimisationStudy:
    """The optimisation study of the TOML file ``path`` (module docs), with the output
    folder ``out`` overridden. ``ParameterError`` naming the file and key for anything not
    allowed; the paths into CarParams and the bounds' ranges are checked on the car when it
    is built (:func:`build_design`)."""
    path = Path(path)
    where, data = read_study_file(path)
    _check_keys(where, "file", data, _KEYS["file"])
    for section in ("study", "optimiser", "run"):
        if not isinstance(data.get(section, {}), dict):
            raise _err(where, section, f"is not a table: write a [{section}] section")
    study_t, run_t = data.get("study", {}), data.get("run", {})
    _check_keys(where, "study", study_t, _KEYS["study"])
    _check_keys(where, "run", run_t, _KEYS["run"])
    model = study_t.get("model", "car")
    if model != "car":
        raise _err(where, "study.model", f"= {model!r} is not allowed: 'car' (the chapter-6 car; the chapter-3 "
                   "model's optimisation is optimise.solve)")
    tables = data.get("variables", [])
    if not isinstance(tables, list) or not tables:
        raise _err(where, "variables", "is missing or empty: a study needs at least one [[variables]] table")
    variables = tuple(_design_variable(where, i, t, model) for i, t in enumerate(tables))
    _check_lambda(where, variables)
    if ("objective" in data) == ("objectives" in data):
        raise _err(where, "objective", "is needed: one [objective] table or an array of [[objectives]] tables "
                   "(a weighted sum), not both")
    frame = any(is_frame_path(v.path) for v in variables)
    if "objective" in data:
        terms = (_term(where, "objective", data["objective"], weighted=False, frame=frame),)
    else:
        if not isinstance(data["objectives"], list) or not data["objectives"]:
            raise _err(where, "objectives", "is not a non-empty array of tables: write [[objectives]] tables")
        terms = tuple(_term(where, f"objectives[{i}]", t, weighted=True, frame=frame)
                      for i, t in enumerate(data["objectives"]))
    constraints = _constraints(where, data.get("constraints", []), frame)
    _check_rigid_references(where, constraints, variables)
    pareto = _pareto(where, data.get("pareto"), constraints)
    optimiser = _optimiser(where, data.get("optimiser", {}))
    name = study_t.get("name", path.stem)
    if not isinstance(name, str) or not re.match(r"^[A-Za-z0-9_.-]+$", name):
        raise _err(where, "study.name", f"= {name!r} is not allowed: letters, digits, '_', '.', '-'")
    description = study_t.get("description", "")
    if not isinstance(description, str):
        raise _err(where, "study.description", "is not a string")
    out = str(out) if out is not None else run_t.get("out", f"results/{name}")
    if not isinstance(out, str) or not out:
        raise _err(where, "run.out", f"= {out!r} is not allowed: a folder path")
    # the sweep loader's checks of the car settings (model, vehicle file, modes, repeated names)
    sweep = check_study(_sweep_study(where, path, study_t, variables))
    return OptimisationStudy(name=name, variables=variables, terms=terms, constraints=constraints,
                             optimiser=optimiser, vehicle=sweep.vehicle, modes=sweep.modes, model=model, out=out,
                             description=description, file=where, pareto=pareto)


def vehicle_path(where: str, path: Path, vehicle_file) -> Optional[str]:
    """The car file ``vehicle_file`` of the study file ``path`` (relative to it) as an
    absolute path, None for the shipped car; ``ParameterError`` when it is not a file."""
    if vehicle_file is None:
        return None
    if not isinstance(vehicle_file, str):
        raise _err(where, "study.vehicle", f"= {vehicle_file!r} is not allowed: a file path")
    resolved = Path(vehicle_file) if Path(vehicle_file).is_absolute() else path.parent / vehicle_file
    if not resolved.is_file():
        raise _err(where, "study.vehicle", f"= {vehicle_file!r}: file {str(resolved)!r} not found")
    return str(resolved.resolve())


def _sweep_study(where, path: Path, study_t: dict, variables) -> Study:
    """The sweep :class:`~optimise.Study` with the same car and variables (values: the
    bounds and the initial value), for the sweep loader's and model builder's checks."""
    vehicle_file = vehicle_path(where, path, study_t.get("vehicle"))
    sweep_vars = tuple(SweepVariable(name=v.name, path=v.path, values=tuple(sorted({v.lower, v.initial, v.upper})),
                                     units=v.units, log=v.log) for v in variables)
    return Study(name="s", model="car", variables=sweep_vars, quantities=("chi",), vehicle=vehicle_file,
                 modes=study_t.get("modes", 6), file=where)


# ---- the design -------------------------------------------------------------------------------


class Design(NamedTuple):
    """A study's car and compiled evaluation: the base ``car``, the ``problem`` (bounded
    variables on ``(car, coefficients)``, and the base ``frame`` after them in a study with
    frame variables), the objective ``specs`` and their ``prepared`` arrays,
    ``evaluate(z) -> (values, jacobian)`` (NumPy; one compiled program), the rigid car's
    values ``rigid_values`` ({spec: value}) of the bounds relative to it, and ``track(z)``
    (None without mode objectives): moves the mode objectives' reference eigenvectors in
    ``prepared`` to the design ``z`` (:func:`optimise.follow_mode`), which later
    evaluations use."""

    car: object
    problem: Problem
    specs: tuple
    prepared: dict
    evaluate: Callable
    rigid_values: dict = {}
    track: Optional[Callable] = None


@dataclasses.dataclass(frozen=True)
class _DesignApply:
    """``apply(base, values)`` of the study's :class:`~optimise.Problem` on ``base = (car,
    coefficients)``: the path variables set on CarParams, then λ through the anti-roll bars.
    Hashable by value, so that one study's program compiles once per process."""

    paths: tuple  # (name, path) of the path variables
    lam: Optional[str]  # the name of the lambda variable, if any
    frame: tuple = ()  # (name, FrameVariable) of the frame variables; base = (car, coefficients, frame)

    def __call__(self, base, values):
        car, coefficients = base[:2]
        params = vehicle.set_car_params(car.params, {p: values[n] for n, p in self.paths})
        if self.lam is not None:
            rates = arb_rates_for_lambda(coefficients, values[self.lam])
            params = eqx.tree_at(lambda p: p.arb_rates, params, rates)
        car = eqx.tree_at(lambda c: c.params, car, params)
        if not self.frame:
            return car, coefficients
        frame = set_frame_sizes(base[2], tuple((var, values[n]) for n, var in self.frame))
        return car_with_frame(car, frame), coefficients, frame


@dataclasses.dataclass(frozen=True)
class _StudyObjective:
    """The study's weighted objective of ``base = (car, coefficients)`` (its terms' sum; no
    constraints), hashable by value."""

    terms: tuple
    specs: tuple

    def __call__(self, base, prepared=None):
        values = objective_values(base[0], self.specs, prepared, frame=_frame_of(base))
        return sum(t.value(values[self.specs.index(t.spec)]) for t in self.terms)


def _frame_of(base):
    """The frame of a design's ``base`` (None without frame variables)."""
    return base[2] if len(base) > 2 else None


def design_car(design: Design, values: dict):
    """The car at the design variables' ``values`` ({name: value})."""
    return design.problem.apply(design.problem.params, {k: jnp.asarray(v, jnp.float64) for k, v in values.items()})[0]


def _values_and_jacobian(z, base, variables, apply, specs, prepared):
    """Every objective's value at the unconstrained design ``z`` and the exact Jacobian
    ``d values / d z`` (forward mode). The terms' targets, scales and weights are applied on
    the host (:func:`_merit`), so they are not part of the compiled program: studies that
    differ only in them share it."""
    problem = Problem(params=base, variables=variables, objective=_StudyObjective((), specs), apply=apply)

    def values(z):
        built = problem.build(z)
        v = objective_values(built[0], specs, prepared, frame=_frame_of(built))
        return v, v

    jac, v = jax.jacfwd(values, has_aux=True)(z)
    return v, jac


_compiled = eqx.filter_jit(_values_and_jacobian)


def build_design(study: OptimisationStudy) -> Design:
    """The car of ``study`` with its variables checked on it (the path exists, names one
    number, and the bounds and initial value are in the car's ranges; ``ParameterError``
    naming the key), the prepared objective settings, and the compiled evaluation."""
    car = vehicle.load_car(study.vehicle, modes=study.modes)
    sweep = _sweep_study(study.file or "study", Path(study.file or "."), {"modes": study.modes}, study.variables)
    sweep = sweep._replace(vehicle=study.vehicle)
    check = lambda params: vehicle.check_car(eqx.tree_at(lambda c: c.params, car, params))  # noqa: E731
    frame_vars = tuple((v.name, parse_frame_path(v.path)) for v in study.variables if is_frame_path(v.path))
    frame = _checked_frame(study, car) if frame_vars else None
    for i, v in enumerate(study.variables):
        if not is_frame_path(v.path) and v.path not in LABELS["car"]:
            _check_path(sweep, i, car.params, check)
    if frame_vars:
        try:
            check_frame_variables(frame, [(parse_frame_path(v.path), v.lower, v.upper) if is_frame_path(v.path)
                                          else (None, 1.0, 1.0) for v in study.variables])
        except ParameterError as e:
            raise ParameterError(f"{study.file or 'study'}: {e}") from None
    coefficients = roll_rate_coefficients(car)
    specs = study.specs
    try:
        prepared = prepare(car, specs)
    except ParameterError as e:
        raise ParameterError(f"{study.where('objective')}: {e}") from None
    apply = _DesignApply(paths=tuple((v.name, v.path) for v in study.variables
                                     if v.path not in LABELS["car"] and not is_frame_path(v.path)),
                         lam=next((v.name for v in study.variables if v.path == "lambda"), None), frame=frame_vars)
    problem = Problem(params=(car, coefficients) + ((frame,) if frame_vars else ()),
                      variables=tuple(Variable(v.name, v.lower, v.upper, v.log) for v in study.variables),
                      objective=_StudyObjective(study.terms, specs), apply=apply)
    # the mode objectives' forward-mode linearisation is kept out of JAX's disk cache (its
    # run-time checks stay traced: loading that program back segfaults, docs/analysis.md);
    # everything else is traced without them, so the disk cache keeps the program
    cacheable = all(s.source_key[0] != "linear" for s in specs)

    def evaluate(z):
        if cacheable:
            with run_time_checks_off():
                v, jac = _compiled(jnp.asarray(z), problem.params, problem.variables, apply, specs, prepared)
        else:
            v, jac = _compiled(jnp.asarray(z), problem.params, problem.variables, apply, specs, prepared)
        return np.asarray(v), np.asarray(jac)

    return Design(car=car, problem=problem, specs=specs, prepared=prepared, evaluate=evaluate,
                  rigid_values=rigid_values(study), track=_mode_tracker(problem, prepared))


_state_matrix = eqx.filter_jit(state_matrix)


def _mode_tracker(problem: Problem, prepared: dict) -> Optional[Callable]:
    """``track(z)`` of :class:`Design` for the mode objectives' references in ``prepared``
    (updated in place), or None when there are none."""
    keys = [k for k in prepared if k[0] == "linear"]
    if not keys:
        return None

    def track(z):
        car = problem.build(jnp.asarray(z))[0]
        for key in keys:
            a, ok = _state_matrix(car, dict(key[1])["speed_kmh"])
            if bool(ok):
                prepared[key] = {**prepared[key], "reference": follow_mode(prepared[key]["reference"], a)}

    return track


def _checked_frame(study: OptimisationStudy, car):
    """The car file's frame, for a study with frame variables (a flexible car's)."""
    if car.n_modes == 0:
        raise ParameterError(f"{study.where('study.modes')} = 0: frame variables need a flexible chassis (modes >= 1)")
    return load_car_frame(study.vehicle)


def rigid_values(study: OptimisationStudy) -> dict:
    """``{spec: value}`` of the study's bounds relative to the rigid car (``reference =
    "rigid"``): their objectives on the study's car with a rigid chassis (one compiled
    call); ``ParameterError`` when the rigid car has no steady state there."""
    specs = tuple(dict.fromkeys(c.spec for c in study.constraints if c.reference == "rigid"))
    if not specs:
        return {}
    rigid = vehicle.load_car(study.vehicle, modes=0)
    with run_time_checks_off():
        values = np.asarray(_rigid_values(rigid, specs))
    if not np.all(np.isfinite(values)):
        bad = [s.name for s, x in zip(specs, values) if not np.isfinite(x)]
        raise ParameterError(f"{study.where('constraints')}: the rigid car's {', '.join(bad)} failed (no steady "
                             "state): no reference for the bounds relative to it")
    return {s: float(x) for s, x in zip(specs, values)}


_rigid_values = eqx.filter_jit(lambda car, specs: objective_values(car, specs))


def _with_rigid_values(study: OptimisationStudy, design: Design) -> OptimisationStudy:
    """``study`` with the rigid car's values set on its bounds relative to it."""
    return study._replace(constraints=tuple(c._replace(rigid_value=design.rigid_values[c.spec])
                                            if c.reference else c for c in study.constraints))


# ---- the optimisation -------------------------------------------------------------------------


class OptimisationResult(NamedTuple):
    """An optimisation's outcome: ``optimum`` ({variable: value}), the weighted
    ``objective`` there, each objective's value ``values`` ({name: value}), the constraints
    (``constraints``: one dict per bound with value and violation), ``converged`` (the
    gradient norm fell below the tolerance with every constraint within its tolerance),
    ``message``, ``iterations``, ``evaluations`` (compiled calls), ``history`` (one dict per
    iteration: iteration, objective, merit, grad_norm, the variables, the objectives'
    values), ``car`` (at the optimum), ``failed`` (a failed steady state or trim ended the
    run) and ``wall_s``."""

    study: OptimisationStudy
    optimum: dict
    objective: float
    values: dict
    constraints: list
    converged: bool
    message: str
    iterations: int
    evaluations: int
    history: list
    car: object
    failed: bool
    wall_s: float


class OptimisationError(RuntimeError):
    """A failed simulation (steady state, trim) during an optimisation; ``result`` holds
    the run so far (its history, the last good design)."""

    def __init__(self, message: str, result: OptimisationResult):
        super().__init__(message)
        self.result = result


def _label(spec: ObjectiveSpec, specs) -> str:
    """A unique column name for an objective (its name, with its settings if it repeats)."""
    if sum(s.name == spec.name for s in specs) == 1:
        return spec.name
    return spec.name + "[" + ",".join(f"{k}={v}" for k, v in spec.settings) + "]"


class _Evaluation(NamedTuple):
    z: np.ndarray
    values: np.ndarray
    jac: np.ndarray


def _objective(study, index, ev: _Evaluation):
    """(weighted objective, its gradient in z)."""
    f, grad = 0.0, np.zeros_like(ev.z)
    for t in study.terms:
        k = index[t.spec]
        f += float(t.value(ev.values[k]))
        grad = grad + float(t.slope(ev.values[k])) * ev.jac[k]
    return f, grad


def _violations(study, index, ev: _Evaluation):
    """(constraint violations g, normalised: feasible <= 0, equalities 0; their Jacobian in z)."""
    g = np.asarray([float(c.violation(ev.values[index[c.spec]])) for c in study.constraints])
    dg = np.asarray([c.sign / c.limit_scale * ev.jac[index[c.spec]] for c in study.constraints])
    return g, dg.reshape(len(study.constraints), ev.z.shape[0])


def _merit(study, index, ev: _Evaluation, multipliers, rho):
    """(weighted objective, augmented merit, its gradient in z, constraint violations)."""
    f, grad = _objective(study, index, ev)
    merit = f
    violations = np.zeros(len(study.constraints))
    for j, c in enumerate(study.constraints):
        k = index[c.spec]
        g = float(c.violation(ev.values[k]))
        violations[j] = g
        active = multipliers[j] + rho * g
        if not c.is_equality:
            active = max(0.0, active)
        merit += (active**2 - multipliers[j] ** 2) / (2.0 * rho)
        grad = grad + active * c.sign / c.limit_scale * ev.jac[k]
    return f, merit, grad, violations


def _infeasibility(study, violations) -> float:
    """The largest constraint violation: an inequality's positive part, an equality's size."""
    return float(max((abs(g) if c.is_equality else max(0.0, g) for c, g in zip(study.constraints, violations)),
                     default=0.0))


def _update_multipliers(study, multipliers, violations, rho) -> np.ndarray:
    """PHR multiplier update: inequalities' multipliers stay >= 0, equalities' are free."""
    updated = multipliers + rho * np.asarray(violations)
    equality = np.asarray([c.is_equality for c in study.constraints], dtype=bool)
    return np.where(equality, updated, np.maximum(0.0, updated))


def optimise_study(study: OptimisationStudy, progress: Optional[Callable] = None, throw: bool = True,
                   design: Optional[Design] = None) -> OptimisationResult:
    """Run ``study`` (module docs): L-BFGS (Optax's direction, Armijo backtracking on the
    host) or Adam on the unconstrained variables, inside augmented-Lagrangian outer
    iterations when there are constraints, or SciPy's SLSQP with the constraints as they
    are. ``progress(entry)`` is called with every history entry. A non-finite objective,
    constraint or gradient (a steady state or trim that failed) ends the run:
    :class:`OptimisationError` with the result so far when ``throw``, else that result with
    ``failed`` True."""
    start = time.perf_counter()
    design = build_design(study) if design is None else design
    study = _with_rigid_values(study, design)
    problem, specs = design.problem, design.specs
    index = {s: k for k, s in enumerate(specs)}
    labels = [_label(s, specs) for s in specs]
    opts = study.optimiser
    multipliers = np.zeros(len(study.constraints))
    rho = float(opts["rho"])
    history: list = []
    counts = {"evaluations": 0}

    def evaluate(z) -> _Evaluation:
        counts["evaluations"] += 1
        v, jac = design.evaluate(z)
        return _Evaluation(np.asarray(z, float), v, jac)

    def finite(ev: _Evaluation) -> bool:
        return bool(np.all(np.isfinite(ev.values)) and np.all(np.isfinite(ev.jac)))

    def record(ev, outer, f, merit, grad, violations):
        values = {k: float(x) for k, x in problem.to_values(jnp.asarray(ev.z)).items()}
        entry = {"iteration": len(history), "outer": outer, "evaluations": counts["evaluations"], "objective": f,
                 "merit": merit, "grad_norm": float(np.linalg.norm(grad)), **values,
                 **{label: float(x) for label, x in zip(labels, ev.values)},
                 **{f"violation_{j}": float(g) for j, g in enumerate(violations)}}
        history.append(entry)
        if progress is not None:
            progress(entry)

    def result(ev, converged, message, failed=False):
        optimum = {k: float(x) for k, x in problem.to_values(jnp.asarray(ev.z)).items()}
        f, _, _, violations = _merit(study, index, ev, multipliers, rho) if finite(ev) else (math.nan,) * 3 + (
            np.full(len(study.constraints), math.nan),)
        cons = [{"name": c.spec.name, "kind": c.kind, "bound": c.limit, "value": float(ev.values[index[c.spec]]),
                 "violation": float(g)} | ({"reference": c.reference, "relative": c.relative,
                                            "relative_bound": c.bound, "rigid_value": c.rigid_value}
                                           if c.reference else {}) for c, g in zip(study.constraints, violations)]
        return OptimisationResult(study=study, optimum=optimum, objective=float(f),
                                  values={label: float(x) for label, x in zip(labels, ev.values)}, constraints=cons,
                                  converged=converged, message=message, iterations=len(history),
                                  evaluations=counts["evaluations"], history=history,
                                  car=design_car(design, optimum), failed=failed,
                                  wall_s=time.perf_counter() - start)

    def failure(ev, good, where):
        bad = [label for label, x in zip(labels, ev.values) if not np.isfinite(x)] or ["a gradient"]
        at = ", ".join(f"{k} = {float(x):.6g}" for k, x in problem.to_values(jnp.asarray(ev.z)).items())
        message = (f"failed simulation {where}: {', '.join(bad)} not finite at {at} (no steady state or trim there; "
                   "narrow the bounds)")
        res = result(good if good is not None else ev, False, message, failed=True)
        if throw:
            raise OptimisationError(message, res)
        return res

    def accept(ev: _Evaluation) -> _Evaluation:
        """Take ``ev`` as the current design: the mode objectives follow their modes to it."""
        if design.track is not None:
            design.track(ev.z)
        return ev

    ev = evaluate(problem.to_z({v.name: v.initial for v in study.variables}))
    if not finite(ev):
        return failure(ev, None, "at the initial design")
    if opts["method"] == "slsqp":
        return _slsqp(study, index, ev, evaluate, finite, accept, record, result, failure)
    converged, message = False, "the iteration limit was reached"
    for outer in range(opts["outer_steps"] if study.constraints else 1):
        f, merit, grad, violations = _merit(study, index, ev, multipliers, rho)
        record(ev, outer, f, merit, grad, violations)
        if opts["method"] == "adam":
            opt = optax.adam(opts["learning_rate"])
        else:
            opt = optax.scale_by_lbfgs(memory_size=opts["memory"])
        with jax.numpy_dtype_promotion("standard"):
            state = opt.init(jnp.asarray(ev.z))
        inner_converged = False
        for _ in range(opts["steps"]):
            if np.linalg.norm(grad) <= opts["tolerance"]:
                inner_converged = True
                break
            with jax.numpy_dtype_promotion("standard"):
                updates, state = opt.update(jnp.asarray(grad), state, jnp.asarray(ev.z))
            step = np.asarray(updates)
            if opts["method"] == "adam":
                trial = evaluate(ev.z + step)
                if not finite(trial):
                    return failure(trial, ev, f"at iteration {len(history)}")
                ev = accept(trial)
            else:
                direction = -step
                slope = float(grad @ direction)
                if not slope < 0.0:
                    # not a descent direction (negative curvature seen): forget the pairs and
                    # restart as L-BFGS's first step, -g min(1, 1/|g|)
                    with jax.numpy_dtype_promotion("standard"):
                        state = opt.init(jnp.asarray(ev.z))
                        updates, state = opt.update(jnp.asarray(grad), state, jnp.asarray(ev.z))
                    direction = -np.asarray(updates)
                    slope = float(grad @ direction)
                t, accepted = 1.0, None
                for _ in range(MAX_HALVINGS):
                    trial = evaluate(ev.z + t * direction)
                    if finite(trial):
                        trial_merit = _merit(study, index, trial, multipliers, rho)[1]
                        if trial_merit <= merit + ARMIJO_C1 * t * slope:
                            accepted = trial
                            break
                    t *= 0.5
                if accepted is None:
                    if not finite(trial):
                        return failure(trial, ev, f"in the line search of iteration {len(history)}")
                    message = "the line search found no decrease (round-off level reached)"
                    inner_converged = np.linalg.norm(grad) <= 1e3 * opts["tolerance"]
                    break
                ev = accept(accepted)
            f, merit, grad, violations = _merit(study, index, ev, multipliers, rho)
            record(ev, outer, f, merit, grad, violations)
        worst = _infeasibility(study, violations)
        if not study.constraints:
            converged = inner_converged or np.linalg.norm(grad) <= opts["tolerance"]
            break
        multipliers = _update_multipliers(study, multipliers, violations, rho)
        if worst > opts["constraint_tol"]:
            rho *= opts["rho_growth"]
        elif inner_converged:
            converged = True
            break
    if converged:
        message = "converged: gradient norm below the tolerance" + (" with the constraints met"
                                                                     if study.constraints else "")
    return result(ev, bool(converged), message)


class _NotFinite(Exception):
    """An evaluation with a non-finite value or derivative inside SciPy's SLSQP (ends it)."""

    def __init__(self, ev: _Evaluation):
        super().__init__("not finite")
        self.ev = ev


#: SLSQP works on each variable's place in its bounds, ``s = sigmoid(z)`` in [0, 1] (the
#: same linear or log scale), with SciPy's bounds [0, 1]: a variable can then end on its
#: bound, where SLSQP's KKT test passes with the bound's multiplier (in ``z`` the bound lies
#: at infinity, the objective flattens towards it and a bounded optimum creeps and never
#: converges). ``s`` is held this far inside [0, 1] so that ``z`` stays finite (relative
#: 1e-12 of the bounds' span).
_S_EDGE = 1e-12


def _z_of_s(s) -> np.ndarray:
    s = np.clip(np.asarray(s, dtype=float), _S_EDGE, 1.0 - _S_EDGE)
    return np.log(s) - np.log1p(-s)


def _dz_ds(z) -> np.ndarray:
    """``dz/ds`` at ``z`` (``s = sigmoid(z)``): the chain rule from ``z`` to ``s``."""
    s = scipy.special.expit(z)
    return 1.0 / (s * (1.0 - s))


def _slsqp(study, index, ev, evaluate, finite, accept, record, result, failure) -> OptimisationResult:
    """SciPy's SLSQP on the variables' places in their bounds ``s`` (:data:`_S_EDGE`): the
    weighted objective, the constraints ``g <= 0`` as SciPy's ``-g >= 0`` and the
    equalities as its ``"eq"`` constraints, every function
    and Jacobian from the one evaluation at each ``s`` (kept until the next ``s``).
    Converged when SciPy reports its KKT test passed and the constraints are met to
    ``constraint_tol``."""
    opts = study.optimiser
    s0 = scipy.special.expit(ev.z)
    current = {"s": s0, "ev": ev, "good": ev, "logged": 0}

    def at(s) -> _Evaluation:
        if not np.array_equal(current["s"], s):
            trial = evaluate(_z_of_s(s))
            if not finite(trial):
                raise _NotFinite(trial)
            current["s"], current["ev"] = np.array(s, dtype=float), trial
        return current["ev"]

    def objective(s):
        e = at(s)
        f, grad = _objective(study, index, e)
        return f, grad * _dz_ds(e.z)

    def constraints(s):
        e = at(s)
        g, dg = _violations(study, index, e)
        return -g, -dg * _dz_ds(e.z)[None, :]

    def log(e: _Evaluation) -> None:
        f, grad = _objective(study, index, e)
        record(e, 0, f, f, grad, _violations(study, index, e)[0])
        current["logged"] += 1

    def iterate(s) -> None:
        current["good"] = accept(at(s))
        log(current["good"])

    equality = np.asarray([c.is_equality for c in study.constraints], dtype=bool)
    cons = [{"type": kind, "fun": lambda s, rows=rows: constraints(s)[0][rows],
             "jac": lambda s, rows=rows: constraints(s)[1][rows]}
            for kind, rows in (("ineq", ~equality), ("eq", equality)) if rows.any()]
    log(ev)
    try:
        res = scipy.optimize.minimize(lambda s: objective(s)[0], s0, method="SLSQP",
                                      jac=lambda s: objective(s)[1], bounds=[(0.0, 1.0)] * ev.z.shape[0],
                                      constraints=cons, callback=iterate,
                                      options={"maxiter": opts["steps"], "ftol": opts["tolerance"]})
    except _NotFinite as bad:
        return failure(bad.ev, current["good"], f"at iteration {current['logged']}")
    final = accept(at(res.x))
    if not np.array_equal(final.z, current["good"].z):
        log(final)
    worst = _infeasibility(study, _violations(study, index, final)[0])
    converged = bool(res.success and worst <= opts["constraint_tol"])
    message = f"SLSQP: {res.message}" + ("" if worst <= opts["constraint_tol"] else
                                         f" (largest constraint violation {worst:.3g})")
    return result(final, converged, message)


# ---- outputs ---------------------------------------------------------------------------------


def result_report(result: OptimisationResult, files: Optional[dict] = None) -> dict:
    """JSON-ready summary: ``optimum``, ``objective``, ``converged`` (the CLI's contract),
    and the study, message, objectives' values, constraints, counts, time, arb rates
    written, the output ``files`` and the ``history``."""
    study = result.study
    return {
        "study": study.name,
        "optimum": result.optimum,
        "objective": result.objective,
        "converged": result.converged,
        "failed": result.failed,
        "message": result.message,
        "values": result.values,
        "units": {_label(s, study.specs): objective_units(s.name) for s in study.specs},
        "constraints": result.constraints,
        "variables": {v.name: {"path": v.path, "lower": v.lower, "upper": v.upper, "initial": v.initial,
                               "log": v.log, "units": v.units} for v in study.variables},
        "modes": study.modes,
        "method": study.optimiser["method"],
        "iterations": result.iterations,
        "evaluations": result.evaluations,
        "wall_s": result.wall_s,
        "car_values": changed_car_values(result),
        "files": files or {},
        "history": result.history,
    }


def frame_sizes(result: OptimisationResult) -> tuple:
    """``((FrameVariable, value (m)), ...)`` of the optimum's frame variables."""
    return tuple((parse_frame_path(v.path), result.optimum[v.name]) for v in result.study.variables
                 if is_frame_path(v.path))


def optimum_frame_file(result: OptimisationResult) -> str:
    """The base car's frame file with the optimum's tube sizes written in (mm)."""
    vehicle_file = result.study.vehicle
    return optimum_frame_text(frame_text(vehicle_file), load_car_frame(vehicle_file), frame_sizes(result))


def write_outputs(result: OptimisationResult, out_dir=None) -> dict:
    """Write ``OUT/NAME.json`` (:func:`result_report`), ``OUT/NAME_history.csv`` (one row
    per iteration) and ``OUT/NAME_car.toml`` (:func:`optimum_car_file`; with frame
    variables also ``OUT/NAME_frame.toml``, :func:`optimum_frame_file`, which the car file
    names; not after a failed run); returns ``{kind: path}``."""
    out = Path(result.study.out if out_dir is None else out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = result.study.name
    files = {"json": str(out / f"{name}.json"), "csv": str(out / f"{name}_history.csv")}
    columns = list(dict.fromkeys(k for entry in result.history for k in entry))
    with open(files["csv"], "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(result.history)
    if not result.failed:
        if frame_sizes(result):
            files["frame"] = str(out / f"{name}_frame.toml")
            Path(files["frame"]).write_text(optimum_frame_file(result))
        files["vehicle"] = str(out / f"{name}_car.toml")
        Path(files["vehicle"]).write_text(optimum_car_file(result, files.get("frame")))
    report = result_report(result, files)
    Path(files["json"]).write_text(json.dumps(report, indent=2))
    return files
