"""Appendix B data set (chapters 6-7): the 14-DOF vehicle's general, mass and hard-point data."""

from pathlib import Path

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import is_concrete
from ._checks import Range, check, checked_field, quantity_range
from ._schema import ParameterError, Quantity, check_sections, read_section, read_toml

HARD_POINT_NAMES = ("A", "B", "C", "D", "E", "F", "H", "L", "M", "P", "Q", "R", "S", "T")
#: Hard points on the sprung mass (chassis side) of each corner (section 6.2.2).
SPRUNG_HARD_POINTS = ("A", "B", "E", "F", "L", "P", "Q", "T")
CORNERS = ("front_left", "front_right", "rear_left", "rear_right")

_TB1 = "Table B.1"
GENERAL = (
    Quantity("a", "mm", "distance of vehicle c.g. from front axle", _TB1),
    Quantity("b", "mm", "distance of vehicle c.g. from rear axle", _TB1),
    Quantity("h_cg", "mm", "vehicle c.g. height", _TB1),
    Quantity("track_front", "mm", "front track width", _TB1),
    Quantity("track_rear", "mm", "rear track width", _TB1),
    Quantity("toe_front", "deg", "static front toe angle", _TB1, lower=-10.0, upper=10.0, lower_open=False),
    Quantity("toe_rear", "deg", "static rear toe angle", _TB1, lower=-10.0, upper=10.0, lower_open=False),
    Quantity("camber_front", "deg", "static front camber angle", _TB1, lower=-10.0, upper=10.0, lower_open=False),
    Quantity("camber_rear", "deg", "static rear camber angle", _TB1, lower=-10.0, upper=10.0, lower_open=False),
)
SPRUNG = (
    Quantity("m", "kg", "sprung mass", _TB1),
    Quantity("Jxx", "kg m2", "sprung mass roll inertia", _TB1),
    Quantity("Jyy", "kg m2", "sprung mass pitch inertia", _TB1),
    Quantity("Jzz", "kg m2", "sprung mass yaw inertia", _TB1),
    Quantity("Jxz", "kg m2", "sprung mass x-z product of inertia", _TB1, lower=None),
)
UNSPRUNG = (
    Quantity("m", "kg", "unsprung mass of one corner", _TB1),
    Quantity("Jxx", "kg m2", "unsprung cambering inertia", _TB1),
    Quantity("Jyy", "kg m2", "unsprung pitching inertia (rotating parts removed)", _TB1),
    Quantity("Jzz", "kg m2", "unsprung yawing inertia", _TB1),
    Quantity("J_wheel", "kg m2", "wheel spin inertia", _TB1),
)
TYRE = (
    Quantity("kz", "N/m", "tyre vertical stiffness", "Table B.4"),
    Quantity("cz", "Ns/m", "tyre vertical damping", "Table B.4", lower_open=False),
    Quantity("sigma_kappa", "m", "longitudinal slip relaxation length", "Table B.4"),
    Quantity("sigma_alpha", "m", "side slip relaxation length", "Table B.4"),
)
SECTIONS = ("general", "sprung", "unsprung_front", "unsprung_rear", "tyre", "hard_points_front", "hard_points_rear")


_GENERAL_RANGES = {q.key: quantity_range(q) for q in GENERAL}
_TYRE_RANGES = {q.key: quantity_range(q) for q in TYRE}


def _general(name: str):
    return checked_field(f"VehicleData.{name}", _GENERAL_RANGES[name])


class RigidBodyData(eqx.Module):
    """Mass (kg) and inertia tensor (kg m^2, body axes x forward, y left, z up) of a body.

    Checked on construction: mass > 0; inertia 3 x 3, symmetric and positive definite.
    """

    mass: Float[Array, ""] = checked_field("RigidBodyData.mass", Range(0.0, low_open=True, what="mass, kg"))
    inertia: Float[Array, "3 3"] = checked_field("RigidBodyData.inertia", Range(what="inertia tensor, kg m2"))

    def __check_init__(self):
        if self.inertia.shape[-2:] != (3, 3):
            raise ParameterError(f"RigidBodyData.inertia must have shape (3, 3); got {self.inertia.shape}")
        if is_concrete(self.inertia):
            j = np.asarray(self.inertia)
            if not np.allclose(j, np.swapaxes(j, -1, -2)):
                raise ParameterError("RigidBodyData.inertia must be symmetric")
            check("RigidBodyData.inertia eigenvalues", np.linalg.eigvalsh(j), Range(0.0, low_open=True,
                  what="the inertia tensor must be positive definite, kg m2"))


class UnsprungData(eqx.Module):
    """One corner's unsprung mass (upright + wheel) and the wheel's spin inertia (kg m^2)."""

    body: RigidBodyData
    wheel_spin_inertia: Float[Array, ""] = checked_field(
        "UnsprungData.wheel_spin_inertia", Range(0.0, low_open=True, what="wheel spin inertia, kg m2")
    )


class CornerHardPoints(eqx.Module):
    """The 14 hard points of a left corner (m), in the corner's local frame.

    Local frame: origin on the ground, in the vehicle centre plane, below the axle centre;
    x forward, y left, z up (Tables B.2, B.3; see docs/assumptions.md). Checked on
    construction: shape (14, 3), finite, every y > 0 (left corner).
    """

    points: Float[Array, "14 3"] = checked_field("CornerHardPoints.points", Range(what="hard points, m"))

    def __check_init__(self):
        if self.points.shape[-2:] != (len(HARD_POINT_NAMES), 3):
            raise ParameterError(f"CornerHardPoints.points must have shape (14, 3); got {self.points.shape}")
        if is_concrete(self.points):
            check("CornerHardPoints.points y", self.points[..., 1], Range(0.0, low_open=True, what="left corner, m"))

    def __getitem__(self, name: str) -> Float[Array, "3"]:
        return self.points[HARD_POINT_NAMES.index(name)]


