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
    """The ``nilpotent/analysis@1`` JSON object of a filtration (``Filtration.to_json``)."""
    return filtration.to_json()


def print_analysis(system, filtration) -> None:
    from rich.table import Table

    from nilpotent.core.lie.brackets import format_word
    from nilpotent.core.model.expressions import format_expression

    console = stdout_console()
    pt = ", ".join(
        f"{n}={format_expression(v)}"
        for n, v in zip(system.coordinate_names, filtration.point, strict=True)
    )
    print_heading(console, system.name, f" at ({literal(pt, 2000)})")
    reached = filtration.growth_vector[-1] if filtration.growth_vector else 0
    if filtration.bracket_generating and filtration.certified_by is not None:
        verdict = f"yes, {filtration.certified_by.statement()}"
    elif filtration.bracket_generating:
        verdict = "yes"
    elif filtration.bracket_generating is False and filtration.invariant_hypersurface is not None:
        verdict = (
            f"NO at the point: the hypersurface {filtration.invariant_hypersurface} = 0 through "
            "it is invariant under every field (the brackets span everything nearby, never on it)"
        )
    elif filtration.bracket_generating is False:
        verdict = (
            f"NO: the brackets span only {reached} of {system.n} dimensions (also at every "
            "nearby point)"
        )
    else:
        verdict = (
            f"UNDETERMINED: brackets of length <= {filtration.max_length} span {reached} of "
            f"{system.n} dimensions at the point"
        )
    console.print(f"bracket generating: {verdict}", markup=False)
    und = filtration.undetermined
    if und is not None:
        console.print(
            f"undetermined: {und['reason']} (ball precision reached: {und['precision_bits']} "
            f"bits; search further with --max-length)",
            markup=False,
        )
    growth = f"({', '.join(map(str, filtration.growth_vector))})"
    if filtration.growth_vector_known_up_to is not None:
        growth += (
            f", known up to bracket length {filtration.growth_vector_known_up_to} only "
            "(where it reaches n is unknown)"
        )
    console.print(f"growth vector: {growth}", markup=False)
    console.print(f"weights: ({', '.join(map(str, filtration.weights))})   step: {filtration.step}")
    nearby = ", ".join(map(str, filtration.generic_growth_vector))
    if filtration.regular is None:
        regular = f"UNDETERMINED (generic growth vector nearby: ({nearby}))"
    elif filtration.regular:
        regular = "regular"
    else:
        regular = f"SINGULAR (generic growth vector nearby: ({nearby}))"
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
            help="Longest bracket length examined at the point (default: automatic, from "
            "max(2n+2, 12) raised while the Hall words fit a budget); matters only at "
            "singular points.",
        ),
    ] = None,
    singular_locus: Annotated[
        bool,
        typer.Option(
            "--singular-locus",
            help="Also give the singular locus: the common zeros of the determinants of "
            "the adapted frames with the generic weights (simplified).",
        ),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Growth vector, weights, step, adapted frame and regular/singular verdict at a point."""
    from nilpotent.core.analysis.filtration import analyze
    from nilpotent.core.analysis.singular import singular_set
    from nilpotent.core.lie.brackets import format_word
    from nilpotent.core.model.expressions import format_expression

    system = load_model_option(model, param)
    point = parse_point_option(at, system)
    with work(f"analyze {system.name}"):
        filtration = analyze(system, point, max_length=max_length)
    if singular_locus:
        with work(f"singular locus of {system.name}"):
            locus = singular_set(system, filtration.generic_growth_vector)
    else:
        locus = None
    if json_out:
        payload = analysis_payload(system, filtration)
        if locus is not None:
            payload["singular_locus"] = format_expression(locus.equation)
            payload["singular_locus_equations"] = [format_expression(e) for e in locus.equations]
            payload["singular_locus_statement"] = locus.statement()
            payload["singular_locus_determinants"] = [
                {"frame": [format_word(w) for w in frame], "determinant": format_expression(d)}
                for frame, d in locus.determinants
            ]
        emit_json(payload)
        return
    print_analysis(system, filtration)
    if locus is not None:
        stdout_console().print(f"singular locus: {locus.statement()}", markup=False)
