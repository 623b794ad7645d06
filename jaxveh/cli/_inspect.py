"""Numerical "symbolic inspection" (thesis section 5.7) of the built-in example systems for
``jaxveh multibody inspect``: reduced mass matrix, forces and ``R`` at a state. It lives
with the CLI because it gathers examples from both the multibody library and the vehicle.
"""

import jax.numpy as jnp
import numpy as np

from ..multibody import dynamics
from ..multibody._examples import (
    DOUBLE_PENDULUM_DEFAULTS,
    FOUR_BAR_DEFAULTS,
    double_pendulum,
    double_pendulum_state,
    flexible_pendulum,
    flexible_pendulum_state,
    four_bar,
    four_bar_angles,
)
from ..params import ParameterError
from ..vehicle import quarter_car, quarter_car_kinematics

#: Examples known to :func:`inspect_example`, with the meaning of their ``q`` / ``qdot``.
EXAMPLES = {
    "double-pendulum": ("theta1 (rad, absolute), theta2 (rad, relative)", "theta1_dot, theta2_dot (rad/s)"),
    "four-bar": ("crank angle (rad, from +y)", "crank rate (rad/s)"),
    "quarter-car": ("bump travel (m), rack travel (m)", "bump rate (m/s), wheel spin rate (rad/s)"),
    "flexible-pendulum": ("swing angle (rad), modal coordinates p0, p1", "swing rate (rad/s), modal rates"),
}
_DEFAULT_Q = {
    "double-pendulum": ((0.0, 0.0), (0.0, 0.0)),
    "four-bar": ((0.7,), (0.0,)),
    "quarter-car": ((0.0, 0.0), (0.0, 0.0)),
    "flexible-pendulum": ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0)),
}


def _example_state(name, q, qdot, values):
    """``(system, params, q_full, z, inputs, param_values)`` for an example at (q, qdot)."""
    if name == "double-pendulum":
        unknown = sorted(set(values) - set(DOUBLE_PENDULUM_DEFAULTS))
        if unknown:
            raise ParameterError(f"unknown --param {unknown}; allowed {sorted(DOUBLE_PENDULUM_DEFAULTS)}")
        v = {**DOUBLE_PENDULUM_DEFAULTS, **values}
        for k in ("m1", "m2", "l1"):
            if not v[k] > 0.0:
                raise ParameterError(f"--param {k}={v[k]:g} must be > 0")
        for k in ("J1", "J2"):
            if not v[k] >= 0.0:
                raise ParameterError(f"--param {k}={v[k]:g} must be >= 0")
        system, params = double_pendulum(v)
        qf, z = double_pendulum_state(system, params, q, qdot)
        return system, params, qf, z, None, v
    if name == "four-bar":
        unknown = sorted(set(values) - set(FOUR_BAR_DEFAULTS))
        if unknown:
            raise ParameterError(f"unknown --param {unknown}; allowed {sorted(FOUR_BAR_DEFAULTS)}")
        v = {**FOUR_BAR_DEFAULTS, **values}
        system, params = four_bar(v)
        coupler, rocker = four_bar_angles(q[0], v)
        qf = jnp.asarray([q[0], coupler - q[0], rocker])
        return system, params, qf, jnp.asarray(qdot, jnp.float64), None, v
    if values:
        raise ParameterError(f"example {name!r} takes no --param")
    if name == "quarter-car":
        system, params = quarter_car()
        qf, _ = quarter_car_kinematics(system, params, q[0], q[1])
        rack = jnp.asarray(q[1], jnp.float64)
        inputs = lambda t: jnp.reshape(rack, (1,))  # noqa: E731
        return system, params, qf, jnp.asarray(qdot, jnp.float64), inputs, {}
    system, params = flexible_pendulum()
    qf, _ = flexible_pendulum_state(system, q[0], q[1:])
    return system, params, qf, jnp.asarray(qdot, jnp.float64), None, {}


def inspect_example(name: str, q=None, qdot=None, values: dict | None = None) -> dict:
    """Reduced mass matrix, reduced internal and external forces and ``R`` of a built-in
    example at independent positions ``q`` and velocities ``qdot`` (see :data:`EXAMPLES`).

    ``internal_forces``: gyroscopic / Coriolis / centrifugal / elastic / damping forces
    reduced to the independent velocities, ``R^T T^T (Q_v + Q_e - M (T_dot y + T S c))``;
    ``external_forces``: gravity (and applied loads) reduced, ``R^T T^T Q_ext``. For the
    double pendulum these are the ``M``, ``Qi``, ``Qe`` printed in thesis section 5.7.
    """
    if name not in EXAMPLES:
        raise ParameterError(f"unknown example {name!r}; choose one of {sorted(EXAMPLES)}")
    dq, dqd = _DEFAULT_Q[name]
    q = tuple(dq) if q is None else tuple(float(x) for x in q)
    qdot = tuple(dqd) if qdot is None else tuple(float(x) for x in qdot)
    if len(q) != len(dq):
        raise ParameterError(f"--q for {name} takes {len(dq)} values: {EXAMPLES[name][0]}; got {len(q)}")
    if len(qdot) != len(dqd):
        raise ParameterError(f"--qdot for {name} takes {len(dqd)} values: {EXAMPLES[name][1]}; got {len(qdot)}")
    system, params, qf, z, inputs, used = _example_state(name, q, qdot, dict(values or {}))
    dyn = dynamics(system, params, qf, z, 0.0, inputs)
    return {
        "example": name,
        "q": list(q),
        "qdot": list(qdot),
        "independent_velocities": [system.y_names[k] for k in system.independent],
        "mass_matrix": np.asarray(dyn.mass_matrix).tolist(),
        "internal_forces": np.asarray(dyn.internal_forces).tolist(),
        "external_forces": np.asarray(dyn.external_forces).tolist(),
        "R": np.asarray(dyn.projection.R).tolist(),
        "joint_velocity_names": list(system.y_names),
        "constraint_residual": float(np.max(np.abs(np.asarray(dyn.projection.phi)), initial=0.0)),
        "params": {k: float(v) for k, v in used.items()},
    }
