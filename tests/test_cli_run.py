"""The main job's report: ``jaxveh run --chapter3-only`` writes the summary, the figures and
the one-page report; the report puts the car's numbers beside the thesis's (the full car
section's pieces are tested in the manoeuvre and vehicle modules)."""

import json

from typer.testing import CliRunner

from jaxveh.cli import app
from jaxveh.cli._run_car import report_markdown


def test_chapter3_main_job_writes_summary_and_report(tmp_path):
    result = CliRunner().invoke(app, ["run", "--out", str(tmp_path), "--chapter3-only", "--json", "--quiet"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert "car" not in summary and 0.0 < summary["load_transfer"]["chi"] < 1.0
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    report = (tmp_path / "report.md").read_text()
    assert "## The chapter-3 model" in report and "## The 14-DOF car" not in report
    for png in ("skidpad.png", "step_steer.png", "bode.png"):
        assert (tmp_path / png).stat().st_size > 10_000 and f"]({png})" in report


def test_report_puts_the_car_beside_the_thesis():
    step = {"yaw_rate_response_time_s": 0.1, "yaw_rate_peak_time_s": 0.2, "yaw_rate_overshoot_pct": 5.0,
            "yaw_rate_steady_deg_s": 20.0, "ay_steady_g": 0.9, "steps": 300}
    pad = {"understeer_gradient_deg_per_g": -0.165, "ay_limit_g": 1.7, "roll_at_0.4g_deg": 0.83,
           "roll_at_1g_deg": 2.01, "sideslip_at_1g_deg": -1.26, "lltd_front_share_at_1g": float("nan")}
    summary = {
        "vehicle": "appendix_a.toml", "wall_time_s": 300.0,
        "load_transfer": {"chi": 0.445, "chi_rigid": 0.45}, "understeer": {"ku_deg_per_g": 0.7,
                                                                          "ku_rigid_deg_per_g": 0.74},
        "step_steer_90kmh": {"rigid": step, "flexible": step},
        "car": {"set_up": {"total_mass_kg": 300.0, "front_load_share": 0.39, "roll_stiffness_distribution": 0.54,
                           "chassis_modes_hz": [30.0, 40.0]},
                "skid_pad": {"rigid": pad, "flexible": pad}, "step_steer_90kmh": {"rigid": step, "flexible": step}},
    }
    report = report_markdown(summary)
    assert "| understeer gradient, deg/g (0.05 g) | -0.165 | -0.165 |" in report
    assert "| roll at 1 g, deg | 2.01 | 2.01 | about 2 |" in report
    assert "| front share of load transfer at 1 g | n/a | n/a |" in report  # beyond the curve
    assert "![skid-pad](car_skid_pad.png)" in report and "30.0, 40.0 Hz" in report


def test_help_texts_keep_square_brackets():
    """Units and study-file keys in square brackets are part of the help (Rich markup would
    swallow them as tags)."""
    runner = CliRunner()
    tyre = runner.invoke(app, ["tyre", "eval", "--help"], terminal_width=200)
    assert tyre.exit_code == 0 and "Slip angle [deg]" in tyre.output
    study = runner.invoke(app, ["optimise", "--help"], terminal_width=200)
    assert study.exit_code == 0 and "[requirement] table" in study.output and "[run] out" in study.output
