"""Suspension kinematics under chassis deformation (thesis sections 7.1.1 and 7.1.3, Figs
7.1, 7.3, 7.4, Table 7.1), on the fast car.

**Wheel parameters.** Each corner's upright pose relative to the chassis frame (the fast
car's ``w``, :mod:`jaxveh.vehicle._corner_kinematics`) read as six wheel parameters, signed
so that their signs read as the thesis's Fig. 7.3b: ``wheelbase`` (the wheel centre's x
move, + forward at the front and rearward at the rear: the wheelbase grows), ``half_track``
(its lateral move outward), ``height`` (the suspension travel, the "unit" entry),
``toe`` (toe-in, rad), ``camber`` (the inclination angle γ as the tyres see it and the
manoeuvres' ``camber`` channel reports it, ISO: + with the wheel's top leaning to the right,
so inward on a left wheel; rad; the thesis's Δγ of Fig. 7.4) and ``caster`` (the upright's
rotation about its spin axis, + with its top rearward, rad); lengths in m.

**Projection matrices** (Fig. 7.3). The fast car's independent coordinates are the thesis's
set ``s = [chassis pose (6), suspension travels (4), wheel spins (4), modal coordinates
(n)]``. ``R`` is the Jacobian of the relative coordinates (chassis pose, each corner's
wheel parameters in the chassis frame, wheel spins, modal coordinates) with respect to
``s``; ``TR`` that of the absolute ones (each upright's global position and ``"zxy"``
angles); both by ``jax.jacfwd`` at a steady state, the rack held. ``R``'s modal columns at
the corners' rows are the deformation gradients: how the wheel parameters move when the
chassis deforms with the travels held.

**Kinematic gradients** (Table 7.1). On the skid-pad (radius R, turning left: the left
wheels are the inner ones) the modal coordinates grow with ay; their exact tangent
``d eta / d ay`` (implicit function theorem through the steady state) premultiplied by the
deformation gradients gives each wheel parameter's change per g due to the chassis
deformation, ``G = dp/d eta · d eta / d ay``. The full model's counterpart (Fig. 7.4) is
``p(s(ay), eta(ay)) - p(s(ay), eta_0)``: the wheel parameters at each steady state less
those with the chassis deformation of ay = 0 (``eta_0``, the first point's extrapolation
along its tangent) at the same travels and rack. At the reference ay the derivative of
``p(s(ay), eta(ay)) - p(s(ay), eta(ay_ref))`` is exactly ``G``, which the tests check by
central differences.

**Modal coordinates** (Fig. 7.1). On the same skid-pad, each mode's coordinate against ay
(linear fit over 0-1.2 g: slope, relative change over that range, coefficient of
determination) and against the sprung mass at a fixed ay; a mode "depends on ay" when its
relative change over 0-1.2 g is at least :data:`AY_DEPENDENCE` of its largest magnitude and
a straight line explains it (R^2 >= :data:`LINEARITY`).
"""

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import GRAVITY, ParameterError, run_time_checks_off
from ..manoeuvre import skid_pad, steady_state
from ..manoeuvre._reports import skid_pad_grid
from ..multibody import rotation_matrix
from ..vehicle import CORNERS, check_car, corner_poses, fast_model
from ..vehicle._fast import split

#: The six wheel parameters of each corner (module docs), in the rows' order.
WHEEL_PARAMETERS = ("wheelbase", "half_track", "height", "toe", "camber", "caster")
#: Thesis Table 7.1 (deg/g, left wheels): camber and toe-in change per g due to the chassis.
THESIS_TABLE_7_1 = {"front": {"camber_deg_per_g": -0.190, "toe_deg_per_g": -0.077},
                    "rear": {"camber_deg_per_g": 0.015, "toe_deg_per_g": 0.105}}
