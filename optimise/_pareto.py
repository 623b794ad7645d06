"""Multi-objective optimisation by the ε-constraint method: a Pareto front as a sweep of
one constraint's bound (``[pareto]`` in an optimisation study file).

For each bound ε of ``pareto.values`` the study's objective is optimised with its
constraint ``pareto.constraint`` held at ``<= ε`` (or ``>= ε``), each run starting from the
previous optimum. All runs share the study's one compiled program (bounds are applied on
the host, :func:`optimise.optimise_study`), so a front costs its optimiser iterations only.
A point whose optimisation failed (no steady state) or did not converge stays in the
front, flagged; the front is the converged points' (objective, constrained quantity) pairs.

A study file's section::

    [pareto]
    constraint = "understeer_gradient"    # the name of one bound of [[constraints]]
    values = [-0.16, -0.14, -0.12]        # its bounds in turn (monotonic), the constraint's units
"""

import csv
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple, Optional

import numpy as np

from ._objectives import objective_units
from ._optimise_study import (
    Design,
    OptimisationStudy,
    _label,
    build_design,
    optimise_study,
)

#: How far inside its bounds a warm start is put (fraction of the bounds' span): the
#: logistic map of the variables needs strictly interior values.
INSIDE = 1e-9


class ParetoResult(NamedTuple):
    """The front: ``bounds`` (the ε values), one :class:`~optimise.OptimisationResult` per
    bound in ``results``, ``wall_s``."""

    study: OptimisationStudy
    bounds: tuple
    results: tuple
    wall_s: float


def _warm_start(study: OptimisationStudy, optimum: dict) -> OptimisationStudy:
    variables = []
    for v in study.variables:
        pad = INSIDE * (v.upper - v.lower)
        variables.append(v._replace(initial=float(np.clip(optimum[v.name], v.lower + pad, v.upper - pad))))
    return study._replace(variables=tuple(variables))


def pareto_front(study: OptimisationStudy, design: Optional[Design] = None,
                 progress: Optional[Callable[[str], None]] = None) -> ParetoResult:
    """Optimise ``study`` once per bound of its ``pareto`` sweep (module docs); ``progress``
    gets a line per point. Failed points are kept (``failed``), the sweep goes on from the
    last good optimum."""
    if study.pareto is None:
        raise ValueError(f"study {study.name!r} has no [pareto] section: nothing to sweep")
    start = time.perf_counter()
    design = build_design(study) if design is None else design
    j = study.pareto.constraint
    current = study
    results = []
    for i, eps in enumerate(study.pareto.values):
        constraints = list(current.constraints)
        constraints[j] = constraints[j]._replace(bound=eps)
        point = current._replace(constraints=tuple(constraints), name=f"{study.name}_{i:02d}")
        res = optimise_study(point, throw=False, design=design)
        results.append(res)
        if progress is not None:
            c = res.constraints[j]
            progress(f"{c['name']} {c['kind']} {eps:.6g}: objective {res.objective:.6g}, {c['name']} "
                     f"{c['value']:.6g}, {'converged' if res.converged else res.message}")
        if not res.failed:
            current = _warm_start(current, res.optimum)
    return ParetoResult(study=study, bounds=study.pareto.values, results=tuple(results),
                        wall_s=time.perf_counter() - start)


def _finite(x) -> Optional[float]:
    return float(x) if np.isfinite(x) else None


def pareto_report(front: ParetoResult) -> dict:
    """JSON-ready front: per bound the optimum, the objective, every objective's value, the
    constrained quantity's value, ``active`` (at its bound within 1e-6 of the bound's
    scale), ``converged``, ``failed``, the message and the counts."""
    study = front.study
    j = study.pareto.constraint
    bound = study.constraints[j]
    points = []
    for eps, r in zip(front.bounds, front.results):
        c = r.constraints[j]
        unit = abs(c["rigid_value"]) if c.get("relative") else 1.0
        active = bool(np.isfinite(c["value"]) and abs(c["value"] - c["bound"]) <= 1e-6 * bound.scale * unit)
        points.append({"bound": eps, "optimum": r.optimum, "objective": _finite(r.objective),
                       "values": {k: _finite(v) for k, v in r.values.items()},
                       "constrained_value": _finite(c["value"]), "active": active, "converged": r.converged,
                       "failed": r.failed, "message": r.message, "iterations": r.iterations,
                       "evaluations": r.evaluations})
    return {"study": study.name, "constraint": {"name": bound.spec.name, "kind": bound.kind,
                                                "units": objective_units(bound.spec.name)},
            "objective_terms": [{"name": t.spec.name, "sense": t.sense, "target": t.target, "scale": t.scale,
                                 "weight": t.weight} for t in study.terms],
            "units": {_label(s, study.specs): objective_units(s.name) for s in study.specs},
            "points": points, "wall_s": front.wall_s}


def _plot(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = report["constraint"]
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    good = [p for p in report["points"] if p["converged"]]
    bad = [p for p in report["points"] if not p["converged"] and not p["failed"]]
    ax.plot([p["constrained_value"] for p in good], [p["objective"] for p in good], "-o", ms=4, label="converged")
    if bad:
        ax.plot([p["constrained_value"] for p in bad], [p["objective"] for p in bad], "x", ms=7,
                label="not converged")
    ax.set_xlabel(f"{c['name']} ({c['units']}), constrained {c['kind']} bound")
    ax.set_ylabel("objective at the optimum")
    ax.set_title(f"{report['study']}: ε-constraint front")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def write_pareto_outputs(front: ParetoResult, out_dir=None) -> dict:
    """Write ``OUT/NAME_pareto.json`` (:func:`pareto_report`), ``OUT/NAME_pareto.csv`` (a
    row per bound: bound, objective, the variables, every objective's value, flags) and
    ``OUT/NAME_pareto.png``; returns ``{kind: path}``."""
    out = Path(front.study.out if out_dir is None else out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = front.study.name
    files = {"json": str(out / f"{name}_pareto.json"), "csv": str(out / f"{name}_pareto.csv"),
             "png": str(out / f"{name}_pareto.png")}
    report = pareto_report(front)
    rows = [{"bound": p["bound"], "objective": p["objective"], **p["optimum"], **p["values"],
             "active": p["active"], "converged": p["converged"], "failed": p["failed"]} for p in report["points"]]
    with open(files["csv"], "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        writer.writeheader()
        writer.writerows(rows)
    report["files"] = files
    Path(files["json"]).write_text(json.dumps(report, indent=2))
    _plot(report, Path(files["png"]))
    return files
