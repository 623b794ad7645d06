"""Root loci of the linearised car (Fig. 7.7): mode tracking along the coupling sweep (MAC
between neighbours), the uncoupled chassis modes at the free-free frequencies and modal
damping, the first chassis mode's coupled frequency, bad input and the CLI contract."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh import analysis
from jaxveh._core import ParameterError
from jaxveh.cli import app
from jaxveh.vehicle import load_car


@pytest.fixture(scope="module")
def car():
    return load_car(modes=6)


@pytest.fixture(scope="module")
def coupling(car):
    return analysis.root_locus(car, "coupling")


def test_tracked_modes_are_continuous(coupling):
    """Every mode's worst MAC between neighbouring points is at least 0.8 (the tracker
    halves an interval until it reaches 0.9), and each locus moves by small steps."""
    assert np.all(coupling.min_mac >= 0.8)
    assert coupling.values[0] == 0.0 and coupling.values[-1] == 1.0 and len(coupling.values) >= 11
    steps = np.abs(np.diff(coupling.eigenvalues, axis=0))
    assert np.max(steps) < 0.25 * np.max(np.abs(coupling.eigenvalues))


def test_uncoupled_chassis_modes_are_the_free_free_modes(car, coupling):
    """With coupling 0 the chassis modes leave the suspension: each free-free mode appears
    with its own natural frequency and its modal damping ratio (2.5 %)."""
    lam0 = coupling.eigenvalues[0]
    natural = np.abs(lam0) / (2.0 * np.pi)
    for f, zeta in zip(np.asarray(car.params.chassis.frequencies_hz), np.asarray(car.params.chassis.damping_ratios()),
                       strict=True):
        k = int(np.argmin(np.abs(natural - f)))
        np.testing.assert_allclose(natural[k], f, rtol=1e-4)
        np.testing.assert_allclose(coupling.damping_ratio[0, k], zeta, rtol=1e-3)


def test_first_chassis_mode_drops_when_coupled(car, coupling):
    j = analysis.first_chassis_mode(coupling, car)
    f0, f1 = coupling.frequency_hz[0, j], coupling.frequency_hz[-1, j]
    np.testing.assert_allclose(f0, float(car.params.chassis.frequencies_hz[0]) * np.sqrt(1 - 0.025**2), rtol=1e-4)
    assert f1 < 0.8 * f0  # the suspension's compliance lowers it (thesis: 38 -> about 17 Hz)


def test_bad_sweeps_are_refused_by_name(car):
    with pytest.raises(ParameterError, match="sweep = 'mass'"):
        analysis.root_locus(car, "mass")
    with pytest.raises(ParameterError, match="no chassis modes"):
        analysis.root_locus(load_car(modes=0), "coupling")
    with pytest.raises(ParameterError, match="out of range"):
        analysis.root_locus(car, "coupling", values=[0.0, 2.0])
    with pytest.raises(ParameterError, match="increasing"):
        analysis.root_locus(car, "speed", values=[50.0, 40.0])


def test_cli_root_locus_coupling_json(coupling):
    result = CliRunner().invoke(app, ["vehicle", "root-locus", "--sweep", "coupling", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    c = report["first_chassis_mode_hz"]
    assert set(c) >= {"uncoupled", "coupled"}
    assert c["coupled"] < c["uncoupled"]
    assert report["sweep"] == "coupling" and report["speed_kmh"] == pytest.approx(50.0)
    assert all(m["min_neighbour_mac"] >= 0.8 for m in report["modes"])


@pytest.mark.slow
def test_cli_root_locus_speed_json():
    """The speed sweep re-trims at every speed: the yaw/sideslip modes move with speed."""
    result = CliRunner().invoke(app, ["vehicle", "root-locus", "--sweep", "speed", "--json"])
    assert result.exit_code == 0, result.output
    report = json.loads(result.stdout)
    assert report["values"][0] == 5.0 and report["values"][-1] == 120.0 and report["speed_kmh"] is None
    lateral = [m for m in report["modes"] if m["label"].startswith("yaw/sideslip")]
    assert lateral and all(m["min_neighbour_mac"] >= 0.8 for m in report["modes"])
    spread = max(np.ptp(m["real_per_s"]) for m in lateral)
    assert spread > 1.0  # 1/s: the handling modes depend on speed
