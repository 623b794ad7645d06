"""Table 7.2's study on the library car (``simplification_study``, ``jaxveh vehicle
simplifications``): the variants' options and the refusals, which come before anything is
compiled. The simplifications themselves are checked on the quarter car in
tests/test_multibody_simplifications.py; the study's numbers come from
experiments/table_7_2_simplifications.py (docs/analysis.md)."""

import pytest
from typer.testing import CliRunner

from jaxveh import ParameterError, analysis as an, multibody as mb
from jaxveh.cli import app
from jaxveh.manoeuvre import Manoeuvre, RampSteer, simulate
from jaxveh.vehicle import load_car

runner = CliRunner()


@pytest.fixture(scope="module")
def car():
    return load_car(modes=1, form="library")


def test_variants_set_their_options(car):
    assert car.system.options == mb.FlexOptions()
    for name, flags in an.SIMPLIFICATIONS.items():
        options = an.variant_car(car, name).system.options
        expected = {k: v for k, v in flags.items() if k != "freeze"}
        assert options == mb.FlexOptions(**expected), name
    assert an.variant_car(car, "frozen_projection").system.options == mb.FlexOptions()
    assert car.system.options == mb.FlexOptions()  # the car itself is not changed


def test_study_refusals_are_named(car):
    with pytest.raises(ParameterError, match="variants = \\['bogus'\\] are not all known: allowed complete"):
        an.simplification_study(car, variants=("bogus",))
    with pytest.raises(ParameterError, match="car has no chassis modes"):
        an.simplification_study(load_car(modes=0, form="library"))
    with pytest.raises(ParameterError, match="rigid has 1 modes: pass the car loaded with modes = 0"):
        an.simplification_study(car, rigid=car)
    with pytest.raises(ParameterError, match="repeats = 0 is out of range: allowed integers >= 1"):
        an.simplification_study(car, repeats=0)
    with pytest.raises(ParameterError, match="freeze_steps = 0 is out of range: allowed integers >= 1"):
        an.simplification_study(car, freeze_steps=0)
    with pytest.raises(ParameterError, match="manoeuvre steers by RampSteer: the study needs a step steer"):
        an.simplification_study(car, manoeuvre=Manoeuvre(steering=RampSteer(rate=0.1, start=0.5, blend=0.1), speed=25.0,
                                                                 duration=2.0))


def test_held_projection_needs_the_library_form(car):
    with pytest.raises(ParameterError, match="freeze_steps = 3 needs form = 'library'"):
        simulate(car, an.table_7_2_step_steer(1.0), form="fast", freeze_steps=3)
    with pytest.raises(ParameterError, match="freeze_steps = -2 is out of range: allowed integers >= 0"):
        simulate(car, an.table_7_2_step_steer(1.0), freeze_steps=-2)


@pytest.mark.parametrize("args, message", [
    (["--variants", "complete,bogus"], "--variants must name some of complete"),
    (["--modes", "0"], "--modes must be >= 1"),
    (["--freeze-steps", "0"], "--freeze-steps must be >= 1, got 0"),
    (["--duration", "0.5"], "--duration must be > 0.6 s"),
    (["--rtol", "2"], "--rtol must be in (0, 1), got 2"),
])
def test_cli_refusals(args, message):
    result = runner.invoke(app, ["vehicle", "simplifications", *args])
    assert result.exit_code == 2
    assert message in result.output
