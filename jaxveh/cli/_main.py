"""Top-level ``jaxveh`` Typer application; each sub-command group lives in its own module."""

from ._analytic import app as analytic_app
from ._chassis import app as chassis_app
from ._common import new_app
from ._multibody import app as multibody_app
from ._optimise import optimise as optimise_command
from ._run import run as run_command
from ._simulate import app as simulate_app
from ._study import sweep as sweep_command
from ._tyre import app as tyre_app
from ._vehicle import rig_app, vehicle_app

app = new_app("jaxveh: differentiable vehicle dynamics with a flexible chassis.", add_completion=False)
app.command("run")(run_command)
app.command("optimise")(optimise_command)
app.command("sweep")(sweep_command)
app.add_typer(analytic_app, name="analytic")
app.add_typer(tyre_app, name="tyre")
app.add_typer(chassis_app, name="chassis")
app.add_typer(multibody_app, name="multibody")
app.add_typer(vehicle_app, name="vehicle")
app.add_typer(rig_app, name="rig")
app.add_typer(simulate_app, name="simulate")


def main() -> None:
    """Console-script entry point."""
    app()
