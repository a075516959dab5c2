"""The typer application and the helpers every ``nilpotent`` command shares.

Commands live in ``cmd_<name>.py`` modules that import :data:`app` and decorate
their function with ``@app.command()`` and :func:`cli_errors`.  The CLI is a thin
shell: it parses, calls the library, prints.

Conventions for every command:

* ``--json`` prints exactly one JSON object on stdout and nothing else;
  progress and logs go to stderr;
* a user mistake (:class:`~nilpotent.errors.NilpotentError`) gives one clear
  message and exit status 2 (``{"error": {"kind", "message"}}`` on stdout under
  ``--json``), never a traceback;
* files are written whole or not at all (:func:`write_atomically`).
"""

from __future__ import annotations

import contextlib
import functools
import math
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from nilpotent import interrupts
from nilpotent.errors import (
    ComputationLimitError,
    NilpotentError,
    OptionError,
    OutputError,
)
from nilpotent.outputs import check_writable, write_atomically
from nilpotent.strict_json import json_safe, json_text  # noqa: F401  (re-exported)

#: Shown at the end of every command's ``--help``: the flags :func:`nilpotent.cli.main`
#: reads wherever they stand on the command line.
GLOBAL_FLAGS_HELP = (
    "Anywhere on the command line: --quiet (no progress on stderr), --debug (the "
    "traceback of an internal error). Exit status: 0 done, 2 a user mistake, 70 a bug, "
    "130/143 interrupted (execute: 3 when the goal is not reached)."
)


class _Commands(typer.Typer):
    """typer's app whose every command's help ends with :data:`GLOBAL_FLAGS_HELP`."""

    def command(self, *args: Any, **kwargs: Any) -> Any:  # type: ignore[override]
        kwargs.setdefault("epilog", GLOBAL_FLAGS_HELP)
        return super().command(*args, **kwargs)


app = _Commands(
    name="nilpotent",
    help=(
        "Geometric control of driftless (nonholonomic) systems: growth vector, "
        "privileged coordinates, nilpotent approximation, simulation, steering, "
        "and the trident snake paper reproduced."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)

F = TypeVar("F", bound=Callable[..., Any])


def _print_version(value: bool) -> None:
    if value:
        from nilpotent.version import __version__

        typer.echo(f"nilpotent {__version__}")
        raise typer.Exit(0)


@app.callback()
def _global_options(
    version: Annotated[bool, typer.Option(
        "--version", callback=_print_version, is_eager=True,
        help="Print the package version and exit.")] = False,
    quiet: Annotated[bool, typer.Option(
        "--quiet", help="No progress on stderr (accepted anywhere on the command line).")
    ] = False,
    debug: Annotated[bool, typer.Option(
        "--debug", help="Print the traceback of an internal error (accepted anywhere on the "
        "command line).")] = False,
) -> None:
    """The options every command accepts (``--quiet`` and ``--debug`` are read by
    :func:`nilpotent.cli.main` wherever they stand, so they never reach here)."""

# --- shared option types ---------------------------------------------------
ModelArg = Annotated[
    str,
    typer.Argument(
        metavar="MODEL",
        help=(
            "A built-in model name (see `nilpotent models`) "
            "or a path to a .toml/.json model file."
        ),
    ),
]
ParamOpt = Annotated[
    list[str] | None,
    typer.Option("--param", metavar="NAME=VALUE", help="Set a model parameter (repeatable)."),
]
AtOpt = Annotated[
    str | None,
    typer.Option(
        "--at",
        metavar="P",
        help="Point NAME=VALUE,...; unnamed coordinates are 0 (default: the origin).",
    ),
]
PlotOpt = Annotated[
    Path | None,
    typer.Option("--plot", metavar="FILE", help="Write a figure (.png, .pdf, .svg, ...)."),
]


def check_plot_path(path: Path | None, option: str = "--plot") -> None:
    """Refuse, before the work, a figure file matplotlib cannot write or that cannot be
    written at all (missing or read-only folder, a folder, ``/proc/...``)."""
    if path is None:
        return
    from matplotlib.backend_bases import FigureCanvasBase

    kinds = FigureCanvasBase.get_supported_filetypes()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in kinds:
        raise OptionError(
            f"{option} {literal(path)}: unknown image type {literal(suffix)!r} "
            f"(use one of {', '.join(sorted(kinds))})"
        )
    check_writable(path, option)


def mathtext_literal(text: str) -> str:
    """``text`` as matplotlib shows it literally: control characters escaped and every
    ``$`` escaped, so that user text is never parsed as mathtext."""
    return literal(text, 120).replace("$", r"\$")


def save_figure(fig: Any, path: Path, user_texts: tuple[str, ...] = ()) -> None:
    """Write ``fig`` to ``path`` whole or not at all.

    ``user_texts`` (a model name, ...) are shown literally wherever they appear in the
    figure's texts (titles, labels, legends): escaped for mathtext and for control
    characters, whatever the plotting code did with them.
    """
    if user_texts:
        from matplotlib.text import Text

        wanted = [(t, mathtext_literal(t)) for t in user_texts if t]
        for artist in fig.findobj(Text):
            content = artist.get_text()
            changed = content
            for raw, safe in wanted:
                if raw != safe and raw in changed:
                    changed = changed.replace(raw, safe)
            if changed != content:
                artist.set_text(changed)
    with write_atomically(path) as tmp:
        fig.savefig(tmp, format=path.suffix.lower().lstrip("."), dpi=120)


# --- limits of integer options (bounded time and memory) ----------------------------
MAX_PERIODS = 1000
"""Most whole periods of a loop (``--periods``)."""
MAX_ITERATIONS = 1000
"""Most planning iterations (``--max-iterations``)."""
MAX_SAMPLES = 1_000_000
"""Most start points of a sweep (``--samples``)."""
MAX_AMPLITUDE_COUNT = 10_000
"""Most amplitudes of a sweep (``--amplitudes A1:A2:N``)."""
MAX_SWEEP_MOTIONS = 2_000_000
"""Most bracket motions of one sweep (amplitudes x start points x brackets x parameter
values); each costs a pair of trajectories in memory."""
MAX_SCALING_AMPLITUDES = 1000
"""Most amplitudes of a scaling study (``scaling --amplitudes``): one simulation each."""
MAX_VARY_COMBINATIONS = 100
"""Most parameter combinations of a sweep (``--vary`` values multiplied): each needs its
own nilpotent approximation."""
MAX_TIME_SAMPLES = 1000
"""Most times at which a sweep's errors along the way are taken (``--time-samples``)."""
MAX_CHUNK_STATES = 40_000_000
"""Most sampled states of one sweep chunk (``--chunk-size`` x ``--time-samples``): each
holds a state of both trajectories in memory while the chunk runs."""
MAX_CHUNK_SIZE = 1_000_000
"""Largest chunk of a sweep (``--chunk-size``)."""
MAX_SEED = 2**63 - 1
"""Largest random seed (``--seed``): within what numpy's generators and OMPL's
(``uint64``, the seed + 1) accept."""
MAX_CORRECTIONS = 1000
"""Most re-plans toward the goal of ``execute`` (``--max-corrections``)."""
MAX_BRACKET_LENGTH = 64
"""Longest bracket length an option may ask for (``--max-length``); the Hall-word budget
of :mod:`nilpotent.core.analysis.filtration` usually bounds it lower."""

JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object on stdout and nothing else.")
]


