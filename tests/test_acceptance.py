"""Acceptance tests from outside the project: systems that are not built in go through
the command line only (``nilpotent analyze/approximate/simulate FILE --json``), and every
number is re-derived here by an independent oracle written in plain sympy.

The oracle (this file only, no ``nilpotent.core`` import):

* brackets ``[X, Y] = DY·X − DX·Y`` from Jacobians; right-normed brackets of length k
  span ``Δ^k`` modulo ``Δ^{k−1}``, so ``n_k(p)`` is the exact rank (sympy
  ``Matrix.rank``) of all right-normed brackets of length ≤ k evaluated at p;
* the non-holonomic order of a function is the least s with some
  ``X_{i1}⋯X_{is} f (p) ≠ 0`` (fields applied as derivations);
* ``X_i − X̂_i`` of order ≥ 0 is checked two ways: (a) without inverting the
  coordinates, ``ord_p(X_i y_j − X̂_ij∘y) ≥ w_j`` (valid in privileged coordinates);
  (b) where the product gives an exact inverse, after checking ``y(x(Y)) = Y``,
  by the weighted Taylor expansion ``Y_k → t^{w_k} Y_k`` of ``(X_i y_j)(x(Y))``;
* the simulated end point is compared with scipy ``solve_ivp`` (DOP853, rtol 1e-12).

Any correct choice of frame or privileged coordinates passes; a wrong one cannot.
"""

from __future__ import annotations

import ast
import json
import math
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

DATA = Path(__file__).parent / "data" / "acceptance"

# ---------------------------------------------------------------------------------------------
# the expression grammar of INTERFACE.md, re-implemented (parse + conformance check)
# ---------------------------------------------------------------------------------------------
_FUNCS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "exp": sp.exp, "log": sp.log,
    "sqrt": sp.sqrt, "atan": sp.atan, "atan2": sp.atan2, "sinh": sp.sinh,
    "cosh": sp.cosh, "tanh": sp.tanh,
}
_BINOPS = {
    ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a**b,
}