#: Skid-pad grid of the analyses (g): the same as :func:`jaxveh.manoeuvre.skid_pad_report`'s
#: (one compiled skid-pad program serves both).
AY_MAX_G, AY_STEP_G = 2.5, 0.05
#: Range of ay (g) of the modal coordinates' line fits and Fig. 7.4 (the thesis's 0-1.2 g).
FIT_AY_MAX_G = 1.2
#: A mode depends on ay when it changes by at least this share of its largest magnitude over
#: the fit range (module docs) ...
AY_DEPENDENCE = 0.1
#: ... and a straight line explains the change (coefficient of determination).
LINEARITY = 0.8

_SIDE = np.asarray([1.0, -1.0, 1.0, -1.0])  # left, right
_AXLE = np.asarray([1.0, 1.0, -1.0, -1.0])  # front, rear


def _spin_axis(w):
    """The uprights' spin axes (4, 3) in the chassis frame: ``A[:, 1]`` of ``"zxy"`` angles
    ``(toe, camber, spin) = w[:, 2:]``."""
    a, b = w[:, 2], w[:, 3]
    return jnp.stack([-jnp.sin(a) * jnp.cos(b), jnp.cos(a) * jnp.cos(b), jnp.sin(b)], axis=1)


def wheel_parameters(w, travel, centre) -> Float[Array, "4 6"]:
    """The corners' :data:`WHEEL_PARAMETERS` (4, 6) from their poses ``w`` (4, 5), travels
    (4,) and design wheel centres (4, 3) (m, rad; module docs for the signs)."""
    axis = _spin_axis(w)
    camber = jnp.arcsin(axis[:, 2])  # the tyres' inclination (jaxveh.vehicle._contact, flat road)
    toe = -_SIDE * jnp.arctan2(-axis[:, 0], axis[:, 1])
    return jnp.stack([_AXLE * (centre[:, 0] + w[:, 0]), _SIDE * (centre[:, 1] + w[:, 1]), centre[:, 2] + travel,
                      toe, camber, -w[:, 4]], axis=1)


def _corner_parameters(model, travel, rack, modes):
    return wheel_parameters(corner_poses(model.geometry, model.kmap, travel, rack, modes), travel,
                            model.geometry.centre)


# ---- projection matrices (Fig. 7.3) -----------------------------------------------------------


class ProjectionMatrices(eqx.Module):
    """``r`` (relative coordinates) and ``tr`` (absolute ones), each ``[rows, columns]``, by
    the names in ``rows`` and ``columns`` (module docs); ``row_groups`` and
    ``column_groups``: the index where each body's block starts (chassis, corners, wheel
    spins, modes), the thesis's partitions."""

    r: Float[Array, "nr ns"]
    tr: Float[Array, "nr ns"]
    rows: tuple = eqx.field(static=True)
    columns: tuple = eqx.field(static=True)
    row_groups: tuple = eqx.field(static=True)
    column_groups: tuple = eqx.field(static=True)


_CHASSIS = ("x", "y", "z", "yaw", "pitch", "roll")


def _zxy_angles(a):
    """``"zxy"`` angles of a rotation matrix (the uprights' library sequence)."""
    return jnp.stack([jnp.arctan2(-a[0, 1], a[1, 1]), jnp.arcsin(jnp.clip(a[2, 1], -1.0, 1.0)),
                      jnp.arctan2(-a[2, 0], a[2, 2])])


def _from_thesis_order(car, s):
    """The fast car's ``q`` from ``s = [chassis pose, travels, spins, modes]``."""
    n = car.n_modes
    return jnp.concatenate([s[:6], s[14:14 + n], s[6:14]])


def _coordinates(car, model, s, rack, absolute: bool):
    n = car.n_modes
    qc, travel, spin = split(car, _from_thesis_order(car, s))
    w = corner_poses(model.geometry, model.kmap, travel, rack, qc[6:])
    if absolute:
        a_c = rotation_matrix("zyx", qc[3:6])
        centres = model.geometry.centre + jnp.concatenate([w[:, :2], travel[:, None]], axis=1)
        positions = qc[None, :3] + centres @ a_c.T
        rel = jax.vmap(lambda ang: rotation_matrix("zxy", ang))(w[:, 2:])
        angles = jax.vmap(lambda a: _zxy_angles(a_c @ a))(rel)
        corners = jnp.concatenate([positions, angles], axis=1)
    else:
        corners = wheel_parameters(w, travel, model.geometry.centre)
    return jnp.concatenate([qc[:6], corners.reshape(-1), spin, qc[6:6 + n]])


