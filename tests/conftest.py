"""Shared test set-up: headless plotting, and a CLI runner returning (status, stdout, stderr)."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest


@pytest.fixture
def run_cli(capsys):
    """Run ``nilpotent ARGS...`` in-process; return (exit status, stdout, stderr)."""
    from nilpotent.cli import main

    def _run(*args: str) -> tuple[int, str, str]:
        capsys.readouterr()
        status = main(list(args))
        out, err = capsys.readouterr()
        return status, out, err

    return _run
