"""``nilpotent models``: list the built-in models with their parameters."""

from __future__ import annotations

from nilpotent.cli.app import JsonOpt, app, cli_errors, emit_json, stdout_console


@app.command("models")
@cli_errors
def models_command(json_out: JsonOpt = False) -> None:
    """List the built-in models, their parameters (with defaults) and what each one is."""
    from rich.table import Table

    from nilpotent.models import list_models, models_to_json

    if json_out:
        emit_json(models_to_json())
        return
    infos = list_models()
    table = Table(title="Built-in models (use a name as MODEL, or a path to a model file)")
    table.add_column("model")
    table.add_column("parameters (default)")
    table.add_column("description")
    for info in infos:
        table.add_row(info.usage, info.parameter_summary() or "-", info.description)
    stdout_console().print(table)