def stderr_console():
    """A rich console on stderr (logs for humans); markup and highlighting are off, so
    user text prints literally (pass it through :func:`literal` for control characters)."""
    from rich.console import Console

    return Console(stderr=True, markup=False, highlight=False, emoji=False)


def stdout_console():
    """A rich console on stdout for human output; markup and highlighting are off, so a
    model named ``[/bold]`` prints as is (pass user text through :func:`literal`)."""
    from rich.console import Console

    return Console(markup=False, highlight=False, emoji=False)


def print_heading(console: Any, name: str, rest: str) -> None:
    """Print ``name`` (user text, shown literally, in bold) followed by ``rest``."""
    from rich.text import Text

    console.print(Text.assemble((literal(name), "bold"), rest))


@contextlib.contextmanager
def work(description: str, total: int | None = None) -> Iterator[Any]:
    """Progress of one long step on stderr (:func:`nilpotent.progress.progress`): a rich
    bar on a terminal, plain rate-limited lines otherwise, nothing under ``--quiet``; within
    a time limit (:func:`nilpotent.planning.budget.time_budget`), no estimate of the time
    left past it."""
    import time

    from nilpotent.progress import progress

    # a budget is in force only once planning's budget module is loaded: no import here
    # (the planning package is heavy for the commands that do not plan)
    budget = sys.modules.get("nilpotent.planning.budget")
    with progress(description, total) as bar:
        limit = budget.current() if budget is not None else None
        if limit is not None:
            bar.deadline = time.monotonic() + limit.left(hard=True)
        yield bar


def load_model_option(spec: str, params: list[str] | None):
    """Load MODEL (a built-in name or a model file) with ``--param`` assignments applied."""
    from nilpotent.core.model.points import parse_param_assignments
    from nilpotent.models import load_system

    values = parse_param_assignments(list(params or []), option="--param")
    return load_system(spec, values)


def parse_point_option(text: str | None, system, option: str = "--at"):
    """Parse a point option (``--at``, ``--from``, ``--to``); ``None`` means the origin."""
    from nilpotent.core.model.points import parse_point

    if text is None:
        return system.origin()
    return parse_point(text, system, option=option)


