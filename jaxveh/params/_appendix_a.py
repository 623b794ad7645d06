"""Appendix A data set (chapter 3): the analytic vehicle, as an Equinox pytree in SI units."""

from pathlib import Path

import equinox as eqx
import jax
from jaxtyping import Array, Float

from .._core import is_concrete
from ._checks import Range, array_module, check_module, checked_field, quantity_range
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
#: Relative tolerance of the consistency checks of the file's total mass, wheelbase and
#: c.g. position against the values derived from the masses and sprung c.g. position.
CONSISTENCY_RTOL = 1e-3
#: Tolerance (m) of the file's vehicle c.g. height hG against the mass-weighted height:
#: Table A.1 rounds heights to 5 mm (its hG = 295 mm; the masses give 294.3 mm).
CG_HEIGHT_ATOL = 2.5e-3
#: Keys of the file that are checked against derived values, not stored.
DERIVED_KEYS = ("m", "a", "b", "l", "hG")

_VEHICLE_SECTIONS = ("mass", "geometry", "suspension", "chassis", "inertia", "steering")
#: Allowed values of every stored :class:`AnalyticVehicle` field (SI), as in the data file,
#: except that kF and kR may be 0 (λ = 0 and 1 are the edges of the design maps); their sum
#: must be positive.
VEHICLE_RANGES: dict[str, Range] = {
    **{
        ("as_" if q.key == "as" else q.key): quantity_range(q)
        for section in _VEHICLE_SECTIONS
        for q in SCHEMA[section]
        if q.key not in DERIVED_KEYS
    },
    "kF": Range(0.0, what="front roll stiffness, Nm/rad"),
    "kR": Range(0.0, what="rear roll stiffness, Nm/rad"),
}
#: Allowed values of every :class:`AxleTyre` field.
TYRE_RANGES: dict[str, Range] = {q.key: quantity_range(q) for q in TYRE}


def _field(name: str):
    return checked_field(f"AnalyticVehicle.{name}", VEHICLE_RANGES[name])


def _tyre_field(name: str):
    return checked_field(f"AxleTyre.{name}", TYRE_RANGES[name])


class AxleTyre(eqx.Module):
    """Simplified Magic Formula of eq. (3.27) (lateral force only, no camber, no combined slip).

    Forces in N, loads in N, slip angles in rad. See ``docs/assumptions.md``. Every field is
    range-checked on construction (:data:`TYRE_RANGES`); :func:`check_axle_tyre` checks an
    existing one (after ``eqx.tree_at``, or with traced values).
    """

    mu0: Float[Array, ""] = _tyre_field("mu0")
    dmu: Float[Array, ""] = _tyre_field("dmu")
    fz0: Float[Array, ""] = _tyre_field("fz0")
    shape: Float[Array, ""] = _tyre_field("shape")
    curvature: Float[Array, ""] = _tyre_field("curvature")
    k_alpha: Float[Array, ""] = _tyre_field("k_alpha")
    fz_peak_ratio: Float[Array, ""] = _tyre_field("fz_peak_ratio")
    scale_front: Float[Array, ""] = _tyre_field("scale_front")
    scale_rear: Float[Array, ""] = _tyre_field("scale_rear")


def _mass_matrix_min_eig(v: "AnalyticVehicle"):
    """Smallest eigenvalue of the mass matrix (3.31), scaled to be dimensionless."""
    xp = array_module(v.ms)
    ms_f = v.ms * v.bs / v.l
    m_f, m_r = ms_f * (v.hsF - v.zF), (v.ms - ms_f) * (v.hsR - v.zR)
    z = xp.zeros_like(v.ms)
    mat = xp.stack(
        [
            xp.stack([v.m, z, -m_f, -m_r], axis=-1),
            xp.stack([z, v.Jz, -v.a * m_f, v.b * m_r], axis=-1),
            xp.stack([-m_f, -v.a * m_f, v.JrF, z], axis=-1),
            xp.stack([-m_r, v.b * m_r, z, v.JrR], axis=-1),
        ],
        axis=-2,
    )
    d = 1.0 / xp.sqrt(xp.diagonal(mat, axis1=-2, axis2=-1))
    return xp.linalg.eigvalsh(mat * d[..., :, None] * d[..., None, :])[..., 0]


