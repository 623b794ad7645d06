"""Top-level ``jaxveh`` Typer application; each sub-command group lives in its own module."""

import typer

app = typer.Typer(
    help="jaxveh: differentiable vehicle dynamics with a flexible chassis.",
    no_args_is_help=True,
    add_completion=False,
)

# Sub-command groups are registered below, one line each.
from ._analytic import app as analytic_app  # noqa: E402

app.add_typer(analytic_app, name="analytic")
from ._run import run as run_command  # noqa: E402

app.command("run")(run_command)
from ._tyre import app as tyre_app  # noqa: E402
app.add_typer(tyre_app, name="tyre")
from ._multibody import app as multibody_app  # noqa: E402
app.add_typer(multibody_app, name="multibody")
from ._chassis import app as chassis_app  # noqa: E402
app.add_typer(chassis_app, name="chassis")


def main() -> None:
    """Console-script entry point."""
    app()