@eqx.filter_jit
def _projection(car, q, rack):
    model = fast_model(car)
    qc, travel, spin = split(car, q)
    s = jnp.concatenate([qc[:6], travel, spin, qc[6:]])
    return (jax.jacfwd(lambda x: _coordinates(car, model, x, rack, absolute=False))(s),
            jax.jacfwd(lambda x: _coordinates(car, model, x, rack, absolute=True))(s))


def projection_matrices(car, state=None, design: bool = False) -> ProjectionMatrices:
    """``R`` and ``TR`` (module docs) at the steady state ``state`` (a
    :class:`jaxveh.manoeuvre.SteadyCornering`; default straight running at 50 km/h, the
    thesis's "constant longitudinal speed and zero lateral acceleration"), or with
    ``design`` at the design pose (every coordinate zero, the rack centred: the left and
    right corners mirror each other exactly)."""
    car = check_car(car)
    if design:
        q, rack = jnp.zeros(14 + car.n_modes), jnp.zeros(())
    else:
        state = steady_state(car, speed=50.0 / 3.6, yaw_rate=0.0) if state is None else state
        q, rack = state.state.q, state.rack
    with run_time_checks_off():
        r, tr = _projection(car, q, rack)
    n = car.n_modes
    modes = tuple(f"mode {k + 1}" for k in range(n))
    rows = (tuple(f"chassis.{c}" for c in _CHASSIS) + tuple(f"{c}.{p}" for c in CORNERS for p in WHEEL_PARAMETERS)
            + tuple(f"{c}.spin" for c in CORNERS) + modes)
    columns = (tuple(f"chassis.{c}" for c in _CHASSIS) + tuple(f"{c}.travel" for c in CORNERS)
               + tuple(f"{c}.spin" for c in CORNERS) + modes)
    return ProjectionMatrices(r=r, tr=tr, rows=rows, columns=columns, row_groups=(0, 6, 12, 18, 24, 30, 34),
                              column_groups=(0, 6, 10, 14))


# ---- kinematic gradients on the skid-pad (Table 7.1, Figs 7.1a, 7.4) ----------------------------


class KinematicGradients(eqx.Module):
    """The skid-pad analysis of :func:`kinematic_gradients` at the lateral accelerations
    ``ay`` (m/s^2; ``ok`` where a steady state exists): ``modes`` (n, nm) the modal
    coordinates and ``modal_gradients`` their exact ``d/d ay`` (per m/s^2);
    ``deformation_gradients`` (n, 4, 6, nm) ``dp / d eta`` at fixed travels and rack (R's
    modal columns); ``gradients`` (n, 4, 6) their product, each wheel parameter's change per
    m/s^2 due to the chassis; ``flexible_part`` (n, 4, 6) the full model's change from
    ay = 0 due to the chassis; ``parameters`` (n, 4, 6) the wheel parameters themselves
    (m, rad)."""

    radius: Float[Array, ""]
    ay: Float[Array, " n"]
    ok: Array
    modes: Float[Array, "n nm"]
    modal_gradients: Float[Array, "n nm"]
    deformation_gradients: Float[Array, "n 4 6 nm"]
    gradients: Float[Array, "n 4 6"]
    flexible_part: Float[Array, "n 4 6"]
    parameters: Float[Array, "n 4 6"]


@eqx.filter_jit
def _along_pad(car, q, rack, modal_gradients, ay):
    model = fast_model(car)

    def point(q, rack):
        qc, travel, _ = split(car, q)
        return qc[6:], travel

    modes, travel = jax.vmap(point)(q, rack)
    eta_0 = modes[0] - ay[0] * modal_gradients[0]  # ay = 0 along the first point's tangent

    def at(travel, rack, eta, eta_dot):
        p, jac = _corner_parameters(model, travel, rack, eta), jax.jacfwd(
            lambda e: _corner_parameters(model, travel, rack, e))(eta)
        return p, jac, jac @ eta_dot, p - _corner_parameters(model, travel, rack, eta_0)

    return jax.vmap(at)(travel, rack, modes, modal_gradients)


