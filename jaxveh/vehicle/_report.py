"""What a chassis engineer asks of a car first: masses, corner weights, wheel and ride rates,
ride frequencies, roll stiffness per axle and its distribution λ, chassis modes, sizes.

:func:`car_rates` evaluates the formulas of :mod:`._rates` for the car's own springs (their
rate and static force at the design length, read from the spring tables), anti-roll bars,
tyres and hard points; :func:`vehicle_info` collects everything in a JSON-ready dict.
"""

import math

import jax
import jax.numpy as jnp

from ._car import CORNER_KEYS, Car, design_spring_lengths, total_mass
from ._rates import AxleRates, axle_rates, corner_sprung_masses, installation_ratios, roll_stiffness_distribution
from ._rigs import bump_rig, check_rig, roll_rig, steer_rig
from ._setup import StaticState, static_equilibrium

AXLES = ("front", "rear")


def spring_at_design(car: Car):
    """``(rate N/m, force N)`` of each corner's spring at its design length (the spring
    table's slope and value there; compression positive)."""
    lengths = design_spring_lengths(car.params.vehicle)

    def one(law, length):
        force, slope = jax.jvp(law.spring, (length,), (jnp.ones_like(length),))
        return -slope, force + law.bump_stop(length)

    return jax.vmap(one)(car.params.springs, lengths)


def car_rates(car: Car) -> dict[str, AxleRates]:
    """Front and rear :class:`AxleRates` of the car at its design position (left corner of
    each axle; the right mirrors it)."""
    v = car.params.vehicle
    rates, forces = spring_at_design(car)
    masses = corner_sprung_masses(v)
    out = {}
    for i, axle in enumerate(AXLES):
        corner = 2 * i
        ratios = installation_ratios(axle, v)
        track = v.track_front if axle == "front" else v.track_rear
        out[axle] = axle_rates(ratios, rates[corner], car.params.arb_rates[i], track,
                               car.params.tyres.vertical_stiffness[corner], masses[i], forces[corner])
    return out


def vehicle_info(car: Car, state: StaticState | None = None) -> dict:
    """Masses, static corner loads, rates, λ, chassis modes and model sizes (SI units and
    the units in the key names), ready for JSON. ``state``: the static set-up (computed
    when not given)."""
    state = static_equilibrium(car) if state is None else state
    v = car.params.vehicle
    rates = car_rates(car)
    system = car.system
    n_aux = 8 + 2  # tyre deflections, powertrain integral and speed filter
    modes = car.params.chassis
    return {
        "total_mass_kg": float(total_mass(v)),
        "sprung_mass_kg": float(v.sprung.mass),
        "unsprung_mass_kg": {"front": float(v.unsprung_front.body.mass), "rear": float(v.unsprung_rear.body.mass)},
        "corner_loads_n": {k: float(x) for k, x in zip(CORNER_KEYS, state.corner_loads, strict=True)},
        "front_load_share": float((state.corner_loads[0] + state.corner_loads[1]) / jnp.sum(state.corner_loads)),
        "wheel_rate_n_per_m": {a: float(rates[a].wheel_rate) for a in AXLES},
        "ride_frequency_hz": {a: float(rates[a].ride_frequency) for a in AXLES},
        "roll_stiffness_nm_per_deg": {a: float(rates[a].roll_stiffness_nm_per_deg) for a in AXLES},
        "roll_stiffness_arb_nm_per_deg": {a: float(rates[a].roll_stiffness_arb * math.pi / 180.0) for a in AXLES},
        "roll_stiffness_distribution": float(roll_stiffness_distribution(rates["front"], rates["rear"])),
        "chassis_modes_hz": [] if modes is None else [float(f) for f in modes.frequencies_hz],
        "chassis_damping_ratio": [] if modes is None else [float(z) for z in modes.damping_ratios()],
        "static": {
            "travel_mm": {k: 1e3 * float(x) for k, x in zip(CORNER_KEYS, state.travel, strict=True)},
            "spring_force_n": {k: float(x) for k, x in zip(CORNER_KEYS, state.spring_forces, strict=True)},
            "ride_height_change_mm": {"front": 1e3 * float(state.ride_heights[0]),
                                      "rear": 1e3 * float(state.ride_heights[1])},
            "pitch_deg": math.degrees(float(state.pitch)),
            "chassis_modal_coordinates": [float(p) for p in state.modes],
            "residual": float(state.residual),
        },
        "model": {
            "chassis_modes": car.n_modes,
            "bodies": system.n_bodies,
            "coordinates": system.n_q,
            "constraints": system.n_constraints,
            "independent_velocities": system.n_dof,
            "auxiliary_states": n_aux,
            "states": system.n_q + system.n_dof + n_aux,
        },
    }


