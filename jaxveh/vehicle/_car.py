"""The assembled chapter-6 car (section 6.1, Table 6.1) built with :mod:`jaxveh.multibody`.

Bodies: the sprung mass as a free flexible body (yaw-pitch-roll sequence ``"zyx"``; the FE
chassis's modes, its rigid part replaced by the Table B.1 sprung mass; 0 modes = rigid
body), four uprights (toe-camber-spin sequence ``"zxy"``, Table B.1 masses and inertias,
reference point and c.g. at the wheel centre) each held by the five links of Table 6.3
between the Appendix B hard points, four wheels spinning on their uprights, and the steering
rack as a rheonomic input moving both front inner track-rod points L along the chassis y
axis. Independent velocities (Table 6.1): per corner the upright's vertical velocity and the
wheel spin, then the chassis's six velocities and its modal velocities.

Force elements: push-rod springs, dampers and anti-roll bars per axle
(:mod:`._suspension`), MF 5.2 tyres at the contact patches (:mod:`._contact`), aerodynamic
loads (:mod:`._aero`) and the rear-wheel powertrain (:mod:`._powertrain`).

Frames: the vehicle frame has its origin on the ground below the design c.g., x forward,
y left, z up; the chassis frame coincides with it at the design position (the FE frame is
written in it). The whole car's c.g. sits at ``(0, 0, h_cg)`` (Table B.1's a, b and h_cg
are the whole car's): the sprung c.g. is placed so that with the unsprung masses at the
wheel centres the total lands there.

Every number is a leaf of :class:`CarParams`; :func:`system_params` and :func:`car_elements`
turn it into the library's parameters and force elements with JAX operations, so gradients
reach hard points, rates, masses, modal data and tyre coefficients, and a new value never
retraces.
"""

from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import fe
from .._core import GRAVITY, ParameterError, as_float, check_range
from ..multibody import FlexibleBody, RigidBody, System, SystemBuilder, SystemParams, TimeInputs
from ..multibody._system import checked_params
from ..params import HARD_POINT_NAMES, CarFile, VehicleData, hard_points_vehicle_frame, read_car_file, set_all
from ..tyre import check_tyre, fsae_tir_path, read_tir, stack_tyres
from ._aero import AeroLoads, AeroMap, aero_map_from_coefficients
from ._contact import AbstractRoad, FlatRoad, TyreContact
from ._corner import QUARTER_CAR_LINKS, WHEEL_CENTRE_HEIGHT
from ._powertrain import AbstractSpeedTarget, ConstantSpeed, Powertrain, SpeedPID
from ._rates import installation_ratios
from ._springs import SpringDamperLaw, linear_spring_damper
from ._suspension import pushrod_suspension

CORNERS = ("front_left", "front_right", "rear_left", "rear_right")
#: Short corner keys used in reports and JSON (same order as ``CORNERS``).
CORNER_KEYS = ("fl", "fr", "rl", "rr")
#: Largest selectable number of chassis modes.
MAX_MODES = 20
#: Chassis-side hard points (points of the modal body) and upright-side ones.
CHASSIS_POINTS = ("A", "B", "E", "F", "L", "P", "Q", "T")
UPRIGHT_POINTS = ("C", "H", "M")
#: Auxiliary chassis points: (name, FE nodes whose mode shapes they take, a rigid bracket).
_BRACKETS = {
    "aero_front": tuple(f"{c}.{n}" for c in CORNERS[:2] for n in "ABEF"),
    "aero_rear": tuple(f"{c}.{n}" for c in CORNERS[2:] for n in "ABEF"),
    "cg": tuple(f"{c}.{n}" for c in CORNERS for n in "ABEF"),
    "differential": tuple(f"{c}.{n}" for c in CORNERS[2:] for n in "ABEF"),
}


