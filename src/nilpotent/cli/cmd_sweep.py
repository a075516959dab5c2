"""``nilpotent sweep``: many bracket motions, original against nilpotent approximation.

Over whole periods the loop frequency drops out (``s = ωt``), so a sweep is over
the amplitude and the start point (and, with ``--vary``, model parameters).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from nilpotent.cli.app import (
    MAX_AMPLITUDE_COUNT,
    MAX_CHUNK_SIZE,
    MAX_CHUNK_STATES,
    MAX_PERIODS,
    MAX_SAMPLES,
    MAX_SEED,
    MAX_SWEEP_MOTIONS,
    MAX_TIME_SAMPLES,
    MAX_VARY_COMBINATIONS,
    AtOpt,
    JsonOpt,
    ModelArg,
    ParamOpt,
    PlotOpt,
    app,
    bounded_float,
    bounded_int,
    check_plot_path,
    check_writable,
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
    write_atomically,
)
from nilpotent.errors import ComputationLimitError, OptionError

MAX_BOUND = 1e12
"""Largest ``--bound`` (the blow-up threshold of a trajectory, model units)."""


def parse_amplitudes(text: str) -> list[float]:
    """``A1:A2:N`` (``N`` log-spaced amplitudes from A1 to A2) or ``A1,A2,...``."""
    from nilpotent.simulation import amplitude_range

    if ":" in text:
        parts = [p.strip() for p in text.split(":")]
        if len(parts) != 3:
            raise OptionError(
                f"--amplitudes expects A1:A2:N or A1,A2,..., got {literal(text, 80)!r}")
        low, high = (parse_float_list(p, "--amplitudes")[0] for p in parts[:2])
        if not (parts[2].isascii() and parts[2].isdigit()):
            raise OptionError(f"--amplitudes {literal(text, 80)}: N must be a positive integer")
        count = bounded_int("--amplitudes N", 1, MAX_AMPLITUDE_COUNT)(parts[2])
        return list(amplitude_range(low, high, count))
    amps = parse_float_list(text, "--amplitudes")
    if len(amps) > MAX_AMPLITUDE_COUNT:
        raise ComputationLimitError(
            f"--amplitudes: {len(amps):,} amplitudes, above the limit {MAX_AMPLITUDE_COUNT:,}")
    return amps


def _split_top_level(text: str) -> list[str]:
    """Split at the commas outside parentheses (``atan2(1,2)`` stays whole)."""
    parts, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:k])
            start = k + 1
    parts.append(text[start:])
    return parts


def parse_vary(items: list[str] | None) -> dict[str, list[Any]]:
    """``--vary NAME=V1,V2,...`` (repeatable); values through the safe expression grammar."""
    from nilpotent.core.model.expressions import parse_expression

    out: dict[str, list[Any]] = {}
    for item in items or []:
        name, eq, values = item.partition("=")
        name = name.strip()
        if not eq or not name or not values.strip():
            raise OptionError(f"--vary expects NAME=V1,V2,..., got {literal(item, 80)!r}")
        if name in out:
            raise OptionError(f"--vary {name} is given twice")
        pieces = _split_top_level(values)
        if any(not p.strip() for p in pieces):
            raise OptionError(f"--vary {item}: empty value")
        out[name] = [parse_expression(p.strip(), {}, where=f"--vary {name}") for p in pieces]
    return out


def _check_vary_values(model: str, param: list[str] | None, varied: dict[str, list[Any]]
                       ) -> None:
    """Check each ``--vary`` value as ``--param`` would be (positive lengths, ...)."""
    from nilpotent.core.model.expressions import format_expression
    from nilpotent.errors import NilpotentError

    for name, values in varied.items():
        for value in values:
            text = format_expression(value)
            try:
                load_model_option(model, [*(param or []), f"{name}={text}"])
            except NilpotentError as exc:
                raise OptionError(f"--vary {literal(name, 60)}={literal(text, 60)}: {exc}"
                                  ) from None


def print_sweep(result) -> None:
    """The summary for humans: statuses, error quantiles and fitted slopes per weight group."""
    from rich.table import Table

    console = stdout_console()
    par = result.parameters
    brackets = ", ".join(f"[X{i},X{j}]" for i, j in par.brackets)
    print_heading(
        console, par.model,
        f": {len(result)} bracket motions {brackets} "
        f"({par.design} design, {par.periods} period(s); ω drops out), "
        f"{result.backend} on {result.engine}, {result.wall_time:.2f} s"
    )
    summary = result.summary()
    console.print(
        f"succeeded {summary['succeeded']} of {summary['count']}; blow-ups {summary['blow_ups']}; "
        f"other early stops {summary['failed'] - summary['blow_ups']}"
    )
    table = Table(title="errors |y − ŷ| per weight group (privileged coordinates)")
    for col in ("weight", "end median", "end p90", "end max", "along median", "along p90",
                "along max"):
        table.add_column(col)

    def cell(v: float | None) -> str:
        return "–" if v is None else f"{v:.2e}"

    for w in result.groups:
        e = summary["endpoint_by_weight"][str(w)]
        a = summary["along_by_weight"][str(w)]
        table.add_row(str(w), cell(e["median"]), cell(e["p90"]), cell(e["max"]),
                      cell(a["median"]), cell(a["p90"]), cell(a["max"]))
    console.print(table)
    fits = Table(title="log–log slope of the error against A (expected w + 1 from q0 = p)")
    for col in ("parameters", "bracket", "weight", "slope (along)", "slope (end point)",
                "expected"):
        fits.add_column(col)
    for fit in result.fits():
        params = ", ".join(f"{k}={v}" for k, v in fit["parameters"].items()) or "–"
        for w, slope in fit["slopes"].items():
            end = fit["endpoint_slopes"][w]
            fits.add_row(
                params, f"[X{fit['bracket'][0]},X{fit['bracket'][1]}]", w,
                "exact" if slope is None else f"{slope:.3f}",
                "exact" if end is None else f"{end:.3f}",
                str(fit["expected_slopes"][w]),
            )
    console.print(fits)


@app.command("sweep")
@cli_errors
def sweep_command(
    model: ModelArg,
    bracket: Annotated[
        list[str],
        typer.Option("--bracket", metavar="I,J",
                     help="Bracket pair (1-based, different fields); repeatable."),
    ],
    amplitudes: Annotated[
        str,
        typer.Option("--amplitudes", metavar="A1:A2:N|A1,A2,...",
                     help="N log-spaced amplitudes from A1 to A2, or a list (all > 0)."),
    ] = "0.01:0.16:5",
    samples: Annotated[
        int,
        typer.Option("--samples", metavar="N",
                     parser=bounded_int("--samples", 0, MAX_SAMPLES),
                     help="Grid: random start points (0: the start p only). Random: rows."),
    ] = 0,
    radius: Annotated[
        float,
        typer.Option("--radius", metavar="R",
                     help="Start points uniform in the ball of radius R round p.",
                     parser=bounded_float("--radius", 0.0)),
    ] = 0.0,
    seed: Annotated[
        int,
        typer.Option("--seed", metavar="S", help="Random seed.",
                     parser=bounded_int("--seed", 0, MAX_SEED, above=OptionError)),
    ] = 0,
    design: Annotated[
        str, typer.Option("--design", metavar="grid|random", help="Sampling design.")
    ] = "grid",
    vary: Annotated[
        list[str] | None,
        typer.Option("--vary", metavar="NAME=V1,V2,...",
                     help="Sweep a model parameter over these values (repeatable)."),
    ] = None,
    periods: Annotated[
        int,
        typer.Option("--periods", metavar="K",
                     help=f"Whole periods of the loop (1 to {MAX_PERIODS}).",
                     parser=bounded_int("--periods", 1, MAX_PERIODS)),
    ] = 1,
    time_samples: Annotated[
        int,
        typer.Option("--time-samples", metavar="N",
                     parser=bounded_int("--time-samples", 2, MAX_TIME_SAMPLES),
                     help="Equally spaced times (ends included) at which the errors along "
                          f"the way are taken (2 to {MAX_TIME_SAMPLES}; 2: start and end "
                          "only, the fastest)."),
    ] = 33,
    rtol: Annotated[float, typer.Option(
        "--rtol", help="Relative tolerance (> 0, at most 1).",
        parser=bounded_float("--rtol", 0.0, 1.0, open_low=True))] = 1e-10,
    bound: Annotated[
        float, typer.Option("--bound", help="Stop (and report) a trajectory once |x_k| > bound "
                            f"(> 0, at most {MAX_BOUND:g}).",
                            parser=bounded_float("--bound", 0.0, MAX_BOUND, open_low=True))
    ] = 1e6,
    chunk_size: Annotated[
        int,
        typer.Option("--chunk-size", metavar="B", help="Trajectory pairs per chunk.",
                     parser=bounded_int("--chunk-size", 1, MAX_CHUNK_SIZE)),
    ] = 4096,
    dask: Annotated[
        str | None,
        typer.Option("--dask", metavar="ADDRESS|local",
                     help="Run the chunks on Dask (needs pip install \"nilpotent[dask]\"): "
                          "tcp://HOST:PORT, HOST:PORT or local."),
    ] = None,
    dask_connect_timeout: Annotated[
        float | None,
        typer.Option("--dask-connect-timeout", metavar="S",
                     parser=bounded_float("--dask-connect-timeout", 0.0, 86400.0,
                                          open_low=True),
                     help="Seconds to reach the --dask scheduler (default 10)."),
    ] = None,
    dask_progress_timeout: Annotated[
        float | None,
        typer.Option("--dask-progress-timeout", metavar="S",
                     parser=bounded_float("--dask-progress-timeout", 0.0, 86400.0,
                                          open_low=True),
                     help="Stop with an error when no chunk finishes for S seconds "
                          "(default 120)."),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option("--out", metavar="FILE.csv", help="Write one CSV row per sample."),
    ] = None,
    plot: PlotOpt = None,
    at: AtOpt = None,
    param: ParamOpt = None,
    json_out: JsonOpt = False,
) -> None:
    """Sweep bracket motions over amplitudes and start points; errors and fitted slopes."""
    from nilpotent.simulation import sweep

    amps = parse_amplitudes(amplitudes)
    if out is not None and out.suffix.lower() != ".csv":
        raise OptionError(f"--out {literal(out)}: the rows are written as CSV (use .csv)")
    check_writable(out, "--out")
    check_plot_path(plot)
    if dask is not None or dask_connect_timeout is not None or dask_progress_timeout is not None:
        from nilpotent.simulation.executors import check_dask

        check_dask(dask, chunk_size, connect_timeout=dask_connect_timeout,
                   progress_timeout=dask_progress_timeout)  # before any work
    if chunk_size * time_samples > MAX_CHUNK_STATES:
        raise ComputationLimitError(
            f"--chunk-size {chunk_size:,} x --time-samples {time_samples:,} sampled states per "
            f"chunk is above the limit {MAX_CHUNK_STATES:,} (memory); lower --chunk-size")
    varied = parse_vary(vary)
    combinations = math.prod(len(v) for v in varied.values())
    if combinations > MAX_VARY_COMBINATIONS:
        raise ComputationLimitError(
            f"--vary asks for {combinations:,} parameter combinations, above the limit "
            f"{MAX_VARY_COMBINATIONS:,} (each needs its own nilpotent approximation); give "
            "fewer values")
    system = load_model_option(model, param)
    _check_vary_values(model, param, varied)
    pairs = [parse_int_pair(b, "--bracket", system.m) for b in bracket]
    point = parse_point_option(at, system)
    if design == "random":  # `samples` rows, each with its own amplitude, bracket and set
        motions = max(samples, 1)
    else:
        motions = (len(amps) * len(pairs) * max(samples, 1)
                   * math.prod(len(v) for v in varied.values()))
    if motions > MAX_SWEEP_MOTIONS:
        raise ComputationLimitError(
            f"the sweep asks for {motions:,} bracket motions (amplitudes x brackets x "
            f"--samples x --vary values), above the limit {MAX_SWEEP_MOTIONS:,}; "
            "lower --samples or the number of amplitudes"
        )

    with work("bracket motions", total=motions) as bar:
        result = sweep(
            system, pairs, amps, point=point, samples=samples, radius=radius, seed=seed,
            design=design, vary=varied or None, periods=periods,
            time_samples=time_samples, rtol=rtol, atol=rtol * 1e-2,
            bound=bound, chunk_size=chunk_size, dask=dask, progress=bar,
            dask_connect_timeout=dask_connect_timeout,
            dask_progress_timeout=dask_progress_timeout,
        )
    if out is not None:
        with write_atomically(out, suffix=".csv") as tmp:
            result.to_csv(tmp)
    if plot is not None:
        fig, _ = result.plot()
        save_figure(fig, plot, (system.name,))
    if json_out:
        emit_json(result.to_json())
        return
    print_sweep(result)
    if out is not None:
        stdout_console().print(f"{len(result)} rows written to {literal(out)}")
    if plot is not None:
        stdout_console().print(f"figure written to {literal(plot)}")
