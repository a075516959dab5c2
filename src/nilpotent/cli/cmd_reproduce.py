"""``nilpotent reproduce``: the trident snake paper reproduced, audited, written as a web page."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from nilpotent.cli.app import (
    JsonOpt,
    app,
    check_writable,
    cli_errors,
    emit_json,
    literal,
    stdout_console,
)


@app.command("reproduce")
@cli_errors
def reproduce_command(
    out: Annotated[
        Path,
        typer.Option(
            "--out",
            metavar="DIR",
            help="Folder to write (default ./nilpotent-paper): index.html, figures/, data/, "
            "audit.json. Replaced whole at the end; an existing folder is replaced only if "
            "it is empty or a previous reproduction.",
        ),
    ] = Path("nilpotent-paper"),
    quick: Annotated[
        bool,
        typer.Option("--quick", help="Fewer amplitudes, samples and frames (tests, CI)."),
    ] = False,
    json_out: JsonOpt = False,
) -> None:
    """Run the paper's pipeline end to end and write an offline page with the audit."""
    from nilpotent.report.pipeline import reproduce

    check_writable(out, "--out", folder=True)
    result = reproduce(out, quick=quick)  # reports its steps through nilpotent.progress
    if json_out:
        emit_json(result.to_json())
        return
    audit = result.audit
    con = stdout_console()
    con.print(f"wrote {literal(result.index, 400)}")
    con.print(
        f"audit: {len(audit.entries)} statements, {len(audit.agreeing)} agree, "
        f"{len(audit.differing)} differ ({literal(result.audit_path, 400)})"
    )
    for entry in audit.differing:
        con.print(f"  differs  {entry.id}: {entry.explanation}", highlight=False, markup=False)
    con.print(
        f"{len(result.figures)} figure files, {len(result.animations)} animation files, "
        f"{len(result.data)} data files; {result.seconds:.1f} s"
    )
