"""One integration-settings value: validated in the library, one error kind from Python
and from the command line, accepted by every numeric entry point."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import nilpotent
from nilpotent.errors import NilpotentError, OptionError
from nilpotent.models import get_model
from nilpotent.numeric import compile_system, integrate
from nilpotent.numeric.settings import DEFAULT_SETTINGS, IntegrationSettings
from nilpotent.numeric.signals import bracket_signal
from nilpotent.simulation.comparison import BRACKET_SETTINGS
from nilpotent.simulation.sweep import SWEEP_SETTINGS
from replay import resimulate

NOT_POSITIVE = st.one_of(
    st.floats(max_value=0.0, allow_nan=False, allow_infinity=False),
    st.sampled_from([math.nan, math.inf, -math.inf]),
)
QUIET = settings(max_examples=12, deadline=None,
                 suppress_health_check=[HealthCheck.function_scoped_fixture])


def _kind(call) -> str:
    with pytest.raises(NilpotentError) as info:
        call()
    return info.value.kind


def _cli_kind(run_cli, *args: str) -> str:
    status, out, _ = run_cli(*args, "--json")
    assert status == 2, out
    return json.loads(out)["error"]["kind"]


def _cli_value(x: float) -> str:
    return repr(x) if math.isfinite(x) else {"nan": "nan", "inf": "inf", "-inf": "-inf"}[str(x)]


def test_the_one_default_and_the_named_overrides_derive_from_it():
    assert IntegrationSettings() == DEFAULT_SETTINGS
    assert (DEFAULT_SETTINGS.method, DEFAULT_SETTINGS.engine) == ("adaptive", "auto")
    assert (DEFAULT_SETTINGS.rtol, DEFAULT_SETTINGS.atol) == (1e-10, 1e-12)
    # each override changes only what it says it changes
    changed = {f.name for f in dataclasses.fields(IntegrationSettings)
               if getattr(SWEEP_SETTINGS, f.name) != getattr(DEFAULT_SETTINGS, f.name)}
    assert changed == {"bound"}
    changed = {f.name for f in dataclasses.fields(IntegrationSettings)
               if getattr(BRACKET_SETTINGS, f.name) != getattr(DEFAULT_SETTINGS, f.name)}
    assert changed == {"rtol", "atol"}
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_SETTINGS.rtol = 1.0  # type: ignore[misc]


@pytest.mark.parametrize(("field", "value"), [
    ("method", "euler"), ("engine", "nope"), ("rtol", 0.0), ("rtol", "1e-3"),
    ("atol", -1e-9), ("steps", 1), ("steps", 2.5), ("max_steps", 0), ("bound", 0.0),
    ("bound", math.inf), ("rtol", True),
])
def test_each_bad_field_is_an_option_error_naming_it(field, value):
    with pytest.raises(OptionError, match=field):
        IntegrationSettings(**{field: value})
    with pytest.raises(OptionError, match=field):
        DEFAULT_SETTINGS.replace(**{field: value})


@QUIET
@given(rtol=NOT_POSITIVE)
def test_a_bad_rtol_is_the_same_kind_from_python_and_the_cli(run_cli, rtol):
    python = _kind(lambda: IntegrationSettings(rtol=rtol))
    via_sweep = _kind(lambda: nilpotent.sweep(get_model("unicycle"), (1, 2), rtol=rtol))
    cli = _cli_kind(run_cli, "sweep", "unicycle", "--bracket", "1,2", "--rtol", _cli_value(rtol))
    assert python == via_sweep == cli == "option"


@QUIET
@given(bound=NOT_POSITIVE)
def test_a_bad_bound_is_the_same_kind_from_python_and_the_cli(run_cli, bound):
    python = _kind(lambda: nilpotent.sweep(get_model("unicycle"), (1, 2), bound=bound))
    cli = _cli_kind(run_cli, "sweep", "unicycle", "--bracket", "1,2", "--bound",
                    _cli_value(bound))
    assert python == cli == "option"


@QUIET
@given(tol=NOT_POSITIVE)
def test_a_bad_plan_tolerance_is_the_same_kind_from_python_and_the_cli(run_cli, tol):
    sys = get_model("unicycle")
    global_kind = _kind(lambda: nilpotent.plan(sys, (0, 0, 0), (0.1, 0, 0), tol=tol))
    local_kind = _kind(lambda: nilpotent.steer(sys, (0, 0, 0), (0.1, 0, 0), tol=tol))
    cli = _cli_kind(run_cli, "plan", "unicycle", "--to", "x=0.1", "--tol", _cli_value(tol))
    assert global_kind == local_kind == cli == "option"


def test_settings_and_the_loose_keywords_give_the_same_integration():
    """``settings=`` is the new way; a loose keyword overrides its field (kept one release)."""
    compiled = compile_system(get_model("unicycle"))
    sig = bracket_signal(2, 1, 2, 0.3)
    x0 = np.zeros((1, 3))
    chosen = IntegrationSettings(rtol=1e-9, atol=1e-11, engine="numpy", method="fixed", steps=32)
    a = integrate(compiled, x0, sig, settings=chosen)
    b = integrate(compiled, x0, sig, rtol=1e-9, atol=1e-11, engine="numpy", method="fixed",
                  steps=32)
    c = integrate(compiled, x0, sig, settings=chosen.replace(steps=64), steps=32)
    assert np.array_equal(a.final, b.final) and np.array_equal(a.final, c.final)
    assert a.engine == "numpy" and a.steps_per_segment == 32
    with pytest.raises(OptionError, match="IntegrationSettings"):
        integrate(compiled, x0, sig, settings={"rtol": 1e-9})  # type: ignore[arg-type]


def test_every_numeric_entry_point_takes_settings():
    sys = get_model("unicycle")
    fixed = IntegrationSettings(method="fixed", engine="numpy", steps=16)
    traj = nilpotent.simulation.simulate(sys, bracket_signal(2, 1, 2, 0.1), settings=fixed)
    assert traj.method == "fixed" and traj.engine == "numpy"
    tight = BRACKET_SETTINGS.replace(engine="numpy", method="adaptive")
    with pytest.raises(OptionError, match="adaptive"):
        # the numpy engine has no adaptive method: the settings reached the integrator
        nilpotent.compare_bracket_motion(sys, (1, 2), 0.1, samples=5, settings=tight)
    study = nilpotent.scaling(sys, (1, 2), (0.05, 0.1), samples=5,
                              settings=BRACKET_SETTINGS.replace(rtol=1e-8, atol=1e-10))
    assert study.floor >= 1e3 * 1e-10  # the noise floor of the tolerances given
    result = nilpotent.sweep(sys, (1, 2), (0.05,), settings=SWEEP_SETTINGS.replace(bound=10.0))
    assert result.parameters.bound == 10.0


def test_the_planners_integrate_with_the_settings_given():
    """steer/plan/execute pass ``settings`` to the integration of the true system: a
    coarse fixed-step integration leaves a plan whose reported end state differs from an
    independent tight re-simulation (tests/replay.py, scipy DOP853 at rtol 1e-12) by far
    more than the default's does (DOP853 at 1e-12: the two agree to ~1e-12)."""

    from nilpotent.planning.simulation import PLANNING_SETTINGS

    sys = get_model("unicycle")
    goal = (0.1, 0.05, -0.1)

    def gap(plan) -> float:
        states = resimulate(sys, plan.start, [s.to_dict() for s in plan.segments])
        return float(np.linalg.norm(states[-1] - np.array(plan.reached)))

    tight = nilpotent.steer(sys, (0, 0, 0), goal)
    coarse = nilpotent.steer(sys, (0, 0, 0), goal, raise_on_failure=False,
                             settings=IntegrationSettings(method="fixed", engine="numpy",
                                                          steps=4))
    assert gap(tight) < 1e-10 < 1e-9 < gap(coarse)
    # the loose engine= keyword (kept one release) is the field of the same name
    alias = nilpotent.steer(sys, (0, 0, 0), goal, engine="scipy")
    named = nilpotent.steer(sys, (0, 0, 0), goal,
                            settings=PLANNING_SETTINGS.replace(engine="scipy"))
    assert alias.segments == named.segments
    # an engine without the adaptive method: the settings reached the integrator, and the
    # mistake is an option error from every planner (never a planning failure)
    wrong = PLANNING_SETTINGS.replace(engine="numpy")
    assert _kind(lambda: nilpotent.steer(sys, (0, 0, 0), goal, settings=wrong)) == "option"
    assert _kind(lambda: nilpotent.plan(sys, (0, 0, 0), goal, settings=wrong)) == "option"
    glob = nilpotent.plan(sys, (0, 0, 0), goal)
    assert _kind(lambda: nilpotent.execute(glob, settings=wrong)) == "option"
    assert _kind(lambda: nilpotent.plan(sys, (0, 0, 0), goal, settings={"rtol": 1})) == "option"