class CarParams(eqx.Module):
    """Every number of the car (SI units), each a differentiable leaf.

    ``vehicle``: Appendix B (c.g., tracks, masses and inertias, tyre vertical data, hard
    points of the left corners; the right corners mirror them). ``chassis``: the FE modal
    body (mode shapes, modal stiffness ``Ke``, per-mode ``stiffness_scale`` µ and
    ``damping_ratio``; its own rigid part is replaced by ``vehicle.sprung``), None for a
    rigid chassis. ``coupling``: the library's coupling factor of the mode shapes at the
    chassis points. ``springs``: spring-damper law of each corner (FL, FR, RL, RR stacked;
    the free lengths set the static ride). ``arb_rates``: front and rear anti-roll bar
    (N m/rad of bar twist). ``tyres``: MF 5.2 tyre of each corner (stacked). ``aero``,
    ``pid``: aerodynamic tables and the speed controller. ``rack_ratio``: rack travel per
    steering-wheel angle (m/rad).
    """

    vehicle: VehicleData
    chassis: object
    coupling: Float[Array, ""]
    springs: SpringDamperLaw
    arb_rates: Float[Array, "2"]
    tyres: object
    aero: AeroMap
    pid: SpeedPID
    rack_ratio: Float[Array, ""]


class Car(eqx.Module):
    """The car: its static multibody ``system`` (topology, names), the library parameters
    ``template`` that are not design data (spin-axis directions, rack direction, gravity),
    the design ``params``, the chassis mode count ``n_modes`` and the ``form`` the car's
    manoeuvres run on by default (both static): ``"fast"`` (the equations in minimal
    coordinates, :mod:`._fast`) or ``"library"`` (this multibody system)."""

    system: System
    template: SystemParams
    params: CarParams
    n_modes: int = eqx.field(static=True)
    form: str = eqx.field(static=True, default="fast")

    @property
    def q_design(self) -> Float[Array, " nq"]:
        return design_coordinates(self)


# ---- mass data -----------------------------------------------------------------------------


def wheel_centres(vehicle: VehicleData) -> Float[Array, "4 3"]:
    """Design wheel centres (m, vehicle frame), rows as ``CORNERS``."""
    h = jnp.full_like(vehicle.a, WHEEL_CENTRE_HEIGHT)
    rows = [
        (vehicle.a, vehicle.track_front / 2.0),
        (vehicle.a, -vehicle.track_front / 2.0),
        (-vehicle.b, vehicle.track_rear / 2.0),
        (-vehicle.b, -vehicle.track_rear / 2.0),
    ]
    return jnp.stack([jnp.stack([x, y, h]) for x, y in rows])


def _unsprung_masses(vehicle: VehicleData) -> Float[Array, "4"]:
    mf, mr = vehicle.unsprung_front.body.mass, vehicle.unsprung_rear.body.mass
    return jnp.stack([mf, mf, mr, mr])


def total_mass(vehicle: VehicleData) -> Float[Array, ""]:
    """Sprung plus the four unsprung masses (kg)."""
    return vehicle.sprung.mass + jnp.sum(_unsprung_masses(vehicle))


def sprung_cg(vehicle: VehicleData) -> Float[Array, "3"]:
    """Sprung c.g. (m, vehicle frame) that puts the whole car's c.g. at ``(0, 0, h_cg)``."""
    mu, w = _unsprung_masses(vehicle), wheel_centres(vehicle)
    target = jnp.stack([jnp.zeros_like(vehicle.h_cg), jnp.zeros_like(vehicle.h_cg), vehicle.h_cg])
    return (total_mass(vehicle) * target - mu @ w) / vehicle.sprung.mass


def _chassis_body(params: CarParams):
    """The chassis body of the library: rigid, or the modal body with the sprung rigid part."""
    v = params.vehicle
    c = sprung_cg(v)
    if params.chassis is None:
        return RigidBody(mass=v.sprung.mass, inertia=v.sprung.inertia, cg=c)
    m = v.sprung.mass
    j_origin = v.sprung.inertia + m * (jnp.dot(c, c) * jnp.eye(3) - jnp.outer(c, c))
    modal = eqx.tree_at(lambda b: (b.invariants.mass, b.invariants.c0, b.invariants.J0), params.chassis,
                        (m, c, j_origin))
    return FlexibleBody(modal=modal, coupling=params.coupling)


# ---- building -------------------------------------------------------------------------------


def _hard_point(points, name):
    return points[HARD_POINT_NAMES.index(name)]


def _bracket_shapes(modal, nodes):
    """Mode shapes of a rigid bracket spread over FE nodes: the mean of theirs."""
    idx = [modal.point_index(n) for n in nodes]
    return (np.mean(np.asarray(modal.point_phi_translation)[idx], axis=0),
            np.mean(np.asarray(modal.point_phi_rotation)[idx], axis=0))


