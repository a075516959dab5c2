"""Strict JSON: the one encoder of everything the tool prints or writes as JSON.

JSON has no NaN or infinity (the interface page, "JSON output"): :func:`json_text`
writes a non-finite float as ``null`` and lists where under ``"undefined"`` of a
top-level object, so a reader knows why the value is missing. numpy scalars and
arrays are converted; an integer too long to print (Python's 4300-digit limit)
is a :class:`~nilpotent.errors.ComputationLimitError`, never a traceback.
"""

from __future__ import annotations

import json
import math
from typing import Any

from nilpotent.errors import ComputationLimitError

__all__ = ["json_object", "json_safe", "json_text"]


def json_safe(obj: Any, *, undefined: list[str] | None = None, where: str = "") -> Any:
    """``obj`` with every value JSON can hold exactly: the one place NaN/infinity are caught.

    Non-finite floats (NaN, ±infinity) become ``null`` and their place is
    appended to ``undefined`` (``"iterations[2].error"``); numpy scalars and
    arrays become Python numbers and lists; tuples become lists; integers too
    long to print (Python's 4300-digit limit) become a
    :class:`~nilpotent.errors.ComputationLimitError`.
    """
    if isinstance(obj, bool) or obj is None or isinstance(obj, str):
        return obj
    if isinstance(obj, int):
        if obj.bit_length() > 14_000:  # about 4200 decimal digits
            raise ComputationLimitError(
                f"{where or 'a result'}: an integer of {obj.bit_length()} bits is too large "
                "to print")
        return int(obj)
    if isinstance(obj, float):
        if math.isfinite(obj):
            return float(obj)
        if undefined is not None:
            undefined.append(where or "$")
        return None
    if isinstance(obj, dict):
        return {str(k): json_safe(v, undefined=undefined, where=f"{where}.{k}" if where else str(k))
                for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v, undefined=undefined, where=f"{where}[{k}]")
                for k, v in enumerate(obj)]
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy is a dependency
        np = None  # type: ignore[assignment]
    if np is not None:
        if isinstance(obj, np.ndarray):
            return json_safe(obj.tolist(), undefined=undefined, where=where)
        if isinstance(obj, np.bool_):
            return bool(obj)
        if isinstance(obj, np.integer):
            return int(obj)
        if isinstance(obj, np.floating):
            return json_safe(float(obj), undefined=undefined, where=where)
    raise TypeError(f"cannot write a {type(obj).__name__} as JSON ({where or 'top level'})")


def json_object(obj: Any) -> Any:
    """``obj`` as strict JSON data: what every ``to_json()`` returns.

    :func:`json_safe`, and for an object with non-finite numbers, their places
    under ``"undefined"`` (``{"paths": [...], "why": ...}``, the interface page, "JSON
    output"), so that ``json.dumps(result.to_json(), allow_nan=False)`` always works.
    """
    undefined: list[str] = []
    clean = json_safe(obj, undefined=undefined)
    if undefined and isinstance(clean, dict):
        clean.setdefault("undefined", {
            "paths": undefined,
            "why": "these quantities are not finite numbers (NaN or infinity) and are null",
        })
    return clean


def json_text(obj: Any) -> str:
    """The JSON text of ``obj``: no NaN/infinity (undefined values become ``null`` and are
    listed under ``"undefined"`` of a top-level object, the interface page, "JSON output")."""
    return json.dumps(json_object(obj), indent=2, allow_nan=False) + "\n"