def literal(text: object, limit: int = 200) -> str:
    """User text made safe to print: control characters escaped, length bounded.

    Escape sequences (``\\x1b[2J``), bidirectional overrides and other
    non-printable characters are shown as Python escapes (``\\x1b``) instead of
    reaching the terminal; past ``limit`` characters the text is cut and the
    number of characters left out is said. Rich markup is not read anywhere in
    the CLI's output (see :func:`stdout_console`), so ``[/bold]`` prints as is.
    """
    raw = str(text)
    clean = "".join(ch if ch.isprintable() else ascii(ch)[1:-1] for ch in raw)
    if len(clean) > limit:
        clean = clean[:limit] + f"... ({len(clean) - limit} more characters)"
    return clean


MESSAGE_LIMIT = 2000
"""Longest error message printed, in characters (the rest is cut, with a count)."""


_stdout = {"written": False}
"""Whether this run printed its result on stdout (whole: an interrupt waits for the end)."""


def stdout_written() -> bool:
    """Whether the running command has printed its result (:func:`emit_json`) already."""
    return _stdout["written"]


def reset_stdout() -> None:
    """Forget that a result was printed (at the start of each command)."""
    _stdout["written"] = False


def _write_stdout(text: str) -> None:
    out = sys.stdout
    if out is None:
        raise OutputError("cannot print the result: stdout is closed")
    try:
        with interrupts.deferred():  # Ctrl-C never cuts a JSON object in two
            out.write(text)
            out.flush()
            _stdout["written"] = True
    except BrokenPipeError:
        raise  # the reader went away: main() exits quietly
    except OSError as exc:
        raise OutputError(f"cannot print the result on stdout ({exc.strerror or exc})") from None


def emit_json(obj: Any) -> None:
    """Print one JSON object on stdout (the only thing printed under ``--json``)."""
    _write_stdout(json_text(obj))


def bounded_message(message: str, limit: int = MESSAGE_LIMIT) -> str:
    """``message`` cut to ``limit`` characters, saying how many were left out."""
    if len(message) <= limit:
        return message
    return message[:limit] + f"... ({len(message) - limit} more characters not shown)"


def emit_error(exc: NilpotentError, as_json: bool) -> None:
    """Report a user error: one JSON object on stdout under ``--json``, else one line on
    stderr; the message is bounded and its control characters escaped."""
    report_error(exc.kind, str(exc), as_json)


def report_error(kind: str, message: str, as_json: bool) -> None:
    """Report an error of ``kind`` (see :func:`emit_error`); never raises."""
    message = bounded_message(message)
    if as_json:
        try:
            _write_stdout(json_text({"error": {"kind": kind, "message": message}}))
            return
        except (OSError, NilpotentError):
            pass  # stdout unusable: say it on stderr instead
    try:
        text = literal(message, MESSAGE_LIMIT + 100)
        sys.stderr.write(f"nilpotent: error: {text}\n")
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass


def cli_errors(func: F) -> F:
    """Turn :class:`NilpotentError` into a clear message and exit status 2.

    The wrapped command must take a ``json_out`` keyword (its ``--json`` flag)
    if it has one; errors are then reported as JSON on stdout. Also mapped
    here: a too deep recursion (input nested too deeply), an ``OSError`` of
    the files the command writes or reads (:class:`OutputError`), running out
    of memory (:class:`ComputationLimitError`). Anything else is an internal
    error, reported by :func:`nilpotent.cli.main` (exit status 70).
    """

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        as_json = bool(kwargs.get("json_out", False))
        try:
            return func(*args, **kwargs)
        except NilpotentError as exc:
            emit_error(exc, as_json)
            raise typer.Exit(2) from None
        except RecursionError:
            emit_error(OptionError("input too deeply nested"), as_json)
            raise typer.Exit(2) from None
        except MemoryError:
            emit_error(ComputationLimitError(
                "out of memory: the computation is too large for this machine "
                "(use a smaller model, fewer samples or shorter brackets)"), as_json)
            raise typer.Exit(2) from None
        except BrokenPipeError:
            raise
        except OSError as exc:
            name = f" {literal(exc.filename)}" if getattr(exc, "filename", None) else ""
            emit_error(OutputError(
                f"cannot access{name}: {exc.strerror or type(exc).__name__}"), as_json)
            raise typer.Exit(2) from None

    return wrapper  # type: ignore[return-value]