#: Relations between fields that every vehicle must satisfy.
VEHICLE_RELATIONS = (
    ("hsF - zF", lambda v: v.hsF - v.zF, Range(0.0, low_open=True, what="front sprung c.g. above its roll centre, m")),
    ("hsR - zR", lambda v: v.hsR - v.zR, Range(0.0, low_open=True, what="rear sprung c.g. above its roll centre, m")),
    ("kF + kR", lambda v: v.kF + v.kR, Range(0.0, low_open=True, what="total roll stiffness, Nm/rad")),
    (
        "mass matrix (3.31)",
        _mass_matrix_min_eig,
        Range(0.0, low_open=True, what="smallest eigenvalue of the normalised mass matrix: JrF, JrR, Jz too small "
              "for the sprung mass and roll arms give negative kinetic energy"),
    ),
)


class AnalyticVehicle(eqx.Module):
    """Chapter-3 vehicle (Appendix A) in SI units: kg, m, rad, Nm/rad, Nms/rad, kg m^2.

    Every field is a float64 leaf, so any subset may be differentiated or vmapped. Fields
    are range-checked on construction (:data:`VEHICLE_RANGES`, :data:`VEHICLE_RELATIONS`);
    the analytic functions check their vehicle again with :func:`check_analytic_vehicle`,
    so values changed with ``eqx.tree_at`` or traced by an optimiser are checked too.

    Quantities that follow from others are properties, never stored, so they cannot go
    stale when a base field changes (e.g. with ``eqx.tree_at``): the total mass ``m``, the
    wheelbase ``l = as + bs``, the vehicle c.g. position ``a``, ``b`` and height ``hG``
    (sprung mass at its c.g., unsprung masses at the axles and their own heights).
    """

    ms: Float[Array, ""] = _field("ms")
    muF: Float[Array, ""] = _field("muF")
    muR: Float[Array, ""] = _field("muR")
    as_: Float[Array, ""] = _field("as_")
    bs: Float[Array, ""] = _field("bs")
    t: Float[Array, ""] = _field("t")
    hsF: Float[Array, ""] = _field("hsF")
    hsR: Float[Array, ""] = _field("hsR")
    huF: Float[Array, ""] = _field("huF")
    huR: Float[Array, ""] = _field("huR")
    zF: Float[Array, ""] = _field("zF")
    zR: Float[Array, ""] = _field("zR")
    kF: Float[Array, ""] = _field("kF")
    kR: Float[Array, ""] = _field("kR")
    cF: Float[Array, ""] = _field("cF")
    cR: Float[Array, ""] = _field("cR")
    epsF: Float[Array, ""] = _field("epsF")
    epsR: Float[Array, ""] = _field("epsR")
    kC: Float[Array, ""] = _field("kC")
    cC: Float[Array, ""] = _field("cC")
    JrF: Float[Array, ""] = _field("JrF")
    JrR: Float[Array, ""] = _field("JrR")
    Jz: Float[Array, ""] = _field("Jz")
    k_stw: Float[Array, ""] = _field("k_stw")
    tyre: AxleTyre

    def __check_init__(self):
        # Field ranges were checked by the converters; relations need all fields.
        if all(is_concrete(x) for x in jax.tree.leaves(self)):
            check_module(self, "AnalyticVehicle", {}, VEHICLE_RELATIONS)

    @property
    def m(self) -> Float[Array, ""]:
        """Total mass ms + muF + muR (kg)."""
        return self.ms + self.muF + self.muR

    @property
    def l(self) -> Float[Array, ""]:  # noqa: E743
        """Wheelbase as + bs (m)."""
        return self.as_ + self.bs

    @property
    def a(self) -> Float[Array, ""]:
        """Vehicle c.g. to front axle, (ms as + muR l)/m (m): unsprung masses at the axles."""
        return (self.ms * self.as_ + self.muR * self.l) / self.m

    @property
    def b(self) -> Float[Array, ""]:
        """Vehicle c.g. to rear axle, l - a (m)."""
        return self.l - self.a

    @property
    def hG(self) -> Float[Array, ""]:
        """Vehicle c.g. height (msF hsF + msR hsR + muF huF + muR huR)/m (m).

        msF = ms bs/l and msR = ms as/l are the front and rear parts of the sprung mass
        (section 3.1), so the per-axle load transfers of (3.4) add up to m hG ay / t.
        """
        ms_f = self.ms * self.bs / self.l
        ms_r = self.ms - ms_f
        return (ms_f * self.hsF + ms_r * self.hsR + self.muF * self.huF + self.muR * self.huR) / self.m