def _auxiliary_points(vehicle: VehicleData):
    """Positions (m, vehicle frame) of the chassis points that carry no link."""
    zero = jnp.zeros_like(vehicle.a)
    return {
        "aero_front": jnp.stack([vehicle.a, zero, vehicle.h_cg]),
        "aero_rear": jnp.stack([-vehicle.b, zero, vehicle.h_cg]),
        "cg": jnp.stack([zero, zero, vehicle.h_cg]),
        "differential": jnp.stack([-vehicle.b, zero, jnp.full_like(zero, WHEEL_CENTRE_HEIGHT)]),
    }


def _build_system(vehicle: VehicleData, modal) -> tuple[System, SystemParams]:
    """The static topology (and a template of its parameters) from concrete data."""
    hp = hard_points_vehicle_frame(vehicle)
    w = np.asarray(wheel_centres(vehicle))
    b = SystemBuilder(gravity=(0.0, 0.0, -GRAVITY))
    b.add_input("rack")
    if modal is None:
        b.add_rigid_body("chassis", float(vehicle.sprung.mass), np.asarray(vehicle.sprung.inertia),
                         cg=np.asarray(sprung_cg(vehicle)))
    else:
        b.add_flexible_body("chassis", modal)
    for k, corner in enumerate(CORNERS):
        pts = np.asarray(hp[corner])
        front = corner.startswith("front")
        unsprung = vehicle.unsprung_front if front else vehicle.unsprung_rear
        up, wh = f"{corner}.upright", f"{corner}.wheel"
        b.add_rigid_body(up, float(unsprung.body.mass), np.asarray(unsprung.body.inertia), parent="chassis",
                         rotation="zxy")
        b.add_rigid_body(wh, 0.0, np.diag([0.0, float(unsprung.wheel_spin_inertia), 0.0]), parent=up,
                         revolute=((0, 0, 0), (0, 1, 0)))
        for n in CHASSIS_POINTS:
            rack = {"input": "rack", "input_direction": (0.0, 1.0, 0.0)} if (n == "L" and front) else {}
            if modal is None:
                b.add_point(f"{corner}.{n}", "chassis", _hard_point(pts, n), **rack)
            else:
                b.add_modal_point(f"{corner}.{n}", "chassis", f"{corner}.{n}", **rack)
        for n in UPRIGHT_POINTS:
            b.add_point(f"{corner}.{n}", up, _hard_point(pts, n) - w[k])
        b.add_point(f"{corner}.W", up, np.zeros(3))
        b.add_point(f"{corner}.hub", wh, np.zeros(3))
        for link, pa, pb in QUARTER_CAR_LINKS:
            length = np.linalg.norm(_hard_point(pts, pa) - _hard_point(pts, pb))
            b.add_link(f"{corner}.{link}", f"{corner}.{pa}", f"{corner}.{pb}", length)
    for name, xyz in _auxiliary_points(vehicle).items():
        shapes = (None, None) if modal is None else _bracket_shapes(modal, _BRACKETS[name])
        b.add_point(f"chassis.{name}", "chassis", np.asarray(xyz), shapes[0], rotation_shapes=shapes[1])
    for corner in CORNERS:
        b.add_independent(f"{corner}.upright", "uz")
        b.add_independent(f"{corner}.wheel", "theta_dot")
    for name in ("ux", "uy", "uz", "wx", "wy", "wz") + tuple(f"p{k}_dot" for k in range(0 if modal is None else
                                                                                             modal.n_modes)):
        b.add_independent("chassis", name)
    return b.build()


def check_car(car: Car) -> Car:
    """Run every check the car's compiled programs would run on its parameters: the tyres'
    coefficients, the chassis's modal stiffness multipliers and damping, the anti-roll-bar
    rates (>= 0), the speed controller's gains, limits and brake balance, and the library
    parameters (masses, inertias, coupling, link lengths, points, gravity). Concrete
    values raise :class:`~jaxveh.ParameterError` naming the value (traced ones fail at run
    time); returns ``car``. Entry points that compile the car without run-time checks
    (:func:`jaxveh._core.run_time_checks_off`) call this first, so a leaf set out of range
    with ``eqx.tree_at`` is still refused by name."""
    p = car.params
    check_range("arb_rates (N m/rad, front and rear)", p.arb_rates, low=0.0)
    p.pid.check("pid.")
    check_tyre(p.tyres)
    if p.chassis is not None:
        for check in (p.chassis._scale, p.chassis._alpha, p.chassis._beta, p.chassis._zeta):
            check()
    checked_params(car.system, _system_params_program(car))
    return car


