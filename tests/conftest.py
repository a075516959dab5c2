"""Shared test set-up: headless plotting, hypothesis settings, a CLI runner, and
``@pytest.mark.every_model``.

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
from hypothesis import HealthCheck, settings

# The suite never flakes (issue 22): no per-example deadline (a loaded machine is 5-10x
# slower; a deadline is a timing assert), no "too slow" health check, and the same
# examples on every run (``derandomize``).  ``HYPOTHESIS_PROFILE=explore`` draws new ones.
settings.register_profile(
    "suite", deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("explore", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "suite"))


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


#: The progress events of the suite's one quick reproduction (``quick_reproduction``).
REPRODUCTION_EVENTS: list = []


@pytest.fixture(scope="session")
def quick_reproduction(tmp_path_factory):
    """One quick ``reproduce`` (the costliest computation of the suite, shared by
    ``test_report_pipeline.py`` and ``test_browser.py`` when they run in one process), run
    by the CLI over a previous reproduction's folder (an ``audit.json`` of the schema and
    a stale file): ``(status, stdout, stale file, Reproduction)``, the last being what the
    command's library call returned."""
    import contextlib
    import io
    import json

    import nilpotent.report.pipeline as pipeline
    from nilpotent.cli import main
    from nilpotent.report import AUDIT_SCHEMA

    target = tmp_path_factory.mktemp("reproduce") / "paper"
    (target / "data").mkdir(parents=True)
    (target / "audit.json").write_text(json.dumps({"schema": AUDIT_SCHEMA}))
    marker = target / "data" / "stale.txt"
    marker.write_text("old")
    calls = []
    real = pipeline.reproduce

    def recording(*args, **kwargs):
        assert kwargs.get("progress") is None  # the command reports through its bar
        calls.append(real(*args, **kwargs, progress=REPRODUCTION_EVENTS.append))
        return calls[-1]

    stdout = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(stdout):
        patch.setattr(pipeline, "reproduce", recording)
        status = main(["reproduce", "--out", str(target), "--quick", "--json", "--quiet"])
    assert len(calls) == 1, (status, stdout.getvalue())
    return status, stdout.getvalue(), marker, calls[0]


@pytest.fixture(scope="session")
def reproduction_events(quick_reproduction) -> list:
    """The progress events the quick reproduction sent to its ``progress=`` callback."""
    return REPRODUCTION_EVENTS
