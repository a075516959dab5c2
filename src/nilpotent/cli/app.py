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
import json
import os
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any, TypeVar

import typer

from nilpotent.errors import NilpotentError, OptionError

app = typer.Typer(
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


def check_plot_path(path: Path | None) -> None:
    """Refuse a ``--plot`` file whose suffix matplotlib cannot write."""
    if path is None:
        return
    from matplotlib.backend_bases import FigureCanvasBase

    kinds = FigureCanvasBase.get_supported_filetypes()
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in kinds:
        raise OptionError(
            f"--plot {path}: unknown image type {suffix!r} (use one of {', '.join(sorted(kinds))})"
        )


def save_figure(fig: Any, path: Path) -> None:
    """Write ``fig`` to ``path`` whole or not at all."""
    with write_atomically(path) as tmp:
        fig.savefig(tmp, format=path.suffix.lower().lstrip("."), dpi=120)


JsonOpt = Annotated[
    bool, typer.Option("--json", help="Print one JSON object on stdout and nothing else.")
]


def stderr_console():
    """A rich console on stderr (progress, logs, tables for humans when stdout is JSON)."""
    from rich.console import Console

    return Console(stderr=True)


def stdout_console():
    from rich.console import Console

    return Console()


def load_model_option(spec: str, params: list[str] | None):
    """Load MODEL (a built-in name or a model file) with ``--param`` assignments applied."""
    from nilpotent.core.points import parse_param_assignments
    from nilpotent.models import load_system

    values = parse_param_assignments(list(params or []), option="--param")
    return load_system(spec, values)


def parse_point_option(text: str | None, system, option: str = "--at"):
    """Parse a point option (``--at``, ``--from``, ``--to``); ``None`` means the origin."""
    from nilpotent.core.points import parse_point

    if text is None:
        return system.origin()
    return parse_point(text, system, option=option)


def emit_json(obj: Any) -> None:
    """Print one JSON object on stdout (the only thing printed under ``--json``)."""
    sys.stdout.write(json.dumps(obj, indent=2, allow_nan=False) + "\n")
    sys.stdout.flush()


def emit_error(exc: NilpotentError, as_json: bool) -> None:
    message = str(exc)
    if as_json:
        emit_json({"error": {"kind": exc.kind, "message": message}})
    else:
        sys.stderr.write(f"nilpotent: error: {message}\n")


def cli_errors(func: F) -> F:
    """Turn :class:`NilpotentError` into a clear message and exit status 2.

    The wrapped command must take a ``json_out`` keyword (its ``--json`` flag)
    if it has one; errors are then reported as JSON on stdout.
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

    return wrapper  # type: ignore[return-value]


def parse_int_pair(text: str, option: str, upper: int) -> tuple[int, int]:
    """Parse ``I,J`` (1-based field indices, distinct, at most ``upper``)."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2 or not all(p.isdigit() for p in parts):
        raise OptionError(f"{option} expects two field numbers I,J (e.g. 1,2), got {text!r}")
    i, j = int(parts[0]), int(parts[1])
    if not (1 <= i <= upper and 1 <= j <= upper):
        raise OptionError(f"{option} {text}: field numbers must be between 1 and {upper}")
    if i == j:
        raise OptionError(f"{option} {text}: the two fields must differ")
    return i, j


def parse_float_list(text: str, option: str) -> list[float]:
    """Parse ``A1,A2,...`` as finite floats (plain decimals only)."""
    out: list[float] = []
    for piece in text.split(","):
        piece = piece.strip()
        try:
            value = float(piece)
        except ValueError:
            raise OptionError(f"{option}: {piece!r} is not a number") from None
        if value != value or value in (float("inf"), float("-inf")):
            raise OptionError(f"{option}: {piece!r} is not a finite number")
        out.append(value)
    if not out:
        raise OptionError(f"{option}: expected at least one number")
    return out


@contextlib.contextmanager
def write_atomically(path: str | os.PathLike[str], suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; move it into place only on success."""
    target = Path(path)
    if target.parent and not target.parent.exists():
        raise OptionError(f"cannot write {target}: folder {target.parent} does not exist")
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=suffix or target.suffix, dir=target.parent or "."
    )
    os.close(fd)
    tmp_path = Path(tmp)
    mask = os.umask(0)
    os.umask(mask)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~mask)  # mkstemp makes it private; the result is ordinary
        os.replace(tmp_path, target)
    finally:
        if tmp_path.exists():
            tmp_path.unlink()