#: Table B.4's tyre values (``CarParams.vehicle.tyre``) and the fields of the four tyres
#: (``CarParams.tyres``) the car loads them into; the car runs on the tyres' fields.
TYRE_TABLE_FIELDS = {"kz": "vertical_stiffness", "cz": "vertical_damping", "sigma_kappa": "sigma_kappa",
                     "sigma_alpha": "sigma_alpha"}


def set_car_params(params: CarParams, values: dict) -> CarParams:
    """``params`` with the values at the paths of ``values`` set (:func:`jaxveh.params.set_all`;
    traceable, vmappable). A Table B.4 value ``vehicle.tyre.kz`` (``cz``, ``sigma_kappa``,
    ``sigma_alpha``) is set on all four tyres too (``tyres.vertical_stiffness``, ...), as
    :func:`load_car` does from the car file, so it acts on the car; a path into the tyres
    themselves (``tyres.vertical_stiffness[0]``, one corner) is applied after it."""
    table = {k: v for k, v in values.items() if k.replace(" ", "").startswith("vehicle.tyre.")}
    for path, value in table.items():
        field = TYRE_TABLE_FIELDS.get(path.replace(" ", "")[len("vehicle.tyre."):])
        if field is not None:
            tyres = eqx.tree_at(lambda t, f=field: getattr(t, f), params.tyres,
                                jnp.broadcast_to(jnp.asarray(value, jnp.float64), getattr(params.tyres, field).shape))
            params = eqx.tree_at(lambda p: p.tyres, params, tyres)
    return set_all(params, values)


def with_params(car: Car, values: dict) -> Car:
    """Copy of ``car`` with the :class:`CarParams` values at the paths of ``values`` set
    (``{"arb_rates[0]": 3e4, "chassis.stiffness_scale[0]": 2.0, "coupling": 0.5}``; paths
    as :func:`jaxveh.params.set_at`, relative to ``car.params``; :func:`set_car_params`:
    a Table B.4 tyre value reaches the four tyres), then checked
    (:func:`check_car`). The structure is unchanged: no recompilation."""
    params = set_car_params(car.params, values)
    return check_car(eqx.tree_at(lambda c: c.params, car, params))


def system_params(car: Car) -> SystemParams:
    """The library parameters of the car from ``car.params`` (JAX operations: differentiable)."""
    p, system = car.params, car.system
    v = p.vehicle
    hp = hard_points_vehicle_frame(v)
    w = wheel_centres(v)
    bodies = list(car.template.bodies)
    bodies[0] = _chassis_body(p)
    points = list(car.template.points)
    joints = list(car.template.joints)

    def set_point(name, position, shapes=None, rotation_shapes=None):
        k = system.point_index(name)
        point = eqx.tree_at(lambda pt: pt.position, points[k], position)
        if shapes is not None:
            point = eqx.tree_at(lambda pt: (pt.shapes, pt.rotation_shapes), point, (shapes, rotation_shapes))
        points[k] = point

    modal = p.chassis
    for k, corner in enumerate(CORNERS):
        front = corner.startswith("front")
        unsprung = v.unsprung_front if front else v.unsprung_rear
        bodies[system.body_names.index(f"{corner}.upright")] = RigidBody(mass=unsprung.body.mass,
                                                                          inertia=unsprung.body.inertia)
        spin = unsprung.wheel_spin_inertia
        bodies[system.body_names.index(f"{corner}.wheel")] = RigidBody(
            mass=jnp.zeros_like(spin), inertia=jnp.diag(jnp.stack([jnp.zeros_like(spin), spin, jnp.zeros_like(spin)])))
        pts = hp[corner]
        for n in CHASSIS_POINTS:
            if modal is None:
                set_point(f"{corner}.{n}", _hard_point(pts, n))
            else:
                j = modal.point_index(f"{corner}.{n}")
                set_point(f"{corner}.{n}", _hard_point(pts, n), modal.point_phi_translation[j],
                          modal.point_phi_rotation[j])
        for n in UPRIGHT_POINTS:
            set_point(f"{corner}.{n}", _hard_point(pts, n) - w[k])
        for link, pa, pb in QUARTER_CAR_LINKS:
            j = system.joint_names.index(f"{corner}.{link}")
            joints[j] = eqx.tree_at(lambda jt: jt.length, joints[j],
                                    jnp.linalg.norm(_hard_point(pts, pa) - _hard_point(pts, pb)))
    for name, xyz in _auxiliary_points(v).items():
        if modal is None:
            set_point(f"chassis.{name}", xyz)
        else:
            idx = np.asarray([modal.point_index(n) for n in _BRACKETS[name]])
            set_point(f"chassis.{name}", xyz, jnp.mean(modal.point_phi_translation[idx], axis=0),
                      jnp.mean(modal.point_phi_rotation[idx], axis=0))
    return eqx.tree_at(lambda s: (s.bodies, s.points, s.joints), car.template,
                       (tuple(bodies), tuple(points), tuple(joints)))


