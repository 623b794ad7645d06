"""Preview control of the chapter-3 vehicle (``jaxveh.analytic.state_space``): the flexible
chassis tends to the rigid one as µ grows, and the Fig. 3.11 trends hold."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh.analytic import state_space, with_distribution
from jaxveh.control import preview_controller, preview_distance
from jaxveh.params import load_analytic_vehicle

SPEED = 100 / 3.6
#: Kp of the flexible model at µ = 1e4 vs the rigid model: the torsion mode (~200 Hz)
#: still adds a residual compliance ~1/µ.
STIFF_LIMIT_RTOL = 1e-3


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


def _gains(vehicle, mu, rigid):
    a_c, b_c = state_space(with_distribution(vehicle, mu=mu), jnp.asarray(SPEED), rigid=rigid)
    return preview_controller(a_c, b_c, jnp.zeros(a_c.shape[0]).at[0].set(1.0))


@pytest.mark.slow
def test_flexible_tends_to_rigid_and_compliance_lengthens_preview(vehicle):
    rigid = _gains(vehicle, 1.0, True)
    stiff, soft = jax.vmap(lambda mu: _gains(vehicle, mu, False).preview)(jnp.array([1e4, 0.1]))
    scale = np.abs(np.asarray(rigid.preview)).max()
    np.testing.assert_allclose(stiff, rigid.preview, atol=STIFF_LIMIT_RTOL * scale)
    lp_rigid = preview_distance(rigid.preview, SPEED, interpolate=True)
    lp_soft = preview_distance(soft, SPEED, interpolate=True)
    # Fig. 3.11d: chassis compliance asks for a longer preview at high speed.
    assert float(lp_soft) > float(lp_rigid)
    assert float(rigid.residual) < 1e-12
