"""Fit Magic Formula 5.2 coefficients to measured forces by least squares.

Levenberg-Marquardt (Optimistix) on residuals normalised by the load, with Jacobians
from autodiff through :func:`tyre_forces`. Stages, as MF-Tyre fitting is usually done:
pure longitudinal slip, pure lateral slip, pure aligning moment, then the combined-slip
coefficients with the pure-slip ones held fixed.
"""

import csv
import warnings
from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jaxtyping import Array, Float

from .._core import check_x64
from ..params import POSITIVE, ParameterError, check_int, check_static
from ._checks import check_tyre
from ._magic_formula import tyre_forces
from ._model import MagicFormulaTyre

#: Columns a measurement CSV must have (SI units; angles may instead be ``*_deg``).
REQUIRED_COLUMNS: tuple[str, ...] = ("fz", "kappa", "alpha", "gamma", "fx", "fy", "mz")
#: Optional columns: wheel speed [m/s] and inflation pressure [Pa].
OPTIONAL_COLUMNS: tuple[str, ...] = ("vx", "pressure")
#: A row is pure longitudinal slip when |alpha| is below this [rad] (0.5 deg), pure lateral
#: when |kappa| is below ``PURE_KAPPA``.
PURE_ALPHA = np.deg2rad(0.5)
PURE_KAPPA = 5.0e-3


class TyreMeasurements(NamedTuple):
    """Measured tyre data, one row per point, SI units and ISO-W signs."""

    fz: Float[Array, " n"]
    kappa: Float[Array, " n"]
    alpha: Float[Array, " n"]
    gamma: Float[Array, " n"]
    fx: Float[Array, " n"]
    fy: Float[Array, " n"]
    mz: Float[Array, " n"]
    vx: Float[Array, " n"]

    def select(self, mask) -> "TyreMeasurements":
        """The rows where ``mask`` is true."""
        mask = np.asarray(mask)
        return TyreMeasurements(*(jnp.asarray(np.asarray(c)[mask]) for c in self))


class FitStage(NamedTuple):
    """One least-squares stage: which rows, which outputs, which coefficients."""

    name: str
    rows: str  # "pure_kappa", "pure_alpha" or "all"
    outputs: tuple[str, ...]  # subset of ("fx", "fy", "mz")
    coefficients: tuple[str, ...]


#: The default stages (coefficients a stage cannot identify keep their start values).
DEFAULT_STAGES: tuple[FitStage, ...] = (
    FitStage(
        "pure longitudinal",
        "pure_kappa",
        ("fx",),
        ("pcx1", "pdx1", "pdx2", "pdx3", "pex1", "pex2", "pex3", "pex4", "pkx1", "pkx2", "pkx3",
         "phx1", "phx2", "pvx1", "pvx2"),
    ),
    FitStage(
        "pure lateral",
        "pure_alpha",
        ("fy",),
        ("pcy1", "pdy1", "pdy2", "pdy3", "pey1", "pey2", "pey3", "pey4", "pky1", "pky2", "pky3",
         "phy1", "phy2", "phy3", "pvy1", "pvy2", "pvy3", "pvy4"),
    ),
    FitStage(
        "pure aligning",
        "pure_alpha",
        ("mz",),
        ("qbz1", "qbz2", "qbz3", "qbz4", "qbz5", "qbz9", "qcz1", "qdz1", "qdz2", "qdz3", "qdz4",
         "qdz6", "qdz7", "qdz8", "qdz9", "qez1", "qez2", "qez3", "qez4", "qhz1", "qhz2", "qhz3", "qhz4"),
    ),
    FitStage(
        "combined",
        "all",
        ("fx", "fy", "mz"),
        ("rbx1", "rbx2", "rcx1", "rex1", "rex2", "rhx1", "rby1", "rby2", "rby3", "rcy1", "rey1",
         "rey2", "rhy1", "rhy2", "rvy1", "rvy2", "rvy3", "rvy4", "rvy5", "rvy6", "ssz1", "ssz2",
         "ssz3", "ssz4"),
    ),
)


