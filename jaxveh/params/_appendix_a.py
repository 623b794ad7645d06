"""Appendix A data set (chapter 3): the analytic vehicle, as an Equinox pytree in SI units."""

from pathlib import Path

import equinox as eqx
from jaxtyping import Array, Float

from ._fields import float_field
from ._schema import ParameterError, Quantity, check_sections, read_section, read_toml

_TA1 = "Table A.1"
_TYRE = "choice, docs/assumptions.md"
_TA1_DAMPING = "Table A.1 value, read as Nms/rad (docs/assumptions.md)"
MASS = (
    Quantity("m", "kg", "vehicle total mass", _TA1),
    Quantity("ms", "kg", "sprung mass", _TA1),
    Quantity("muF", "kg", "front unsprung mass", _TA1),
    Quantity("muR", "kg", "rear unsprung mass", _TA1),
)
GEOMETRY = (
    Quantity("a", "mm", "vehicle c.g. to front axle", _TA1),
    Quantity("b", "mm", "vehicle c.g. to rear axle", _TA1),
    Quantity("as", "mm", "sprung mass c.g. to front axle", _TA1),
    Quantity("bs", "mm", "sprung mass c.g. to rear axle", _TA1),
    Quantity("l", "mm", "wheelbase", _TA1),
    Quantity("t", "mm", "front and rear track", _TA1),
    Quantity("hG", "mm", "vehicle c.g. height", _TA1),
    Quantity("hsF", "mm", "height of front sprung mass c.g.", _TA1),
    Quantity("hsR", "mm", "height of rear sprung mass c.g.", _TA1),
    Quantity("huF", "mm", "height of front unsprung mass c.g.", _TA1),
    Quantity("huR", "mm", "height of rear unsprung mass c.g.", _TA1),
    Quantity("zF", "mm", "front roll centre height", _TA1, lower=None),
    Quantity("zR", "mm", "rear roll centre height", _TA1, lower=None),
)
SUSPENSION = (
    Quantity("kF", "Nm/deg", "front roll stiffness", _TA1),
    Quantity("kR", "Nm/deg", "rear roll stiffness", _TA1),
    Quantity("cF", "Nms/rad", "front roll damping", _TA1_DAMPING, lower_open=False),
    Quantity("cR", "Nms/rad", "rear roll damping", _TA1_DAMPING, lower_open=False),
    Quantity("epsF", "-", "front roll steer coefficient", _TA1, lower=-1.0, upper=1.0),
    Quantity("epsR", "-", "rear roll steer coefficient", _TA1, lower=-1.0, upper=1.0),
)
CHASSIS = (
    Quantity("kC", "Nm/deg", "chassis torsional stiffness", _TA1),
    Quantity("cC", "Nms/rad", "chassis torsional damping", _TA1_DAMPING, lower_open=False),
)
INERTIA = (
    Quantity("JrF", "kg m2", "front half roll inertia", _TA1),
    Quantity("JrR", "kg m2", "rear half roll inertia", _TA1),
    Quantity("Jz", "kg m2", "total yaw inertia", _TA1),
)
STEERING = (Quantity("k_stw", "-", "steering ratio", _TA1),)
TYRE = (
    Quantity("mu0", "-", "friction coefficient at nominal load", _TYRE),
    Quantity("dmu", "-", "friction load sensitivity", _TYRE, lower=-1.0, upper=1.0),
    Quantity("fz0", "N", "nominal tyre load", _TYRE),
    Quantity("shape", "-", "MF shape factor C", _TYRE, lower=1.0, upper=2.0),
    Quantity("curvature", "-", "MF curvature factor E", _TYRE, lower=None, upper=1.0, upper_open=True),
    Quantity("k_alpha", "1/rad", "peak cornering stiffness per unit nominal load", _TYRE),
    Quantity("fz_peak_ratio", "-", "load of peak cornering stiffness over fz0", _TYRE),
    Quantity("scale_front", "-", "front axle cornering stiffness scale", _TYRE),
    Quantity("scale_rear", "-", "rear axle cornering stiffness scale", _TYRE),
)
SCHEMA = {
    "mass": MASS,
    "geometry": GEOMETRY,
    "suspension": SUSPENSION,
    "chassis": CHASSIS,
    "inertia": INERTIA,
    "steering": STEERING,
    "tyre": TYRE,
}
#: Relative tolerance of the consistency checks m = ms + muF + muR, l = a + b = as + bs.
CONSISTENCY_RTOL = 1e-3