def check_axle_tyre(tyre: AxleTyre) -> AxleTyre:
    """Check every field of ``tyre`` (:data:`TYRE_RANGES`); return it (use the result).

    Concrete values raise :class:`ParameterError`; traced values raise at run time.
    """
    return check_module(tyre, "AxleTyre", TYRE_RANGES)


def check_analytic_vehicle(vehicle: AnalyticVehicle) -> AnalyticVehicle:
    """Check every field and relation of ``vehicle`` and its tyre; return it (use the result).

    Concrete values raise :class:`ParameterError` naming the field and its allowed range;
    traced values (an optimiser's) raise at run time via ``eqx.error_if``.
    """
    vehicle = check_module(vehicle, "AnalyticVehicle", VEHICLE_RANGES, VEHICLE_RELATIONS)
    tyre = check_axle_tyre(vehicle.tyre)
    return vehicle if tyre is vehicle.tyre else eqx.tree_at(lambda v: v.tyre, vehicle, tyre)


def _check_close(
    where: str, name: str, value: float, expected: float, formula: str, unit: str, atol: float = 0.0
) -> None:
    if abs(value - expected) > max(CONSISTENCY_RTOL * abs(expected), atol):
        tol = f"tolerance {atol:g} {unit}" if atol else f"relative tolerance {CONSISTENCY_RTOL:g}"
        raise ParameterError(
            f"{where}: {name} = {value:g} {unit} is inconsistent with {formula} = {expected:g} {unit} ({tol})"
        )


def analytic_vehicle_from_dict(table: dict, where: str = "<dict>") -> AnalyticVehicle:
    """Build :class:`AnalyticVehicle` from a parsed TOML table, validating every field.

    The file's ``m``, ``l``, ``a``, ``b`` and ``hG`` are checked against the values derived
    from the masses, the sprung c.g. position and the heights (they are not stored).
    """
    check_sections(table, tuple(SCHEMA), where)
    v = {}
    for section, quantities in SCHEMA.items():
        v[section] = read_section(table, section, quantities, where)
    ms, g = v["mass"], v["geometry"]
    _check_close(where, "[mass].m", ms["m"], ms["ms"] + ms["muF"] + ms["muR"], "ms + muF + muR", "kg")
    _check_close(where, "[geometry].l", g["l"], g["a"] + g["b"], "a + b (c.g. must lie inside the wheelbase)", "m")
    inside = "as + bs (sprung c.g. must lie inside the wheelbase)"
    _check_close(where, "[geometry].l", g["l"], g["as"] + g["bs"], inside, "m")
    for key in ("hsF", "hsR"):
        roll_centre = g["zF"] if key == "hsF" else g["zR"]
        if g[key] <= roll_centre:
            raise ParameterError(f"{where} [geometry].{key} must be above its roll centre height")
    stored = {("as_" if k == "as" else k): val for k, val in g.items() if k not in DERIVED_KEYS}
    masses = {k: val for k, val in ms.items() if k not in DERIVED_KEYS}
    try:
        vehicle = AnalyticVehicle(
            **masses, **stored, **v["suspension"], **v["chassis"], **v["inertia"], **v["steering"],
            tyre=AxleTyre(**v["tyre"]),
        )
    except ParameterError as e:
        raise ParameterError(f"{where}: {e}") from None
    at_axles = "(ms as + muR l)/m (unsprung masses at the axles)"
    _check_close(where, "[geometry].a", g["a"], float(vehicle.a), at_axles, "m")
    _check_close(
        where, "[geometry].hG", g["hG"], float(vehicle.hG), "(msF hsF + msR hsR + muF huF + muR huR)/m", "m",
        atol=CG_HEIGHT_ATOL,
    )
    return vehicle


def load_analytic_vehicle(path: str | Path | None = None) -> AnalyticVehicle:
    """Load an Appendix-A-style vehicle file (default: the shipped ``appendix_a.toml``)."""
    table, where = read_toml(path, "jaxveh.params", "data/appendix_a.toml", "vehicle")
    return analytic_vehicle_from_dict(table, where)