class FitReport(NamedTuple):
    """Result of :func:`fit_tir`: the tyre and, per stage run, RMS residuals [N or Nm]."""

    tyre: MagicFormulaTyre
    stages: tuple[dict, ...]


def read_tyre_csv(path: str | Path) -> TyreMeasurements:
    """Read measurements from a CSV with a header row.

    Columns (SI, ISO-W): ``fz`` [N], ``kappa`` [-], ``alpha`` [rad] (or ``alpha_deg``),
    ``gamma`` [rad] (or ``gamma_deg``), ``fx``, ``fy`` [N], ``mz`` [Nm]; optional ``vx``
    [m/s] and ``pressure`` [Pa]. MF 5.2 has no pressure terms: data at several pressures
    are fitted as one tyre (a warning says so).

    Raises:
        ParameterError: a required column is missing or a value is not a finite number.
    """
    path = Path(path)
    with path.open(newline="") as fh:
        rows = list(csv.reader(line for line in fh if line.strip() and not line.startswith("#")))
    if not rows:
        raise ParameterError(f"{path}: empty CSV (expected a header with {', '.join(REQUIRED_COLUMNS)})")
    header = [h.strip().lower() for h in rows[0]]
    try:
        table = np.array([[float(v) for v in r] for r in rows[1:]], dtype=np.float64)
        table = table.reshape(len(rows) - 1, len(header))
    except ValueError as err:
        raise ParameterError(f"{path}: every value must be a number ({err})") from None
    if not np.all(np.isfinite(table)):
        raise ParameterError(f"{path}: values must be finite")
    cols: dict[str, np.ndarray] = {h: table[:, i] for i, h in enumerate(header)}
    for name in ("alpha", "gamma"):
        if name not in cols and f"{name}_deg" in cols:
            cols[name] = np.deg2rad(cols[f"{name}_deg"])
    missing = [c for c in REQUIRED_COLUMNS if c not in cols]
    if missing:
        raise ParameterError(f"{path}: missing column(s) {', '.join(missing)}; required: {', '.join(REQUIRED_COLUMNS)}")
    if table.shape[0] == 0:
        raise ParameterError(f"{path}: no data rows")
    if "pressure" in cols and np.ptp(cols["pressure"]) > 0.01 * np.abs(cols["pressure"]).max():
        warnings.warn(
            "MF 5.2 has no pressure dependence: rows at different pressures are fitted as one tyre", stacklevel=2
        )
    vx = cols.get("vx", np.full(table.shape[0], np.nan))
    return TyreMeasurements(*(jnp.asarray(cols[c]) for c in REQUIRED_COLUMNS), jnp.asarray(vx))


def _with(tyre: MagicFormulaTyre, names: tuple[str, ...], values: Float[Array, " k"]) -> MagicFormulaTyre:
    """``tyre`` with the coefficients ``names`` replaced by the entries of ``values``."""
    return eqx.tree_at(lambda t: [getattr(t, n) for n in names], tyre, [values[i] for i in range(len(names))])


def _residuals(tyre: MagicFormulaTyre, data: TyreMeasurements, outputs: tuple[str, ...]) -> Float[Array, " m"]:
    """Model minus measurement, forces over Fz and Mz over Fz R0 (dimensionless)."""
    model = _predict(tyre, data)
    scale = jnp.maximum(jnp.abs(data.fz), 1e-3 * tyre.fnomin)
    parts = []
    for out in outputs:
        norm = scale * tyre.unloaded_radius if out == "mz" else scale
        parts.append((getattr(model, out) - getattr(data, out)) / norm)
    return jnp.concatenate(parts)


@eqx.filter_jit
def _solve(tyre, names, data, outputs, rtol, atol, max_steps):
    y0 = jnp.stack([getattr(tyre, n) for n in names])
    fn = lambda y, _: _residuals(_with(tyre, names, y), data, outputs)  # noqa: E731
    sol = optx.least_squares(fn, optx.LevenbergMarquardt(rtol=rtol, atol=atol), y0, max_steps=max_steps, throw=False)
    return sol.value, sol.result == optx.RESULTS.successful, sol.stats["num_steps"]