def kinematic_gradients(car, radius: float = 50.0) -> KinematicGradients:
    """The skid-pad kinematic analysis (module docs) on a circle of ``radius`` m turning
    left, at the grid of :func:`jaxveh.manoeuvre.skid_pad_report` (0.05 g to the limit in
    steps of 0.05 g): two compiled programs, the skid-pad's (shared) and this one's."""
    car = check_car(car)
    pad = skid_pad(car, radius, skid_pad_grid(AY_MAX_G, AY_STEP_G))
    dmodes = pad.gradients["modes"]
    with run_time_checks_off():
        params, jac, grads, flex = _along_pad(car, pad.states.state.q, pad.states.rack, dmodes, pad.ay)
    return KinematicGradients(radius=pad.radius, ay=pad.ay, ok=pad.ok, modes=pad.states.channels["modes"],
                              modal_gradients=dmodes, deformation_gradients=jac, gradients=grads, flexible_part=flex,
                              parameters=params)


def _reference_index(kg: KinematicGradients, ay_ref_g: float) -> int:
    ay_g = np.asarray(kg.ay) / GRAVITY
    i = int(np.argmin(np.abs(ay_g - ay_ref_g)))
    if abs(ay_g[i] - ay_ref_g) > 1e-9 or not bool(kg.ok[i]):
        raise ParameterError(f"reference ay = {ay_ref_g!r} g is not allowed: a multiple of {AY_STEP_G} g from "
                             f"{AY_STEP_G} g up to the car's limit on the skid-pad "
                             f"({ay_g[np.asarray(kg.ok)][-1]:.2f} g)")
    return i


def gradient_table(kg: KinematicGradients, ay_ref_g: float = 0.3) -> dict:
    """Table 7.1 at ``ay_ref_g``: per corner (``front``/``rear`` the left wheels as the
    thesis, ``front_right``/``rear_right``) the change per g due to the chassis of camber
    and toe-in (deg/g), caster (deg/g), wheelbase and half track (mm/g)."""
    i = _reference_index(kg, ay_ref_g)
    g = np.asarray(kg.gradients[i]) * GRAVITY
    out = {}
    for key, k in (("front", 0), ("rear", 2), ("front_right", 1), ("rear_right", 3)):
        row = dict(zip(WHEEL_PARAMETERS, g[k], strict=True))
        out[key] = {"camber_deg_per_g": float(np.degrees(row["camber"])),
                    "toe_deg_per_g": float(np.degrees(row["toe"])),
                    "caster_deg_per_g": float(np.degrees(row["caster"])),
                    "wheelbase_mm_per_g": float(1e3 * row["wheelbase"]),
                    "half_track_mm_per_g": float(1e3 * row["half_track"])}
    return out


def modal_ay_dependence(kg: KinematicGradients, ay_max_g: float = FIT_AY_MAX_G) -> list[dict]:
    """Per mode (Fig. 7.1a): the line fit of its coordinate against ay over the converged
    points up to ``ay_max_g`` (slope per g, relative change over that range, R^2) and whether
    it depends on ay (module docs)."""
    ay_g = np.asarray(kg.ay) / GRAVITY
    keep = np.asarray(kg.ok) & (ay_g <= ay_max_g + 1e-9)
    x, out = ay_g[keep], []
    for k, p in enumerate(np.asarray(kg.modes)[keep].T):
        slope, intercept = np.polyfit(x, p, 1)
        residual = p - (slope * x + intercept)
        spread = np.sum((p - p.mean()) ** 2)
        r2 = float(1.0 - np.sum(residual**2) / spread) if spread > 0 else 1.0
        change = float(abs(slope) * (x[-1] - x[0]) / np.max(np.abs(p)))
        out.append({"mode": k + 1, "slope_per_g": float(slope), "relative_change": change, "r_squared": r2,
                    "depends_on_ay": bool(change >= AY_DEPENDENCE and r2 >= LINEARITY)})
    return out


