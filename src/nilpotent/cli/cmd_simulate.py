"""``nilpotent simulate``: a bracket motion of the system and of its nilpotent approximation."""

from __future__ import annotations

from nilpotent.cli.app import (
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
    parse_int_pair,
    parse_point_option,
    print_heading,
    save_figure,
    stdout_console,
    work,
)
from nilpotent.cli.bracket_options import AmplitudeOpt, BracketOpt, OmegaOpt, PeriodsOpt


def print_comparison(comp) -> None:
    from rich.table import Table

    console = stdout_console()
    i, j = comp.bracket
    print_heading(
        console, comp.system.name,
        f": bracket motion [X{i},X{j}], A = {comp.amplitude:g}, "
        f"ω = {comp.omega:g}, {comp.periods} period(s); approximation in "
        f"{comp.approximation.coordinates.method} privileged coordinates"
    )
    table = Table(title="end points (model coordinates)")
    for col in ("coordinate", "weight", "original", "approximation", "prediction p+KπA²[Xi,Xj](p)"):
        table.add_column(col)
    for k, name in enumerate(comp.system.coordinate_names):
        table.add_row(
            name,
            str(comp.weights[k]),
            f"{comp.final_original[k]: .10g}",
            f"{comp.final_approximation[k]: .10g}",
            f"{comp.prediction[k]: .10g}",
        )
    console.print(table)
    console.print(f"end-point difference: {comp.endpoint_error:.3e}")
    console.print(f"largest difference along the way: {comp.max_error:.3e}")
    for w, e in comp.errors_by_weight.items():
        console.print(f"  weight {w} (privileged coordinates, max over time): {e:.3e}")
    console.print(f"integration tolerance: {comp.tolerance:.1e}")


@app.command("simulate")
@cli_errors
def simulate_command(
    model: ModelArg,
    bracket: BracketOpt,
    amplitude: AmplitudeOpt = 0.1,
    omega: OmegaOpt = 1.0,
    periods: PeriodsOpt = 1,
    at: AtOpt = None,
    param: ParamOpt = None,
    plot: PlotOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Simulate u_I = -Aω sin ωt, u_J = Aω cos ωt on the system and its nilpotent approximation."""
    from nilpotent.simulation import compare_bracket_motion

    check_plot_path(plot)
    system = load_model_option(model, param)
    pair = parse_int_pair(bracket, "--bracket", system.m)
    point = parse_point_option(at, system)
    with work(f"simulate {system.name}"):
        comp = compare_bracket_motion(
            system, pair, amplitude, omega=omega, periods=periods, point=point
        )
    if plot is not None:
        fig, _ = comp.plot()
        save_figure(fig, plot, (system.name,))
    if json_out:
        emit_json(comp.to_json())
        return
    print_comparison(comp)
    if plot is not None:
        stdout_console().print(f"figure written to {literal(plot)}")
