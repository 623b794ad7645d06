"""Input validation of the analytic API: named errors for bad inputs, concrete and traced,
and no false alarms on the legitimate edges (λ = 0 and 1, roll centres below ground, zero
damping)."""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxveh.analytic as an
from jaxveh.analytic._maps import design_map, minimum_stiffness
from jaxveh.params import ParameterError, load_analytic_vehicle

STATE = jnp.zeros(9).at[1].set(0.1)  # straight running with some yaw rate


@pytest.fixture(scope="module")
def vehicle():
    return load_analytic_vehicle()


@pytest.mark.parametrize(
    "changes, match",
    [
        ({"ms": -1.0}, r"AnalyticVehicle\.ms must lie in \(0, inf\) \(sprung mass, kg\); got -1"),
        ({"muR": 0.0}, r"AnalyticVehicle\.muR must lie in \(0, inf\) \(rear unsprung mass, kg\); got 0"),
        ({"JrF": 0.0}, r"AnalyticVehicle\.JrF must lie in \(0, inf\) \(front half roll inertia, kg m2\)"),
        ({"t": -1.2}, r"AnalyticVehicle\.t must lie in \(0, inf\) \(front and rear track, m\)"),
        ({"bs": 0.0}, r"AnalyticVehicle\.bs must lie in \(0, inf\) \(sprung mass c\.g\. to rear axle, m\)"),
        ({"hsR": np.nan}, r"AnalyticVehicle\.hsR must lie in \(0, inf\)"),
        ({"kC": 0.0}, r"AnalyticVehicle\.kC must lie in \(0, inf\) \(chassis torsional stiffness, Nm/rad\)"),
        ({"kF": -10.0}, r"AnalyticVehicle\.kF must lie in \[0, inf\) \(front roll stiffness, Nm/rad\)"),
        ({"cR": -1.0}, r"AnalyticVehicle\.cR must lie in \[0, inf\) \(rear roll damping, Nms/rad\)"),
        ({"epsF": 1.5}, r"AnalyticVehicle\.epsF must lie in \(-1, 1\] \(front roll steer coefficient\)"),
        ({"k_stw": 0.0}, r"AnalyticVehicle\.k_stw must lie in \(0, inf\) \(steering ratio\)"),
        ({"kF": 0.0, "kR": 0.0}, r"AnalyticVehicle: kF \+ kR must lie in \(0, inf\) \(total roll stiffness"),
        ({"hsF": 0.02}, r"AnalyticVehicle: hsF - zF must lie in \(0, inf\) \(front sprung c\.g\. above its roll"),
        ({"JrR": 0.1}, r"AnalyticVehicle: mass matrix \(3\.31\) must lie in \(0, inf\)"),
    ],
)
def test_bad_vehicle_fields_name_field_and_range(vehicle, changes, match):
    # On construction ...
    with pytest.raises(ParameterError, match=match):
        dataclasses.replace(vehicle, **changes)
    # ... and in every analytic function, for values set with eqx.tree_at (no __init__).
    names = tuple(changes)
    bad = eqx.tree_at(lambda v: [getattr(v, n) for n in names], vehicle, [jnp.asarray(x) for x in changes.values()])
    with pytest.raises(ParameterError, match=match):
        an.chi(bad)
    with pytest.raises(ParameterError, match=match):
        an.vector_field(bad, STATE, 20.0, 0.01, an.FLEXIBLE)


@pytest.mark.parametrize(
    "name, value, match",
    [
        ("shape", 2.5, r"AxleTyre\.shape must lie in \(1, 2\] \(MF shape factor C\); got 2\.5"),
        ("curvature", 1.0, r"AxleTyre\.curvature must lie in \(-inf, 1\) \(MF curvature factor E\)"),
        ("fz0", 0.0, r"AxleTyre\.fz0 must lie in \(0, inf\) \(nominal tyre load, N\)"),
        ("scale_rear", -1.0, r"AxleTyre\.scale_rear must lie in \(0, inf\)"),
    ],
)
def test_bad_axle_tyre(vehicle, name, value, match):
    with pytest.raises(ParameterError, match=match):
        dataclasses.replace(vehicle.tyre, **{name: value})
    bad = eqx.tree_at(lambda v: getattr(v.tyre, name), vehicle, jnp.asarray(value))
    with pytest.raises(ParameterError, match=match):
        an.understeer_gradient(bad)
    with pytest.raises(ParameterError, match=match):
        an.lateral_force(bad.tyre, 0.02, 1000.0, 1.0)


def test_traced_bad_values_raise_at_run_time(vehicle):
    """An optimiser's traced values: eqx.error_if, no silent NaN."""

    @eqx.filter_jit
    def chi_of_ms(ms):
        return an.chi(eqx.tree_at(lambda v: v.ms, vehicle, ms))

    assert np.isfinite(float(chi_of_ms(jnp.asarray(200.0))))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"AnalyticVehicle\.ms must lie in \(0, inf\)"):
        chi_of_ms(jnp.asarray(-200.0))

    @eqx.filter_jit
    def ku_of_lam(lam):
        return an.understeer_gradient(an.with_distribution(vehicle, lam=lam))

    with pytest.raises(eqx.EquinoxRuntimeError, match=r"lam must lie in \[0, 1\] \(roll stiffness proportion"):
        ku_of_lam(jnp.asarray(1.2))
    # Under eager jax.grad the tracers carry known values: the named error is raised at once.
    with pytest.raises(ParameterError, match=r"mu must lie in \(0, inf\)"):
        jax.grad(lambda mu: an.chi(an.with_distribution(vehicle, mu=mu)))(jnp.asarray(-0.5))
    # Speed traced in a vmapped linearisation.
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"speed must lie in \(0, inf\) \(forward speed u"):
        eqx.filter_jit(jax.vmap(lambda u: an.eigenvalues(vehicle, u)))(jnp.asarray([10.0, 0.0]))


