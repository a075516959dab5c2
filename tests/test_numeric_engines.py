"""The engine registry: its data (names, methods) are consistent, every engine class
is registered, 'auto' resolves as documented, and every available engine agrees with
the others on the trident snake (a second method as the oracle)."""

from __future__ import annotations

import numpy as np
import pytest

from nilpotent.errors import OptionError
from nilpotent.models import get_model
from nilpotent.numeric import compile_fields, compile_system, integrate
from nilpotent.numeric.engines import AUTO_NUMBA_BATCH, ENGINES, choose_engine, engine_names
from nilpotent.numeric.engines.base import Engine
from nilpotent.numeric.integrate import METHODS
from nilpotent.numeric.signals import bracket_inputs


def test_registry_data_is_consistent():
    assert engine_names()[0] == "auto" and "auto" not in ENGINES
    for name, engine in ENGINES.items():
        assert isinstance(engine, Engine) and engine.name == name
        assert engine.methods and set(engine.methods) <= set(METHODS)
        assert engine.summary
    registered = {type(e) for e in ENGINES.values()}
    assert set(Engine.__subclasses__()) <= registered
    for method in METHODS:
        assert any(method in e.methods for e in ENGINES.values())


def test_unknown_engine_or_method_mismatch_is_refused():
    cs = compile_system(get_model("unicycle"))
    with pytest.raises(OptionError, match="unknown engine"):
        choose_engine(cs, "adaptive", "euler", 1)
    with pytest.raises(OptionError, match="runs on the engines"):
        choose_engine(cs, "fixed", "scipy", 1)


def test_auto_policy():
    import sympy as sp

    x = sp.Symbol("x")
    fresh = compile_fields([x], [[sp.Integer(3)]], name="never-compiled-engine-test")
    assert choose_engine(fresh, "adaptive", "auto", 1).name == "scipy"
    assert choose_engine(fresh, "fixed", "auto", 1).name == "numpy"
    big = choose_engine(fresh, "adaptive", "auto", AUTO_NUMBA_BATCH).name
    assert big == ("heyoka" if ENGINES["heyoka"].available() else "numba")


@pytest.mark.slow
def test_every_available_engine_gives_the_same_end_points():
    snake = compile_system(get_model("trident-snake"))
    rng = np.random.default_rng(5)
    x0 = rng.uniform(-0.1, 0.1, (4, 6))
    inputs = bracket_inputs(3, 1, 2, rng.uniform(0.05, 0.3, 4))
    finals = {}
    for name, engine in ENGINES.items():
        if not engine.available():
            continue
        method = "adaptive" if "adaptive" in engine.methods else "fixed"
        sol = integrate(snake, x0, inputs, engine=name, method=method, rtol=1e-12, atol=1e-14,
                        steps=256)
        assert sol.all_ok and sol.engine == name
        finals[name] = np.asarray(sol.final)
    reference = finals.pop("scipy")
    for final in finals.values():
        np.testing.assert_allclose(final, reference, atol=1e-9, rtol=0)
