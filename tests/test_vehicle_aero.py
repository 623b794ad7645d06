"""Aerodynamic loads (``jaxveh.vehicle._aero``): the tables against the quadratic law, the
element's forces on a free rigid body through the library (deceleration, heave and pitch
accelerations in closed form), reverse motion, and named errors."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh import multibody as mb, vehicle
from jaxveh._core import ParameterError

CDA, CLA, SHARE, RHO = 1.1, 2.6, 0.45, 1.2
MASS, IYY = 250.0, 90.0


@pytest.fixture(scope="module")
def car():
    b = mb.SystemBuilder(gravity=(0.0, 0.0, 0.0))
    b.add_rigid_body("car", MASS, np.diag([60.0, IYY, 110.0]))
    b.add_point("ref", "car", (0.0, 0.0, 0.0))
    b.add_point("front", "car", (0.8, 0.0, 0.0))
    b.add_point("rear", "car", (-0.75, 0.0, 0.0))
    for name in ("ux", "uy", "uz", "wx", "wy", "wz"):
        b.add_independent("car", name)
    system, params = b.build()
    aero = vehicle.aero_map_from_coefficients(CDA, CLA, SHARE, RHO)
    return system, params, vehicle.AeroLoads.on(system, "car", "ref", "front", "rear", aero)


def test_tables_follow_the_quadratic_law():
    aero = vehicle.aero_map_from_coefficients(CDA, CLA, SHARE, RHO)
    for u in (0.0, 10.0, 17.3, 25.0):
        drag, front, rear = aero.loads(u)
        q = 0.5 * RHO * u**2
        np.testing.assert_allclose(drag, q * CDA, rtol=2e-3, atol=1e-12)
        np.testing.assert_allclose(front + rear, q * CLA, rtol=2e-3, atol=1e-12)
        np.testing.assert_allclose(front, SHARE * (front + rear), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("yaw", [0.0, 0.6])
def test_loads_on_a_free_body(car, yaw):
    """Moving forward at 20 m/s (body axes): decelerates by drag / m, heaves down by the
    downforce / m, pitches by the front/rear split's moment / Iyy, whatever its yaw."""
    system, params, aero = car
    q = jnp.zeros(system.n_q).at[3].set(yaw)  # first rotation of the default sequence
    z = jnp.asarray([20.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    z_dot = mb.dynamics(system, params, q, z, elements=(aero,)).z_dot
    drag, front, rear = (float(x) for x in aero.aero.loads(20.0))
    np.testing.assert_allclose(z_dot[0], -drag / MASS, rtol=1e-12)
    np.testing.assert_allclose(z_dot[2], -(front + rear) / MASS, rtol=1e-12)
    np.testing.assert_allclose(z_dot[4], (0.8 * front - 0.75 * rear) / IYY, rtol=1e-12)
    np.testing.assert_allclose(z_dot[np.asarray([1, 3, 5])], 0.0, atol=1e-12)


def test_drag_opposes_reverse_motion(car):
    system, params, aero = car
    z = jnp.asarray([-12.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    z_dot = mb.dynamics(system, params, jnp.zeros(system.n_q), z, elements=(aero,)).z_dot
    assert float(z_dot[0]) > 0.0
    np.testing.assert_allclose(z_dot[0], float(aero.aero.loads(12.0)[0]) / MASS, rtol=1e-12)


def test_named_errors(car):
    system, _, _ = car
    with pytest.raises(ParameterError, match="front_share"):
        vehicle.aero_map_from_coefficients(1.0, 2.0, 1.5)
    with pytest.raises(ParameterError, match="start at 0"):
        vehicle.AeroMap(speed=jnp.asarray([5.0, 10.0]), drag=jnp.zeros(2), downforce_front=jnp.zeros(2),
                        downforce_rear=jnp.zeros(2))
    with pytest.raises(ParameterError, match="1-D tables"):
        vehicle.AeroMap(speed=jnp.asarray([0.0, 10.0]), drag=jnp.zeros(3), downforce_front=jnp.zeros(2),
                        downforce_rear=jnp.zeros(2))
