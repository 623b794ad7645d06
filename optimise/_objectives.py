"""Objectives of the flexible car for design optimisation: pure, differentiable scalar
functions of a :class:`jaxveh.vehicle.Car` (its numbers in ``car.params``), registered by
name in :data:`OBJECTIVES` so that study files can name them.

Each objective wraps what jaxveh computes; none re-derives the physics:

- skid-pad quantities (understeer gradient, steering sensitivity, roll, camber and rear
  steer gradients) from one steady state on a circle, :func:`jaxveh.manoeuvre.skid_pad_core`
  (Newton by Optimistix; the gradients with respect to ay come from the same linear solve,
  the derivatives with respect to the car's parameters by the implicit function theorem);
- χ at low ay from the left and right steady turns, :func:`jaxveh.analysis.load_transfer_core`;
- the first coupled chassis mode's frequency and damping ratio from the exact linearisation
  about straight running (:func:`jaxveh.manoeuvre.straight_trim`,
  :func:`jaxveh.analysis.linear_field`): the eigenvalue of the state matrix whose eigenvector
  matches (largest MAC) a reference eigenvector, the mode that
  :func:`jaxveh.analysis.first_chassis_mode` identifies on the base car's coupling root
  locus (:func:`first_mode_reference`); its derivative is the first-order perturbation
  ``d lambda = w^H dA v / (w^H v)`` (left and right eigenvectors), as
  :func:`jaxveh.analysis.eigenvalue_sensitivities` computes it, here as a JAX rule so that
  forward and reverse mode both work;
- the yaw-rate response of a small step steer, the yaw-rate frequency response's bandwidth
  and peak, the four-post RMS load variation and the preview distance from the same exact
  linearisation (:mod:`optimise._response`);
- the yaw-rate response of a step steer of any size from the fast car's time run
  (:mod:`optimise._step_steer`; ``step_steer_*``);
- straight-line braking (deceleration, dive, front load share) and braking in a turn (yaw
  rate, heading and path against the initial circle) from the fast car's time runs
  (:mod:`optimise._braking`; ``braking_*``, ``brake_in_turn_*``);
- bump steer and camber gain from each corner's kinematics at the design pose
  (:func:`suspension_kinematics`: the fast car's exact corner solve, differentiated along the
  wheel travel);
- the chassis frame's mass and torsional stiffness (FE, :mod:`jaxveh.fe`): functions of a
  :class:`jaxveh.fe.Frame` (:data:`FRAME_OBJECTIVES`), not of ``CarParams``, whose chassis is
  the frame's modal reduction.

A steady state or trim that does not converge makes the objective NaN (the caller reports
it; :func:`optimise.optimise_study` raises :class:`optimise.OptimisationError`).

Objectives sharing one computation (the skid-pad point at one ay and radius, the load
transfer at one pair of ay) are evaluated once by :func:`objective_values`.
"""

from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import jaxveh.fe as fe
from jaxveh import GRAVITY, ParameterError
from jaxveh.analysis import (
    LOW_AY_PAIR_G,
    SKID_PAD_RADIUS,
    WHEEL_PARAMETERS,
    first_chassis_mode,
    linear_field,
    linearise,
    load_transfer_core,
    root_locus,
    wheel_parameters,
)
from jaxveh.manoeuvre import skid_pad_core, straight_trim
from jaxveh.vehicle import CORNERS, car_rates, corner_poses, fast_model, installation_ratios

from ._braking import BRAKE_IN_TURN_SETTINGS, BRAKING_SETTINGS, brake_in_turn_objectives, braking_metrics
from ._response import (
    linear_io,
    preview_distance_of,
    step_metrics_of,
    sweep_rms_of,
    yaw_rate_bandwidth_of,
    yaw_rate_gain_peak_of,
)
from ._step_steer import SETTINGS as STEP_STEER_SETTINGS, step_steer_metrics

#: Lateral acceleration (g) of the skid-pad objectives by default: the linear range.
DEFAULT_AY_G = 0.05
#: Speed (km/h) of the linearisation of the mode objectives by default (the root loci's).
DEFAULT_SPEED_KMH = 50.0
#: Speed (km/h) of the step-steer and steering frequency-response objectives by default (Fig. 7.6's).
STEP_SPEED_KMH = 90.0
#: Speed (km/h) of the four-post objective by default (:func:`jaxveh.manoeuvre.four_post`'s).
FOUR_POST_SPEED_KMH = 50.0
#: Speed (km/h) and points of the preview objective by default (section 7.5's).
PREVIEW_SPEED_KMH = 100.0
N_PREVIEW = 250
#: Options (name -> default) of the step-steer objectives: the cubic's rise, the run's
#: length and the window of the steady value (s).
STEP_OPTIONS = {"rise_s": 0.2, "duration_s": 5.0, "settle_s": 0.5}
#: Options of the steering frequency-response objectives (Hz): the reference (steady) gain's
#: frequency and the top of the band searched.
BAND_OPTIONS = {"f_ref_hz": 0.05, "f_max_hz": 20.0}
#: Options of the four-post objective: the tyre, the post pattern, the post amplitude (m)
#: and the sweep's band (Hz) (Fig. 7.9's rig, :func:`jaxveh.manoeuvre.four_post`).
SWEEP_OPTIONS = {"corner": "front_left", "pattern": "warp", "amplitude_m": 0.002, "f0_hz": 0.5, "f1_hz": 30.0}
#: Damped frequencies below this (Hz) are not vibration modes (the neutral and real modes).
MIN_MODE_HZ = 1e-3


# ---- the roll stiffness distribution as a traced design variable ---------------------------


