"""The public surface: every re-exported name resolves and is documented."""

from __future__ import annotations

import inspect
import subprocess
import sys

import pytest

import nilpotent


@pytest.mark.parametrize("name", sorted(nilpotent._LAZY))
def test_reexport_resolves_and_has_docstring(name):
    obj = getattr(nilpotent, name)
    if callable(obj):
        assert inspect.getdoc(obj), f"nilpotent.{name} has no docstring"


def test_import_nilpotent_is_light():
    code = (
        "import sys, nilpotent;"
        "print(','.join(m for m in ('scipy', 'matplotlib', 'numba') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_public_functions_document_their_parameters():
    """Every parameter of the main entry points is named in its docstring."""
    from nilpotent.sweep import sweep

    funcs = {n: getattr(nilpotent, n) for n in
             ("analyze", "approximate", "compare_bracket_motion", "plan")}
    funcs["sweep"] = sweep
    for name, func in funcs.items():
        doc = inspect.getdoc(func) or ""
        missing = [
            p for p in inspect.signature(func).parameters
            if p not in ("self", "kwargs", "args") and p not in doc
        ]
        assert not missing, f"nilpotent.{name}: undocumented parameters {missing}"
