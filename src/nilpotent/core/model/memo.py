"""Per-object memo tables for the modules that need them (a system stays immutable).

A :class:`~nilpotent.core.model.system.ControlSystem` is a frozen value: it
holds no cache.  A module that memoises work done on a system (the bracket
fields of :mod:`nilpotent.core.lie.brackets`, the polynomial fields of
:mod:`nilpotent.core.lie.polynomial_fields`, the frame contexts of
:mod:`nilpotent.core.coordinates.privileged`) owns an :class:`IdentityMemo`
of its own, at module level.

Entries are keyed on the object's *identity* (two equal systems built
separately do not share work, as when the cache lived on the system): an
entry goes when its object is garbage-collected.  An entry whose value refers
back to its object would keep it alive forever; such tables get a
``maxsize`` (least recently used entries dropped first).
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from collections.abc import Callable
from typing import Any, Generic, TypeVar

__all__ = ["IdentityMemo"]

V = TypeVar("V")


class IdentityMemo(Generic[V]):
    """A table ``object -> value`` keyed on identity, freed with the object.

    Parameters
    ----------
    maxsize : int or None
        Most objects kept (least recently used dropped first), or ``None``
        for no bound (for values that do not refer to their object).

    Examples
    --------
    >>> class Box:
    ...     pass
    >>> memo: IdentityMemo[list] = IdentityMemo()
    >>> b = Box()
    >>> memo.get(b, list) is memo.get(b, list)
    True
    >>> del b
    >>> len(memo)
    0
    """

    def __init__(self, maxsize: int | None = None) -> None:
        self._maxsize = maxsize
        self._table: OrderedDict[int, tuple[weakref.ref, V]] = OrderedDict()

    def __len__(self) -> int:
        return len(self._table)

    def peek(self, obj: Any) -> V | None:
        """The value of ``obj``, or ``None`` if it has none (nothing is built)."""
        hit = self._table.get(id(obj))
        return None if hit is None or hit[0]() is not obj else hit[1]

    def get(self, obj: Any, factory: Callable[[], V]) -> V:
        """The value of ``obj``, built by ``factory()`` the first time."""
        key = id(obj)
        hit = self._table.get(key)
        if hit is not None and hit[0]() is obj:
            if self._maxsize is not None:
                self._table.move_to_end(key)
            return hit[1]
        value = factory()
        self._table[key] = (weakref.ref(obj, self._forget(key)), value)
        if self._maxsize is not None:
            while len(self._table) > self._maxsize:
                self._table.popitem(last=False)
        return value

    def _forget(self, key: int) -> Callable[[weakref.ref], None]:
        table = weakref.ref(self._table)

        def forget(ref: weakref.ref) -> None:
            t = table()
            if t is not None and key in t and t[key][0] is ref:
                del t[key]

        return forget