def _rows(data: TyreMeasurements, which: str) -> np.ndarray:
    kappa, alpha = np.abs(np.asarray(data.kappa)), np.abs(np.asarray(data.alpha))
    if which == "pure_kappa":
        return alpha <= PURE_ALPHA
    if which == "pure_alpha":
        return kappa <= PURE_KAPPA
    return np.ones_like(kappa, dtype=bool)


def fit_tir(
    data: TyreMeasurements,
    start: MagicFormulaTyre | None = None,
    stages: tuple[FitStage, ...] = DEFAULT_STAGES,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_steps: int = 400,
) -> FitReport:
    """Fit MF 5.2 coefficients to measurements, stage by stage.

    Args:
        data: measurements (:func:`read_tyre_csv`).
        start: initial coefficients (and all coefficients not fitted); default the shipped
            FSAE tyre with ``FNOMIN`` set to the median measured load. Checked like any
            tyre (``ParameterError`` names a coefficient out of range).
        stages: what to fit in which order (default :data:`DEFAULT_STAGES`); a stage with
            fewer rows than coefficients, or only combined rows missing, is skipped.
        rtol, atol, max_steps: Levenberg-Marquardt settings (> 0, > 0, >= 1).

    Returns:
        :class:`FitReport` with the fitted tyre and, per stage, the rows used, RMS
        residuals before and after [N, Nm], steps taken and whether it converged.
    """
    check_x64()
    for name, tol in (("rtol", rtol), ("atol", atol)):
        check_static(name, tol, POSITIVE)
    max_steps = check_int("max_steps", max_steps, 1, "Levenberg-Marquardt steps per stage")
    if start is None:
        from ._tir import load_fsae_tyre

        start = eqx.tree_at(lambda t: t.fnomin, load_fsae_tyre(), jnp.median(data.fz))
    tyre = check_tyre(start)
    report = []
    for stage in stages:
        mask = _rows(data, stage.rows)
        if stage.rows == "all":
            mask &= (np.abs(np.asarray(data.kappa)) > PURE_KAPPA) & (np.abs(np.asarray(data.alpha)) > PURE_ALPHA)
        n_rows = int(mask.sum())
        if n_rows * len(stage.outputs) <= len(stage.coefficients):
            report.append(dict(stage=stage.name, rows=n_rows, skipped=True))
            continue
        subset = data.select(mask)
        rows_for_fit = subset if stage.rows != "all" else data
        before = _rms(tyre, subset, stage.outputs)
        values, ok, steps = _solve(tyre, stage.coefficients, rows_for_fit, stage.outputs, rtol, atol, max_steps)
        tyre = _with(tyre, stage.coefficients, values)
        report.append(
            dict(stage=stage.name, rows=n_rows, skipped=False, converged=bool(ok), steps=int(steps),
                 rms_before=before, rms_after=_rms(tyre, subset, stage.outputs))
        )
    return FitReport(tyre, tuple(report))


def _predict(tyre: MagicFormulaTyre, data: TyreMeasurements):
    """Model forces at the measured operating points (missing speed: LONGVL)."""
    vx = jnp.where(jnp.isnan(data.vx), tyre.longvl, data.vx)
    return jax.vmap(tyre_forces, in_axes=(None, 0, 0, 0, 0, 0))(tyre, data.fz, data.kappa, data.alpha, data.gamma, vx)


_predict_jit = eqx.filter_jit(_predict)


def _rms(tyre: MagicFormulaTyre, data: TyreMeasurements, outputs: tuple[str, ...]) -> dict[str, float]:
    """RMS error per output [N or Nm]."""
    model = _predict_jit(tyre, data)
    return {o: float(jnp.sqrt(jnp.mean((getattr(model, o) - getattr(data, o)) ** 2))) for o in outputs}


def write_tyre_csv(path: str | Path, data: TyreMeasurements) -> Path:
    """Write measurements in the format :func:`read_tyre_csv` reads."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    columns = list(REQUIRED_COLUMNS)
    if np.all(np.isfinite(np.asarray(data.vx))):
        columns.append("vx")
    table = np.column_stack([np.asarray(getattr(data, c)) for c in columns])
    np.savetxt(path, table, delimiter=",", header=",".join(columns), comments="", fmt="%.17g")
    return path