def modes_vs_sprung_mass(car, masses, ay_g: float = 0.3, radius: float = 50.0) -> Float[Array, "n nm"]:
    """Modal coordinates at ``ay_g`` on the skid-pad of ``radius`` m against the sprung mass
    (kg, Fig. 7.1b): one steady state per mass (the compiled steady-state program serves
    every mass)."""
    masses = np.asarray(masses, float)
    if masses.ndim != 1 or not np.all(masses > 0.0):
        raise ParameterError("masses must be a 1-D sequence of positive sprung masses (kg)")
    if not ay_g > 0.0:
        raise ParameterError(f"ay_g = {ay_g!r} is out of range: allowed > 0 (g, turning left on the skid-pad)")
    rows = []
    for m in masses:
        c = eqx.tree_at(lambda c: c.params.vehicle.sprung.mass, car, jnp.asarray(m))
        rows.append(steady_state(c, radius=radius, ay=ay_g * GRAVITY).channels["modes"])
    return jnp.stack(rows)


def kinematic_gradients_report(car, radius: float = 50.0, ay_ref_g: float = 0.3) -> dict:
    """JSON-ready Table 7.1 (:func:`gradient_table` at ``ay_ref_g``) with the thesis's values,
    the modal coordinates' ay dependence (Fig. 7.1a, :func:`modal_ay_dependence`) and the
    curves of Fig. 7.4 up to 1.2 g: per corner the camber and toe-in change due to the chassis
    by the full model and by the linear approximation (gradient times ay), deg."""
    if not radius > 0.0:
        raise ParameterError(f"radius = {radius!r} is out of range: allowed > 0 (m)")
    start = time.perf_counter()
    kg = kinematic_gradients(car, radius)
    table = gradient_table(kg, ay_ref_g)
    wall = time.perf_counter() - start
    i = _reference_index(kg, ay_ref_g)
    ay_g = np.asarray(kg.ay) / GRAVITY
    keep = np.asarray(kg.ok) & (ay_g <= FIT_AY_MAX_G + 1e-9)
    # the curves start at ay = 0, where the chassis's part is zero by definition
    ay_curve = np.concatenate([[0.0], ay_g[keep]])
    full = np.degrees(np.concatenate([np.zeros((1, 4, 6)), np.asarray(kg.flexible_part)[keep]]))
    linear = ay_curve[:, None, None] * np.degrees(np.asarray(kg.gradients[i]))[None] * GRAVITY
    cam, toe = WHEEL_PARAMETERS.index("camber"), WHEEL_PARAMETERS.index("toe")
    return {
        "radius_m": float(radius),
        "reference_ay_g": float(ay_g[i]),
        "turn": "left (positive ay): front and rear are the left (inner) wheels, as Table 7.1",
        "camber_convention": "inclination angle gamma, ISO: + with the wheel's top leaning right (the tyres' and the "
                             "camber channel's; the thesis's delta gamma)",
        "modes": car.n_modes,
        **table,
        "thesis_table_7_1": THESIS_TABLE_7_1,
        "modal_gradients_per_g": (np.asarray(kg.modal_gradients[i]) * GRAVITY).tolist(),
        "modal_ay_dependence": modal_ay_dependence(kg),
        "modal_coordinates": {"ay_g": ay_g[keep].tolist(), "modes": np.asarray(kg.modes)[keep].tolist()},
        "ay_limit_g": float(ay_g[np.asarray(kg.ok)][-1]),
        "wall_time_s": wall,
        "curve": {
            "ay_g": ay_curve.tolist(),
            "corners": list(CORNERS),
            "camber_full_deg": full[:, :, cam].tolist(),
            "camber_linear_deg": linear[:, :, cam].tolist(),
            "toe_full_deg": full[:, :, toe].tolist(),
            "toe_linear_deg": linear[:, :, toe].tolist(),
        },
    }