# --- integer options with bounds ---------------------------------------------------
def bounded_int(option: str, low: int, high: int, what: str = "",
                above: type[NilpotentError] = ComputationLimitError) -> Callable[[Any], int]:
    """A typer ``parser`` for a whole-number option between ``low`` and ``high``.

    The text is read without ever reaching Python's 4300-digit conversion limit.
    Not a whole number: a usage error; below ``low``: an
    :class:`~nilpotent.errors.OptionError`; above ``high`` (what the tool can do in
    bounded time and memory): a :class:`~nilpotent.errors.ComputationLimitError`
    naming the limit and the option (``what`` may say more), or ``above`` where the
    bound is the range of the value's type (a seed: :class:`OptionError`).
    """

    def parse(value: Any) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            number = value
        else:
            text = str(value).strip()
            digits = text.lstrip("+-")
            if not digits or not (digits.isascii() and digits.isdigit()) or len(text) - len(
                    digits) > 1:
                raise typer.BadParameter(f"{literal(value, 60)!r} is not a whole number")
            if len(digits.lstrip("0")) > 30:
                raise above(
                    f"{option} {literal(text, 40)}: far above the limit {high:,}{what}")
            number = int(text)
        if number < low:
            raise OptionError(f"{option} must be >= {low}, got {number}")
        if number > high:
            raise above(f"{option} {number:,} is above the limit {high:,}{what}")
        return number

    parse.__name__ = f"{option.lstrip('-').replace('-', '_')}_integer"
    return parse


# --- real-number options: finite, within a documented range --------------------------
def bounded_float(
    option: str,
    low: float,
    high: float | None = None,
    *,
    open_low: bool = False,
    floor: float | None = None,
    what: str = "",
) -> Callable[[Any], float]:
    """A typer ``parser`` for a real-number option in ``[low, high]`` (``(low, high]`` with
    ``open_low``): the one check of every real number the command line takes.

    ``high`` defaults to :data:`nilpotent.core.model.points.MAX_MAGNITUDE` (1e6), the
    documented magnitude of user numbers.  Text that is not a number: a usage error;
    ``nan``, ``inf``, past the range of a double or outside the range: an
    :class:`~nilpotent.errors.OptionError` naming the option.  ``floor`` (above
    ``low``): values below it are allowed in principle but cost unbounded time or
    memory, refused with a :class:`~nilpotent.errors.ComputationLimitError` (``what``
    says why).
    """

    def parse(value: Any) -> float:
        from nilpotent.core.model.points import MAX_MAGNITUDE, check_magnitude

        top = MAX_MAGNITUDE if high is None else high
        if isinstance(value, bool):
            raise typer.BadParameter(f"{literal(value, 60)!r} is not a number")
        if isinstance(value, int | float):
            number = value
        else:
            text = str(value).strip()
            try:
                number = float(text)
            except ValueError:
                raise typer.BadParameter(f"{literal(value, 60)!r} is not a number") from None
            if not math.isfinite(number) and not any(w in text.lower() for w in ("inf", "nan")):
                raise OptionError(f"{option} {literal(text, 40)}: beyond the range of a double "
                                  f"(allowed: {low:g} to {top:g})")
        number = check_magnitude(number, option, low=low, high=top)
        if open_low and number == low:
            raise OptionError(f"{option} must be > {low:g}, got {number:g}")
        if floor is not None and number < floor:
            raise ComputationLimitError(
                f"{option} {number:g} is below the limit {floor:g}{what}")
        return number

    parse.__name__ = f"{option.lstrip('-').replace('-', '_')}_number"
    return parse


def parse_int_pair(text: str, option: str, upper: int) -> tuple[int, int]:
    """Parse ``I,J`` (1-based field indices, distinct, at most ``upper``)."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2 or not all(p.isascii() and p.isdigit() for p in parts):
        raise OptionError(
            f"{option} expects two field numbers I,J (e.g. 1,2), got {literal(text, 80)!r}")
    # the number is read without reaching Python's 4300-digit limit (a field number
    # past the model's count is refused below whatever its size)
    i, j = (int(p) if len(p.lstrip("0")) <= 9 else upper + 1 for p in parts)
    if not (1 <= i <= upper and 1 <= j <= upper):
        raise OptionError(
            f"{option} {literal(text, 80)}: field numbers must be between 1 and {upper}")
    if i == j:
        raise OptionError(f"{option} {literal(text, 80)}: the two fields must differ")
    return i, j


def parse_float_list(text: str, option: str) -> list[float]:
    """Parse ``A1,A2,...`` as finite floats (plain decimals only) of magnitude at most
    :data:`nilpotent.core.model.points.MAX_MAGNITUDE`."""
    from nilpotent.core.model.points import check_magnitude

    out: list[float] = []
    for piece in text.split(","):
        piece = piece.strip()
        try:
            value = float(piece)
        except ValueError:
            raise OptionError(f"{option}: {literal(piece, 60)!r} is not a number") from None
        out.append(check_magnitude(value, f"{option} {literal(piece, 60)}"))
    if not out:
        raise OptionError(f"{option}: expected at least one number")
    return out
