"""``nilpotent scaling``: how the approximation error scales with the loop amplitude."""

from __future__ import annotations

from typing import Annotated

import typer

from nilpotent.cli.app import (
    MAX_SCALING_AMPLITUDES,
    AtOpt,
    JsonOpt,
    ModelArg,
    ParamOpt,
    PlotOpt,
    app,
    check_plot_path,
    cli_errors,
    emit_json,
    literal,
    load_model_option,
    parse_float_list,
    parse_int_pair,
    parse_point_option,
    print_heading,
    save_figure,
    stdout_console,
    work,
)
from nilpotent.cli.bracket_options import BracketOpt, OmegaOpt, PeriodsOpt
from nilpotent.errors import ComputationLimitError


def print_scaling(study) -> None:
    from rich.table import Table

    console = stdout_console()
    i, j = study.bracket
    print_heading(
        console, study.system.name,
        f": bracket motion [X{i},X{j}], ω = {study.omega:g}, "
        f"{study.periods} period(s); errors max over time of |y − ŷ| in privileged coordinates"
    )
    table = Table()
    table.add_column("amplitude")
    for w in study.errors:
        table.add_column(f"weight {w}")
    for k, a in enumerate(study.amplitudes):
        table.add_row(f"{a:g}", *[f"{study.errors[w][k]:.3e}" for w in study.errors])
    console.print(table)
    for w, slope in study.slopes.items():
        shown = "n/a (errors at the noise floor: exact in this group)" if slope is None else (
            f"{slope:.3f}"
        )
        console.print(
            f"weight {w}: fitted log–log slope {shown}; expected {study.expected_slopes[w]}"
        )


@app.command("scaling")
@cli_errors
def scaling_command(
    model: ModelArg,
    bracket: BracketOpt,
    amplitudes: Annotated[
        str | None,
        typer.Option(
            "--amplitudes",
            metavar="A1,A2,...",
            help="Amplitudes (> 0, at least two different; default 0.01,0.02,0.04,0.08,0.16).",
        ),
    ] = None,
    omega: OmegaOpt = 1.0,
    periods: PeriodsOpt = 1,
    at: AtOpt = None,
    param: ParamOpt = None,
    plot: PlotOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Fit the log–log slope of the approximation error per weight group (expected w + 1)."""
    from nilpotent.simulation import DEFAULT_AMPLITUDES, scaling_study

    amps = (
        list(DEFAULT_AMPLITUDES)
        if amplitudes is None
        else parse_float_list(amplitudes, "--amplitudes")
    )
    if len(amps) > MAX_SCALING_AMPLITUDES:
        raise ComputationLimitError(
            f"--amplitudes: {len(amps):,} amplitudes, above the limit {MAX_SCALING_AMPLITUDES:,} "
            "of a scaling study (one simulation each); use fewer amplitudes, or `nilpotent "
            "sweep` for large studies")
    check_plot_path(plot)
    system = load_model_option(model, param)
    pair = parse_int_pair(bracket, "--bracket", system.m)
    point = parse_point_option(at, system)
    with work(f"scaling {system.name}"):
        study = scaling_study(system, pair, amps, omega=omega, periods=periods, point=point)
    if plot is not None:
        fig, _ = study.plot()
        save_figure(fig, plot, (system.name,))
    if json_out:
        emit_json(study.to_json())
        return
    print_scaling(study)
    if plot is not None:
        stdout_console().print(f"figure written to {literal(plot)}")
