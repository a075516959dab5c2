"""Shared test set-up: headless plotting, a CLI runner, and ``@pytest.mark.every_model``.

``@pytest.mark.every_model`` runs a test once per entry of the model registry
(:data:`nilpotent.models.MODELS`, each built from its ``example_spec``: the
joint-form trident included, ``car-trailers:1`` for the family); the test takes
the built :class:`~nilpotent.core.model.system.ControlSystem` as its ``model``
argument.  ``@pytest.mark.every_model(slow=("trident-snake-joints",))`` marks
the runs on the named models slow.  A new built-in model is therefore checked by every such property
without editing any test.  Tests that work at a point use :func:`model_point`: the origin, or the
registry's ``example_at`` for a model undefined there (``kinematic-snake``).
"""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers",
        "every_model: run once per built-in model of nilpotent.models.MODELS "
        "(the test's `model` argument is the built ControlSystem)",
    )


def every_model_spec() -> list[str]:
    """The spec of every registry entry, in registry order (``car-trailers:1`` for the family)."""
    from nilpotent.models import MODELS

    return [info.example_spec for info in MODELS.values()]


def model_point(model) -> tuple:
    """The registry's example point of the built-in ``model`` (the origin unless ``example_at``)."""
    from nilpotent.models import MODELS

    return MODELS[model.name.partition(":")[0]].example_point(model)


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    marker = metafunc.definition.get_closest_marker("every_model")
    if marker is not None:
        slow = set(marker.kwargs.get("slow", ()))
        params = [
            pytest.param(spec, id=spec, marks=[pytest.mark.slow] if spec in slow else [])
            for spec in every_model_spec()
        ]
        metafunc.parametrize("model", params, indirect=True)


@pytest.fixture
def model(request: pytest.FixtureRequest):
    """The built-in model named by the ``every_model`` parameter."""
    from nilpotent.models import get_model

    return get_model(request.param)


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