def design_coordinates(car: Car) -> Float[Array, " nq"]:
    """Design position: chassis frame on the vehicle frame, uprights at the wheel centres,
    zero angles, modes and spins (every loop closes at zero rack)."""
    w = wheel_centres(car.params.vehicle)
    q = [jnp.zeros(6 + car.n_modes)]
    for k in range(4):
        q += [jnp.concatenate([w[k], jnp.zeros(3)]), jnp.zeros(1)]
    return jnp.concatenate(q)


def design_spring_lengths(vehicle: VehicleData) -> Float[Array, "4"]:
    """Spring lengths |T - S| (m) of the four corners at the design position."""
    hp = (vehicle.hard_points_front.points,) * 2 + (vehicle.hard_points_rear.points,) * 2
    return jnp.stack([jnp.linalg.norm(_hard_point(p, "T") - _hard_point(p, "S")) for p in hp])


def corner_hard_points(vehicle: VehicleData) -> dict[str, dict]:
    """``{corner: {point name: xyz}}`` in the vehicle frame (m), right corners mirrored."""
    hp = hard_points_vehicle_frame(vehicle)
    return {c: {n: _hard_point(hp[c], n) for n in HARD_POINT_NAMES} for c in CORNERS}


def car_elements(car: Car, speed_target: AbstractSpeedTarget | None = None, road: AbstractRoad = FlatRoad(),
                 powertrain: bool = True, tyre_horizontal: bool = True) -> tuple:
    """Force elements of the car: front and rear push-rod suspensions (with their anti-roll
    bars), the four tyres (``tyre_horizontal=False``: normal loads only), aerodynamics and
    (with ``powertrain``) the rear-wheel drive and the four brakes aiming at ``speed_target``
    (default: hold 0 m/s)."""
    p, system = car.params, car.system
    hp = corner_hard_points(p.vehicle)
    laws = [jax.tree.map(lambda x, k=k: x[k], p.springs) for k in range(4)]
    front = pushrod_suspension(system, ("front_left.", "front_right."), [hp["front_left"], hp["front_right"]],
                               laws[:2], p.arb_rates[0])
    rear = pushrod_suspension(system, ("rear_left.", "rear_right."), [hp["rear_left"], hp["rear_right"]],
                              laws[2:], p.arb_rates[1])
    tyres = TyreContact.on(system, {c: (f"{c}.hub", f"{c}.W") for c in CORNERS}, p.tyres, road, tyre_horizontal)
    aero = AeroLoads.on(system, "chassis", "chassis.cg", "chassis.aero_front", "chassis.aero_rear", p.aero)
    elements = (front, rear, tyres, aero)
    if powertrain:
        target = ConstantSpeed(0.0) if speed_target is None else speed_target
        brakes = tuple((f"{c}.hub", f"{c}.W", c.startswith("front")) for c in CORNERS)
        elements += (Powertrain.on(system, "chassis", "chassis.cg", ("rear_left.hub", "rear_right.hub"),
                                   "chassis.differential", p.pid, target, brakes, speed_feedforward(p)),)
    return elements


def speed_feedforward(params: CarParams) -> Float[Array, ""]:
    """The powertrain's feedforward gain (N m per m/s^2): the wheel torque that accelerates
    the car's total mass at the tyres' mean unloaded radius (the wheels' spin inertia and the
    loaded radius are left to the PI loop)."""
    return total_mass(params.vehicle) * jnp.mean(params.tyres.unloaded_radius)