class TyreData(eqx.Module):
    """Table B.4: vertical stiffness (N/m), damping (Ns/m), relaxation lengths (m)."""

    kz: Float[Array, ""] = checked_field("TyreData.kz", _TYRE_RANGES["kz"])
    cz: Float[Array, ""] = checked_field("TyreData.cz", _TYRE_RANGES["cz"])
    sigma_kappa: Float[Array, ""] = checked_field("TyreData.sigma_kappa", _TYRE_RANGES["sigma_kappa"])
    sigma_alpha: Float[Array, ""] = checked_field("TyreData.sigma_alpha", _TYRE_RANGES["sigma_alpha"])


class VehicleData(eqx.Module):
    """Appendix B data set in SI units (m, kg, rad); every number range-checked on construction."""

    a: Float[Array, ""] = _general("a")
    b: Float[Array, ""] = _general("b")
    h_cg: Float[Array, ""] = _general("h_cg")
    track_front: Float[Array, ""] = _general("track_front")
    track_rear: Float[Array, ""] = _general("track_rear")
    toe_front: Float[Array, ""] = _general("toe_front")
    toe_rear: Float[Array, ""] = _general("toe_rear")
    camber_front: Float[Array, ""] = _general("camber_front")
    camber_rear: Float[Array, ""] = _general("camber_rear")
    sprung: RigidBodyData
    unsprung_front: UnsprungData
    unsprung_rear: UnsprungData
    tyre: TyreData
    hard_points_front: CornerHardPoints
    hard_points_rear: CornerHardPoints

    @property
    def wheelbase(self) -> Float[Array, ""]:
        return self.a + self.b


def _read_points(table, section: str, where: str) -> jnp.ndarray:
    if section not in table:
        raise ParameterError(f"{where}: missing section [{section}]")
    data = table[section]
    unknown = sorted(set(data) - set(HARD_POINT_NAMES))
    if unknown:
        raise ParameterError(f"{where} [{section}]: unknown hard point(s) {unknown}; allowed {list(HARD_POINT_NAMES)}")
    rows = []
    for name in HARD_POINT_NAMES:
        if name not in data:
            raise ParameterError(f"{where} [{section}]: missing hard point {name}")
        xyz = data[name]
        ok = isinstance(xyz, list) and len(xyz) == 3 and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in xyz
        )
        if not ok:
            raise ParameterError(f"{where} [{section}].{name} must be a list of 3 numbers [x, y, z] in mm, got {xyz!r}")
        if xyz[1] <= 0.0:
            raise ParameterError(
                f"{where} [{section}].{name}: y = {xyz[1]:g} mm must be > 0 (left corner, y points left)"
            )
        rows.append([float(v) * 1e-3 for v in xyz])
    return jnp.asarray(rows)


def _inertia(d) -> jnp.ndarray:
    jxz = d.get("Jxz", 0.0)
    return jnp.asarray([[d["Jxx"], 0.0, -jxz], [0.0, d["Jyy"], 0.0], [-jxz, 0.0, d["Jzz"]]])


def vehicle_data_from_dict(table: dict, where: str = "<dict>") -> VehicleData:
    """Build :class:`VehicleData` from a parsed TOML table, validating every field."""
    check_sections(table, SECTIONS, where)
    g = read_section(table, "general", GENERAL, where)
    s = read_section(table, "sprung", SPRUNG, where)
    uf = read_section(table, "unsprung_front", UNSPRUNG, where)
    ur = read_section(table, "unsprung_rear", UNSPRUNG, where)
    t = read_section(table, "tyre", TYRE, where)
    # Product of inertia: J = [[Jxx, 0, -Jxz], ...] must stay positive definite.
    if s["Jxz"] ** 2 >= s["Jxx"] * s["Jzz"]:
        raise ParameterError(f"{where} [sprung].Jxz: |Jxz| must be < sqrt(Jxx*Jzz) for a positive-definite inertia")
    return VehicleData(
        **{k: v for k, v in g.items()},
        sprung=RigidBodyData(s["m"], _inertia(s)),
        unsprung_front=UnsprungData(RigidBodyData(uf["m"], _inertia(uf)), uf["J_wheel"]),
        unsprung_rear=UnsprungData(RigidBodyData(ur["m"], _inertia(ur)), ur["J_wheel"]),
        tyre=TyreData(**t),
        hard_points_front=CornerHardPoints(_read_points(table, "hard_points_front", where)),
        hard_points_rear=CornerHardPoints(_read_points(table, "hard_points_rear", where)),
    )


def load_vehicle_data(path: str | Path | None = None) -> VehicleData:
    """Load an Appendix-B-style vehicle file (default: the shipped ``appendix_b.toml``)."""
    table, where = read_toml(path, "jaxveh.params", "data/appendix_b.toml", "vehicle")
    return vehicle_data_from_dict(table, where)


def hard_points_vehicle_frame(data: VehicleData) -> dict[str, Float[Array, "14 3"]]:
    """Hard points of all four corners in the vehicle frame (m).

    Vehicle frame: origin on the ground below the vehicle c.g., x forward, y left, z up.
    Front corners sit at x = +a, rear at x = -b; right corners mirror y.
    """
    mirror = jnp.asarray([[1.0, -1.0, 1.0]])
    x_axis = jnp.asarray([[1.0, 0.0, 0.0]])
    front = data.hard_points_front.points + data.a * x_axis
    rear = data.hard_points_rear.points - data.b * x_axis
    return {
        "front_left": front,
        "front_right": front * mirror,
        "rear_left": rear,
        "rear_right": rear * mirror,
    }
