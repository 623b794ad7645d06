"""``jaxveh chassis`` command line: JSON contracts, files written, named errors."""

import inspect
import json

import numpy as np
import pytest
from typer.testing import CliRunner

from jaxveh.cli import app

runner = CliRunner()


def run_json(*args):
    r = runner.invoke(app, ["chassis", *args, "--json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def test_torsion_json():
    out = run_json("torsion")
    assert set(out) >= {"torsional_stiffness_Nm_per_deg", "mass_kg"}
    assert 300.0 < out["torsional_stiffness_Nm_per_deg"] < 500.0
    assert 20.0 < out["mass_kg"] < 27.0


@pytest.mark.parametrize("method", ["truncation", "craig-bampton"])
def test_modes_json(method):
    out = run_json("modes", "--n", "6", "--method", method)
    assert len(out["modes"]) == 6
    f = [m["freq_hz"] for m in out["modes"]]
    assert f == sorted(f) and f[0] > 20.0
    assert all(isinstance(m["label"], str) and m["label"] for m in out["modes"])
    # default modal damping (thesis 7.3): ζ = 0.025 on every mode
    assert out["damping"] == {"damping_ratio": 0.025, "alpha": 0.0, "beta": 0.0}
    assert [m["damping_ratio"] for m in out["modes"]] == [0.025] * 6


def test_modes_rayleigh_damping_ratios():
    """--beta alone selects Rayleigh damping: ζ_i = β ω_i / 2, over-critical for β = 0.01 s."""
    out = run_json("modes", "--n", "2", "--beta", "0.01")
    for m in out["modes"]:
        assert m["damping_ratio"] == pytest.approx(0.01 * np.pi * m["freq_hz"], rel=1e-12)
    assert out["modes"][0]["damping_ratio"] > 1.0
    r = runner.invoke(app, ["chassis", "modes", "--n", "1", "--beta", "0.01"])
    assert r.exit_code == 0 and "(over-critical)" in r.output and "zeta 1.2355" in r.output


def test_json_option_does_not_shadow_json_module():
    from jaxveh.cli import _chassis

    for command in (_chassis.torsion, _chassis.modes, _chassis.compare):
        params = inspect.signature(command).parameters
        assert "as_json" in params and "json" not in params


def test_compare_json():
    out = run_json("compare", "--n", "8")
    assert len(out["nrfd"]) == 8 and len(out["mac_diagonal"]) == 8
    assert max(out["nrfd"][:4]) < 1e-2


@pytest.mark.slow
def test_export_and_plot(tmp_path):
    r = runner.invoke(app, ["chassis", "export", "--out", str(tmp_path / "m.npz"), "--n", "4"])
    assert r.exit_code == 0, r.output
    with np.load(tmp_path / "m.npz") as d:
        assert d["K"].shape == d["M"].shape and d["modes"].shape[1] == 4
        assert d["dof_map"].shape == (d["K"].shape[0], 2)
    r = runner.invoke(app, ["chassis", "plot", "--out", str(tmp_path / "fig")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "fig" / "frame.png").stat().st_size > 10_000
    assert (tmp_path / "fig" / "modes.png").stat().st_size > 10_000


def test_bad_options_are_named_errors(tmp_path):
    r = runner.invoke(app, ["chassis", "modes", "--n", "100000", "--json"])
    assert r.exit_code != 0 and "--n" in r.output and "n_modes = 100000 is out of range" in r.output
    r = runner.invoke(app, ["chassis", "modes", "--damping-ratio", "1.5"])
    assert r.exit_code != 0 and r"damping_ratio must lie in [0, 1)" in r.output
    r = runner.invoke(app, ["chassis", "modes", "--alpha", "-1"])
    assert r.exit_code != 0 and "alpha (Rayleigh mass-proportional damping, 1/s) must lie in [0, inf)" in r.output
    r = runner.invoke(app, ["chassis", "modes", "--method", "guyan"])
    assert r.exit_code != 0 and "method = 'guyan'" in r.output
    r = runner.invoke(app, ["chassis", "torsion", "--frame", str(tmp_path / "no.toml")])
    assert r.exit_code != 0 and "does not exist" in r.output
    r = runner.invoke(app, ["chassis", "export", "--out", str(tmp_path / "m.txt")])
    assert r.exit_code != 0 and "--out must end in .npz" in r.output