def steering_rack(car: Car, steering_wheel_angle):
    """Rack travel (m, along the chassis y axis) for a steering-wheel angle (rad, positive to
    the left): ``-rack_ratio`` x angle. The track rods sit behind the axle (Table B.2: L and
    M at x = -61 mm), so a left turn moves the rack to the right."""
    return -car.params.rack_ratio * steering_wheel_angle


def steering(car: Car, steering_wheel_angle) -> TimeInputs:
    """Rack input from a steering-wheel angle law ``steering_wheel_angle(t)`` (rad, positive
    to the left), see :func:`steering_rack`."""
    return TimeInputs(lambda t: steering_rack(car, steering_wheel_angle(t)))


# ---- loading --------------------------------------------------------------------------------


def _tyre(name: str, key: str, where: str, vehicle: VehicleData):
    path = fsae_tir_path() if name == fsae_tir_path().name else Path(name)
    if not path.is_file():
        raise ParameterError(f"{where} [files].{key}: tyre file {name!r} does not exist")
    tyre = read_tir(path)
    t = vehicle.tyre  # Table B.4 is the car's: vertical stiffness, damping, relaxation lengths
    return eqx.tree_at(lambda y: (y.vertical_stiffness, y.vertical_damping, y.sigma_kappa, y.sigma_alpha), tyre,
                       (t.kz, t.cz, t.sigma_kappa, t.sigma_alpha))


def _frame(name: str, where: str):
    if name == "fsae_2009_frame.toml":
        return fe.load_frame()
    if not Path(name).is_file():
        raise ParameterError(f"{where} [files].frame: frame file {name!r} does not exist")
    return fe.load_frame(name)


#: The forms a car's equations come in (see :class:`Car`).
FORMS = ("fast", "library")


def check_form(form) -> str:
    """``form`` if it names one of :data:`FORMS`, else a :class:`ParameterError`."""
    if form not in FORMS:
        raise ParameterError(f"form = {form!r} is not available: allowed {', '.join(map(repr, FORMS))}")
    return form


def _check_modes(modes) -> int:
    if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or not 0 <= modes <= MAX_MODES:
        raise ParameterError(f"modes = {modes!r} is out of range: allowed integers 0 (rigid chassis) to {MAX_MODES}")
    return int(modes)


def _springs(file: CarFile, rest_lengths, preloads):
    """Spring-damper laws of the four corners with the free lengths that carry ``preloads``."""
    laws = []
    for k, corner in enumerate(CORNERS):
        s = file.sections["suspension_front" if corner.startswith("front") else "suspension_rear"]
        rate = s["spring_rate"]
        laws.append(linear_spring_damper(rate, rest_lengths[k] + preloads[k] / rate, s["damping"],
                                         rest_lengths[k] - s["bump_stop_clearance"], s["bump_stop_rate"]))
    return jax.tree.map(lambda *x: jnp.stack(x), *laws)


def _with_file_stiffness_scale(chassis, scale: tuple):
    """``chassis`` with the car file's per-mode stiffness multipliers µ (modes beyond the
    list keep 1; entries beyond the chassis's modes are not used)."""
    if not scale:
        return chassis
    n = min(len(scale), chassis.stiffness_scale.shape[0])
    return eqx.tree_at(lambda c: c.stiffness_scale, chassis,
                       chassis.stiffness_scale.at[:n].set(jnp.asarray(scale[:n])))


