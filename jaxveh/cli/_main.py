"""Top-level ``jaxveh`` Typer application; each sub-command group lives in its own module."""

import os
import sys

import typer

from ._analytic import app as analytic_app
from ._chassis import app as chassis_app
from ._multibody import app as multibody_app
from ._optimise import optimise as optimise_command
from ._run import run as run_command
from ._simulate import app as simulate_app
from ._study import sweep as sweep_command
from ._tyre import app as tyre_app
from ._vehicle import rig_app, vehicle_app

app = typer.Typer(
    help="jaxveh: differentiable vehicle dynamics with a flexible chassis.",
    no_args_is_help=True,
    add_completion=False,
)
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


#: The XLA flag the command line runs with: single-threaded Eigen on the CPU. With the
#: default multi-threaded pool, batched LAPACK solves that XLA runs concurrently each split
#: their batch over the same pool and wait for it; on a 2-core machine the pool is full of
#: waiters and the program hangs (seen with the 6-mode car's steady states, jaxlib 0.10.2:
#: lapack_dtrsm_ffi in ParallelBatchMap; docs/objectives.md).
SERIAL_EIGEN = "--xla_cpu_multi_thread_eigen=false"


def main() -> None:
    """Console-script entry point. XLA reads its flags when JAX starts, before this runs,
    so without the Eigen flag in ``XLA_FLAGS`` (:data:`SERIAL_EIGEN`; set it either way
    yourself to choose) the command re-executes itself once with it."""
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_cpu_multi_thread_eigen" not in flags:
        env = dict(os.environ, XLA_FLAGS=f"{flags} {SERIAL_EIGEN}".strip())
        code = "from jaxveh.cli import app; app(prog_name='jaxveh')"
        os.execve(sys.executable, [sys.executable, "-c", code, *sys.argv[1:]], env)
    app()
