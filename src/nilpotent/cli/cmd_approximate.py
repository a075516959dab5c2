"""``nilpotent approximate``: privileged coordinates and the nilpotent approximation."""

from __future__ import annotations

from typing import Annotated, Any

import typer

from nilpotent.cli.app import (
    MAX_BRACKET_LENGTH,
    AtOpt,
    JsonOpt,
    ModelArg,
    ParamOpt,
    app,
    bounded_int,
    cli_errors,
    emit_json,
    literal,
    load_model_option,
    parse_point_option,
    stdout_console,
    work,
)
from nilpotent.errors import OptionError


def approximation_payload(system, approx) -> dict[str, Any]:
    """The ``nilpotent/approximation@1`` JSON object (``NilpotentApproximation.to_json``)."""
    return approx.to_json()


@app.command("approximate")
@cli_errors
def approximate_command(
    model: ModelArg,
    at: AtOpt = None,
    method: Annotated[
        str,
        typer.Option(
            "--method",
            help="Privileged coordinates: linear, algebraic, exponential (2nd kind), "
            "exponential-1 (1st kind), or auto (the cheapest privileged one).",
        ),
    ] = "auto",
    param: ParamOpt = None,
    max_length: Annotated[
        int | None,
        typer.Option(
            "--max-length",
            parser=bounded_int("--max-length", 1, MAX_BRACKET_LENGTH),
            help="Longest bracket length examined at the point (default: automatic, raised "
            "within a budget of Hall words while the brackets do not span); matters only "
            "at singular points.",
        ),
    ] = None,
    latex: Annotated[bool, typer.Option("--latex", help="Print the result as LaTeX.")] = False,
    json_out: JsonOpt = False,
) -> None:
    """Privileged coordinates at a point and the nilpotent approximation, with its certificate."""
    from nilpotent.core.coordinates.approximation import approximate
    from nilpotent.core.coordinates.privileged import METHODS

    if json_out and latex:
        raise OptionError("--json and --latex are exclusive: choose one output format")
    if method != "auto" and method not in METHODS:
        raise OptionError(
            f"--method {literal(method, 60)!r} is unknown; "
            f"choose one of: auto, {', '.join(METHODS)}"
        )
    system = load_model_option(model, param)
    point = parse_point_option(at, system)
    with work(f"approximate {system.name}"):
        approx = approximate(system, point, method=method, max_length=max_length)
    if json_out:
        emit_json(approximation_payload(system, approx))
    elif latex:
        print(approx.to_latex())
    else:
        text = str(approx)
        if system.name != literal(system.name):
            text = text.replace(system.name, literal(system.name))
        stdout_console().print(text, markup=False, highlight=False)