def load_car(path: str | Path | None = None, modes: int = 6, form: str = "fast") -> Car:
    """The car from a car file (default: the shipped ``car.toml``) with ``modes`` chassis
    modes (0 = rigid chassis, up to 20). ``form``: what manoeuvres integrate by default,
    ``"fast"`` (the equations in minimal coordinates) or ``"library"`` (the multibody
    system, the reference); both read the same :class:`CarParams`, and the set-up, rigs and
    rates always use the multibody system.

    The springs' free lengths are set so that the car at rest on a flat road has every
    suspension at its design position (Tables B.2/B.3), see :func:`rest_spring_preloads`.
    The file's optional ``[chassis] stiffness_scale`` sets the modes' stiffness multipliers
    µ (mode 1 first; modes beyond the list keep 1, entries beyond ``modes`` are unused).
    """
    form = check_form(form)
    modes = _check_modes(modes)
    file = read_car_file(path)
    v = file.vehicle
    chassis = None
    if modes:
        zeta = file.sections["chassis"]["damping_ratio"]
        chassis = fe.frame_modal_body(_frame(file.files["frame"], file.where), modes, damping_ratio=zeta)
        chassis = _with_file_stiffness_scale(chassis, file.stiffness_scale)
    tyres = stack_tyres([
        _tyre(file.files["tyre_front" if c.startswith("front") else "tyre_rear"],
              "tyre_front" if c.startswith("front") else "tyre_rear", file.where, v) for c in CORNERS])
    a, pt = file.sections["aero"], file.sections["powertrain"]
    sf, sr = file.sections["suspension_front"], file.sections["suspension_rear"]
    rest = design_spring_lengths(v)
    params = CarParams(
        vehicle=v,
        chassis=chassis,
        coupling=as_float(file.sections["chassis"]["coupling"]),
        springs=_springs(file, rest, [0.0] * 4),
        arb_rates=jnp.asarray([sf["arb_rate"], sr["arb_rate"]]),
        tyres=tyres,
        aero=aero_map_from_coefficients(a["cda"], a["cla"], a["front_share"], a["density"], a["max_speed"]),
        pid=SpeedPID(kp=pt["kp"], ki=pt["ki"], kd=pt["kd"], tau=pt["tau"], t_min=pt["torque_min"],
                     t_max=pt["torque_max"], brake_front_share=pt["brake_front_share"]),
        rack_ratio=as_float(file.sections["steering"]["rack_ratio"]),
    )
    system, template = _build_system(v, chassis)
    car = Car(system=system, template=template, params=params, n_modes=modes, form=form)
    preloads = rest_spring_preloads(car)
    return eqx.tree_at(lambda c: c.params.springs, car, _springs(file, rest, preloads))


def rest_spring_preloads(car: Car) -> Float[Array, "4"]:
    """Spring forces (N, compression) that hold the car at rest with every suspension at its
    design position: the corner loads of the a/b split (Table B.1, whole-car c.g. at
    ``(0, 0, h_cg)``, all loads vertical) less the unsprung weight, carried to the spring by
    the installation ratio, ``F_s = (W_c - m_u g) / (-dl_s/dz)`` (virtual work; the contact
    point moves with the wheel centre at zero camber)."""
    v = car.params.vehicle
    loads = static_corner_loads(v)
    mu = _unsprung_masses(v)
    ratios = [installation_ratios(axle, v) for axle in ("front", "rear")]
    spring = jnp.stack([ratios[0].spring] * 2 + [ratios[1].spring] * 2)
    return (loads - mu * GRAVITY) / (-spring)


def static_corner_loads(vehicle: VehicleData) -> Float[Array, "4"]:
    """Corner loads (N) of the a/b split: ``m g b / 2l`` front, ``m g a / 2l`` rear."""
    w = total_mass(vehicle) * GRAVITY / (2.0 * vehicle.wheelbase)
    return jnp.stack([w * vehicle.b, w * vehicle.b, w * vehicle.a, w * vehicle.a])


def with_rest_preloads(car: Car, iterations: int = 8) -> Car:
    """The car with its spring tables shifted along the length axis so that each spring
    carries its :func:`rest_spring_preloads` force at its design length (the perch
    adjusted after a change of spring, mass or hard point). Newton on the shift: exact
    for piecewise-linear tables in a few iterations."""
    rest = design_spring_lengths(car.params.vehicle)
    preloads = rest_spring_preloads(car)
    laws = car.params.springs

    def shift_one(law, length, preload):
        def step(_, s):
            f, df = jax.jvp(law.spring, (length - s,), (jnp.ones_like(s),))
            return s + (f - preload) / df

        return jax.lax.fori_loop(0, iterations, step, jnp.zeros_like(length))

    shift = jax.vmap(shift_one)(laws, rest, preloads)
    return eqx.tree_at(lambda c: c.params.springs.spring_length, car, laws.spring_length + shift[:, None])


#: :func:`system_params` as one compiled program (one per car structure): the checks of
#: :func:`check_car` read its values without a few hundred eager operations per call.
_system_params_program = eqx.filter_jit(system_params)
