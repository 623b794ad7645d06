"""Coefficient checks of the Magic Formula tyre (see "Input validation" in ``docs/tyre.md``).

A :class:`~jaxveh.tyre.MagicFormulaTyre` is checked on construction (concrete values raise
:class:`~jaxveh.params.ParameterError` naming the coefficient and its allowed range). The
public functions of :mod:`jaxveh.tyre` check their tyre again with :func:`check_tyre`, so
coefficients changed with ``eqx.tree_at`` or traced by an optimiser are checked too (at run
time, with one ``eqx.branched_error_if``). Loads ``fz <= 0`` are not refused: they are the
tyre's lift-off, handled by design; nor is zero speed.
"""

import functools
from typing import TYPE_CHECKING

from ..params import NON_NEGATIVE, POSITIVE, Range, check_module

if TYPE_CHECKING:
    from ._model import MagicFormulaTyre

#: Coefficients that must be > 0: loads, radii, speeds, stiffnesses and the factors the
#: Magic Formula divides by or that must keep their sign (shape factors, peak friction, the
#: load of peak cornering stiffness, the scale factors of nominal load, friction, shape
#: and relaxation length) and the constant relaxation lengths.
POSITIVE_COEFFICIENTS: tuple[str, ...] = (
    "fnomin", "unloaded_radius", "vxlow", "longvl", "vertical_stiffness",
    "pcx1", "pdx1", "pcy1", "pdy1", "pky2", "qcz1",
    "lfzo", "lmux", "lmuy", "lcx", "lcy", "lsgkp", "lsgal",
    "sigma_kappa", "sigma_alpha",
)  # fmt: skip
#: Coefficients that must be >= 0: the vertical damping and the other scaling factors
#: (MF-Tyre's user scaling factors are non-negative multipliers, 1 by default).
NON_NEGATIVE_COEFFICIENTS: tuple[str, ...] = (
    "vertical_damping",
    "lex", "lkx", "lhx", "lvx", "lgax", "ley", "lky", "lhy", "lvy", "lgay", "ltr", "lres", "lgaz",
    "lxal", "lyka", "lvyka", "ls", "lgyr", "lmx", "lvmx", "lmy",
)  # fmt: skip
#: With ``relaxation_model == "mf52"`` the relaxation-length coefficients must be > 0.
MF52_RELAXATION_COEFFICIENTS: tuple[str, ...] = ("ptx1", "pty1", "pty2")


def _range(name: str, rng: Range) -> Range:
    from ._model import coefficient_fields

    doc = {f.name: f.metadata["doc"] for f in coefficient_fields()}[name]
    return Range(rng.low, rng.high, rng.low_open, rng.high_open, f"{name.upper()}: {doc}")


@functools.cache
def coefficient_ranges(relaxation_model: str) -> dict[str, Range]:
    """Allowed values of the checked coefficients of a tyre with this relaxation model."""
    out = {n: _range(n, POSITIVE) for n in POSITIVE_COEFFICIENTS}
    out |= {n: _range(n, NON_NEGATIVE) for n in NON_NEGATIVE_COEFFICIENTS}
    if relaxation_model == "mf52":
        out |= {n: _range(n, POSITIVE) for n in MF52_RELAXATION_COEFFICIENTS}
    return out


def check_tyre(tyre: "MagicFormulaTyre") -> "MagicFormulaTyre":
    """Check the coefficients of ``tyre`` (:func:`coefficient_ranges`); return it (use it).

    Concrete values raise :class:`~jaxveh.params.ParameterError`; traced values raise at
    run time through ``eqx.error_if``.
    """
    return check_module(tyre, "MagicFormulaTyre", coefficient_ranges(tyre.relaxation_model))


def tyre_checked(fn):
    """``fn(tyre, ...)`` with the tyre checked first (the public functions of the package)."""

    @functools.wraps(fn)
    def checked(tyre, *args, **kwargs):
        return fn(check_tyre(tyre), *args, **kwargs)

    return checked