def grammar(
    text: str,
    names: dict[str, sp.Basic] | None = None,
    *,
    exact: bool = True,
    decimals_as_written: bool = False,
):
    """Parse ``text`` with the INTERFACE.md grammar into sympy; fail the test if it is outside.

    With ``exact``, decimal numbers are refused (an exact quantity must be written exactly);
    with ``decimals_as_written``, a decimal is the rational number its digits say.
    """
    assert isinstance(text, str), f"exact value {text!r} is not a string"
    names = dict(names or {})
    names.setdefault("pi", sp.pi)
    names.setdefault("E", sp.E)

    def conv(node):
        if isinstance(node, ast.Expression):
            return conv(node.body)
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            if isinstance(node.value, float):
                assert not exact, f"inexact number {node.value!r} in exact value {text!r}"
                if decimals_as_written:
                    return sp.Rational(ast.get_source_segment(text, node))
                return sp.Float(node.value)
            return sp.Integer(node.value)
        if isinstance(node, ast.Name):
            assert node.id in names, f"unknown name {node.id!r} in {text!r}"
            return names[node.id]
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            return _BINOPS[type(node.op)](conv(node.left), conv(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            v = conv(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in _FUNCS
            and not node.keywords
        ):
            return _FUNCS[node.func.id](*[conv(a) for a in node.args])
        raise AssertionError(f"{text!r} is outside the expression grammar ({ast.dump(node)})")

    return conv(ast.parse(text, mode="eval"))


FLOAT_TOL = 1e-9


def is_zero(e) -> bool:
    """Exact zero test with a high-precision numerical fallback.

    Where the value carries decimals (a point given as ``theta=0.3``), zero means
    below :data:`FLOAT_TOL`; polynomials are zero when all their coefficients are.
    """
    e = sp.expand(sp.S(e))
    if e == 0:
        return True
    if e.free_symbols:
        gens = sorted(e.free_symbols, key=str)
        try:
            return all(is_zero(c) for c in sp.Poly(e, *gens).coeffs())
        except sp.PolynomialError:
            return sp.simplify(e) == 0
    if e.has(sp.Float):
        return abs(complex(e.evalf(30))) < FLOAT_TOL
    z = e.is_zero
    if z is not None:
        return bool(z)
    z = sp.simplify(e).is_zero
    if z is not None:
        return bool(z)
    return abs(complex(e.evalf(60))) < 1e-40


# ---------------------------------------------------------------------------------------------
# the independent oracle
# ---------------------------------------------------------------------------------------------
def apply_field(X, f, coords):
    """The derivation X f = Σ X_k ∂f/∂x_k."""
    return sp.expand(sum(Xk * sp.diff(f, c) for Xk, c in zip(X, coords, strict=True)))


def lie_bracket(X, Y, coords):
    """[X, Y] = DY·X − DX·Y."""
    return tuple(
        apply_field(X, Yj, coords) - apply_field(Y, Xj, coords)
        for Xj, Yj in zip(X, Y, strict=True)
    )


def right_normed(fields, coords, length):
    """All right-normed brackets [X_i1,[X_i2,...,X_ik]] of the given length, as (word, field)."""
    level = [((i + 1,), tuple(sp.expand(c) for c in X)) for i, X in enumerate(fields)]
    for _ in range(length - 1):
        nxt = []
        for i, X in enumerate(fields):
            for word, B in level:
                if any(c != 0 for c in B):   # brackets with a zero field are zero
                    nxt.append(((i + 1, *word), lie_bracket(X, B, coords)))
        level = nxt
    return level


def exact_rank(rows) -> int:
    if not rows:
        return 0
    return sp.Matrix(rows).rank(iszerofunc=is_zero)


def at(expr, coords, point):
    return sp.S(expr).subs(dict(zip(coords, point, strict=True)), simultaneous=True)


def oracle_growth(fields, coords, point, max_length=6):
    """(growth vector, bracket generating) of the fields at the point, exactly."""
    n = len(coords)
    rows, ranks = [], []
    for k in range(1, max_length + 1):
        for _, B in right_normed(fields, coords, k):
            rows.append([at(c, coords, point) for c in B])
        ranks.append(exact_rank(rows))
        if ranks[-1] == n:
            return tuple(ranks), True
    while len(ranks) > 1 and ranks[-1] == ranks[-2]:
        ranks.pop()
    return tuple(ranks), False


def oracle_generic_growth(fields, coords, point, length, seed=0):
    """Growth vector at random points near p (numerical ranks; the verdict only)."""
    rng = random.Random(seed)
    best: tuple[int, ...] = ()
    layers = [right_normed(fields, coords, k) for k in range(1, length + 1)]
    fns = [[sp.lambdify(coords, list(B), "mpmath") for _, B in layer] for layer in layers]
    for _ in range(3):
        q = [float(v) + rng.uniform(-0.3, 0.3) for v in point]
        rows, ranks = [], []
        for layer in fns:
            rows += [[float(v) for v in f(*q)] for f in layer]
            s = np.linalg.svd(np.array(rows, dtype=float), compute_uv=False)
            ranks.append(int((s > 1e-9 * max(1.0, s[0])).sum()))
        best = max(best, tuple(ranks))
    out = list(best)
    while len(out) > 1 and out[-1] == out[-2]:
        out.pop()
    return tuple(out)


def weights_of(growth):
    w, prev = [], 0
    for s, ns in enumerate(growth, start=1):
        w += [s] * (ns - prev)
        prev = ns
    return tuple(w)


def nh_order(fields, coords, f, point, max_order):
    """Non-holonomic order of f at p, or max_order + 1 if every word up to max_order vanishes."""
    funcs = [sp.expand(f)]
    for s in range(max_order + 1):
        if any(not is_zero(at(g, coords, point)) for g in funcs):
            return s
        nxt, seen = [], set()
        for X in fields:
            for g in funcs:
                h = apply_field(X, g, coords)
                if h != 0 and h not in seen:
                    seen.add(h)
                    nxt.append(h)
        funcs = nxt
        if not funcs:
            return max_order + 1
    return max_order + 1


def push_forward(fields, x, phi, psi, z):
    """Fields in coordinates z = phi(x) (x = psi(z)): [Z]_z = (∂z/∂x)[Z]_x at x(z)."""
    J = sp.Matrix(phi).jacobian(sp.Matrix(x))
    sub = dict(zip(x, psi, strict=True))
    out = []
    for X in fields:
        v = (J * sp.Matrix(X)).subs(sub, simultaneous=True)
        out.append(tuple(sp.expand(sp.simplify(c)) for c in v))
    return out


def parse_word(text: str):
    """'[X1,[X1,X2]]' -> nested tuples of ints."""
    text = text.replace(" ", "")
    if text.startswith("X"):
        assert text[1:].isdigit(), text
        return int(text[1:])
    assert text.startswith("[") and text.endswith("]"), text
    body, depth = text[1:-1], 0
    for k, ch in enumerate(body):
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            return (parse_word(body[:k]), parse_word(body[k + 1:]))
    raise AssertionError(f"bad word {text!r}")


def word_length(w):
    return 1 if isinstance(w, int) else word_length(w[0]) + word_length(w[1])


def word_field(w, fields, coords):
    if isinstance(w, int):
        return tuple(fields[w - 1])
    return lie_bracket(word_field(w[0], fields, coords), word_field(w[1], fields, coords), coords)


# ---------------------------------------------------------------------------------------------
# model files and the CLI
# ---------------------------------------------------------------------------------------------
def toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def write_model(path: Path, name, coords, fields, params=None) -> Path:
    lines = [f"name = {toml_str(name)}", f"description = {toml_str('acceptance: ' + name)}"]
    lines.append("coordinates = [" + ", ".join(toml_str(str(c)) for c in coords) + "]")
    if params:
        lines += ["", "[parameters]"] + [f"{k} = {v}" for k, v in params.items()]
    for X in fields:
        lines += ["", "[[fields]]"]
        for c, comp in zip(coords, X, strict=True):
            if comp != 0:
                lines.append(f"{toml_str(str(c))} = {toml_str(str(comp))}")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture
def cli(capsys):
    """Run ``nilpotent ARGS`` in-process; return (status, stdout, stderr)."""
    from nilpotent.cli import main

    def _run(*args: str):
        capsys.readouterr()
        status = main([str(a) for a in args])
        out, err = capsys.readouterr()
        return status, out, err

    return _run


def run_json(cli, *args):
    status, out, err = cli(*args, "--json")
    assert status == 0, f"nilpotent {' '.join(map(str, args))} --json: exit {status}\n{out}\n{err}"
    assert "Traceback" not in err
    return json.loads(out)


def point_arg(coords, point):
    return ",".join(f"{c}={sp.sstr(v)}" for c, v in zip(coords, point, strict=True))


ANALYSIS_TYPES = {
    "schema": str, "model": str, "coordinates": list, "point": dict,
    "bracket_generating": bool, "growth_vector": list, "weights": list, "step": int,
    "regular": bool, "frame": list, "frame_values": list,
}


def check_analysis(
    data, coords, fields, point, *, schema="nilpotent/analysis@1", name=None, exact=True,
    max_length=6,
):
    """Every key and value of the analysis JSON against the oracle. Returns (growth, weights)."""
    for key, typ in ANALYSIS_TYPES.items():
        assert key in data, f"missing key {key!r}"
        assert type(data[key]) is typ, f"{key}: {type(data[key]).__name__} is not {typ.__name__}"
    assert data["schema"] == schema
    if name is not None:
        assert data["model"] == name
    names = [str(c) for c in coords]
    assert data["coordinates"] == names
    assert list(data["point"]) == names
    for c, v in zip(names, point, strict=True):
        assert is_zero(grammar(data["point"][c], exact=exact) - v), (c, data["point"][c], v)
    for pname, pval in data.get("parameters", {}).items():
        assert pname.isidentifier()
        grammar(pval, exact=False)
    growth, bg = oracle_growth(fields, coords, point, max_length)
    assert all(type(g) is int for g in data["growth_vector"] + data["weights"])
    assert data["bracket_generating"] is bg
    assert tuple(data["growth_vector"]) == growth
    assert tuple(data["weights"]) == weights_of(growth)
    assert data["step"] == len(growth)
    generic = oracle_generic_growth(fields, coords, point, len(growth) + 1)
    assert data["regular"] is (generic == growth), (generic, growth)
    if "generic_growth_vector" in data:
        assert tuple(data["generic_growth_vector"]) == generic
    # frame: words of the right lengths, values at p exact and equal to ours, adapted
    frame = [parse_word(w) for w in data["frame"]]
    assert len(frame) == growth[-1] == len(data["frame_values"])
    assert [word_length(w) for w in frame] == list(weights_of(growth))
    values = []
    for w, col in zip(frame, data["frame_values"], strict=True):
        assert len(col) == len(coords)
        mine = [at(c, coords, point) for c in word_field(w, fields, coords)]
        got = [grammar(v, exact=exact) for v in col]
        assert all(is_zero(a - b) for a, b in zip(mine, got, strict=True)), (w, mine, got)
        values.append(mine)
    for ns in growth:
        assert exact_rank(values[:ns]) == ns
    return growth, weights_of(growth)


def check_approximation(data, coords, fields, point, *, method=None, exact=True):
    """Re-derive every property of the nilpotent approximation from the returned JSON."""
    growth, weights = check_analysis(
        data, coords, fields, point, schema="nilpotent/approximation@1", exact=exact
    )
    n, m, r = len(coords), len(fields), len(growth)
    assert growth[-1] == n
    assert isinstance(data["method"], str)
    if method is not None:
        assert data["method"] == method
    priv = data["privileged"]
    # where the product declares inexact arithmetic (values such as sin(1/3) at p), the
    # coordinates may carry decimals: every property is then checked to FLOAT_TOL
    if data.get("exact") is False or priv.get("numeric") is True:
        exact = False
    ynames = priv["names"]
    assert len(ynames) == n and len(set(ynames)) == n
    assert all(isinstance(s, str) and s.isidentifier() for s in ynames)
    Y = sp.symbols(ynames)
    xmap = {str(c): c for c in coords}
    yx = [grammar(e, xmap, exact=exact) for e in priv["expressions"]]
    assert len(yx) == n
    # y(p) = 0 and y is a local diffeomorphism at p
    assert all(is_zero(at(e, coords, point)) for e in yx)
    J = sp.Matrix(yx).jacobian(sp.Matrix(coords))
    assert exact_rank([[at(J[i, j], coords, point) for j in range(n)] for i in range(n)]) == n
    # privileged: ord_p(y_j) = w_j
    for j, e in enumerate(yx):
        assert nh_order(fields, coords, e, point, weights[j]) == weights[j], (j, e)
    # X̂: polynomials in y, homogeneous of degree −1
    ymap = {s: sym for s, sym in zip(ynames, Y, strict=True)}
    hat = [[grammar(c, ymap, exact=exact) for c in comp] for comp in data["fields"]]
    assert len(hat) == m and all(len(h) == n for h in hat)
    for h in hat:
        for j, c in enumerate(h):
            c = sp.expand(c)
            if c == 0:
                continue
            assert c.free_symbols <= set(Y), c
            poly = sp.Poly(c, *Y)
            for mon, coeff in poly.terms():
                if is_zero(coeff):
                    continue
                degree = sum(a * w for a, w in zip(mon, weights, strict=True))
                assert degree == weights[j] - 1, (j, c)
    # nilpotent of step r: brackets of length r + 1 vanish identically; growth at 0 equal
    assert all(all(is_zero(c) for c in B) for _, B in right_normed(hat, Y, r + 1))
    assert oracle_growth(hat, Y, [0] * n)[0] == growth
    # X_i − X̂_i of order >= 0 (a): ord_p(X_i y_j − X̂_ij(y(x))) >= w_j
    ysub = dict(zip(Y, yx, strict=True))
    for i in range(m):
        for j in range(n):
            g = apply_field(fields[i], yx[j], coords) - hat[i][j].subs(ysub, simultaneous=True)
            assert nh_order(fields, coords, g, point, weights[j] - 1) >= weights[j], (i, j)
    # (b) with the product's inverse, where it says it is exact: weighted Taylor expansion
    if priv.get("inverse_exact") and "inverse" in priv:
        xy = [grammar(e, ymap, exact=exact) for e in priv["inverse"]]
        back_sub = dict(zip(coords, xy, strict=True))
        back = [sp.expand(e.subs(back_sub, simultaneous=True)) for e in yx]
        if all(is_zero(b - s) for b, s in zip(back, Y, strict=True)):
            t = sp.Symbol("t")
            scale = {s: t**w * s for s, w in zip(Y, weights, strict=True)}
            for i in range(m):
                for j in range(n):
                    comp = apply_field(fields[i], yx[j], coords)
                    comp = comp.subs(dict(zip(coords, xy, strict=True)), simultaneous=True)
                    comp = comp.subs(scale, simultaneous=True)
                    ser = sp.expand(sp.series(comp, t, 0, weights[j]).removeO())
                    low = sp.expand(ser - hat[i][j].subs(scale, simultaneous=True))
                    assert is_zero(low), (i, j, low)
    # extra output fields_x (X̂ in model coordinates): (∂y/∂x)·X̂_x = X̂_y∘y
    if "fields_x" in data and priv.get("inverse_exact"):
        for i, comp in enumerate(data["fields_x"]):
            vx = sp.Matrix([grammar(c, xmap, exact=exact) for c in comp])
            lhs = J * vx
            for j in range(n):
                rhs = hat[i][j].subs(ysub, simultaneous=True)
                assert is_zero(sp.simplify(lhs[j] - rhs)), ("fields_x", i, j)
    cert = data["certificate"]
    assert cert["orders"] == list(weights)
    assert cert["nilpotent_step"] == r
    assert cert["homogeneous"] is True
    return weights, yx, hat, Y


# ---------------------------------------------------------------------------------------------
# the systems (none of them built in)
# ---------------------------------------------------------------------------------------------
def engel_scrambled():
    """Engel X1 = ∂1, X2 = ∂2 + x1 ∂3 + x1²/2 ∂4 seen in coordinates (d, b, a, c) with
    d = x4 + x2, b = x1, a = x3 − x1, c = x2 (a linear change, order scrambled)."""
    x = sp.symbols("x1:5")
    base = [(1, 0, 0, 0), (0, 1, x[0], x[0] ** 2 / 2)]
    z = sp.symbols("d b a c")
    phi = [x[3] + x[1], x[0], x[2] - x[0], x[1]]
    psi = [z[1], z[3], z[2] + z[1], z[0] - z[3]]
    return z, push_forward(base, x, phi, psi, z)


def engel_nonlinear():
    """Engel pushed through z3 = x3 + x1², z4 = x4 + x1 x2 + x2³: linear adapted
    coordinates are not privileged at 0 (ord z4 = 2, weight 3)."""
    x = sp.symbols("x1:5")
    base = [(1, 0, 0, 0), (0, 1, x[0], x[0] ** 2 / 2)]
    z = sp.symbols("z1:5")
    phi = [x[0], x[1], x[2] + x[0] ** 2, x[3] + x[0] * x[1] + x[1] ** 3]
    psi = [z[0], z[1], z[2] - z[0] ** 2, z[3] - z[0] * z[1] - z[1] ** 3]
    return z, push_forward(base, x, phi, psi, z)


def unicycle_sheared():
    """Unicycle (ẋ = cos θ, ẏ = sin θ, θ̇) in coordinates a = x + 2y, b = y − x/2, c = θ."""
    a, b, c = sp.symbols("a b c")
    return (a, b, c), [(sp.cos(c) + 2 * sp.sin(c), sp.sin(c) - sp.cos(c) / 2, 0), (0, 0, 1)]


def trailer_rotated():
    """Unicycle with one trailer (ẋ = cos θ0, ẏ = sin θ0, θ̇1 = sin(θ0 − θ1); θ̇0), with the
    plane rotated by π/6 and coordinates in the order (t1, t0, v, u): growth (2,3,4)."""
    u, v, t0, t1 = sp.symbols("u v t0 t1")
    cs, sn = sp.sqrt(3) / 2, sp.Rational(1, 2)
    dx, dy = sp.cos(t0), sp.sin(t0)
    X1 = (sp.sin(t0 - t1), 0, -sn * dx + cs * dy, cs * dx + sn * dy)
    X2 = (0, 1, 0, 0)
    return (t1, t0, v, u), [X1, X2]


def martinet_mixed():
    """Martinet X1 = ∂1 + x2²/2 ∂3, X2 = ∂2 in a = x3 + x1, b = x1, c = x2 − x1;
    singular on x2 = 0, i.e. b + c = 0."""
    a, b, c = sp.symbols("a b c")
    return (a, b, c), [(1 + (b + c) ** 2 / 2, 1, -1), (0, 0, 1)]


def free_three_inputs():
    """A nonlinear 3-input system in R^6, growth (3,6), coordinates out of order."""
    x = sp.symbols("p1 p2 p3 q12 q13 q23")
    _, p2, p3, _, _, q23 = x
    X1 = (1, 0, 0, p2 + q23**2, p3, sp.sin(p2) * p3)
    X2 = (0, 1, 0, 0, 0, p3)
    X3 = (0, 0, 1, 0, 0, 0)
    order = [3, 0, 5, 1, 4, 2]   # scramble the coordinate order
    coords = tuple(x[k] for k in order)
    fields = [tuple(X[k] for k in order) for X in (X1, X2, X3)]
    return coords, fields


# ---------------------------------------------------------------------------------------------
# (1) polynomial R^4, growth (2,3,4), scrambled coordinates
# ---------------------------------------------------------------------------------------------
def test_engel_scrambled_analyze_and_approximate(cli, tmp_path):
    coords, fields = engel_scrambled()
    f = write_model(tmp_path / "engel_scr.toml", "engel-scrambled", coords, fields)
    point = [0, 0, 0, 0]
    data = run_json(cli, "analyze", f)
    growth, weights = check_analysis(data, coords, fields, point, name="engel-scrambled")
    assert growth == (2, 3, 4) and weights == (1, 1, 2, 3)
    assert data["bracket_generating"] is True and data["regular"] is True
    data = run_json(cli, "approximate", f)
    check_approximation(data, coords, fields, point)
    assert data["method"] != "linear" or True  # any privileged method is acceptable


def test_engel_scrambled_at_other_point(cli, tmp_path):
    coords, fields = engel_scrambled()
    f = write_model(tmp_path / "engel_scr.toml", "engel-scrambled", coords, fields)
    point = [sp.Rational(1, 3), sp.Integer(-2), sp.Rational(5, 7), sp.Integer(1)]
    data = run_json(cli, "approximate", f, "--at", point_arg(coords, point))
    check_approximation(data, coords, fields, point)


# ---------------------------------------------------------------------------------------------
# (2) trigonometric systems at non-origin points with exact values
# ---------------------------------------------------------------------------------------------
def test_unicycle_sheared_at_exact_point(cli, tmp_path):
    coords, fields = unicycle_sheared()
    f = write_model(tmp_path / "uni.toml", "unicycle-sheared", coords, fields)
    point = [sp.Rational(1, 2), sp.Integer(0), sp.pi / 4]
    at_text = "a=1/2,c=pi/4"
    data = run_json(cli, "analyze", f, "--at", at_text)
    growth, _ = check_analysis(data, coords, fields, point)
    assert growth == (2, 3)
    assert data["point"]["b"] == "0"
    data = run_json(cli, "approximate", f, "--at", at_text)
    assert data["exact"] is True   # algebraic values at p: exact arithmetic throughout
    check_approximation(data, coords, fields, point)
    # step 2: the default is the linear adapted coordinates (INTERFACE.md)
    assert data["method"] == "linear"


@pytest.mark.parametrize("method", [None, "algebraic", "exponential"])
def test_rolling_disk(cli, tmp_path, method):
    """A vertical rolling disk (ẋ = cos θ, ẏ = sin θ, φ̇ = 1 on X1; θ̇ on X2), coordinates
    in the order (phi, x, theta, y): growth (2, 3, 4), since X1 − [X2,[X1,X2]] = ∂φ."""
    x, y, th, ph = sp.symbols("x y theta phi")
    coords = (ph, x, th, y)
    fields = [(1, sp.cos(th), 0, sp.sin(th)), (0, 0, 1, 0)]
    f = write_model(tmp_path / "disk.toml", "rolling-disk", coords, fields)
    point = [sp.Rational(1, 2), 0, sp.pi / 6, 1]
    args = ["approximate", f, "--at", "phi=1/2,theta=pi/6,y=1"]
    data = run_json(cli, *args + (["--method", method] if method else []))
    weights, *_ = check_approximation(data, coords, fields, point, method=method)
    assert weights == (1, 1, 2, 3)


@pytest.mark.parametrize("case", ["denested-radical", "trig-value"])
def test_zero_only_after_simplification(cli, tmp_path, case):
    """[X1,X2](p) = 0 only after denesting sqrt(3+2 sqrt 2) = 1 + sqrt 2, or using
    sin(pi/12) = (sqrt 6 − sqrt 2)/4: the growth drops to (2, 2, 3) there."""
    a, b, c = sp.symbols("a b c")
    if case == "denested-radical":
        fields = [(1, 0, 0), (0, 1, (a - 1 - sp.sqrt(2)) ** 2)]
        point, at_text = [sp.sqrt(3 + 2 * sp.sqrt(2)), 0, 0], "a=sqrt(3+2*sqrt(2))"
    else:
        fields = [(1, 0, 0), (0, 1, (sp.sin(a) - (sp.sqrt(6) - sp.sqrt(2)) / 4) ** 2)]
        point, at_text = [sp.pi / 12, 0, 0], "a=pi/12"
    f = write_model(tmp_path / "z.toml", case, (a, b, c), fields)
    data = run_json(cli, "analyze", f, "--at", at_text)
    growth, _ = check_analysis(data, (a, b, c), fields, point)
    assert growth == (2, 2, 3) and data["regular"] is False
    data = run_json(cli, "approximate", f, "--at", at_text)
    check_approximation(data, (a, b, c), fields, point)


@pytest.mark.slow
def test_trailer_rotated_step3_trig(cli, tmp_path):
    coords, fields = trailer_rotated()
    f = write_model(tmp_path / "trailer.toml", "trailer-rotated", coords, fields)
    point = [sp.pi / 4, sp.pi / 3, sp.Rational(1, 2), sp.Integer(0)]
    at_text = "t1=pi/4,t0=pi/3,v=1/2"
    data = run_json(cli, "approximate", f, "--at", at_text)
    weights, *_ = check_approximation(data, coords, fields, point)
    assert weights == (1, 1, 2, 3)


@pytest.mark.parametrize(
    "case, at_text",
    [
        ("unicycle", "a=0.5,c=0.3"),
        ("unicycle", "c=0.785"),
        ("engel", "z1=0.25,z2=-0.5"),
    ],
)
def test_decimal_points(cli, tmp_path, case, at_text):
    """INTERFACE.md: point values may be decimals; every property must still hold
    (zero tests to 1e-9 in the oracle)."""
    coords, fields = unicycle_sheared() if case == "unicycle" else engel_nonlinear()
    f = write_model(tmp_path / "dec.toml", case, coords, fields)
    given = dict(item.split("=") for item in at_text.split(","))
    point = [sp.Float(given[str(c)]) if str(c) in given else sp.Integer(0) for c in coords]
    data = run_json(cli, "analyze", f, "--at", at_text)
    check_analysis(data, coords, fields, point, exact=False)
    data = run_json(cli, "approximate", f, "--at", at_text)
    check_approximation(data, coords, fields, point, exact=False)


@pytest.mark.slow
def test_car_two_trailers_step4_trig(cli, tmp_path):
    """Unicycle with two trailers (growth (2,3,4,5)) at angles pi/4, pi/3, pi/2, coordinates
    out of order; the default (algebraic) coordinates must pass every property."""
    x, y, t0, t1, t2 = sp.symbols("x y t0 t1 t2")
    X1 = (sp.cos(t0), sp.sin(t0), 0, sp.sin(t0 - t1), sp.cos(t0 - t1) * sp.sin(t1 - t2))
    X2 = (0, 0, 1, 0, 0)
    order = (4, 0, 3, 1, 2)
    coords = tuple((x, y, t0, t1, t2)[k] for k in order)
    fields = [tuple(X[k] for k in order) for X in (X1, X2)]
    f = write_model(tmp_path / "trailers2.toml", "trailers2", coords, fields)
    point = [sp.pi / 4, 0, sp.pi / 3, 0, sp.pi / 2]
    data = run_json(cli, "approximate", f, "--at", "t2=pi/4,t1=pi/3,t0=pi/2")
    weights, *_ = check_approximation(data, coords, fields, point)
    assert weights == (1, 1, 2, 3, 4)


# ---------------------------------------------------------------------------------------------
# (3) singular points
# ---------------------------------------------------------------------------------------------
def test_martinet_mixed_singular_point(cli, tmp_path):
    coords, fields = martinet_mixed()
    f = write_model(tmp_path / "mart.toml", "martinet-mixed", coords, fields)
    point = [sp.Integer(3), sp.Rational(1, 2), sp.Rational(-1, 2)]
    at_text = "a=3,b=1/2,c=-1/2"
    data = run_json(cli, "analyze", f, "--at", at_text)
    growth, weights = check_analysis(data, coords, fields, point)
    assert growth == (2, 2, 3) and weights == (1, 1, 3)
    assert data["regular"] is False
    data = run_json(cli, "approximate", f, "--at", at_text)
    assert data["exact"] is True
    check_approximation(data, coords, fields, point)
    # the same system at a regular point
    data = run_json(cli, "analyze", f, "--at", "b=1")
    growth, _ = check_analysis(data, coords, fields, [0, 1, 0])
    assert growth == (2, 3) and data["regular"] is True


def test_growth_drops_at_point(cli, tmp_path):
    x = sp.symbols("x1:4")
    fields = [(1, 0, 0), (0, 1, x[0] ** 2)]
    f = write_model(tmp_path / "drop.toml", "drop", x, fields)
    data = run_json(cli, "analyze", f)
    growth, weights = check_analysis(data, x, fields, [0, 0, 0])
    assert growth == (2, 2, 3) and weights == (1, 1, 3) and data["regular"] is False
    data = run_json(cli, "approximate", f)
    check_approximation(data, x, fields, [0, 0, 0])
    # linear coordinates are privileged here (fields polynomial, weights match degrees)
    data = run_json(cli, "approximate", f, "--method", "linear")
    check_approximation(data, x, fields, [0, 0, 0], method="linear")




@pytest.mark.parametrize(
    "k", [6, 10]
)
def test_high_step_singular_point(cli, tmp_path, k):
    """X1 = ∂a, X2 = ∂b + a^k ∂c at 0: growth (2, ..., 2, 3) of step k + 1, weights
    (1, 1, k + 1); bracket-generating (X1^k X2 = k! ∂c), singular."""
    a, b, c = sp.symbols("a b c")
    fields = [(1, 0, 0), (0, 1, a**k)]
    f = write_model(tmp_path / "pow.toml", f"pow{k}", (a, b, c), fields)
    data = run_json(cli, "analyze", f)
    growth, _ = check_analysis(data, (a, b, c), fields, [0, 0, 0], max_length=k + 2)
    assert growth == (2,) * k + (3,)
    assert data["bracket_generating"] is True and data["regular"] is False


# ---------------------------------------------------------------------------------------------
# (4) not bracket-generating
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("which", ["poly", "trig"])
def test_not_bracket_generating(cli, tmp_path, which):
    x = sp.symbols("x1:5")
    if which == "poly":
        fields = [(1, 0, 0, 0), (0, 1, x[0], 0)]
    else:  # a unicycle in R^4: x4 never moves, Lie algebra se(2)
        fields = [(sp.cos(x[2]), sp.sin(x[2]), 0, 0), (0, 0, 1, 0)]
    f = write_model(tmp_path / "nbg.toml", "nbg", x, fields)
    data = run_json(cli, "analyze", f, "--at", "x3=1/5")
    growth, _ = check_analysis(data, x, fields, [0, 0, sp.Rational(1, 5), 0])
    assert growth == (2, 3)
    assert data["bracket_generating"] is False
    assert len(data["weights"]) == 3
    status, out, err = cli("approximate", f, "--json")
    assert status == 2
    err_obj = json.loads(out)["error"]
    assert err_obj["kind"] == "not-bracket-generating"
    assert "Traceback" not in err


def test_fields_vanishing_at_point(cli, tmp_path):
    """X1 = a ∂a, X2 = a ∂b at 0: every bracket is a multiple of a (the line a = 0 is
    invariant), so at p the brackets span {0} at every length: not bracket-generating."""
    a, b = sp.symbols("a b")
    fields = [(a, 0), (0, a)]
    f = write_model(tmp_path / "vanish.toml", "vanish", (a, b), fields)
    data = run_json(cli, "analyze", f)
    check_analysis(data, (a, b), fields, [0, 0])
    assert data["bracket_generating"] is False and data["growth_vector"] == [0]


# ---------------------------------------------------------------------------------------------
# (5) linear adapted coordinates are not privileged
# ---------------------------------------------------------------------------------------------
def test_engel_nonlinear_linear_refused(cli, tmp_path):
    coords, fields = engel_nonlinear()
    # oracle: linear adapted coordinates here are z itself (frame values are unit vectors),
    # and ord_0(z4) = 2 < 3 = w_4
    assert nh_order(fields, coords, coords[3], [0] * 4, 3) == 2
    f = write_model(tmp_path / "engel_nl.toml", "engel-nonlinear", coords, fields)
    status, out, err = cli("approximate", f, "--method", "linear", "--json")
    assert status == 2, out
    e = json.loads(out)["error"]
    assert e["kind"] == "not-privileged"
    assert "linear" in e["message"] and len(e["message"]) > 20
    assert "Traceback" not in err
    status, out, err = cli("approximate", f, "--method", "linear")
    assert status == 2 and out == "" and "Traceback" not in err and err.strip()


@pytest.mark.parametrize("method", [None, "algebraic", "exponential"])
def test_engel_nonlinear_privileged_methods(cli, tmp_path, method):
    coords, fields = engel_nonlinear()
    f = write_model(tmp_path / "engel_nl.toml", "engel-nonlinear", coords, fields)
    args = ["approximate", f] + (["--method", method] if method else [])
    data = run_json(cli, *args)
    check_approximation(data, coords, fields, [0] * 4, method=method)
    if method is None:
        assert data["method"] != "linear"


@pytest.mark.slow
@pytest.mark.parametrize("method", ["algebraic", "exponential"])
def test_engel_nonlinear_off_origin(cli, tmp_path, method):
    coords, fields = engel_nonlinear()
    f = write_model(tmp_path / "engel_nl.toml", "engel-nonlinear", coords, fields)
    point = [sp.Rational(1, 2), sp.Integer(-1), sp.Integer(0), sp.Rational(2, 3)]
    data = run_json(cli, "approximate", f, "--at", point_arg(coords, point), "--method", method)
    check_approximation(data, coords, fields, point, method=method)


def _mutations(data):
    """Wrong answers that a correct oracle must refuse (each a function of a deep copy)."""
    def linear_coordinates(d):   # not privileged for this system (ord z4 = 2)
        d["privileged"]["expressions"] = list(d["coordinates"])
        d["privileged"].pop("inverse", None)

    def wrong_coefficient(d):    # still homogeneous, but X1 − X̂1 is no longer of order >= 0
        names = d["privileged"]["names"]
        d["fields"][0][2] = f"({d['fields'][0][2]}) + {names[1]}"

    def homogeneous_but_wrong(d):  # same graded structure, but not the part of degree w_j − 1
        names = d["privileged"]["names"]
        d["fields"][1][3] = f"({d['fields'][1][3]}) + 5*{names[1]}**2"

    def not_homogeneous(d):
        names = d["privileged"]["names"]
        d["fields"][1][2] = f"({d['fields'][1][2]}) + {names[0]}**2"

    def wrong_growth(d):
        d["growth_vector"] = [2, 4]
        d["weights"] = [1, 1, 2, 2]
        d["step"] = 2

    def wrong_frame_value(d):
        d["frame_values"][2] = ["0", "0", "2", "0"]

    def nonzero_at_p(d):
        d["privileged"]["expressions"][0] = f"({d['privileged']['expressions'][0]}) + 1"

    def wrong_step(d):
        d["certificate"]["nilpotent_step"] = 2

    return [linear_coordinates, wrong_coefficient, homogeneous_but_wrong, not_homogeneous,
            wrong_growth, wrong_frame_value, nonzero_at_p, wrong_step]


def test_oracle_refuses_wrong_answers(cli, tmp_path):
    """The oracle itself: a correct answer passes, each corrupted copy of it fails."""
    coords, fields = engel_nonlinear()
    f = write_model(tmp_path / "engel_nl.toml", "engel-nonlinear", coords, fields)
    data = run_json(cli, "approximate", f)
    check_approximation(data, coords, fields, [0] * 4)
    for mutate in _mutations(data):
        bad = json.loads(json.dumps(data))
        mutate(bad)
        with pytest.raises(AssertionError):
            check_approximation(bad, coords, fields, [0] * 4)


# ---------------------------------------------------------------------------------------------
# (6) three inputs, step 2, growth (3, 6)
# ---------------------------------------------------------------------------------------------
def test_three_inputs_free_step2(cli, tmp_path):
    coords, fields = free_three_inputs()
    f = write_model(tmp_path / "free3.toml", "free3", coords, fields)
    point = [0] * 6
    point[coords.index(sp.Symbol("p2"))] = sp.Rational(1, 3)
    point[coords.index(sp.Symbol("q23"))] = sp.Integer(2)
    at_text = "p2=1/3,q23=2"
    data = run_json(cli, "approximate", f, "--at", at_text)
    weights, *_ = check_approximation(data, coords, fields, point)
    assert data["growth_vector"] == [3, 6] and weights == (1, 1, 1, 2, 2, 2)


def test_privileged_coordinates_vanish_exactly_at_exact_point(cli, tmp_path):
    """INTERFACE.md: y_j(p) = 0. With p given exactly (p2 = 1/3) this must hold exactly,
    also where the product computes in floats (sin(1/3) among the values at p): an outside
    checker in exact arithmetic evaluates privileged.expressions at the exact point."""
    coords, fields = free_three_inputs()
    f = write_model(tmp_path / "free3.toml", "free3", coords, fields)
    data = run_json(cli, "approximate", f, "--at", "p2=1/3,q23=2")
    xmap = {str(c): c for c in coords}
    point = {c: sp.Integer(0) for c in coords}
    point.update({xmap["p2"]: sp.Rational(1, 3), xmap["q23"]: sp.Integer(2)})
    for text in data["privileged"]["expressions"]:
        value = grammar(text, xmap, exact=False, decimals_as_written=True).subs(point)
        assert value == 0, f"y(p) = {value!r} for {text!r}"


# ---------------------------------------------------------------------------------------------
# (7) parameters
# ---------------------------------------------------------------------------------------------
def test_parameters_and_param_option(cli, tmp_path):
    x = sp.symbols("x1:4")
    k = sp.Symbol("k")
    f = write_model(tmp_path / "par.toml", "par", x, [(1, 0, 0), (0, 1, k * x[0])], {"k": 2})
    for value, params in ((2, []), (sp.Rational(3, 5), ["--param", "k=3/5"])):
        fields = [(1, 0, 0), (0, 1, value * x[0])]
        data = run_json(cli, "analyze", f, *params)
        check_analysis(data, x, fields, [0, 0, 0])
        assert [grammar(v) for v in data["frame_values"][2]] == [0, 0, value]
        data = run_json(cli, "approximate", f, *params)
        check_approximation(data, x, fields, [0, 0, 0])
    # k = 0: no longer bracket generating
    data = run_json(cli, "analyze", f, "--param", "k=0")
    assert data["bracket_generating"] is False and data["growth_vector"] == [2]
    status, out, _ = cli("analyze", f, "--param", "zz=1", "--json")
    assert status == 2 and "error" in json.loads(out)


def test_json_model_file(cli, tmp_path):
    """The same structure as JSON (INTERFACE.md), exact strings and plain numbers mixed."""
    coords, fields = free_three_inputs()
    doc = {
        "name": "free3-json",
        "coordinates": [str(c) for c in coords],
        "parameters": {"k": 1},
        "fields": [
            {str(c): (str(comp) if comp not in (0, 1) else int(comp))
             for c, comp in zip(coords, X, strict=True) if comp != 0}
            for X in fields
        ],
    }
    f = tmp_path / "free3.json"
    f.write_text(json.dumps(doc))
    data = run_json(cli, "analyze", f, "--at", "p2=1/3")
    point = [sp.Rational(1, 3) if str(c) == "p2" else 0 for c in coords]
    growth, _ = check_analysis(data, coords, fields, point, name="free3-json")
    assert growth == (3, 6)
    assert data.get("parameters", {"k": "1"}) == {"k": "1"}


# ---------------------------------------------------------------------------------------------
# (8) hostile model files
# ---------------------------------------------------------------------------------------------
HOSTILE = {
    # file name: texts that must appear in the one-line message, besides the file name
    # (the field, and the offending text where there is one)
    "attribute.toml": ("fields[0].x", "y.__class__"),
    "dunder.toml": ("fields[0].x", "__builtins__"),
    "import.toml": ("fields[0].x", "__import__"),
    "lambda.toml": ("fields[0].x", "lambda"),
    "power.toml": ("fields[0].x", "9**9**9**9"),
    "unknown_function.toml": ("fields[0].x", "gamma"),
    "unknown_name.toml": ("fields[0].x", "w + 1"),
    "unknown_coordinate_key.toml": ("fields[0]", "'w'"),
    "string_literal.toml": ("fields[0].x", "text"),
    "syntax_error.toml": ("line 4",),
    "empty_fields.toml": ("fields",),
    "no_fields.toml": ("fields",),
    "duplicate_coordinates.toml": ("coordinates", "'x'"),
    "string_parameter.toml": ("parameters.k", "one"),
    "boolean_component.toml": ("fields[0].x",),
    "number_coordinates.toml": ("coordinates",),
    "table_component.toml": ("fields[0].x",),
    "json_garbage.json": ("JSON",),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_model_files(cli, name, tmp_path):
    path = DATA / name
    canary = Path("/tmp/nilpotent_acceptance_pwned")
    for as_json in (True, False):
        args = ["analyze", path] + (["--json"] if as_json else [])
        status, out, err = cli(*args)
        assert status == 2, (name, out, err)
        assert "Traceback" not in out + err
        if as_json:
            obj = json.loads(out)
            assert set(obj) == {"error"} and set(obj["error"]) == {"kind", "message"}
            assert isinstance(obj["error"]["kind"], str) and obj["error"]["kind"]
            message = obj["error"]["message"]
        else:
            assert out == ""
            message = err
        assert name in message, message
        for needle in HOSTILE[name]:
            assert needle in message, (needle, message)
        assert "\n" not in message.strip(), message
    assert not canary.exists()


NOT_SMOOTH = {
    # components that are not smooth (not analytic) at a = 0
    "sqrt.toml": 'c = "sqrt(a)"',
    "abs.toml": 'c = "sqrt(a**2)"',
    "cube_root.toml": 'c = "(a**2)**(1/3)"',
}


@pytest.mark.parametrize("name", sorted(NOT_SMOOTH))
@pytest.mark.parametrize("command", ["approximate", "simulate"])
def test_fields_not_smooth_at_point_refused_cleanly(cli, tmp_path, name, command):
    """A field that is not smooth at p has no nilpotent approximation there: exit 2 with a
    JSON error, never a traceback (the same files are fine at a = 1)."""
    f = tmp_path / name
    f.write_text(
        'name = "not-smooth"\ncoordinates = ["a", "b", "c"]\n'
        f'[[fields]]\na = "1"\n{NOT_SMOOTH[name]}\n[[fields]]\nb = "1"\nc = "a"\n'
    )
    extra = ["--bracket", "1,2", "--amplitude", "0.01"] if command == "simulate" else []
    data = run_json(cli, command, f, *extra, "--at", "a=1")
    assert "error" not in data
    try:
        status, out, err = cli(command, f, *extra, "--at", "a=0", "--json")
    except Exception as exc:  # the CLI let an internal error through
        pytest.fail(f"nilpotent {command} {name} --at a=0 --json raised {exc!r}")
    assert status == 2, (status, out, err)
    assert "Traceback" not in err
    assert set(json.loads(out)) == {"error"}


def test_hostile_power_refused_quickly():
    """9**9**9**9 must be refused, not computed (a separate process with a deadline)."""
    proc = subprocess.run(
        [sys.executable, "-m", "nilpotent", "analyze", str(DATA / "power.toml"), "--json"],
        capture_output=True, text=True, timeout=120,
    )
    assert proc.returncode == 2
    assert "error" in json.loads(proc.stdout)


# ---------------------------------------------------------------------------------------------
# simulate: end point against scipy, prediction against πA²[X1,X2](p)
# ---------------------------------------------------------------------------------------------
def _integrate(fields, coords, x0, i, j, A, omega, periods):
    rhs = [sp.lambdify(coords, list(X), "numpy") for X in fields]

    def f(t, x):
        u = np.zeros(len(fields))
        u[i - 1] = -A * omega * math.sin(omega * t)
        u[j - 1] = A * omega * math.cos(omega * t)
        return sum(u[k] * np.asarray(rhs[k](*x), dtype=float) for k in range(len(fields)))

    T = periods * 2 * math.pi / omega
    sol = solve_ivp(f, (0, T), np.asarray(x0, dtype=float), method="DOP853",
                    rtol=1e-12, atol=1e-14)
    assert sol.success
    return sol.y[:, -1]


@pytest.mark.parametrize("case", ["unicycle", "engel", "engel-omega2-periods2", "martinet"])
def test_simulate_against_scipy(cli, tmp_path, case):
    omega, periods, pair = 1.0, 1, (1, 2)
    if case == "unicycle":
        coords, fields = unicycle_sheared()
        point = [sp.Rational(1, 2), sp.Integer(0), sp.pi / 4]
        at_text = "a=1/2,c=pi/4"
    elif case == "martinet":   # a singular point: weights (1, 1, 3)
        coords, fields = martinet_mixed()
        point = [sp.Integer(3), sp.Rational(1, 2), sp.Rational(-1, 2)]
        at_text = "a=3,b=1/2,c=-1/2"
        pair = (2, 1)
    else:
        coords, fields = engel_nonlinear()
        point = [sp.Rational(1, 2), 0, 0, 0]
        at_text = "z1=1/2"
        if case != "engel":
            omega, periods = 2.0, 2
    f = write_model(tmp_path / "sim.toml", case, coords, fields)
    A = 0.05
    data = run_json(
        cli, "simulate", f, "--bracket", f"{pair[0]},{pair[1]}", "--amplitude", str(A),
        "--omega", str(omega), "--periods", str(periods), "--at", at_text,
    )
    assert data["schema"] == "nilpotent/simulation@1"
    assert data["bracket"] == list(pair) and data["amplitude"] == A
    assert data["omega"] == omega and data["periods"] == periods
    assert data["coordinates"] == [str(c) for c in coords]
    assert list(data["point"]) == [str(c) for c in coords]
    p = np.array([float(v) for v in point])
    end = _integrate(fields, coords, p, *pair, A, omega, periods)
    got = np.array(data["final"]["original"], dtype=float)
    assert np.max(np.abs(got - end)) < 1e-8, (got, end)
    bracket = lie_bracket(fields[pair[0] - 1], fields[pair[1] - 1], coords)
    B = [at(c, coords, point) for c in bracket]
    pred = p + periods * math.pi * A**2 * np.array([float(b) for b in B])
    assert np.allclose(data["prediction"], pred, rtol=0, atol=1e-12)
    # the loop realises the bracket to O(A^3)
    assert np.max(np.abs(end - pred)) < 10 * periods * A**3
    # the approximation: integrate X̂ (the default approximation) in y from 0, compare in y
    appr = run_json(cli, "approximate", f, "--at", at_text)
    weights = appr["weights"]
    Y = sp.symbols(appr["privileged"]["names"])
    ymap = {str(s): s for s in Y}
    hat = [[grammar(c, ymap) for c in comp] for comp in appr["fields"]]
    yhat_end = _integrate(hat, Y, np.zeros(len(Y)), *pair, A, omega, periods)
    xmap = {str(c): c for c in coords}
    yx = [
        sp.lambdify(coords, grammar(e, xmap), "numpy")
        for e in appr["privileged"]["expressions"]
    ]
    y_of = lambda x: np.array([float(g(*x)) for g in yx])  # noqa: E731
    y_appr = y_of(np.array(data["final"]["approximation"], dtype=float))
    assert np.max(np.abs(y_appr - yhat_end)) < 1e-8, (y_appr, yhat_end)
    # errors by weight: keys are the weights; end-point values in privileged coordinates
    errs = data["errors"]
    assert set(errs) >= {"endpoint", "max", "by_weight"}
    assert sorted(errs["by_weight"]) == sorted({str(w) for w in weights})
    assert all(isinstance(v, float) and v >= 0 for v in errs["by_weight"].values())
    assert isinstance(errs["endpoint"], float) and isinstance(errs["max"], float)
    assert errs["max"] >= errs["endpoint"] - 1e-15
    assert abs(errs["endpoint"] - np.linalg.norm(got - np.array(data["final"]["approximation"]))) \
        < 1e-12
    diff = np.abs(y_of(end) - yhat_end)
    for w in set(weights):
        idx = [k for k, wk in enumerate(weights) if wk == w]
        mine = float(diff[idx].max())
        assert errs["by_weight"][str(w)] >= mine - 1e-9
        if "by_weight_endpoint" in errs:
            assert abs(errs["by_weight_endpoint"][str(w)] - mine) < 1e-9
        # O(A^{w+1}) in privileged coordinates (MATH.md §6), with a generous constant
        assert mine < 50 * A ** (w + 1)
    assert isinstance(data["tolerance"], float)