class AxleTyre(eqx.Module):
    """Simplified Magic Formula of eq. (3.27) (lateral force only, no camber, no combined slip).

    Forces in N, loads in N, slip angles in rad. See ``docs/assumptions.md``.
    """

    mu0: Float[Array, ""] = float_field()
    dmu: Float[Array, ""] = float_field()
    fz0: Float[Array, ""] = float_field()
    shape: Float[Array, ""] = float_field()
    curvature: Float[Array, ""] = float_field()
    k_alpha: Float[Array, ""] = float_field()
    fz_peak_ratio: Float[Array, ""] = float_field()
    scale_front: Float[Array, ""] = float_field()
    scale_rear: Float[Array, ""] = float_field()


class AnalyticVehicle(eqx.Module):
    """Chapter-3 vehicle (Appendix A) in SI units: kg, m, rad, Nm/rad, Nms/rad, kg m^2.

    Every field is a float64 leaf, so any subset may be differentiated or vmapped.
    """

    m: Float[Array, ""] = float_field()
    ms: Float[Array, ""] = float_field()
    muF: Float[Array, ""] = float_field()
    muR: Float[Array, ""] = float_field()
    a: Float[Array, ""] = float_field()
    b: Float[Array, ""] = float_field()
    as_: Float[Array, ""] = float_field()
    bs: Float[Array, ""] = float_field()
    t: Float[Array, ""] = float_field()
    hG: Float[Array, ""] = float_field()
    hsF: Float[Array, ""] = float_field()
    hsR: Float[Array, ""] = float_field()
    huF: Float[Array, ""] = float_field()
    huR: Float[Array, ""] = float_field()
    zF: Float[Array, ""] = float_field()
    zR: Float[Array, ""] = float_field()
    kF: Float[Array, ""] = float_field()
    kR: Float[Array, ""] = float_field()
    cF: Float[Array, ""] = float_field()
    cR: Float[Array, ""] = float_field()
    epsF: Float[Array, ""] = float_field()
    epsR: Float[Array, ""] = float_field()
    kC: Float[Array, ""] = float_field()
    cC: Float[Array, ""] = float_field()
    JrF: Float[Array, ""] = float_field()
    JrR: Float[Array, ""] = float_field()
    Jz: Float[Array, ""] = float_field()
    k_stw: Float[Array, ""] = float_field()
    tyre: AxleTyre

    @property
    def l(self) -> Float[Array, ""]:  # noqa: E743
        """Wheelbase (m)."""
        return self.a + self.b


def _check_close(where: str, name: str, value: float, expected: float, formula: str, unit: str) -> None:
    if abs(value - expected) > CONSISTENCY_RTOL * abs(expected):
        raise ParameterError(
            f"{where}: {name} = {value:g} {unit} is inconsistent with {formula} = {expected:g} {unit} "
            f"(relative tolerance {CONSISTENCY_RTOL:g})"
        )


def analytic_vehicle_from_dict(table: dict, where: str = "<dict>") -> AnalyticVehicle:
    """Build :class:`AnalyticVehicle` from a parsed TOML table, validating every field."""
    check_sections(table, tuple(SCHEMA), where)
    v = {}
    for section, quantities in SCHEMA.items():
        v[section] = read_section(table, section, quantities, where)
    ms, g = v["mass"], v["geometry"]
    _check_close(where, "[mass].m", ms["m"], ms["ms"] + ms["muF"] + ms["muR"], "ms + muF + muR", "kg")
    _check_close(where, "[geometry].l", g["l"], g["a"] + g["b"], "a + b (c.g. must lie inside the wheelbase)", "m")
    _check_close(where, "[geometry].l", g["l"], g["as"] + g["bs"], "as + bs (sprung c.g. must lie inside the wheelbase)", "m")
    for key in ("hsF", "hsR"):
        roll_centre = g["zF"] if key == "hsF" else g["zR"]
        if g[key] <= roll_centre:
            raise ParameterError(f"{where} [geometry].{key} must be above its roll centre height")
    geometry = {("as_" if k == "as" else k): val for k, val in g.items() if k != "l"}
    return AnalyticVehicle(
        **ms, **geometry, **v["suspension"], **v["chassis"], **v["inertia"], **v["steering"],
        tyre=AxleTyre(**v["tyre"]),
    )


def load_analytic_vehicle(path: str | Path | None = None) -> AnalyticVehicle:
    """Load an Appendix-A-style vehicle file (default: the shipped ``appendix_a.toml``)."""
    table, where = read_toml(path, "jaxveh.params", "data/appendix_a.toml", "vehicle")
    return analytic_vehicle_from_dict(table, where)
