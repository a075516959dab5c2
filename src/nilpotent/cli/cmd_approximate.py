"""``nilpotent approximate``: privileged coordinates and the nilpotent approximation."""

from __future__ import annotations

from typing import Annotated, Any

import typer

from nilpotent.cli.app import (
    AtOpt,
    JsonOpt,
    ModelArg,
    ParamOpt,
    app,
    cli_errors,
    emit_json,
    literal,
    load_model_option,
    parse_point_option,
    stdout_console,
    work,
)
from nilpotent.cli.cmd_analyze import analysis_payload
from nilpotent.errors import OptionError


def approximation_payload(system, approx) -> dict[str, Any]:
    """The ``nilpotent/approximation@1`` JSON object (INTERFACE.md)."""
    from nilpotent.core.expressions import format_expression

    coords = approx.coordinates
    cert = approx.certificate
    payload = analysis_payload(system, approx.filtration)
    payload["schema"] = "nilpotent/approximation@1"
    payload["method"] = coords.method
    payload["privileged"] = {
        "names": [str(s) for s in coords.names],
        "expressions": [format_expression(e) for e in coords.forward],
        "inverse": [format_expression(e) for e in coords.inverse],
        "inverse_exact": coords.inverse_exact,
        "forward_exact": coords.forward_exact,
        "numeric": coords.numeric,
    }
    payload["fields"] = [[format_expression(c) for c in f] for f in approx.fields]
    payload["fields_x"] = [[format_expression(c) for c in f] for f in approx.fields_x]
    payload["certificate"] = {
        "orders": list(cert.orders),
        "weights": list(cert.weights),
        "nilpotent_step": cert.nilpotent_step,
        "homogeneous": cert.homogeneous,
        "growth_vector_at_0": list(cert.growth_vector_at_0),
        "remainder_order_ok": cert.remainder_order_ok,
        "remainder_orders": list(cert.remainder_orders),
        "step": cert.step,
        "growth_vector": list(cert.growth_vector),
        "pushforward_ok": cert.pushforward_ok,
        "privileged": cert.privileged,
        "exact": cert.exact,
        "ok": cert.ok,
        "failures": list(cert.failures()),
    }
    return payload


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
    latex: Annotated[bool, typer.Option("--latex", help="Print the result as LaTeX.")] = False,
    json_out: JsonOpt = False,
) -> None:
    """Privileged coordinates at a point and the nilpotent approximation, with its certificate."""
    from nilpotent.core.approximation import approximate
    from nilpotent.core.privileged import METHODS

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
        approx = approximate(system, point, method=method)
    if json_out:
        emit_json(approximation_payload(system, approx))
    elif latex:
        print(approx.to_latex())
    else:
        text = str(approx)
        if system.name != literal(system.name):
            text = text.replace(system.name, literal(system.name))
        stdout_console().print(text, markup=False, highlight=False)
