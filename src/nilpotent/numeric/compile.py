"""The numeric compiler: symbolic vector fields → vectorised callables over a batch.

Any system given by coordinates, fields (sympy expressions) and parameter
values — an original model, a nilpotent approximation, in model or privileged
coordinates — becomes a :class:`CompiledSystem` with

* ``field_values(x)``: ``(B, n, m)``, ``[b, j, i]`` = ``x_{j+1}``-component of
  ``X_{i+1}`` at ``x[b]``;
* ``rhs(x, u)``: ``(B, n)``, ``Σ_i u[b, i] X_i(x[b])``;
* ``jacobian(x)``: ``(B, m, n, n)``, ``[b, i, j, k] = ∂X_{i+1}^j/∂x_k`` at ``x[b]``;
* ``kernels``: the numba module (single-state ``fields``/``rhs`` and the batched
  integrators of :mod:`nilpotent.numeric.kernels`), compiled on first use;

and any vector map given by expressions (the privileged coordinates ``y(x)``
and their inverse ``x(y)``) becomes a :class:`CompiledMap` (:func:`compile_map`)
through the same code generator: there is no second compiler.
:func:`compile_system` is memoised per (system, backend): simulations, plans and
sweeps that compile the same system share one :class:`CompiledSystem` (whose
generated modules are the on-disk cache of :mod:`nilpotent.numeric.cache`).

Code is printed from the expressions with sympy's code printers (common
subexpressions eliminated), written to a ``.py`` file in the cache directory
(:mod:`nilpotent.numeric.cache`) named by a hash of the expressions, and
imported from there: numba's on-disk cache then makes a second process start in
a fraction of a second.  The expressions come from a
:class:`~nilpotent.core.model.system.ControlSystem` (user text has been parsed by the
safe grammar before); no user string is ever evaluated here.

Backends: ``"numpy"`` (always), ``"numba"`` (parallel over the batch),
``"jax"`` (optional extra, imported lazily), ``"auto"`` (numba for batches of
at least :data:`NUMBA_MIN_BATCH` states, numpy below).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from types import ModuleType
from typing import Any

import numpy as np
import sympy as sp
from sympy.printing.numpy import JaxPrinter, NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from nilpotent.core.model.expressions import as_expr
from nilpotent.errors import MissingExtraError, ModelError, OptionError
from nilpotent.numeric.cache import content_key, load_generated_module

#: ``backend="auto"`` uses numba from this batch size on.
NUMBA_MIN_BATCH = 2048

BACKENDS = ("auto", "numpy", "numba", "jax")

_SMALL_INT = 2**31

# numpy's error model: a division by zero gives inf/nan (reported as a non-finite
# state by the integrators) instead of raising inside a parallel kernel.
_NJIT = '@njit(cache=True, error_model="numpy")'
_NJIT_PARALLEL = '@njit(cache=True, parallel=True, error_model="numpy")'


def numba_available() -> bool:
    """Whether numba can be imported."""
    return importlib.util.find_spec("numba") is not None


def _float_constants(expr: sp.Basic) -> sp.Basic:
    """Replace every symbol-free subexpression by a 17-digit Float (small integers kept).

    Keeps integer exponents integral (fast ``x**2``) and keeps huge integers and
    exact constants (``sqrt(3)``, ``pi``) out of the generated code.
    """
    if expr.is_Atom:
        if isinstance(expr, sp.Integer) and abs(int(expr)) < _SMALL_INT:
            return expr
        if expr.is_number:
            return _to_float(expr)
        return expr
    if not expr.free_symbols:
        return _to_float(expr)
    return expr.func(*[_float_constants(a) for a in expr.args])


def _split_shifted_trig(expr: sp.Basic) -> sp.Basic:
    """Rewrite ``sin(z + c)``, ``cos(z + c)`` (``c`` a number) with ``sin z``, ``cos z``.

    The generated code then shares ``sin z``/``cos z`` between fields that use
    the same angle with different offsets (the trident snake's legs): fewer
    calls of the trigonometric functions, which dominate the cost.
    """

    def shifted(e: sp.Basic) -> bool:
        if not isinstance(e, sp.sin | sp.cos) or not e.args[0].is_Add:
            return False
        return any(a.is_number for a in e.args[0].args)

    def rewrite(e: sp.Basic) -> sp.Basic:
        terms = [as_expr(a) for a in e.args[0].args]
        c = sp.Add(*[a for a in terms if a.is_number])
        z = sp.Add(*[a for a in terms if not a.is_number])
        if isinstance(e, sp.sin):
            return sp.sin(z) * sp.cos(c) + sp.cos(z) * sp.sin(c)
        return sp.cos(z) * sp.cos(c) - sp.sin(z) * sp.sin(c)

    return expr.replace(shifted, rewrite)


def _to_float(value: sp.Basic) -> sp.Float:
    num = sp.N(value, 17)
    if not num.is_real:
        raise ModelError(f"constant {value} in a field is not a real number")
    return sp.Float(num, 17)


class _NumbaPrinter(PythonCodePrinter):
    """Python code for numba: ``math.*`` functions, floats printed in full."""

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})


@dataclass(frozen=True)
class _Prepared:
    """Fields with coordinates renamed ``q0..``, constants as floats, and their CSE."""

    n: int
    m: int
    replacements: tuple[tuple[sp.Symbol, sp.Expr], ...]
    reduced: tuple[sp.Expr, ...]  # n*m entries, index i*n + j


def _has_imaginary(exprs: Sequence[sp.Basic]) -> bool:
    return any(isinstance(e, sp.Basic) and e.has(sp.I) for e in exprs)


def _real_cse(
    flat: Sequence[sp.Expr],
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """``sympy.cse`` of real expressions that keeps them free of the imaginary unit.

    The ``"basic"`` optimisations pull a sign out of a power's base, and sympy
    then evaluates ``(-a)**0.5`` with ``a ≥ 0`` as ``1.0*I*a**0.5``: printed as
    ``1j*…``, numpy computes a complex number and storing it into the float
    array silently drops its imaginary part (a point outside the field's domain
    gets the value 0 instead of NaN), and numba refuses to compile.  Whenever
    that happens the plain elimination is used instead (it only replaces
    repeated subexpressions by symbols, so no sign is moved), and without any
    elimination if even that shows an ``I``.  The printed code then computes
    ``(-a)**0.5`` in floating point: NaN for ``a > 0``, exactly 0 at ``a = 0``
    (where the exact value ``I·sqrt(a)`` is the real 0 too).
    """
    for optimizations in ("basic", None):
        reps, reduced = sp.cse(list(flat), symbols=sp.numbered_symbols("c"),
                               optimizations=optimizations)
        reps_l: list[tuple[sp.Symbol, sp.Expr]] = list(reps)  # type: ignore[arg-type]
        reduced_l: list[sp.Expr] = list(reduced)  # type: ignore[arg-type]
        if not _has_imaginary([e for _, e in reps_l] + reduced_l):
            return reps_l, reduced_l
    return [], list(flat)


def _refuse_imaginary(exprs: Sequence[sp.Basic], name: str) -> None:
    """Refuse to print code for an expression with ``I`` (its value would lose a part)."""
    for e in exprs:
        if isinstance(e, sp.Basic) and e.has(sp.I):
            raise ModelError(f"{name}: the expression {e} is not real (it contains I)")


def _prepare(
    fields: tuple[tuple[sp.Expr, ...], ...], n: int, name: str = "system"
) -> _Prepared:
    flat = [fields[i][j] for i in range(len(fields)) for j in range(n)]
    reps, reduced = _real_cse(flat)
    _refuse_imaginary([e for _, e in reps] + list(reduced), name)
    return _Prepared(n, len(fields), tuple(reps), tuple(as_expr(e) for e in reduced))


@dataclass(frozen=True, eq=False)
class CompiledSystem:
    """Vectorised numeric form of ``dx/dt = Σ u_i X_i(x)`` (see the module docstring).

    Build with :func:`compile_fields` or :func:`compile_system`.

    Attributes
    ----------
    name:
        A label (model name).
    coordinate_names:
        Names of the state components, in order.
    fields:
        The compiled fields, parameters substituted, coordinates renamed
        ``q0..q{n-1}`` (``fields[i][j]`` = ``q_j``-component of ``X_{i+1}``).
    key:
        Hash of the fields (coordinates renamed, parameters substituted; not the
        name): names the generated files, and systems with the same key share
        their compiled integrators in a process.
    backend:
        Backend of :meth:`field_values`, :meth:`rhs`, :meth:`jacobian`.
    """

    name: str
    coordinate_names: tuple[str, ...]
    fields: tuple[tuple[sp.Expr, ...], ...]
    key: str
    backend: str = "auto"

    def __reduce__(self) -> tuple[Any, ...]:
        # picklable (e.g. for Dask workers): the loaded modules are not sent,
        # the receiving process imports them from the cache again
        return (
            CompiledSystem,
            (self.name, self.coordinate_names, self.fields, self.key, self.backend),
        )

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    @property
    def m(self) -> int:
        return len(self.fields)

    # --- generated modules -------------------------------------------------
    @cached_property
    def _prepared(self) -> _Prepared:
        return _prepare(self.fields, self.n, self.name)

    @cached_property
    def numpy_module(self) -> ModuleType:
        """The generated numpy module (``fields(x)``, ``rhs(x, u)`` over a batch)."""
        return load_generated_module(
            f"np_{self.key}", None, lambda: _numpy_source(self._prepared, self.name)
        )

    @cached_property
    def jacobian_module(self) -> ModuleType:
        """The generated numpy module of the Jacobians ``jacobian(x)``."""
        return load_generated_module(
            f"npjac_{self.key}", None, lambda: _jacobian_source(self.fields, self.n, self.name)
        )

    @cached_property
    def kernels(self) -> ModuleType:
        """The generated numba module: ``fields``, ``rhs``, batched versions, integrators."""
        if not numba_available():
            raise MissingExtraError("numba is not installed: pip install numba")
        from nilpotent.numeric.kernels import integrator_source

        def make() -> str:
            return _numba_source(self._prepared, self.name) + integrator_source(self.n, self.m)

        from nilpotent.numeric.kernels import KERNEL_VERSION

        return load_generated_module(f"nb_{self.key}_{KERNEL_VERSION}", None, make)

    @cached_property
    def jax_functions(self) -> tuple[Any, Any]:
        """``(fields, rhs)`` as jitted JAX functions of batches."""
        if importlib.util.find_spec("jax") is None:
            raise MissingExtraError(
                "the JAX backend needs jax: pip install nilpotent[jax]"
            )
        import jax  # pyright: ignore[reportMissingImports]  (the optional [jax] extra)

        module = load_generated_module(
            f"jax_{self.key}", None, lambda: _jax_source(self._prepared, self.name)
        )
        return jax.jit(module.fields), jax.jit(module.rhs)

    # --- evaluation --------------------------------------------------------
    def _pick(self, batch: int) -> str:
        if self.backend != "auto":
            return self.backend
        return "numba" if batch >= NUMBA_MIN_BATCH and numba_available() else "numpy"

    def _states(self, x: Any) -> np.ndarray:
        arr = np.asarray(x, dtype=np.float64)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.n:
            raise OptionError(f"states must have shape (B, {self.n}), got {np.shape(x)}")
        return np.ascontiguousarray(arr)

    def field_values(self, x: Any) -> np.ndarray:
        """``(B, n, m)`` field values at a batch of states ``x`` (``(B, n)`` or ``(n,)``)."""
        xs = self._states(x)
        backend = self._pick(xs.shape[0])
        if backend == "numba":
            out = np.empty((xs.shape[0], self.n, self.m))
            self.kernels.fields_batch(xs, out)
            return out
        if backend == "jax":
            return np.asarray(self.jax_functions[0](xs))
        return self.numpy_module.fields(xs)

    def rhs(self, x: Any, u: Any) -> np.ndarray:
        """``(B, n)``: ``Σ_i u[b, i] X_i(x[b])`` for states ``(B, n)`` and inputs ``(B, m)``."""
        xs = self._states(x)
        us = np.asarray(u, dtype=np.float64)
        if us.ndim == 1:
            us = us[None, :]
        if us.shape != (xs.shape[0], self.m):
            us = np.broadcast_to(us, (xs.shape[0], self.m))
        us = np.ascontiguousarray(us)
        backend = self._pick(xs.shape[0])
        if backend == "numba":
            out = np.empty_like(xs)
            self.kernels.rhs_batch(xs, us, out)
            return out
        if backend == "jax":
            return np.asarray(self.jax_functions[1](xs, us))
        return self.numpy_module.rhs(xs, us)

    def jacobian(self, x: Any) -> np.ndarray:
        """``(B, m, n, n)``: ``[b, i, j, k] = ∂X_{i+1}^j/∂x_k`` at ``x[b]`` (numpy)."""
        return self.jacobian_module.jacobian(self._states(x))


def compile_fields(
    coordinates: Sequence[sp.Symbol],
    fields: Sequence[Sequence[sp.Expr]],
    params: Mapping[str | sp.Symbol, Any] | None = None,
    *,
    name: str = "system",
    backend: str = "auto",
) -> CompiledSystem:
    """Compile fields given symbolically into a :class:`CompiledSystem`.

    Parameters
    ----------
    coordinates:
        The coordinate symbols, in order (any names).
    fields:
        ``fields[i][j]``: ``coordinates[j]``-component of ``X_{i+1}`` (sympy).
    params:
        Values of the other symbols appearing in the fields (by name or symbol).
        Every free symbol must be a coordinate or be given here.
    name:
        Label for messages and generated files.
    backend:
        One of :data:`BACKENDS`.

    Raises
    ------
    OptionError
        An unknown ``backend``.
    ModelError
        A field without one component per coordinate, a free symbol that is
        neither a coordinate nor given in ``params``, a component that is not
        real (it contains the imaginary unit ``I`` once parameters are
        substituted, e.g. ``sqrt(p*x**2)`` with ``p = -1``), or a constant that
        is not a real number.
    """
    if backend not in BACKENDS:
        raise OptionError(f"unknown backend {backend!r} (choose from {', '.join(BACKENDS)})")
    coords = tuple(coordinates)
    n = len(coords)
    rows = [tuple(f) for f in fields]
    if not rows or any(len(r) != n for r in rows):
        raise ModelError(f"{name}: every field needs {n} components")
    qs = sp.symbols(f"q0:{n}", real=True)
    subs: dict[sp.Basic, sp.Basic] = {c: q for c, q in zip(coords, qs, strict=True)}
    for k, v in (params or {}).items():
        sym = k if isinstance(k, sp.Symbol) else sp.Symbol(str(k))
        subs[sym] = v if isinstance(v, sp.Basic) else sp.Float(float(v))
    compiled: list[tuple[sp.Expr, ...]] = []
    for i, row in enumerate(rows, start=1):
        out = []
        for j, e in enumerate(row):
            expr = as_expr(e).xreplace(subs)
            # second pass: parameters given as plain symbols with assumptions differ
            free = expr.free_symbols - set(qs)
            if free:
                by_name = {str(k): v for k, v in subs.items()}
                expr = expr.xreplace({s: by_name[str(s)] for s in free if str(s) in by_name})
                free = expr.free_symbols - set(qs)
            if free:
                raise ModelError(
                    f"{name}: field X{i}, component {j + 1} uses "
                    f"{', '.join(sorted(map(str, free)))}, which is neither a coordinate "
                    "nor a parameter with a value"
                )
            if expr.has(sp.I):
                raise ModelError(
                    f"{name}: field X{i}, component {j + 1} is not real: {expr} contains "
                    "the imaginary unit I (e.g. the square root of a negative number)"
                )
            out.append(_float_constants(_split_shifted_trig(expr)))
        compiled.append(tuple(out))
    fields_t = tuple(compiled)
    key = content_key(str(n), *(sp.srepr(e) for f in fields_t for e in f))
    return CompiledSystem(name, tuple(str(c) for c in coords), fields_t, key, backend)


def compile_system(system: Any, *, backend: str = "auto") -> CompiledSystem:
    """Compile a :class:`~nilpotent.core.model.system.ControlSystem` (parameters substituted).

    Memoised per ``(system, backend)`` (the 128 most recent): compiling is
    symbolic work (substitution, hashing) worth doing once per system.

    Parameters
    ----------
    system : ControlSystem
        The system (or anything hashable with ``coordinates``, ``specialized_fields``
        and ``name``).
    backend : str
        As in :func:`compile_fields`.
    """
    return _compile_system(system, backend)


@lru_cache(maxsize=128)
def _compile_system(system: Any, backend: str) -> CompiledSystem:
    return compile_fields(
        system.coordinates,
        system.specialized_fields,
        name=system.name,
        backend=backend,
    )


@dataclass(frozen=True, eq=False)
class CompiledMap:
    """A compiled map ``R^n → R^k``, ``z ↦ (f_1(z), …, f_k(z))``, over any batch shape.

    Built by :func:`compile_map` (``k = n`` for a change of coordinates);
    calling it on an array of shape ``(..., n)`` returns ``(..., k)`` (one
    point ``(n,)`` gives ``(k,)``).  Picklable: the receiving process reloads
    the generated module from the cache.

    Attributes
    ----------
    system : CompiledSystem
        The map as the "fields" of a :class:`CompiledSystem` (numpy backend):
        the ``k`` values in columns of ``n`` (the last one zero-padded).
    size : int
        ``k``, the number of values (``0``: as many as coordinates).
    """

    system: CompiledSystem
    size: int = 0

    @property
    def name(self) -> str:
        return self.system.name

    @property
    def n(self) -> int:
        return self.system.n

    @property
    def outputs(self) -> int:
        """``k``, the number of values at each point."""
        return self.size or self.n

    def __call__(self, points: Any) -> np.ndarray:
        arr = np.asarray(points, dtype=np.float64)
        if arr.ndim == 0 or arr.shape[-1] != self.n:
            raise OptionError(f"{self.name}: points must have shape (..., {self.n}), "
                              f"got {arr.shape}")
        flat = np.ascontiguousarray(arr.reshape(-1, self.n))
        columns = self.system.numpy_module.fields(flat)  # (N, n, columns)
        if not self.size:
            return columns[:, :, 0].reshape(arr.shape)
        values = columns.transpose(0, 2, 1).reshape(flat.shape[0], -1)[:, : self.size]
        return values.reshape((*arr.shape[:-1], self.size))


def compile_map(
    coordinates: Sequence[sp.Symbol],
    expressions: Sequence[sp.Expr],
    params: Mapping[str | sp.Symbol, Any] | None = None,
    *,
    name: str = "map",
    outputs: int | None = None,
) -> CompiledMap:
    """Compile the map ``coordinates ↦ expressions``.

    Parameters
    ----------
    coordinates : Sequence[sympy.Symbol]
        The ``n`` argument symbols, in order.
    expressions : Sequence[sympy.Expr]
        The sympy expressions of them: ``n`` of them for a change of
        coordinates (e.g. ``PrivilegedCoordinates.forward`` of the model
        coordinates, or ``.inverse`` of the privileged names), or ``outputs``.
    params : Mapping or None
        Values of the other symbols (as in :func:`compile_fields`).
    name : str
        Label for messages and generated files.
    outputs : int or None
        ``None``: a change of coordinates (as many expressions as
        coordinates); a number ``k >= 1``: any ``k`` values (a robot's
        outline, :class:`nilpotent.planning.robot.Robot`).

    Raises
    ------
    ModelError
        A count that differs from the coordinates' (or from ``outputs``), or a
        symbol without a value.
    """
    exprs = tuple(expressions)
    n = len(tuple(coordinates))
    if outputs is None:
        if len(exprs) != n:
            raise ModelError(f"{name}: a map needs as many expressions as coordinates")
        return CompiledMap(compile_fields(coordinates, [exprs], params, name=name,
                                          backend="numpy"))
    if outputs < 1 or len(exprs) != outputs:
        raise ModelError(f"{name}: {outputs} values announced, {len(exprs)} expressions given")
    padded = exprs + (sp.Integer(0),) * (-len(exprs) % n)
    columns = [padded[k : k + n] for k in range(0, len(padded), n)]
    return CompiledMap(compile_fields(coordinates, columns, params, name=name, backend="numpy"),
                       outputs)


# --- code generation ---------------------------------------------------------
def _header(kind: str) -> str:
    # no model name here: the text (and so numba's cache of it) depends on the fields
    # only, and a renamed model with the same fields reuses the cached file unchanged
    return f'"""Generated by nilpotent.numeric.compile ({kind}). Do not edit."""\n'



def _numpy_source(prep: _Prepared, name: str) -> str:
    printer = NumPyPrinter({"fully_qualified_modules": True})
    lines = [_header("numpy"), "import numpy", "", ""]
    body = [f"    q{k} = x[:, {k}]" for k in range(prep.n)]
    body += [f"    {s} = {printer.doprint(e)}" for s, e in prep.replacements]
    lines.append("def fields(x):")
    lines += body
    lines.append(f"    F = numpy.zeros((x.shape[0], {prep.n}, {prep.m}))")
    for i in range(prep.m):
        for j in range(prep.n):
            e = prep.reduced[i * prep.n + j]
            if e != 0:
                lines.append(f"    F[:, {j}, {i}] = {printer.doprint(e)}")
    lines += ["    return F", "", ""]
    lines.append("def rhs(x, u):")
    lines += body
    lines.append(f"    out = numpy.zeros((x.shape[0], {prep.n}))")
    for j in range(prep.n):
        terms = _rhs_terms(prep, j, printer, "u[:, {i}]")
        if terms:
            lines.append(f"    out[:, {j}] = {terms}")
    lines += ["    return out", ""]
    _check_printer(printer, name)
    return "\n".join(lines)


def _rhs_terms(prep: _Prepared, j: int, printer: Any, ufmt: str) -> str:
    terms = []
    for i in range(prep.m):
        e = prep.reduced[i * prep.n + j]
        if e == 0:
            continue
        u = ufmt.format(i=i)
        terms.append(u if e == 1 else f"{u} * ({printer.doprint(e)})")
    return " + ".join(terms)


def _check_printer(printer: Any, name: str) -> None:
    missing = getattr(printer, "_not_supported", set())
    if missing:
        raise ModelError(
            f"{name}: cannot compile {', '.join(sorted(map(str, missing)))} to numeric code"
        )


def _numba_source(prep: _Prepared, name: str) -> str:
    printer = _NumbaPrinter()
    lines = [
        _header("numba"),
        "import math",
        "",
        "import numpy as np",
        "from numba import njit, prange",
        "",
        f"N = {prep.n}",
        f"M = {prep.m}",
        "",
        "",
    ]
    body = [f"    q{k} = x[{k}]" for k in range(prep.n)]
    body += [f"    {s} = {printer.doprint(e)}" for s, e in prep.replacements]
    lines += [_NJIT, "def fields(x, F):"]
    lines += body
    for i in range(prep.m):
        for j in range(prep.n):
            e = prep.reduced[i * prep.n + j]
            lines.append(f"    F[{j}, {i}] = {printer.doprint(e) if e != 0 else '0.0'}")
    lines += ["", "", _NJIT, "def rhs(x, u, out):"]
    lines += body
    for j in range(prep.n):
        terms = _rhs_terms(prep, j, printer, "u[{i}]")
        lines.append(f"    out[{j}] = {terms or '0.0'}")
    lines += [
        "",
        "",
        _NJIT_PARALLEL,
        "def fields_batch(x, F):",
        "    for b in prange(x.shape[0]):",
        "        fields(x[b], F[b])",
        "",
        "",
        _NJIT_PARALLEL,
        "def rhs_batch(x, u, out):",
        "    for b in prange(x.shape[0]):",
        "        rhs(x[b], u[b], out[b])",
        "",
    ]
    _check_printer(printer, name)
    return "\n".join(lines)


def _jacobian_source(fields: tuple[tuple[sp.Expr, ...], ...], n: int, name: str) -> str:
    qs = sp.symbols(f"q0:{n}", real=True)
    flat = [
        sp.diff(fields[i][j], qs[k])
        for i in range(len(fields))
        for j in range(n)
        for k in range(n)
    ]
    reps, reduced_exprs = _real_cse(flat)
    reduced = [as_expr(e) for e in reduced_exprs]
    _refuse_imaginary([e for _, e in reps] + reduced, name)
    printer = NumPyPrinter({"fully_qualified_modules": True})
    m = len(fields)
    lines = [_header("numpy jacobian"), "import numpy", "", "", "def jacobian(x):"]
    lines += [f"    q{k} = x[:, {k}]" for k in range(n)]
    lines += [f"    {s} = {printer.doprint(e)}" for s, e in reps]
    lines.append(f"    J = numpy.zeros((x.shape[0], {m}, {n}, {n}))")
    idx = 0
    for i in range(m):
        for j in range(n):
            for k in range(n):
                e = reduced[idx]
                idx += 1
                if e != 0:
                    lines.append(f"    J[:, {i}, {j}, {k}] = {printer.doprint(e)}")
    lines += ["    return J", ""]
    _check_printer(printer, name)
    return "\n".join(lines)


def _jax_source(prep: _Prepared, name: str) -> str:
    printer = JaxPrinter({"fully_qualified_modules": True})
    lines = [_header("jax"), "import jax.numpy", "", ""]
    body = [f"    q{k} = x[:, {k}]" for k in range(prep.n)]
    body += [f"    {s} = {printer.doprint(e)}" for s, e in prep.replacements]
    lines.append("def fields(x):")
    lines += body
    lines.append("    z = jax.numpy.zeros(x.shape[0], dtype=x.dtype)")
    cols = []
    for i in range(prep.m):
        comps = ", ".join(
            f"z + ({printer.doprint(prep.reduced[i * prep.n + j])})" for j in range(prep.n)
        )
        cols.append(f"jax.numpy.stack([{comps}], axis=-1)")
    lines.append(f"    return jax.numpy.stack([{', '.join(cols)}], axis=-1)")
    lines += ["", "", "def rhs(x, u):"]
    lines += body
    lines.append("    z = jax.numpy.zeros(x.shape[0], dtype=x.dtype)")
    comps = []
    for j in range(prep.n):
        terms = _rhs_terms(prep, j, printer, "u[:, {i}]")
        comps.append(f"z + ({terms or '0.0'})")
    lines.append(f"    return jax.numpy.stack([{', '.join(comps)}], axis=-1)")
    lines.append("")
    _check_printer(printer, name)
    return "\n".join(lines)
