"""`ControlSystem`: a driftless control-affine system ``dx/dt = Σ_i u_i X_i(x)``.

Conventions (see ``docs/conventions.md``):

* ``coordinates`` is the ordered tuple of coordinate symbols ``x_1..x_n``;
* ``fields[i][j]`` is the component of the field ``X_{i+1}`` along ``∂/∂x_{j+1}``
  (fields are numbered from 1 for users: ``X1, X2, ...``);
* ``parameters`` maps parameter names to exact sympy numbers (or floats);
  the fields may contain the parameter symbols, and :meth:`ControlSystem.specialized`
  substitutes their values.

A system is an immutable value; derive variants with :meth:`with_parameters`
or :func:`dataclasses.replace`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp

from nilpotent import typeset
from nilpotent.core.model.expressions import as_expr, exact_decimals, negative_root
from nilpotent.core.model.memo import IdentityMemo
from nilpotent.core.model.outline import Limits, Outline
from nilpotent.errors import ModelError

Expr = sp.Expr


@dataclass(frozen=True)
class ControlSystem:
    """A driftless control system given by its vector fields.

    ``limits`` and ``geometry`` do not change the dynamics: they take no part
    in equality and hashing (systems compare by their fields).

    Parameters
    ----------
    name:
        Short name of the model (``"unicycle"``, a file stem, ...).
    coordinates:
        Coordinate symbols ``(x_1, ..., x_n)``, in order.
    fields:
        ``fields[i][j]`` is the ``x_{j+1}``-component of ``X_{i+1}``.
    parameters:
        ``(name, value)`` pairs; values are sympy numbers. The fields may use
        ``sympy.Symbol(name)`` for each parameter.
    description:
        One line saying what the model is.
    limits:
        Box limits on coordinates (:class:`~nilpotent.core.model.outline.Limits`;
        the ``[limits]`` table of model files).
    geometry:
        The robot's outline for collision checks
        (:class:`~nilpotent.core.model.outline.Outline`), or ``None``.

    Raises
    ------
    ModelError
        No coordinates, duplicate coordinates, no fields, a field whose number
        of components is not the number of coordinates, or a name used both as
        a coordinate and as a parameter.

    Examples
    --------
    >>> import sympy as sp
    >>> x, y, th = sp.symbols("x y theta")
    >>> s = ControlSystem("unicycle", (x, y, th), ((sp.cos(th), sp.sin(th), 0), (0, 0, 1)))
    >>> s.n, s.m
    (3, 2)
    """

    name: str
    coordinates: tuple[sp.Symbol, ...]
    fields: tuple[tuple[Expr, ...], ...]
    parameters: tuple[tuple[str, Expr], ...] = ()
    description: str = ""
    limits: Limits = field(default_factory=Limits, compare=False, hash=False)
    geometry: Outline | None = field(default=None, compare=False, hash=False)

    def __post_init__(self) -> None:
        coords = tuple(self.coordinates)
        if not coords:
            raise ModelError(f"model {self.name!r}: no coordinates")
        names = [str(c) for c in coords]
        dup = sorted({c for c in names if names.count(c) > 1})
        if dup:
            raise ModelError(f"model {self.name!r}: duplicate coordinates {', '.join(dup)}")
        # internal values (never user text: that goes through core.expressions)
        flds = tuple(tuple(as_expr(e) for e in f) for f in self.fields)
        if not flds:
            raise ModelError(f"model {self.name!r}: no fields")
        for i, f in enumerate(flds, start=1):
            if len(f) != len(coords):
                raise ModelError(
                    f"model {self.name!r}: field X{i} has {len(f)} components, "
                    f"expected {len(coords)} (one per coordinate)"
                )
        params = tuple((str(k), as_expr(v)) for k, v in dict(self.parameters).items())
        clash = set(dict(params)) & set(names)
        if clash:
            raise ModelError(
                f"model {self.name!r}: names used both as coordinate and parameter: "
                f"{', '.join(sorted(clash))}"
            )
        if not isinstance(self.limits, Limits):
            raise ModelError(f"model {self.name!r}: limits must be a Limits value")
        self.limits.check_names(names, f"model {self.name!r}")
        if self.geometry is not None:
            unknown = self.geometry.free_names() - set(names) - set(dict(params))
            if unknown:
                raise ModelError(
                    f"model {self.name!r}: geometry uses unknown names {', '.join(sorted(unknown))}"
                )
        _check_real(self.name, coords, flds, params)
        if self.geometry is not None:
            _check_real_geometry(self.name, coords, self.geometry, params)
        object.__setattr__(self, "coordinates", coords)
        object.__setattr__(self, "fields", flds)
        object.__setattr__(self, "parameters", params)

    # --- basic shape -------------------------------------------------------
    @property
    def n(self) -> int:
        """Dimension of the state space."""
        return len(self.coordinates)

    @property
    def m(self) -> int:
        """Number of control fields (inputs)."""
        return len(self.fields)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(str(c) for c in self.coordinates)

    @property
    def parameter_values(self) -> dict[str, Expr]:
        return dict(self.parameters)

    # --- derived systems ---------------------------------------------------
    def with_parameters(self, values: Mapping[str, object]) -> ControlSystem:
        """Return the same system with some parameter values replaced.

        Unknown parameter names raise :class:`ModelError`.
        """
        current = dict(self.parameters)
        for k, v in values.items():
            if k not in current:
                known = ", ".join(current) or "none"
                raise ModelError(
                    f"model {self.name!r} has no parameter {k!r} (parameters: {known})"
                )
            current[k] = as_expr(v)  # values are numbers, never user text
        return ControlSystem(
            self.name, self.coordinates, self.fields, tuple(current.items()), self.description,
            self.limits, self.geometry,
        )

    @property
    def specialized_fields(self) -> tuple[tuple[Expr, ...], ...]:
        """The fields with every parameter replaced by its value.

        Decimals (in the fields or the parameter values) are read as the exact
        rationals they denote (``0.7`` is ``7/10``,
        :func:`nilpotent.core.decide.spans.exact_decimals`), so that every computation
        on the fields is exact.
        """
        return _SPECIALIZED.get(self, lambda: _specialize(self))

    def specialized(self) -> ControlSystem:
        """The same system with the parameters substituted (and then dropped).

        The limits are kept; the geometry is dropped (its expressions may use
        the parameters).
        """
        return ControlSystem(
            self.name, self.coordinates, self.specialized_fields, (), self.description,
            self.limits,
        )

    def field_matrix(self) -> sp.ImmutableMatrix:
        """The ``n × m`` matrix whose column ``i`` is ``X_{i+1}`` (parameters substituted)."""
        return sp.ImmutableMatrix(self.n, self.m, lambda j, i: self.specialized_fields[i][j])

    def origin(self) -> tuple[Expr, ...]:
        return tuple(sp.Integer(0) for _ in self.coordinates)

    def point(
        self, values: Sequence[object] | Mapping[str, object] | None = None
    ) -> tuple[Expr, ...]:
        """A point as a tuple of sympy numbers, from a sequence or a name→value mapping.

        Missing names are 0.  Numbers only (ints, fractions, floats, sympy
        numbers); user text must go through :func:`nilpotent.core.model.points.parse_point`.
        """
        if values is None:
            return self.origin()
        if isinstance(values, Mapping):
            names = self.coordinate_names
            unknown = [k for k in values if k not in names]
            if unknown:
                raise ModelError(
                    f"model {self.name!r} has no coordinate {unknown[0]!r} "
                    f"(coordinates: {', '.join(names)})"
                )
            return tuple(as_expr(values.get(k, 0)) for k in names)
        vals = tuple(as_expr(v) for v in values)
        if len(vals) != self.n:
            raise ModelError(f"a point of {self.name!r} has {self.n} coordinates, got {len(vals)}")
        return vals

    def __str__(self) -> str:
        lines = [f"{self.name}: coordinates ({', '.join(self.coordinate_names)})"]
        for i, f in enumerate(self.fields, start=1):
            terms = [f"({e})∂{c}" for e, c in zip(f, self.coordinate_names, strict=True) if e != 0]
            lines.append(f"  X{i} = " + (" + ".join(terms) or "0"))
        return "\n".join(lines)

    # --- display (nilpotent.typeset) -------------------------------------------------
    def to_latex(self) -> str:
        """The fields, coordinates and parameters as LaTeX (``align*``)."""
        return typeset.system_display(self).latex()

    def _repr_latex_(self) -> str:
        return self.to_latex()

    def _repr_html_(self) -> str:
        return typeset.system_display(self).html()


def _check_real(
    name: str,
    coords: tuple[sp.Symbol, ...],
    fields: tuple[tuple[Expr, ...], ...],
    params: tuple[tuple[str, Expr], ...],
) -> None:
    """Refuse a field component that is not real at the real points of an open set.

    With the coordinates read as real numbers and the parameters given their
    values, sympy rewrites ``sqrt(-x**2)`` as ``I*Abs(x)`` and ``sqrt(-exp(x))``
    as ``I*exp(x/2)``: a component containing the imaginary unit ``I`` (or a
    non-integer power of a negative number, ``(-1)**(1/3)``) then is not real
    wherever it is non-zero, and no computation could give it a real
    value (a numeric one would silently drop the imaginary part).  Components
    that are real on some open set and complex elsewhere (``sqrt(1 - x**2)``)
    are kept: they evaluate to NaN outside their domain.
    """
    real: dict[sp.Basic, sp.Basic] = {c: sp.Dummy(str(c), real=True) for c in coords}
    back = {d: c for c, d in real.items()}
    real.update({sp.Symbol(k): v for k, v in params})
    for i, f in enumerate(fields, start=1):
        for c, e in zip(coords, f, strict=True):
            seen = e if _imaginary(e) or not _may_turn_imaginary(e) else e.xreplace(real)
            if _imaginary(seen):
                shown = "" if seen is e else (
                    " (" + str(seen.xreplace(back)) + " for real coordinates"
                    + (" and the parameters' values" if params else "") + ")"
                )
                raise ModelError(
                    f"model {name!r}: field X{i}[{c}] is not real: {e}{shown} holds the "
                    "imaginary unit or a fractional power of a negative number (the square "
                    "root of a negative quantity?)"
                )


def _may_turn_imaginary(e: sp.Basic) -> bool:
    """Whether reading the symbols as real numbers may make sympy bring out an ``I``.

    Only a power with a non-integer exponent (``sqrt(-x**2)`` → ``I*Abs(x)``) or a
    logarithm can (the grammar's other functions are real on the reals); the
    rewriting is skipped otherwise: it is the costly part of the check.
    """
    return e.has(sp.log) or any(p.exp.is_integer is not True for p in e.atoms(sp.Pow))


def _imaginary(e: sp.Basic) -> bool:
    """Whether ``e`` holds ``I`` or a non-integer power of a negative number (``(-1)**(1/3)``)."""
    return any(part is sp.I or negative_root(part) for part in sp.preorder_traversal(e))


def _check_real_geometry(
    name: str, coords: tuple[sp.Symbol, ...], geometry: Outline,
    params: tuple[tuple[str, Expr], ...],
) -> None:
    """Refuse an outline expression that is not real (as :func:`_check_real` for fields)."""
    real: dict[sp.Basic, sp.Basic] = {c: sp.Dummy(str(c), real=True) for c in coords}
    real.update({sp.Symbol(k): v for k, v in params})
    for label, e in zip(geometry.labels(), geometry.expressions(), strict=True):
        if _imaginary(e) or (_may_turn_imaginary(e)
                             and _imaginary(as_expr(e).xreplace(real))):
            raise ModelError(
                f"model {name!r}: {label} = {e} is not real for real coordinates"
                + (" and the parameters' values" if params else "")
                + " (the square root or a fractional power of a negative quantity?)"
            )


def _specialize(system: ControlSystem) -> tuple[tuple[Expr, ...], ...]:
    subs = [(sp.Symbol(k), exact_decimals(v)) for k, v in system.parameters]
    return tuple(
        tuple(exact_decimals(e.subs(subs) if subs else e) for e in f) for f in system.fields
    )


# the specialized fields per system (the system itself holds no state)
_SPECIALIZED: IdentityMemo[tuple[tuple[Expr, ...], ...]] = IdentityMemo()
