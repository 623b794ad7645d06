"""The fast car's four-corner push-rod suspension against the library's two
PushrodSuspension elements: the same point forces at random point positions and
velocities; the other elements kept, in order."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.multibody as mb
from jaxveh.vehicle import ConstantSpeed, PushrodSuspension, car_elements, fast_dynamics, fast_model, load_car
from jaxveh.vehicle._fast_suspension import split_suspensions, suspension_forces


@pytest.fixture(scope="module")
def setup():
    car = load_car(modes=6)
    elements = car_elements(car, ConstantSpeed(25.0))
    model = fast_model(car)
    q = jnp.zeros(20).at[2].set(0.01).at[12:16].set(0.004)
    u = jnp.zeros(20).at[0].set(25.0).at[16:].set(80.0)
    kin = jax.jit(lambda q, u: fast_dynamics(car, model, q, u, jnp.zeros(10), 0.3, lambda t: jnp.zeros(1),
                                             elements).kinematics)(q, u)
    return car, model, elements, kin


def test_split_keeps_other_elements_in_order(setup):
    _, _, elements, _ = setup
    suspensions, others = split_suspensions(elements)
    assert [type(e) for e in others] == [type(e) for e in elements if not isinstance(e, PushrodSuspension)]
    assert len(suspensions.points) == 4
    assert suspensions.partner == (1, 0, 3, 2)


def test_same_forces_as_library_elements(setup):
    car, model, elements, kin = setup
    pushrods = tuple(e for e in elements if isinstance(e, PushrodSuspension))
    suspensions, _ = split_suspensions(elements)
    library = jax.jit(lambda k: mb.element_forces(car.system, model.params, pushrods, k, jnp.zeros((0,)))[0])
    fast = jax.jit(lambda k: suspension_forces(suspensions, k))
    rng = np.random.default_rng(0)
    for _ in range(10):
        moved = mb.Kinematics(**{**vars(kin), "x": kin.x + rng.normal(size=kin.x.shape) * 3e-3,
                                 "xd": kin.xd + rng.normal(size=kin.x.shape) * 0.5})
        expected, got = library(moved), fast(moved)
        assert float(jnp.max(jnp.abs(got - expected))) <= 1e-12 * float(jnp.max(jnp.abs(expected)))