def _simulate(vehicle, t_end=1.0, **kwargs):
    return an.simulate(vehicle, an.ConstantSteer(0.01), an.RIGID, 20.0, t_end, **kwargs)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda v: an.with_distribution(v, lam=1.5), r"lam must lie in \[0, 1\]"),
        (lambda v: an.with_distribution(v, mu=0.0), r"mu must lie in \(0, inf\)"),
        (lambda v: an.vector_field(v, STATE, 0.0, 0.0, an.RIGID), r"speed must lie in \(0, inf\)"),
        (lambda v: an.state_space(v, -10.0), r"speed must lie in \(0, inf\)"),
        (lambda v: an.vehicle_modes(v, 0.0), r"speed must lie in \(0, inf\)"),
        (lambda v: an.frequency_response(v, 10.0, [-1.0, 1.0]), r"freqs_hz must lie in \[0, inf\) \(frequency, Hz\)"),
        (lambda v: an.skidpad_steady_state(v, 0.0, an.RIGID), r"ay must lie in \(0, inf\) \(lateral acceleration"),
        (lambda v: an.skidpad_steady_state(v, 5.0, an.RIGID, radius=0.0), r"radius must lie in \(0, inf\)"),
        (lambda v: an.skidpad_sweep(v, jnp.asarray([0.0, 5.0]), an.RIGID), r"ay must lie in \(0, inf\)"),
        (lambda v: an.steering_sensitivity(v, -1.0, an.RIGID), r"ay must lie in \(0, inf\)"),
        (lambda v: _simulate(v, t_end=0.0), r"t_end must lie in \(0, inf\)"),
        (lambda v: _simulate(v, n_save=1), r"n_save must be a Python int >= 2"),
        (lambda v: _simulate(v, rtol=0.0), r"rtol must lie in \(0, inf\)"),
        (lambda v: _simulate(v, y0=jnp.zeros(8)), r"y0 must have shape \(9,\)"),
        (lambda v: an.SmoothStep(0.02, 0.0, 0.0), r"SmoothStep\.rise must lie in \(0, inf\) \(rise time, s\)"),
        (lambda v: design_map(v, "chi", [0.5], [0.0]), r"mu_values must lie in \(0, inf\)"),
        (lambda v: design_map(v, "chi", [-0.1], [1.0]), r"lam_values must lie in \[0, 1\]"),
        (lambda v: minimum_stiffness(v, "chi_error", 0.02, (0.7, 0.3)), r"lam_range must satisfy low < high"),
        (lambda v: minimum_stiffness(v, "chi_error", 0.02, mu_bounds=(0.0, 10.0)), r"mu_bounds must lie in \(0, inf\)"),
    ],
)
def test_bad_arguments_name_argument_and_range(vehicle, call, match):
    with pytest.raises(ParameterError, match=match):
        call(vehicle)


def test_step_steer_metrics_window(vehicle):
    steer = an.SmoothStep(0.02, 0.0, 0.1)
    traj = an.simulate(vehicle, steer, an.RIGID, 20.0, 1.0, n_save=11)
    with pytest.raises(ParameterError, match=r"settle_window must lie in \(0, 1\)"):
        an.step_steer_metrics(traj, steer, settle_window=2.0)


def test_traced_smooth_step_rise_is_checked():
    step = eqx.filter_jit(lambda rise: an.SmoothStep(0.02, 0.0, rise)(0.05))
    assert float(step(jnp.asarray(0.1))) == pytest.approx(0.01)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"SmoothStep\.rise must lie in \(0, inf\)"):
        step(jnp.asarray(0.0))


def test_legitimate_edges_are_not_refused(vehicle):
    # λ = 0 and 1 are the edges of Figs. 3.3, 3.4; the maps are finite there.
    grid = np.asarray(design_map(vehicle, "chi", [0.0, 1.0], [0.1, 10.0]))
    assert np.all(np.isfinite(grid))
    # Roll centres below the ground, negative roll steer, zero damping: valid vehicles.
    v = dataclasses.replace(vehicle, zF=-0.02, epsR=-0.05, cF=0.0, cR=0.0, cC=0.0)
    assert np.isfinite(float(an.understeer_gradient(v)))
    assert np.all(np.isfinite(np.asarray(an.eigenvalues(v, 15.0))))
    # A wheel lifting off in the (3.27) tyre is the model's own business: zero force, no error.
    assert float(an.lateral_force(vehicle.tyre, 0.05, -100.0, 1.0)) == 0.0


def test_checks_do_not_retrace(vehicle):
    @eqx.filter_jit
    @eqx.debug.assert_max_traces(max_traces=1)
    def ku(v):
        return an.understeer_gradient(v)

    ku(vehicle)
    ku(eqx.tree_at(lambda v: v.kC, vehicle, vehicle.kC * 2.0))
