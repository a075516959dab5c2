"""``nilpotent analyze``: growth vector, weights, adapted frame and verdicts at a point."""

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
    print_heading,
    stdout_console,
    work,
)


def analysis_payload(system, filtration) -> dict[str, Any]:
    """The ``nilpotent/analysis@1`` JSON object of a filtration (INTERFACE.md)."""
    from nilpotent.core.brackets import format_word
    from nilpotent.core.expressions import format_expression
    from nilpotent.core.points import format_point

    return {
        "schema": "nilpotent/analysis@1",
        "model": system.name,
        "coordinates": list(system.coordinate_names),
        "parameters": {k: format_expression(v) for k, v in system.parameters},
        "point": format_point(system, filtration.point),
        "bracket_generating": filtration.bracket_generating,
        "growth_vector": list(filtration.growth_vector),
        "weights": list(filtration.weights),
        "step": filtration.step,
        "regular": filtration.regular,
        "generic_growth_vector": list(filtration.generic_growth_vector),
        "exact": filtration.exact,
        "max_length": filtration.max_length,
        "frame": [format_word(w) for w in filtration.frame],
        "frame_values": [[format_expression(v) for v in col] for col in filtration.frame_values],
    }


def print_analysis(system, filtration) -> None:
    from rich.table import Table

    from nilpotent.core.brackets import format_word
    from nilpotent.core.expressions import format_expression

    console = stdout_console()
    pt = ", ".join(
        f"{n}={format_expression(v)}"
        for n, v in zip(system.coordinate_names, filtration.point, strict=True)
    )
    print_heading(console, system.name, f" at ({literal(pt, 2000)})")
    verdict = "yes" if filtration.bracket_generating else (
        "NO: the brackets span only "
        f"{filtration.growth_vector[-1] if filtration.growth_vector else 0}"
        f" of {system.n} dimensions"
    )
    if not filtration.bracket_generating and filtration.generic_growth_vector[-1] == system.n:
        verdict += (
            f" at the point with brackets of length <= {filtration.max_length}, while they "
            "span everything at nearby points (a longer bracket may still add a direction: "
            "--max-length)"
        )
    console.print(f"bracket generating: {verdict}")
    console.print(f"growth vector: ({', '.join(map(str, filtration.growth_vector))})")
    console.print(f"weights: ({', '.join(map(str, filtration.weights))})   step: {filtration.step}")
    regular = "regular" if filtration.regular else (
        "SINGULAR (generic growth vector nearby: "
        f"({', '.join(map(str, filtration.generic_growth_vector))}))"
    )
    console.print(f"point: {regular}")
    table = Table(title="adapted frame Y_j (value at the point)")
    table.add_column("j")
    table.add_column("weight")
    table.add_column("word")
    for name in system.coordinate_names:
        table.add_column(name)
    for j, (word, col) in enumerate(zip(filtration.frame, filtration.frame_values, strict=True)):
        table.add_row(
            str(j + 1),
            str(filtration.weights[j]),
            format_word(word),
            *[format_expression(v) for v in col],
        )
    console.print(table)


@app.command("analyze")
@cli_errors
def analyze_command(
    model: ModelArg,
    at: AtOpt = None,
    param: ParamOpt = None,
    max_length: Annotated[
        int | None,
        typer.Option(
            "--max-length",
            parser=bounded_int("--max-length", 1, MAX_BRACKET_LENGTH),
            help="Longest bracket length examined at the point (default: 2n+2, at least 12, "
            "within a budget of Hall words); matters only at singular points.",
        ),
    ] = None,
    singular_locus: Annotated[
        bool,
        typer.Option(
            "--singular-locus",
            help="Also give the singular locus: the determinant of the adapted frame "
            "(only where the frame is square).",
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Growth vector, weights, step, adapted frame and regular/singular verdict at a point."""
    from nilpotent.core.expressions import format_expression
    from nilpotent.core.filtration import analyze
    from nilpotent.core.filtration import singular_locus as locus_of

    system = load_model_option(model, param)
    point = parse_point_option(at, system)
    with work(f"analyze {system.name}"):
        filtration = analyze(system, point, max_length=max_length)
    if singular_locus:
        with work(f"singular locus of {system.name}"):
            locus = locus_of(system, filtration)
    else:
        locus = None
    if json_out:
        payload = analysis_payload(system, filtration)
        if locus is not None:
            payload["singular_locus"] = format_expression(locus)
        emit_json(payload)
        return
    print_analysis(system, filtration)
    if locus is not None:
        stdout_console().print(f"singular locus: {format_expression(locus)} = 0")
