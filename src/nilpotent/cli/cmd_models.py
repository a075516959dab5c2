"""``nilpotent models``: list the built-in models with their parameters."""

from __future__ import annotations

from nilpotent.cli.app import JsonOpt, app, cli_errors, emit_json, stdout_console


@app.command("models")
@cli_errors
def models_command(json_out: JsonOpt = False) -> None:
    """List the built-in models, their parameters (with defaults) and what each one is."""
    from rich.table import Table

    from nilpotent.core.expressions import format_expression
    from nilpotent.models import list_models

    infos = list_models()
    if json_out:
        emit_json(
            {
                "schema": "nilpotent/models@1",
                "models": [
                    {
                        "name": info.usage,
                        "example": info.example_spec,
                        "description": info.description,
                        "parameters": {
                            k: format_expression(v) for k, v in info.parameters.items()
                        },
                        "parameter_rule": info.parameter_summary(),
                    }
                    for info in infos
                ],
            }
        )
        return
    table = Table(title="Built-in models (use a name as MODEL, or a path to a model file)")
    table.add_column("model")
    table.add_column("parameters (default)")
    table.add_column("description")
    for info in infos:
        table.add_row(info.usage, info.parameter_summary() or "-", info.description)
    stdout_console().print(table)
