"""Suspension rates from the kinematics (``jaxveh.vehicle._rates``): installation ratios
against finite differences of the push-rod chain, roll stiffness against the energy of the
non-linear chain, the design of spring and anti-roll-bar rates, errors, and a gradient with
respect to a hard point."""

import math

import equinox as eqx
import jax
import numpy as np
import pytest

from jaxveh import vehicle
from jaxveh._core import ParameterError
from jaxveh.params import HARD_POINT_NAMES, load_analytic_vehicle, load_vehicle_data

H = 1e-4  # m, finite-difference step in wheel travel


@pytest.fixture(scope="module")
def data():
    return load_vehicle_data()


@pytest.mark.parametrize("axle", ["front", "rear"])
def test_installation_ratios_against_finite_differences(data, axle):
    r = vehicle.installation_ratios(axle, data)
    up, down = vehicle.installation_ratios(axle, data, H), vehicle.installation_ratios(axle, data, -H)
    np.testing.assert_allclose(r.spring, (up.spring_length - down.spring_length) / (2 * H), rtol=1e-6)
    np.testing.assert_allclose(r.rocker, (up.rocker_angle - down.rocker_angle) / (2 * H), rtol=1e-6)
    assert abs(float(r.rocker_angle)) < 1e-12  # design position
    assert -1.2 < float(r.spring) < -0.9  # the spring shortens about as much as the wheel rises


def test_roll_stiffness_is_the_energy_curvature_of_the_chain(data):
    """Roll the axle by ±φ (wheels at ±t φ / 2): springs and bar store E(φ); the axle's roll
    stiffness is E''(0) = 2 E(φ) / φ² for small φ."""
    k_s, k_arb, track = 30_000.0, 400.0, float(data.track_front)
    phi = 2e-3
    z = track * phi / 2
    design, up, down = (vehicle.installation_ratios("front", data, b) for b in (0.0, z, -z))
    springs = 0.5 * k_s * ((up.spring_length - design.spring_length) ** 2
                           + (down.spring_length - design.spring_length) ** 2)
    bar = 0.5 * k_arb * (up.rocker_angle - down.rocker_angle) ** 2
    rates = vehicle.axle_rates(design, k_s, k_arb, track, 150_000.0, 46.0)
    np.testing.assert_allclose(2 * (springs + bar) / phi**2, rates.roll_stiffness, rtol=2e-3)
    np.testing.assert_allclose(2 * springs / phi**2, rates.roll_stiffness_springs, rtol=2e-3)


def test_design_rates_reach_the_appendix_a_roll_stiffnesses(data):
    """Spring and bar rates for chosen ride frequencies give back those frequencies and
    Appendix A's 205 / 175 N m/deg (λ = 0.54) exactly."""
    analytic = load_analytic_vehicle()
    masses = vehicle.corner_sprung_masses(data)
    kz = data.tyre.kz
    axles = {}
    for axle, f, k_roll, track, m in (("front", 2.4, analytic.kF, data.track_front, masses[0]),
                                      ("rear", 2.0, analytic.kR, data.track_rear, masses[1])):
        r = vehicle.installation_ratios(axle, data)
        k_s, k_arb = vehicle.design_rates(r, f, k_roll, track, kz, m)
        assert float(k_s) > 0 and float(k_arb) > 0
        axles[axle] = vehicle.axle_rates(r, k_s, k_arb, track, kz, m)
        np.testing.assert_allclose(axles[axle].ride_frequency, f, rtol=1e-12)
        np.testing.assert_allclose(axles[axle].roll_stiffness, k_roll, rtol=1e-12)
    np.testing.assert_allclose(axles["front"].roll_stiffness_nm_per_deg, 205.0, rtol=2e-3)
    np.testing.assert_allclose(axles["rear"].roll_stiffness_nm_per_deg, 175.0, rtol=2e-3)
    lam = vehicle.roll_stiffness_distribution(axles["front"], axles["rear"])
    np.testing.assert_allclose(lam, float(analytic.kF / (analytic.kF + analytic.kR)), rtol=1e-12)


def test_design_rates_refuse_unreachable_targets(data):
    r = vehicle.installation_ratios("rear", data)
    with pytest.raises(ParameterError, match="roll_stiffness"):  # springs alone too stiff in roll
        vehicle.design_rates(r, 3.5, 10_000.0, 1.21, 150_000.0, 66.0)
    with pytest.raises(ParameterError, match="ride_frequency"):  # stiffer than the tyre
        vehicle.design_rates(r, 40.0, 1e6, 1.21, 150_000.0, 66.0)
    with pytest.raises(ParameterError, match="axle"):
        vehicle.installation_ratios("middle", data)


def test_spring_ratio_gradient_wrt_rocker_pivot_height(data):
    """d(dl_s/dz)/d(z of the rocker point P) by jax.grad through the assembly and the chain,
    against a central difference."""
    k = HARD_POINT_NAMES.index("P")

    def ratio(dz):
        points = data.hard_points_front.points.at[k, 2].add(dz)
        moved = eqx.tree_at(lambda d: d.hard_points_front.points, data, points)
        return vehicle.installation_ratios("front", moved).spring

    grad = float(jax.grad(ratio)(0.0))
    h = 1e-5
    fd = (float(ratio(h)) - float(ratio(-h))) / (2 * h)
    assert abs(grad) > 0.1  # per metre: the pivot height matters
    np.testing.assert_allclose(grad, fd, rtol=1e-5)
    assert math.isfinite(grad)