def _list(x, scale=1.0):
    """Plain floats; NaN (undefined) becomes None so the JSON stays valid."""
    return [None if not math.isfinite(v) else v for v in (float(y) * scale for y in jnp.ravel(x))]


def bump_report(car: Car, travel_mm, flexible: bool = True, state=None) -> dict:
    """Bump rig of both axles as plain lists, the left wheel of each (contract of
    ``jaxveh rig bump --json``): ``travel_mm``, ``camber_deg``, ``toe_deg``, ``track_mm``,
    ``fz_n``, ``wheel_centre_x_mm``, ``wheel_centre_y_mm``."""
    out = {}
    for axle in AXLES:
        r = check_rig(car, f"bump rig, {axle} axle",
                      bump_rig(car, jnp.asarray(travel_mm, jnp.float64) * 1e-3, axle, state, flexible))
        out[axle] = {
            "travel_mm": _list(r["travel"][:, 0], 1e3),
            "camber_deg": _list(r["camber"][:, 0], 180.0 / math.pi),
            "toe_deg": _list(r["toe"][:, 0], 180.0 / math.pi),
            "track_mm": _list(r["track"], 1e3),
            "fz_n": _list(r["fz"][:, 0]),
            "wheel_centre_x_mm": _list(r["wheel_centre_x"][:, 0], 1e3),
            "wheel_centre_y_mm": _list(r["wheel_centre_y"][:, 0], 1e3),
        }
    return out


def steer_report(car: Car, steering_wheel_deg, flexible: bool = True, state=None) -> dict:
    """Steering rig as plain lists: ``steering_wheel_deg`` and under ``front``:
    ``left_deg``, ``right_deg`` (road-wheel angles, positive left), ``left_camber_deg``,
    ``right_camber_deg``, ``track_mm``, ``scrub_radius_mm`` (left wheel), ``ackermann_pct``
    (null at zero steer, where it is undefined)."""
    angles = jnp.asarray(steering_wheel_deg, jnp.float64)
    r = check_rig(car, "steer rig", steer_rig(car, jnp.radians(angles), state, flexible))
    deg = 180.0 / math.pi
    return {
        "steering_wheel_deg": _list(angles),
        "front": {
            "left_deg": _list(r["steer"][:, 0], deg),
            "right_deg": _list(r["steer"][:, 1], deg),
            "left_camber_deg": _list(r["camber"][:, 0], deg),
            "right_camber_deg": _list(r["camber"][:, 1], deg),
            "track_mm": _list(r["track"], 1e3),
            "scrub_radius_mm": _list(r["scrub_radius"][:, 0], 1e3),
            "ackermann_pct": _list(r["ackermann"]),
        },
    }


def roll_report(car: Car, roll_deg, flexible: bool = True, state=None) -> dict:
    """Roll rig as plain lists: ``roll_deg``; per axle the left wheel's ``camber_deg`` and
    ``toe_deg`` (road axes: roll camber, roll steer), the right wheel's, and the axle's
    ``roll_moment_nm``; ``roll_stiffness_nm_per_deg`` per axle at zero roll."""
    angles = jnp.asarray(roll_deg, jnp.float64)
    r = check_rig(car, "roll rig", roll_rig(car, jnp.radians(angles), state, flexible))
    zero = roll_rig(car, jnp.zeros((1,)), state, flexible)
    deg = 180.0 / math.pi
    out = {"roll_deg": _list(angles)}
    for i, axle in enumerate(AXLES):
        left, right = 2 * i, 2 * i + 1
        out[axle] = {
            "camber_deg": _list(r["camber"][:, left], deg),
            "toe_deg": _list(r["toe"][:, left], deg),
            "right_camber_deg": _list(r["camber"][:, right], deg),
            "right_toe_deg": _list(r["toe"][:, right], deg),
            "roll_moment_nm": _list(r["moment"][:, i]),
        }
    out["roll_stiffness_nm_per_deg"] = {a: float(zero["stiffness"][0, i]) / deg for i, a in enumerate(AXLES)}
    return out