class RollRateCoefficients(NamedTuple):
    """What λ = kF / (kF + kR) needs of the car: the springs' roll stiffness per axle
    ``springs_front``/``springs_rear`` and the car's total roll stiffness ``total`` (N m/rad
    of roll), and the roll stiffness per unit bar rate ``(dθ/dz t)^2`` per axle
    ``bar_front``/``bar_rear`` (N m/rad of roll per N m/rad of bar twist); from
    :func:`jaxveh.vehicle.car_rates` and :func:`jaxveh.vehicle.installation_ratios` (NumPy
    set-up, not traceable)."""

    springs_front: jax.Array
    springs_rear: jax.Array
    bar_front: jax.Array
    bar_rear: jax.Array
    total: jax.Array


def roll_rate_coefficients(car) -> RollRateCoefficients:
    """:class:`RollRateCoefficients` of ``car`` (eager: the rates are computed from quarter
    cars built in NumPy)."""
    rates = car_rates(car)
    f, r = rates["front"], rates["rear"]
    v = car.params.vehicle
    return RollRateCoefficients(
        springs_front=jnp.asarray(f.roll_stiffness_springs),
        springs_rear=jnp.asarray(r.roll_stiffness_springs),
        bar_front=jnp.asarray((installation_ratios("front", v).rocker * v.track_front) ** 2),
        bar_rear=jnp.asarray((installation_ratios("rear", v).rocker * v.track_rear) ** 2),
        total=jnp.asarray(f.roll_stiffness + r.roll_stiffness),
    )


def arb_rates_for_lambda(coefficients: RollRateCoefficients, lam):
    """Anti-roll-bar rates (N m/rad of bar twist, front and rear) for the roll stiffness
    distribution ``lam`` in (0, 1): :func:`jaxveh.analysis.arb_rates_for_distribution`'s
    rule (total roll stiffness kept while both bars stay >= 0, beyond that the softer axle's
    bar 0 and the other raised) in traceable form, with the car's coefficients computed
    beforehand (:func:`roll_rate_coefficients`).

    ``arb_rates_for_distribution`` checks λ with NumPy and computes the car's rates from
    quarter cars built in NumPy, so neither can be traced; this is its formula on the
    coefficients, tested equal to it. The coefficients depend on the springs, the
    geometry and the bars of the base car: a study that varies those together with λ is
    refused (:func:`optimise.load_optimisation_study`)."""
    c = coefficients
    lam = jnp.asarray(lam, jnp.float64)
    k_front = jnp.maximum(lam * c.total, c.springs_front)
    k_rear = jnp.maximum((1.0 - lam) * c.total, c.springs_rear)
    k_front = jnp.maximum(k_front, lam / (1.0 - lam) * k_rear)
    k_rear = jnp.maximum(k_rear, (1.0 - lam) / lam * k_front)
    return jnp.stack([(k_front - c.springs_front) / c.bar_front, (k_rear - c.springs_rear) / c.bar_rear], axis=-1)


# ---- the computations objectives share -------------------------------------------------------


def _nan_unless(ok, value):
    return jnp.where(ok, value, jnp.nan)


