"""``jaxveh multibody``: inspect the built-in multibody examples (thesis chapter 5)."""

import typer

from ._common import emit_json, fail, new_app

app = new_app("Flexible multibody library (thesis chapter 5): inspect built-in examples.")

_VALUE_OPTIONS = ("--q", "--qdot")


def _parse_values(args: list[str]) -> dict[str, list[float]]:
    """Parse ``--q v1 v2 ... --qdot w1 w2 ...`` from the raw extra arguments; values may be
    negative (``-0.5``), so they are read here rather than by Click."""
    out: dict[str, list[float]] = {}
    current = None
    for token in args:
        if token in _VALUE_OPTIONS:
            current = token
            out[current] = []
            continue
        if current is None:
            fail(f"unexpected argument {token!r}; use --q VALUES... and --qdot VALUES...")
        try:
            out[current].append(float(token))
        except ValueError:
            fail(f"{current}: {token!r} is not a number")
    for key, vals in out.items():
        if not vals:
            fail(f"{key} needs at least one number")
    return out


def _parse_params(items: list[str]) -> dict[str, float]:
    values = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep:
            fail(f"--param {item!r}: expected NAME=VALUE")
        try:
            values[name.strip()] = float(text)
        except ValueError:
            fail(f"--param {name}: {text!r} is not a number")
    return values


@app.command(context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def inspect(
    ctx: typer.Context,
    example: str = typer.Argument(
        ..., help="double-pendulum | four-bar | quarter-car | flexible-pendulum"
    ),
    param: list[str] = typer.Option([], "--param", help="NAME=VALUE, e.g. --param m2=1.2 (repeatable)"),
    as_json: bool = typer.Option(False, "--json", help="print JSON only"),
) -> None:
    """Print the reduced mass matrix, internal and external forces and R of EXAMPLE.

    Positions and velocities of the independent coordinates follow as
    ``--q V1 [V2 ...]`` and ``--qdot W1 [W2 ...]`` (negative numbers allowed). For the
    double pendulum (thesis section 5.7) these are theta1 (absolute) and theta2 (relative),
    in rad and rad/s; parameters m1, m2 (kg), J1, J2 (kg m^2), l1, a1, a2 (m), g (m/s^2).
    """
    from ..multibody import AssemblyError
    from ..params import ParameterError
    from ._inspect import inspect_example

    values = _parse_values(list(ctx.args))
    try:
        result = inspect_example(example, values.get("--q"), values.get("--qdot"), _parse_params(param))
    except (ParameterError, AssemblyError) as e:
        fail(str(e))
    if as_json:
        emit_json(result)
        return
    typer.echo(f"{result['example']}: independent velocities {result['independent_velocities']}")
    typer.echo(f"params: {result['params']}")
    for key in ("mass_matrix", "internal_forces", "external_forces"):
        typer.echo(f"{key}: {result[key]}")
    typer.echo(f"constraint residual: {result['constraint_residual']:.3e}")
