"""Characteristic curves of a tyre (the panels of Fig. B.1) and their peaks.

All evaluated with one vmapped, jitted call of :func:`tyre_forces` per curve family.
"""

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..params import Range, check, check_int, check_static
from ._checks import check_tyre
from ._magic_formula import tyre_forces
from ._model import MagicFormulaTyre

_KAPPA_MAX = Range(0.0, low_open=True, what="largest |kappa| of the curves, -")
_ALPHA_MAX = Range(0.0, 90.0, low_open=True, high_open=True, what="largest |alpha| of the curves, deg")
_LOAD = Range(what="normal load, N; <= 0 is lift-off (zero force)")

#: Fig. B.1 slip ranges. Its loads, 250/500/750/1000 N, are 1/3, 2/3, 1 and 4/3 of the
#: shipped tyre's FNOMIN (750 N); :func:`default_loads` applies that rule to any tyre.
FIG_B1_KAPPA_MAX = 0.3
FIG_B1_ALPHA_MAX_DEG = 15.0


def default_loads(tyre: MagicFormulaTyre) -> tuple[float, ...]:
    """Loads [N] of the Fig. B.1 panels: FNOMIN x (1/3, 2/3, 1, 4/3) (250-1000 N for FSAE)."""
    fnomin = float(tyre.fnomin)
    return tuple(fnomin * k / 3.0 for k in (1, 2, 3, 4))


@eqx.filter_jit
def _sweep(tyre, fz, kappa, alpha, gamma, vx):
    """Forces on a grid: loads (n_fz,) x points (n,), one gamma and vx."""
    point = lambda f, k, a: tyre_forces(tyre, f, k, a, gamma, vx)  # noqa: E731
    per_load = jax.vmap(point, in_axes=(None, 0, 0))
    return jax.vmap(per_load, in_axes=(0, None, None))(fz, kappa, alpha)


class PureSlipCurves(NamedTuple):
    """Pure-slip curves at several loads: rows are loads, columns slip points."""

    loads: Float[Array, " n_fz"]
    kappa: Float[Array, " n"]
    alpha: Float[Array, " n"]
    fx: Float[Array, "n_fz n"]
    fy: Float[Array, "n_fz n"]
    mz: Float[Array, "n_fz n"]


def pure_slip_curves(
    tyre: MagicFormulaTyre,
    loads=None,
    n: int = 601,
    kappa_max: float = FIG_B1_KAPPA_MAX,
    alpha_max_deg: float = FIG_B1_ALPHA_MAX_DEG,
    gamma: float = 0.0,
) -> PureSlipCurves:
    """Fx(kappa) at alpha = 0, and Fy(alpha), Mz(alpha) at kappa = 0, at each load [N]
    (default :func:`default_loads`). ``n`` >= 2, ``kappa_max`` > 0 and ``alpha_max_deg`` in
    (0, 90) are checked."""
    tyre = check_tyre(tyre)
    n = check_int("n", n, 2, "points per curve")
    check_static("kappa_max", kappa_max, _KAPPA_MAX)
    check_static("alpha_max_deg", alpha_max_deg, _ALPHA_MAX)
    loads = check("loads", default_loads(tyre) if loads is None else loads, _LOAD)
    kappa = jnp.linspace(-kappa_max, kappa_max, n)
    alpha = jnp.deg2rad(jnp.linspace(-alpha_max_deg, alpha_max_deg, n))
    zero = jnp.zeros_like(kappa)
    g, vx = jnp.asarray(gamma, dtype=jnp.float64), tyre.longvl
    lon = _sweep(tyre, loads, kappa, zero, g, vx)
    lat = _sweep(tyre, loads, zero, alpha, g, vx)
    return PureSlipCurves(loads, kappa, alpha, lon.fx, lat.fy, lat.mz)


def combined_slip_curves(
    tyre: MagicFormulaTyre,
    fz: float | None = None,
    alphas_deg=(1.0, 2.0, 4.0, 6.0, 8.0, 10.0),
    n: int = 301,
    kappa_max: float = FIG_B1_KAPPA_MAX,
):
    """Fx and Fy over kappa in [-kappa_max, kappa_max] at each slip angle (both signs) [N],
    at load ``fz`` [N] (default FNOMIN: 750 N for the shipped tyre, as Fig. B.1(d)).
    ``n`` >= 2 and ``kappa_max`` > 0 are checked."""
    tyre = check_tyre(tyre)
    n = check_int("n", n, 2, "points per curve")
    check_static("kappa_max", kappa_max, _KAPPA_MAX)
    fz = float(tyre.fnomin) if fz is None else check_static("fz", fz, _LOAD)
    a = np.deg2rad(np.asarray(alphas_deg, dtype=np.float64))
    a = jnp.asarray(np.concatenate([-a[::-1], a]))
    kappa = jnp.linspace(-kappa_max, kappa_max, n)
    grid = _combined(tyre, jnp.asarray(fz, dtype=jnp.float64), a, kappa)
    return a, kappa, grid.fx, grid.fy


@eqx.filter_jit
def _combined(tyre, fz, alphas, kappa):
    """Forces on a grid: slip angles (n_a,) x kappa (n,), one load, camber 0."""
    point = lambda al, k: tyre_forces(tyre, fz, k, al, 0.0, tyre.longvl)  # noqa: E731
    return jax.vmap(jax.vmap(point, in_axes=(None, 0)), in_axes=(0, None))(alphas, kappa)


def peak_table(tyre: MagicFormulaTyre, loads=None, n: int = 3001) -> list[dict[str, float]]:
    """Peak |Fx|, |Fy|, max and min Mz per load, and the slips where they occur.

    Keys: ``fz`` [N], ``fx_peak`` [N] at ``kappa_peak`` [-] (driving side), ``fy_peak``
    [N] = max |Fy| at ``alpha_peak_deg``, ``mz_max`` / ``mz_min`` [Nm] at
    ``alpha_mz_max_deg`` / ``alpha_mz_min_deg``; over the Fig. B.1 slip ranges, at
    ``loads`` [N] (default :func:`default_loads`). The Fy
    peak is searched on the positive slip-angle side (ISO-W: Fy < 0 there).
    """
    c = pure_slip_curves(tyre, loads, n=n)
    kappa, alpha_deg = np.asarray(c.kappa), np.rad2deg(np.asarray(c.alpha))
    rows = []
    for i, fz in enumerate(np.asarray(c.loads)):
        fx, mz = np.asarray(c.fx[i]), np.asarray(c.mz[i])
        fy = np.where(alpha_deg >= 0.0, np.abs(np.asarray(c.fy[i])), 0.0)
        rows.append(
            dict(
                fz=float(fz),
                fx_peak=float(fx.max()),
                kappa_peak=float(kappa[fx.argmax()]),
                fy_peak=float(fy.max()),
                alpha_peak_deg=float(alpha_deg[fy.argmax()]),
                mz_max=float(mz.max()),
                alpha_mz_max_deg=float(alpha_deg[mz.argmax()]),
                mz_min=float(mz.min()),
                alpha_mz_min_deg=float(alpha_deg[mz.argmin()]),
            )
        )
    return rows