def skid_pad_point(car, ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """The steady state on a circle of ``radius`` (m) at ``ay_g`` (g), turning left, as a
    one-point :class:`jaxveh.manoeuvre.SkidPad` (pure; differentiable)."""
    return skid_pad_core(car, jnp.asarray(radius, jnp.float64), jnp.reshape(jnp.asarray(ay_g * GRAVITY), (1,)))


def _corner_index(corner: str) -> int:
    if corner not in CORNERS:
        raise ParameterError(f"corner = {corner!r} is not allowed: one of {', '.join(CORNERS)}")
    return CORNERS.index(corner)


def _ku(pad):
    return _nan_unless(pad.ok[0], pad.understeer_gradient[0])


def _steering_sensitivity(pad):
    return 1.0 / _ku(pad)


def _roll_gradient(pad):
    return _nan_unless(pad.ok[0], pad.gradients["roll"][0] * GRAVITY)


def _camber_gradient(pad, corner="front_left"):
    return _nan_unless(pad.ok[0], pad.gradients["camber"][0, _corner_index(corner)] * GRAVITY)


#: The rear-steer objective's ``corner`` naming the rear axle: the mean of both rear wheels.
REAR_AXLE = "rear"


def _rear_steer_gradient(pad, corner="rear_left"):
    if corner != REAR_AXLE and not corner.startswith("rear"):
        raise ParameterError(f"corner = {corner!r} is not allowed: rear_left, rear_right or rear (the axle's mean; "
                             "the front wheels steer)")
    if corner == REAR_AXLE:
        angle = jnp.mean(pad.gradients["road_wheel_angle"][0, 2:])
    else:
        angle = pad.gradients["road_wheel_angle"][0, _corner_index(corner)]
    return _nan_unless(pad.ok[0], angle * GRAVITY)


def understeer_gradient(car, ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """Understeer gradient ku = d delta / d ay (deg/g) at ``ay_g`` (g) on ``radius`` (m):
    :attr:`jaxveh.manoeuvre.SkidPad.understeer_gradient`, delta the mean front road-wheel
    angle; negative: oversteer. NaN without a steady state."""
    return _ku(skid_pad_point(car, ay_g, radius))


def steering_sensitivity(car, ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """Steering sensitivity 1 / ku (g/deg) at ``ay_g`` (g) on ``radius`` (m), as
    ``jaxveh simulate skid-pad`` reports it (the thesis's Fig. 7.5b); infinite at neutral
    steer, so prefer :func:`understeer_gradient` near it."""
    return _steering_sensitivity(skid_pad_point(car, ay_g, radius))


def roll_gradient(car, ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """Roll gradient d roll / d ay (deg/g; positive: the chassis rolls towards the outside)
    at ``ay_g`` (g) on ``radius`` (m)."""
    return _roll_gradient(skid_pad_point(car, ay_g, radius))


def camber_gradient(car, corner="front_left", ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """Camber gradient (deg/g) of the wheel ``corner`` (a name of
    :data:`jaxveh.vehicle.CORNERS`; left turn: the left wheels are the inner ones) at
    ``ay_g`` (g) on ``radius`` (m): the derivative of the camber channel (inclination to the
    road, ISO sign) with respect to ay, everything included (roll, suspension travel, chassis
    deformation; Table 7.1's chassis-only part is :func:`jaxveh.analysis.kinematic_gradients`)."""
    return _camber_gradient(skid_pad_point(car, ay_g, radius), corner)


def rear_steer_gradient(car, corner="rear_left", ay_g=DEFAULT_AY_G, radius=SKID_PAD_RADIUS):
    """Steer (toe) gradient of the rear wheel ``corner`` (deg/g; road-wheel angle, positive
    left) at ``ay_g`` (g) on ``radius`` (m): roll steer, compliance steer and the chassis's
    deformation together. ``corner = "rear"``: the rear axle's, the mean of both wheels
    (in a turn the outer wheel's travel, and so its roll steer, is the larger: the car
    also heaves)."""
    return _rear_steer_gradient(skid_pad_point(car, ay_g, radius), corner)


#: The axles a kinematic objective's ``corner`` may name (the mean of both wheels).
AXLES = {"front": (0, 1), "rear": (2, 3)}


def suspension_kinematics(car):
    """Each corner's wheel parameters (:data:`jaxveh.analysis.WHEEL_PARAMETERS`) differentiated
    with respect to its own wheel travel (4, 6; per m of travel: m/m, rad/m) at the design
    pose: travels 0, rack centred, chassis undeformed (the fast car's exact corner solve)."""
    model = fast_model(car)
    modes, rack = jnp.zeros(car.n_modes), jnp.zeros(())

    def parameters(travel):
        return wheel_parameters(corner_poses(model.geometry, model.kmap, travel, rack, modes), travel,
                                model.geometry.centre)

    jac = jax.jacfwd(parameters)(jnp.zeros(len(CORNERS)))  # (corner, parameter, travel)
    return jnp.stack([jac[k, :, k] for k in range(len(CORNERS))])


def _corner_rows(corner: str) -> tuple:
    if corner in AXLES:
        return AXLES[corner]
    if corner not in CORNERS:
        raise ParameterError(f"corner = {corner!r} is not allowed: one of {', '.join(CORNERS)}, front or rear (the "
                             "axle's mean)")
    return (CORNERS.index(corner),)


#: Each corner's sign that turns the inclination angle γ into camber positive with the top of
#: the wheel outwards (left wheels: -γ; right wheels: γ).
_TOP_OUTWARD = np.asarray([-1.0, 1.0, -1.0, 1.0])


def _per_travel_deg(rates, corner, parameter, signs=None):
    rows = np.asarray(_corner_rows(corner))
    values = rates[rows, WHEEL_PARAMETERS.index(parameter)] * (1.0 if signs is None else signs[rows])
    return jnp.degrees(jnp.mean(values))


def _bump_steer(rates, corner="front_left"):
    return _per_travel_deg(rates, corner, "toe")


def _camber_gain(rates, corner="front_left"):
    return _per_travel_deg(rates, corner, "camber", _TOP_OUTWARD)


def allowed_corners(name: str) -> tuple:
    """The values the ``corner`` setting of the objective ``name`` allows."""
    if name == "rear_steer_gradient":
        return tuple(c for c in CORNERS if c.startswith("rear")) + (REAR_AXLE,)
    if OBJECTIVES[name].source == "kinematics":
        return CORNERS + tuple(AXLES)
    return CORNERS


def bump_steer(car, corner="front_left"):
    """Bump steer (deg/m): the toe-in change of the wheel ``corner`` (a name of
    :data:`jaxveh.vehicle.CORNERS`, or ``front``/``rear``: the axle's mean) per metre of its
    own wheel travel (positive in bump) at the design pose, the rack centred and the chassis
    undeformed; positive: the wheel toes in as it rises."""
    return _bump_steer(suspension_kinematics(car), corner)


def camber_gain(car, corner="front_left"):
    """Camber gain (deg/m): the camber change of the wheel ``corner`` (or ``front``/``rear``:
    the axle's mean) per metre of its own wheel travel at the design pose, the rack centred
    and the chassis undeformed, camber positive with the top of the wheel outwards (SAE;
    the left wheels' ``camber`` channel, the tyre's inclination γ, has the other sign), so a
    negative gain: the top leans inwards as the wheel rises."""
    return _camber_gain(suspension_kinematics(car), corner)


def _chi(lt):
    return _nan_unless(jnp.all(lt.ok[:2]), lt.chi_low_ay)


def load_transfer_point(car, ay_g=LOW_AY_PAIR_G, radius=SKID_PAD_RADIUS):
    """:class:`jaxveh.analysis.LoadTransfer` at the two lateral accelerations ``ay_g`` (g) on
    ``radius`` (m) (pure; differentiable)."""
    return load_transfer_core(car, jnp.asarray(np.asarray(ay_g, float) * GRAVITY), jnp.asarray(radius, jnp.float64))


def chi(car, ay_g=LOW_AY_PAIR_G, radius=SKID_PAD_RADIUS):
    """χ at low ay (1): the front axle's incremental share of the lateral load transfer
    between the two ``ay_g`` (g) on ``radius`` (m),
    :attr:`jaxveh.analysis.LoadTransfer.chi_low_ay`. NaN without the steady states."""
    return _chi(load_transfer_point(car, ay_g, radius))


# ---- the first coupled chassis mode ----------------------------------------------------------


def state_matrix(car, speed_kmh=DEFAULT_SPEED_KMH):
    """``(A, ok)``: the fast car's state matrix about straight running at ``speed_kmh``
    (km/h), as :func:`jaxveh.analysis.linearise` builds it (forward-mode Jacobian of
    :func:`jaxveh.analysis.linear_field` at the trim), and whether the trim converged."""
    speed = jnp.asarray(speed_kmh / 3.6, jnp.float64)
    trim = straight_trim(car, speed, "fast")
    field, x0 = linear_field(car, trim, speed, ("y",))
    w0 = jnp.zeros(15)
    return jax.jacfwd(lambda x: field(x, w0)[0])(x0), trim.ok


def _mac(reference, vectors):
    num = jnp.abs(jnp.conj(reference) @ vectors) ** 2
    return num / (jnp.sum(jnp.abs(reference) ** 2) * jnp.sum(jnp.abs(vectors) ** 2, axis=0))


def _select(a, reference):
    lam, left, right = jax.lax.linalg.eig(a, compute_left_eigenvectors=True, compute_right_eigenvectors=True)
    keep = lam.imag >= 2.0 * jnp.pi * MIN_MODE_HZ
    k = jnp.argmax(jnp.where(keep, _mac(reference, right), -1.0))
    return lam[k], left[:, k], right[:, k]


@jax.custom_jvp
def matched_eigenvalue(a, reference):
    """``(real, imag)`` (1/s) of the eigenvalue of ``a`` (real, n x n) with a positive
    imaginary part whose right eigenvector has the largest MAC with ``reference`` (complex,
    n). Differentiable in ``a`` by first-order perturbation (simple eigenvalue; the
    selection is held)."""
    lam, _, _ = _select(a, reference)
    return lam.real, lam.imag


@matched_eigenvalue.defjvp
def _matched_eigenvalue_jvp(primals, tangents):
    a, reference = primals
    da, _ = tangents
    lam, left, right = _select(a, reference)
    da = da.astype(right.dtype)
    d = (jnp.conj(left) @ da @ right) / (jnp.conj(left) @ right)
    return (lam.real, lam.imag), (d.real, d.imag)


def first_mode_reference(car, speed_kmh=DEFAULT_SPEED_KMH) -> np.ndarray:
    """The reference eigenvector (complex, the fast car's state) of the first coupled chassis
    mode of ``car``: followed with :func:`jaxveh.analysis.root_locus` along the coupling
    factor from 0 (the free-free frame's first mode, :func:`jaxveh.analysis.first_chassis_mode`)
    to the car's own coupling, at ``speed_kmh`` (km/h). NumPy: a set-up step, once per
    study; compiles :func:`jaxveh.analysis.linearise`."""
    if car.n_modes == 0:
        raise ParameterError("the first chassis mode needs a flexible chassis: the car has modes = 0")
    coupling = float(car.params.coupling)
    if not coupling > 0.0:
        raise ParameterError("the first coupled chassis mode needs coupling > 0: the car's coupling is 0")
    locus = root_locus(car, "coupling", np.asarray([0.0, coupling]), speed=speed_kmh / 3.6)
    j = first_chassis_mode(locus, car)
    # the same state matrix as state_matrix's, from the program the locus compiled
    lam, vec = np.linalg.eig(np.asarray(linearise(car, speed_kmh / 3.6).a))
    target = locus.eigenvalues[-1, j]
    return vec[:, int(np.argmin(np.abs(lam - target)))]


def follow_mode(reference, a) -> np.ndarray:
    """The eigenvector of ``a`` (a state matrix, NumPy) with a positive imaginary part that
    has the largest MAC with ``reference``: the reference of the same mode one step further
    along a design path (mode tracking). A fixed reference loses a mode whose shape changes
    along the path: near an avoided crossing two eigenvectors resemble it alike and the
    selection jumps from one to the other (seen in study (d): the first coupled chassis
    mode at 28.1 Hz and a 22.6 Hz mode both at MAC 0.640 with the shipped car's)."""
    lam, vec = np.linalg.eig(np.asarray(a))
    reference = np.asarray(reference)
    mac = np.abs(np.conj(reference) @ vec) ** 2 / (np.sum(np.abs(reference) ** 2) * np.sum(np.abs(vec) ** 2, axis=0))
    return vec[:, int(np.argmax(np.where(lam.imag >= 2.0 * np.pi * MIN_MODE_HZ, mac, -1.0)))]


def _mode(car, reference, speed_kmh):
    a, ok = state_matrix(car, speed_kmh)
    re, im = matched_eigenvalue(a, jnp.asarray(reference))
    return _nan_unless(ok, re), _nan_unless(ok, im)


def first_mode_frequency(car, reference, speed_kmh=DEFAULT_SPEED_KMH):
    """Damped frequency Im(lambda) / 2 pi (Hz) of the first coupled chassis mode (the
    eigenvalue matching ``reference``, :func:`first_mode_reference`) about straight running
    at ``speed_kmh`` (km/h). NaN without the trim."""
    return _mode(car, reference, speed_kmh)[1] / (2.0 * jnp.pi)


def first_mode_damping_ratio(car, reference, speed_kmh=DEFAULT_SPEED_KMH):
    """Damping ratio -Re(lambda) / |lambda| (1) of the first coupled chassis mode (see
    :func:`first_mode_frequency`)."""
    re, im = _mode(car, reference, speed_kmh)
    return -re / jnp.hypot(re, im)


# ---- responses of the linearised car (optimise._response) -----------------------------------


def steering_response(car, speed_kmh=STEP_SPEED_KMH):
    """The car linearised about straight running at ``speed_kmh`` (km/h) with the yaw rate
    as its output (:class:`optimise._response.LinearIO`; pure)."""
    return linear_io(car, speed_kmh, ("yaw_rate",))


def road_response(car, speed_kmh=FOUR_POST_SPEED_KMH):
    """The car linearised about straight running at ``speed_kmh`` (km/h) with the four
    contact-patch loads as its outputs (pure)."""
    return linear_io(car, speed_kmh, ("fz",))


def _response_time(io, **step):
    return step_metrics_of(io, **{**STEP_OPTIONS, **step}).response_time


def _peak_time(io, **step):
    return step_metrics_of(io, **{**STEP_OPTIONS, **step}).peak_time


def _overshoot(io, **step):
    return step_metrics_of(io, **{**STEP_OPTIONS, **step}).overshoot


def _bandwidth(io, **band):
    return yaw_rate_bandwidth_of(io, **{**BAND_OPTIONS, **band})


def _gain_peak(io, **band):
    return yaw_rate_gain_peak_of(io, **{**BAND_OPTIONS, **band})


def _rms_fz(io, **sweep):
    return sweep_rms_of(io, **{**SWEEP_OPTIONS, **sweep})


def yaw_rate_response_time(car, speed_kmh=STEP_SPEED_KMH, **step):
    """Yaw-rate response time (s) of a small step steer at ``speed_kmh`` (km/h): from 50 % of
    the steering input to 90 % of the steady yaw rate (ISO 7401), on the linearised car
    (:func:`optimise._response.step_metrics_of`; ``step``: ``rise_s``, ``duration_s``,
    ``settle_s``)."""
    return _response_time(steering_response(car, speed_kmh), **step)


def yaw_rate_peak_time(car, speed_kmh=STEP_SPEED_KMH, **step):
    """Yaw-rate peak time (s) of a small step steer, from 50 % of the input (see
    :func:`yaw_rate_response_time`); NaN without a peak before the settling window."""
    return _peak_time(steering_response(car, speed_kmh), **step)


def yaw_rate_overshoot(car, speed_kmh=STEP_SPEED_KMH, **step):
    """Yaw-rate overshoot (% of the steady yaw rate) of a small step steer (see
    :func:`yaw_rate_response_time`)."""
    return _overshoot(steering_response(car, speed_kmh), **step)


def yaw_rate_bandwidth(car, speed_kmh=STEP_SPEED_KMH, **band):
    """Yaw-rate bandwidth (Hz) of the linearised car at ``speed_kmh`` (km/h): the first
    frequency where the gain per steering-wheel angle falls to -3 dB of its value at
    ``f_ref_hz`` (``band``: ``f_ref_hz``, ``f_max_hz``)."""
    return _bandwidth(steering_response(car, speed_kmh), **band)


def yaw_rate_gain_peak(car, speed_kmh=STEP_SPEED_KMH, **band):
    """The yaw-rate gain's peak over its value at ``f_ref_hz`` (1) up to ``f_max_hz`` (see
    :func:`yaw_rate_bandwidth`)."""
    return _gain_peak(steering_response(car, speed_kmh), **band)


def rms_fz_variation(car, speed_kmh=FOUR_POST_SPEED_KMH, **sweep):
    """RMS contact-patch load variation (N) of one tyre on the four-post rig at
    ``speed_kmh`` (km/h), a sine sweep of the posts (``sweep``: ``corner``, ``pattern``,
    ``amplitude_m``, ``f0_hz``, ``f1_hz``), quasi-stationary on the linearised car
    (:func:`optimise._response.sweep_rms_of`)."""
    return _rms_fz(road_response(car, speed_kmh), **sweep)


def step_steer_response_time(car, reverse=False, **settings):
    """Yaw-rate response time (s) of the fast car's step steer, from 50 % of the input to
    90 % of the steady yaw rate (ISO 7401), at any angle (:func:`optimise._step_steer.
    step_steer_metrics`; ``settings``: ``speed_kmh``, ``angle_deg``, ``rise_s``, ``duration_s``,
    ``settle_s``, ``rtol``; ``reverse``: ready for ``jax.grad`` instead of forward mode)."""
    return step_steer_metrics(car, **settings, reverse=reverse).response_time


def step_steer_peak_time(car, reverse=False, **settings):
    """Yaw-rate peak time (s, from 50 % of the input) of the fast car's step steer (see
    :func:`step_steer_response_time`); NaN without a peak before the settling window."""
    return step_steer_metrics(car, **settings, reverse=reverse).peak_time


def step_steer_overshoot(car, reverse=False, **settings):
    """Yaw-rate overshoot (% of the steady yaw rate) of the fast car's step steer (see
    :func:`step_steer_response_time`)."""
    return step_steer_metrics(car, **settings, reverse=reverse).overshoot


def step_steer_steady_yaw_rate(car, reverse=False, **settings):
    """Steady yaw rate (deg/s) after the fast car's step steer (see
    :func:`step_steer_response_time`): the mean over the last ``settle_s``."""
    return step_steer_metrics(car, **settings, reverse=reverse).steady


def preview_length(car, speed_kmh=PREVIEW_SPEED_KMH, n_preview=N_PREVIEW):
    """Preview distance Lp (m) of the TI-optimal preview driver on the linearised car at
    ``speed_kmh`` (km/h) with ``n_preview`` points (section 7.5; eq. 3.46's 98 %)."""
    return preview_distance_of(car, speed_kmh, n_preview)


# ---- the frame --------------------------------------------------------------------------------


def braking_deceleration(car, reverse=False, **settings):
    """Mean deceleration (g) over the hold of straight-line braking at ``decel_g``
    (:func:`optimise._braking.braking_metrics`; ``settings``: ``speed_kmh``,
    ``final_speed_kmh``, ``decel_g``, ``settle_s``, ``rtol``): the target's when the car can
    give it, else the most its tyres and brake balance give."""
    return braking_metrics(car, **settings, reverse=reverse).deceleration


def braking_pitch_gradient(car, reverse=False, **settings):
    """Pitch per g of deceleration (deg/g; negative: the nose dives) over the braking hold (as
    :func:`braking_deceleration`)."""
    return braking_metrics(car, **settings, reverse=reverse).pitch_gradient


def braking_front_load_share(car, reverse=False, **settings):
    """The front axle's share of the tyre loads over the braking hold (as
    :func:`braking_deceleration`)."""
    return braking_metrics(car, **settings, reverse=reverse).front_load_share


def brake_in_turn_yaw_ratio(car, reverse=False, **settings):
    """Braking in a turn: yaw rate ``after_s`` into the braking over the initial circle's at
    the current speed (1: the car stays on its circle; above: it turns in)
    (:func:`optimise._braking.brake_in_turn_objectives`; ``settings``: ``speed_kmh``,
    ``radius_m``, ``decel_g``, ``after_s``, ``rtol``)."""
    return brake_in_turn_objectives(car, **settings, reverse=reverse)["yaw_rate_ratio_to_reference"]


def brake_in_turn_heading_deviation(car, reverse=False, **settings):
    """Braking in a turn: heading deviation (deg, into the turn positive) from the initial
    circle ``after_s`` into the braking (as :func:`brake_in_turn_yaw_ratio`)."""
    return brake_in_turn_objectives(car, **settings, reverse=reverse)["heading_deviation_deg"]


def brake_in_turn_path_deviation(car, reverse=False, **settings):
    """Braking in a turn: the c.g.'s distance outside the initial circle (m; negative inside)
    ``after_s`` into the braking (as :func:`brake_in_turn_yaw_ratio`)."""
    return brake_in_turn_objectives(car, **settings, reverse=reverse)["path_deviation_m"]


def chassis_mass(frame: fe.Frame):
    """Mass of the chassis frame (kg), :func:`jaxveh.fe.frame_mass`."""
    return fe.frame_mass(frame)


def torsional_stiffness(frame: fe.Frame):
    """Torsional stiffness of the chassis frame (N m/deg) by the FE torsion test,
    :func:`jaxveh.fe.torsion_test` (section 6.2.2)."""
    return fe.torsion_test(frame).stiffness_nm_per_deg


# ---- the registry -------------------------------------------------------------------------------


class Source(NamedTuple):
    """A computation objectives share: ``compute(car, **settings)`` and its ``settings``
    (name -> default); ``prepare(car, settings) -> {name: array}``, optional, computes
    array settings once per study (NumPy) before anything is traced; ``time_run``: whether
    ``compute`` integrates in time and takes ``reverse`` (Diffrax's adjoint: forward mode
    by default, reverse mode with ``reverse=True``)."""

    compute: Callable
    settings: dict
    prepare: Callable | None = None
    time_run: bool = False


def _prepare_reference(car, settings):
    return {"reference": first_mode_reference(car, settings["speed_kmh"])}


SOURCES = {
    "steering_response": Source(steering_response, {"speed_kmh": STEP_SPEED_KMH}),
    "road_response": Source(road_response, {"speed_kmh": FOUR_POST_SPEED_KMH}),
    "preview": Source(preview_length, {"speed_kmh": PREVIEW_SPEED_KMH, "n_preview": N_PREVIEW}),
    "step_steer": Source(step_steer_metrics, STEP_STEER_SETTINGS, time_run=True),
    "braking": Source(braking_metrics, BRAKING_SETTINGS, time_run=True),
    "brake_in_turn": Source(brake_in_turn_objectives, BRAKE_IN_TURN_SETTINGS, time_run=True),
    "skid_pad": Source(skid_pad_point, {"ay_g": DEFAULT_AY_G, "radius": SKID_PAD_RADIUS}),
    "kinematics": Source(suspension_kinematics, {}),
    "load_transfer": Source(load_transfer_point, {"ay_g": tuple(LOW_AY_PAIR_G), "radius": SKID_PAD_RADIUS}),
    "linear": Source(lambda car, speed_kmh, reference: _mode(car, reference, speed_kmh),
                     {"speed_kmh": DEFAULT_SPEED_KMH}, _prepare_reference),
}


class Objective(NamedTuple):
    """A registered objective: ``function`` (the pure function of the car, its settings as
    keyword arguments), ``units``, ``description``, the shared computation ``source`` (a
    key of :data:`SOURCES`), ``extract(data, **options)`` from that computation's result,
    and its own ``options`` (name -> default) beyond the source's settings."""

    function: Callable
    units: str
    description: str
    source: str
    extract: Callable
    options: dict = {}

    @property
    def settings(self) -> dict:
        """Every setting (the source's and the objective's own) with its default."""
        return {**SOURCES[self.source].settings, **self.options}


def _frequency(mode):
    return mode[1] / (2.0 * jnp.pi)


def _damping(mode):
    return -mode[0] / jnp.hypot(mode[0], mode[1])


#: The objectives of the car by name (study files name them).
OBJECTIVES = {
    "understeer_gradient": Objective(understeer_gradient, "deg/g", "understeer gradient d delta / d ay at ay_g "
                                     "on the circle of radius (negative: oversteer)", "skid_pad", _ku),
    "steering_sensitivity": Objective(steering_sensitivity, "g/deg", "1 / understeer gradient (Fig. 7.5b; "
                                      "infinite at neutral steer)", "skid_pad", _steering_sensitivity),
    "roll_gradient": Objective(roll_gradient, "deg/g", "chassis roll per g at ay_g", "skid_pad", _roll_gradient),
    "camber_gradient": Objective(camber_gradient, "deg/g", "camber change per g of one wheel (corner) at ay_g, "
                                 "everything included", "skid_pad", _camber_gradient, {"corner": "front_left"}),
    "rear_steer_gradient": Objective(rear_steer_gradient, "deg/g", "road-wheel angle change per g of a rear "
                                     "wheel (corner; rear: the axle's mean) at ay_g", "skid_pad", _rear_steer_gradient,
                                     {"corner": "rear_left"}),
    "bump_steer": Objective(bump_steer, "deg/m", "toe-in change per m of the wheel's own travel (corner; front, "
                            "rear: the axle's mean) at the design pose", "kinematics", _bump_steer,
                            {"corner": "front_left"}),
    "camber_gain": Objective(camber_gain, "deg/m", "camber change (top outwards positive) per m of the wheel's "
                             "own travel (corner; front, rear: the axle's mean) at the design pose", "kinematics",
                             _camber_gain,
                             {"corner": "front_left"}),
    "chi": Objective(chi, "1", "front share of the lateral load transfer at low ay, between the two ay_g",
                     "load_transfer", _chi),
    "first_mode_frequency": Objective(first_mode_frequency, "Hz", "damped frequency of the first coupled chassis "
                                      "mode about straight running at speed_kmh", "linear", _frequency),
    "first_mode_damping_ratio": Objective(first_mode_damping_ratio, "1", "damping ratio of the first coupled "
                                          "chassis mode about straight running at speed_kmh", "linear", _damping),
    "yaw_rate_response_time": Objective(yaw_rate_response_time, "s", "yaw-rate response time of a small step "
                                        "steer (50 % input to 90 % steady, ISO 7401), linearised car",
                                        "steering_response", _response_time, STEP_OPTIONS),
    "yaw_rate_peak_time": Objective(yaw_rate_peak_time, "s", "yaw-rate peak time of a small step steer (from 50 % "
                                    "input), linearised car", "steering_response", _peak_time, STEP_OPTIONS),
    "yaw_rate_overshoot": Objective(yaw_rate_overshoot, "%", "yaw-rate overshoot of a small step steer, linearised "
                                    "car", "steering_response", _overshoot, STEP_OPTIONS),
    "yaw_rate_bandwidth": Objective(yaw_rate_bandwidth, "Hz", "first frequency where the yaw-rate gain per "
                                    "steering-wheel angle falls to -3 dB of its value at f_ref_hz",
                                    "steering_response", _bandwidth, BAND_OPTIONS),
    "yaw_rate_gain_peak": Objective(yaw_rate_gain_peak, "1", "largest yaw-rate gain up to f_max_hz over the gain "
                                    "at f_ref_hz", "steering_response", _gain_peak, BAND_OPTIONS),
    "step_steer_response_time": Objective(step_steer_response_time, "s", "yaw-rate response time of a step steer "
                                          "of any size (50 % input to 90 % steady, ISO 7401), the fast car's time "
                                          "run", "step_steer", lambda m: m.response_time),
    "step_steer_peak_time": Objective(step_steer_peak_time, "s", "yaw-rate peak time of a step steer of any size "
                                      "(from 50 % input), the fast car's time run", "step_steer",
                                      lambda m: m.peak_time),
    "step_steer_overshoot": Objective(step_steer_overshoot, "%", "yaw-rate overshoot of a step steer of any size, "
                                      "the fast car's time run", "step_steer", lambda m: m.overshoot),
    "step_steer_steady_yaw_rate": Objective(step_steer_steady_yaw_rate, "deg/s", "steady yaw rate after a step "
                                            "steer of any size, the fast car's time run", "step_steer",
                                            lambda m: m.steady),
    "braking_deceleration": Objective(braking_deceleration, "g", "mean deceleration over the hold of straight-line "
                                      "braking at decel_g (the most the car gives when the target is beyond it), "
                                      "the fast car's time run", "braking", lambda m: m.deceleration),
    "braking_pitch_gradient": Objective(braking_pitch_gradient, "deg/g", "pitch per g of deceleration in "
                                        "straight-line braking (negative: dive)", "braking",
                                        lambda m: m.pitch_gradient),
    "braking_front_load_share": Objective(braking_front_load_share, "1", "front axle's share of the tyre loads in "
                                          "straight-line braking", "braking", lambda m: m.front_load_share),
    "brake_in_turn_yaw_ratio": Objective(brake_in_turn_yaw_ratio, "1", "braking in a turn: yaw rate after_s into "
                                         "the braking over the initial circle's at the current speed (above 1: "
                                         "turns in)", "brake_in_turn", lambda m: m["yaw_rate_ratio_to_reference"]),
    "brake_in_turn_heading_deviation": Objective(brake_in_turn_heading_deviation, "deg", "braking in a turn: "
                                                 "heading deviation from the initial circle (into the turn "
                                                 "positive)", "brake_in_turn", lambda m: m["heading_deviation_deg"]),
    "brake_in_turn_path_deviation": Objective(brake_in_turn_path_deviation, "m", "braking in a turn: distance "
                                              "outside the initial circle (negative inside)", "brake_in_turn",
                                              lambda m: m["path_deviation_m"]),
    "rms_fz_variation": Objective(rms_fz_variation, "N", "RMS contact-patch load variation of one tyre over a "
                                  "four-post sine sweep (quasi-stationary, linearised car)", "road_response",
                                  _rms_fz, SWEEP_OPTIONS),
    "preview_length": Objective(preview_length, "m", "preview distance of the TI-optimal preview driver "
                                "(section 7.5)", "preview", lambda lp: lp),
}

#: The shared computation the frame's objectives name (:attr:`ObjectiveSpec.source_key`).
FRAME_SOURCE = "frame"
#: Objectives of the chassis frame (functions of a :class:`jaxveh.fe.Frame`): name ->
#: (function, units, description). Available in car studies with frame variables
#: (``frame.sections...`` paths, :mod:`optimise._frame_design`).
FRAME_OBJECTIVES = {
    "chassis_mass": (chassis_mass, "kg", "mass of the chassis frame (FE)"),
    "torsional_stiffness": (torsional_stiffness, "N m/deg", "torsional stiffness of the chassis frame (FE torsion "
                                                            "test)"),
}


class ObjectiveSpec(NamedTuple):
    """One objective of a study: its ``name`` in :data:`OBJECTIVES` and its ``settings``
    (sorted ``(key, value)`` pairs; hashable, so a spec can be a static argument)."""

    name: str
    settings: tuple

    @property
    def source_key(self) -> tuple:
        """``(source, settings of the source)``: objectives with one key share a computation
        (the frame's objectives: ``("frame", ())``)."""
        if self.name in FRAME_OBJECTIVES:
            return FRAME_SOURCE, ()
        objective = OBJECTIVES[self.name]
        own = SOURCES[objective.source].settings
        return objective.source, tuple((k, v) for k, v in self.settings if k in own)

    @property
    def options(self) -> dict:
        """The objective's own settings (beyond its source's)."""
        if self.name in FRAME_OBJECTIVES:
            return {}
        objective = OBJECTIVES[self.name]
        return {k: v for k, v in self.settings if k in objective.options}


def objective_spec(name: str, settings: dict | None = None, frame: bool = False) -> ObjectiveSpec:
    """An :class:`ObjectiveSpec` of ``name`` with ``settings`` over the defaults (settings
    that are arrays, a :class:`Source`'s prepared ones, are not part of the spec); with
    ``frame``, the frame's objectives (:data:`FRAME_OBJECTIVES`, no settings) too.
    ``ParameterError`` for an unknown objective or setting."""
    if frame and name in FRAME_OBJECTIVES:
        if settings:
            raise ParameterError(f"objective {name!r} has no setting {sorted(settings)[0]!r}: allowed none")
        return ObjectiveSpec(name, ())
    if name not in OBJECTIVES:
        extra = " (an objective of the frame, not of the car)" if name in FRAME_OBJECTIVES else ""
        raise ParameterError(f"objective {name!r} is not known{extra}: allowed {', '.join(OBJECTIVES)}")
    defaults = OBJECTIVES[name].settings
    settings = dict(settings or {})
    unknown = sorted(set(settings) - set(defaults))
    if unknown:
        raise ParameterError(f"objective {name!r} has no setting {unknown[0]!r}: allowed "
                             f"{', '.join(defaults) or 'none'}")
    merged = {**defaults, **settings}
    return ObjectiveSpec(name, tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in merged.items())))


def prepare(car, specs) -> dict:
    """The prepared (array) settings of every source of ``specs`` that needs them:
    ``{source_key: {name: array}}`` (NumPy, before tracing)."""
    out = {}
    for spec in specs:
        key = spec.source_key
        if key[0] == FRAME_SOURCE:
            continue
        source = SOURCES[key[0]]
        if source.prepare is not None and key not in out:
            out[key] = source.prepare(car, dict(key[1]))
    return out


def objective_values(car, specs, prepared=None, frame=None, reverse=False, overrides=None):
    """The values of the objectives ``specs`` (a tuple of :class:`ObjectiveSpec`) of ``car``
    as one array (their units, :func:`objective_units`), each shared computation done once;
    ``prepared``: :func:`prepare`'s arrays; ``frame``: the chassis frame, for the frame's
    objectives (:data:`FRAME_OBJECTIVES`). Pure and differentiable; NaN where a steady
    state, trim or time run failed. The time runs (``step_steer_*``) differentiate in forward
    mode (``jax.jacfwd``, what studies use) or, with ``reverse``, in reverse mode (``jax.grad``).
    ``overrides``: settings given as (traced) values to every computation that has them,
    e.g. ``{"speed_kmh": v}`` for a sweep over speed (one program for every speed)."""
    prepared = {} if prepared is None else prepared
    overrides = {} if overrides is None else overrides
    data = {}
    for spec in specs:
        key = spec.source_key
        if key[0] == FRAME_SOURCE:
            if frame is None:
                raise ParameterError(f"objective {spec.name!r} is a function of the chassis frame: it needs the "
                                     "frame (a study with frame variables)")
        elif key not in data:
            source = SOURCES[key[0]]
            extra = {"reverse": reverse} if source.time_run else {}
            settings = dict(key[1])
            settings |= {k: v for k, v in overrides.items() if k in settings}
            data[key] = source.compute(car, **settings, **prepared.get(key, {}), **extra)

    def value(s):
        if s.source_key[0] == FRAME_SOURCE:
            return FRAME_OBJECTIVES[s.name][0](frame)
        return OBJECTIVES[s.name].extract(data[s.source_key], **s.options)

    return jnp.stack([jnp.asarray(value(s), jnp.float64) for s in specs])


def objective_units(name: str) -> str:
    """The units of the objective ``name`` (of the car's or the frame's)."""
    return FRAME_OBJECTIVES[name][1] if name in FRAME_OBJECTIVES else OBJECTIVES[name].units
