"""CLI contracts of ``jaxveh analytic`` and ``jaxveh run`` (checked by users' scripts)."""

import json

import pytest
import typer.main
from typer.testing import CliRunner

from jaxveh.cli import app

runner = CliRunner()


def _json(args):
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def test_lltd_contract():
    out = _json(["analytic", "lltd", "--lam", "0.54", "--mu", "1", "--json"])
    for key in ("chi", "chi_rigid", "zeta", "dchi_dlam"):
        assert isinstance(out[key], float)
    assert out["chi"] < out["chi_rigid"]  # λ > ζ: a flexible chassis moves load transfer rearwards


def test_understeer_contract():
    out = _json(["analytic", "understeer", "--lam", "0.54", "--mu", "1", "--json"])
    assert out["ku_rigid_deg_per_g"] == pytest.approx(0.74, abs=0.005)
    assert isinstance(out["ku_deg_per_g"], float)


def test_eig_contract():
    out = _json(["analytic", "eig", "--speed-kmh", "50", "--mu", "1", "--json"])
    labels = {m["label"] for m in out["modes"]}
    assert {"torsion", "roll", "yaw/sideslip"} <= labels
    for m in out["modes"]:
        assert m["freq_hz"] > 0 and 0 < m["damping_ratio"] <= 1


def test_step_steer_contract():
    out = _json(["analytic", "step-steer", "--speed-kmh", "90", "--t-end", "3", "--json"])
    for name in ("rigid", "flexible"):
        for key in ("yaw_rate_response_time_s", "yaw_rate_overshoot_pct", "ay_steady_g"):
            assert isinstance(out[name][key], float)
    assert 0.5 < out["rigid"]["ay_steady_g"] < 0.9


def test_map_writes_plot_and_json(tmp_path):
    args = ["analytic", "map", "--quantity", "ku_error", "--n-lam", "5", "--n-mu", "4", "--json"]
    args += ["--out", str(tmp_path)]
    out = _json(args)
    assert len(out["values"]) == 5 and len(out["values"][0]) == 4
    assert (tmp_path / "map_ku_error.png").stat().st_size > 1000
    assert (tmp_path / "map_ku_error.json").exists()


@pytest.mark.parametrize(
    "args,message",
    [
        (["analytic", "lltd", "--lam", "1.5"], "lam (roll stiffness proportion kF/(kF+kR)) must be in (0, 1)"),
        (
            ["analytic", "understeer", "--mu", "-1"],
            "mu (normalised chassis torsional stiffness kC/(kF+kR)) must be > 0",
        ),
        (["analytic", "eig", "--speed-kmh", "0"], "speed_kmh must be > 0"),
        (["analytic", "map", "--quantity", "grip"], "quantity must be one of"),
        (["analytic", "lltd", "--vehicle", "missing.toml"], "vehicle file 'missing.toml' does not exist"),
    ],
)
def test_bad_input_named_errors(args, message):
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert message in result.output


def test_preview_contract():
    out = _json(["analytic", "preview", "--speed-kmh", "100", "--mu", "1", "--json"])
    assert isinstance(out["preview_distance_m"], float)
    assert len(out["gains"]) == 201 and all(isinstance(g, float) for g in out["gains"])
    # Lp is a multiple of u dt and lies within the previewed 200 points.
    step = 100 / 3.6 * 0.01
    assert 0 < out["preview_distance_m"] <= 200 * step
    assert out["preview_distance_m"] / step == pytest.approx(round(out["preview_distance_m"] / step), abs=1e-9)
    assert out["riccati_residual"] < 1e-9


@pytest.mark.parametrize("group", ["analytic", "tyre", "chassis", "multibody", "run"])
def test_json_option_is_bound_to_as_json(group):
    """`--json` is one parameter name everywhere (`as_json`), never `json` or `json_out`."""
    root = typer.main.get_command(app)
    command = root.commands[group]
    commands = list(command.commands.items()) if hasattr(command, "commands") else [(group, command)]
    checked = 0
    for name, cmd in commands:
        for param in cmd.params:
            if "--json" in getattr(param, "opts", []):
                assert param.name == "as_json", f"{group} {name}: --json is bound to {param.name!r}"
                checked += 1
    assert checked >= 1
