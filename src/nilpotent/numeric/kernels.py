"""Source of the numba integrator kernels appended to each compiled system's module.

:func:`integrator_source` returns Python text that, placed after the generated
``rhs(x, u, out)`` of a system (see :mod:`nilpotent.numeric.compile`), defines

``integrate_batch(x0, durations, omegas, constant, cos, sin, ts, adaptive,
nfixed, rtol, atol, max_steps, min_step, bound, xf, samples, info)``

a ``prange`` loop over the batch.  Per trajectory it integrates
``dx/dt = Σ u_i(t) X_i(x)`` through the input segments
(:class:`~nilpotent.numeric.signals.Signal`), restarting at each segment
boundary (inputs may jump there), with the DOP853 tableau
(:data:`~nilpotent.numeric.tableaux.DOP853`) unrolled into straight-line code:

* ``adaptive=True``: scipy's step control (safety 0.9, factors in [0.2, 10],
  exponent −1/8, initial step as ``scipy.integrate._ivp.common.select_initial_step``),
  error norm of Hairer's DOP853 with scale ``atol + rtol·max(|x|, |x_new|)``;
  steps are shortened to land on the sample times ``ts``;
* ``adaptive=False``: ``nfixed`` equal steps per segment, each piece between two
  sample times getting ``ceil(nfixed·length/duration)`` equal steps.

``info[b] = (status, accepted steps, rejected steps, Σ local error estimates)``
with status 0 ok, 1 too many steps, 2 step below ``min_step``, 3 ``|x|`` above
``bound``, 4 non-finite state.  Samples not reached stay as given (NaN).
"""

from __future__ import annotations

import hashlib

from nilpotent.numeric.tableaux import DOP853, ButcherTableau


def _combo(coeffs: tuple[float, ...], arr: str = "K") -> str:
    terms = [f"{c!r} * {arr}[{s}, k]" for s, c in enumerate(coeffs) if c != 0.0]
    return " + ".join(terms) if terms else "0.0"


def _step_source(t: ButcherTableau) -> str:
    lines = [
        '@njit(cache=True, error_model="numpy")',
        "def _step(tl, x, h, w, a, bc, bs, K, xs, u, xnew):",
        "    # K[0] holds f(tl, x) on entry; fills K[1..S-1] and xnew.",
    ]
    for s in range(1, t.stages):
        lines.append("    for k in range(N):")
        lines.append(f"        xs[k] = x[k] + h * ({_combo(t.a[s])})")
        lines.append(f"    _f(tl + {t.c[s]!r} * h, xs, w, a, bc, bs, u, K[{s}])")
    lines.append("    for k in range(N):")
    lines.append(f"        xnew[k] = x[k] + h * ({_combo(t.b)})")
    lines += ["", ""]
    lines += [
        '@njit(cache=True, error_model="numpy")',
        "def _error_norm(h, x, xnew, K, rtol, atol):",
        "    # K[S] holds f(tl + h, xnew).",
        "    e5sq = 0.0",
        "    e3sq = 0.0",
        "    for k in range(N):",
        "        sc = atol + rtol * max(abs(x[k]), abs(xnew[k]))",
        f"        e5 = ({_combo(t.e5)}) / sc",
        f"        e3 = ({_combo(t.e3)}) / sc",
        "        e5sq += e5 * e5",
        "        e3sq += e3 * e3",
        "    if e5sq == 0.0 and e3sq == 0.0:",
        "        return 0.0",
        "    return abs(h) * e5sq / math.sqrt((e5sq + 0.01 * e3sq) * N)",
        "",
        "",
    ]
    return "\n".join(lines)


_DRIVER = '''
@njit(cache=True, error_model="numpy")
def _inputs(tl, w, a, bc, bs, u):
    for i in range(M):
        u[i] = a[i]
    nk = bc.shape[1]
    if nk > 0:
        c1 = math.cos(w * tl)
        s1 = math.sin(w * tl)
        ck = c1
        sk = s1
        for k in range(nk):
            for i in range(M):
                u[i] += bc[i, k] * ck + bs[i, k] * sk
            if k + 1 < nk:
                ck, sk = ck * c1 - sk * s1, sk * c1 + ck * s1


@njit(cache=True, error_model="numpy")
def _f(tl, x, w, a, bc, bs, u, out):
    _inputs(tl, w, a, bc, bs, u)
    rhs(x, u, out)


@njit(cache=True, error_model="numpy")
def _rms_scaled(v, x, rtol, atol):
    acc = 0.0
    for k in range(N):
        r = v[k] / (atol + rtol * abs(x[k]))
        acc += r * r
    return math.sqrt(acc / N)


@njit(cache=True, error_model="numpy")
def _initial_step(x, f0, dur, w, a, bc, bs, rtol, atol, xs, f1, u):
    d0 = _rms_scaled(x, x, rtol, atol)
    d1 = _rms_scaled(f0, x, rtol, atol)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, dur)
    for k in range(N):
        xs[k] = x[k] + h0 * f0[k]
    _f(h0, xs, w, a, bc, bs, u, f1)
    for k in range(N):
        f1[k] = f1[k] - f0[k]
    d2 = _rms_scaled(f1, x, rtol, atol) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (ORDER + 1))
    return min(100.0 * h0, h1, dur)


@njit(cache=True, error_model="numpy")
def _bad_state(x, bound):
    for k in range(N):
        v = x[k]
        if not math.isfinite(v):
            return 4
        if abs(v) > bound:
            return 3
    return 0


@njit(cache=True, error_model="numpy")
def _integrate_one(x0, dur, om, a, bc, bs, ts, adaptive, nfixed, rtol, atol,
                   max_steps, min_step, bound, xf, samples, info):
    x = x0.copy()
    K = np.empty((STAGES + 1, N))
    xs = np.empty(N)
    xnew = np.empty(N)
    u = np.empty(M)
    nts = ts.shape[0]
    isamp = 0
    while isamp < nts and ts[isamp] <= 0.0:
        samples[isamp, :] = x
        isamp += 1
    status = _bad_state(x, bound)
    accepted = 0
    rejected = 0
    errsum = 0.0
    t0 = 0.0
    nseg = dur.shape[0]
    for s in range(nseg):
        if status != 0:
            break
        d = dur[s]
        w = om[s]
        aa = a[s]
        cc = bc[s]
        ss = bs[s]
        tl = 0.0
        _f(0.0, x, w, aa, cc, ss, u, K[0])
        if _bad_state(K[0], INF) != 0:
            status = 4
            break
        if adaptive:
            # the guess may fall below min_step where a coordinate crosses 0 (its scale
            # atol + rtol|x| is tiny): start at min_step, and stop only if the error
            # control itself shrinks the step below it (scipy has no such floor at all)
            h = max(_initial_step(x, K[0], d, w, aa, cc, ss, rtol, atol, xs, K[1], u),
                    min_step)
        else:
            h = d / nfixed
        just_rejected = False
        while tl < d:
            # the next stop: a sample time inside the segment, else its end
            piece_end = d
            if isamp < nts and ts[isamp] - t0 < d * (1.0 - 1e-14):
                piece_end = ts[isamp] - t0
            if piece_end - tl <= 4e-16 * max(1.0, abs(t0 + tl)):
                tl = piece_end
            else:
                if adaptive:
                    if h < min_step:
                        status = 2
                        break
                    hs = h
                    landing = False
                    if tl + hs >= piece_end:
                        hs = piece_end - tl
                        landing = True
                else:
                    npiece = int(math.ceil(nfixed * (piece_end - tl) / d - 1e-9))
                    if npiece < 1:
                        npiece = 1
                    hs = (piece_end - tl) / npiece
                    landing = False
                if accepted + rejected >= max_steps:
                    status = 1
                    break
                if adaptive:
                    _step(tl, x, hs, w, aa, cc, ss, K, xs, u, xnew)
                    _f(tl + hs, xnew, w, aa, cc, ss, u, K[STAGES])
                    err = _error_norm(hs, x, xnew, K, rtol, atol)
                    if err <= 1.0:
                        if err == 0.0:
                            factor = MAX_FACTOR
                        else:
                            factor = min(MAX_FACTOR, SAFETY * err ** ERR_EXP)
                        if just_rejected and factor > 1.0:
                            factor = 1.0
                        just_rejected = False
                        hn = hs * factor
                        if landing:
                            tl = piece_end
                            if hn < h:
                                hn = h
                        else:
                            tl = tl + hs
                        h = hn
                        accepted += 1
                        xmax = 0.0
                        for k in range(N):
                            x[k] = xnew[k]
                            K[0, k] = K[STAGES, k]
                            xmax = max(xmax, abs(x[k]))
                        errsum += err * (atol + rtol * xmax)
                    else:
                        rejected += 1
                        just_rejected = True
                        if math.isfinite(err):
                            h = hs * max(MIN_FACTOR, SAFETY * err ** ERR_EXP)
                        else:
                            h = hs * MIN_FACTOR
                        continue
                else:
                    for _ in range(npiece):
                        if accepted >= max_steps:
                            status = 1
                            break
                        _step(tl, x, hs, w, aa, cc, ss, K, xs, u, xnew)
                        tl = tl + hs
                        for k in range(N):
                            x[k] = xnew[k]
                        _f(tl, x, w, aa, cc, ss, u, K[0])
                        accepted += 1
                        status = _bad_state(x, bound)
                        if status != 0:
                            break
                    if status != 0:
                        break
                    tl = piece_end
                status = _bad_state(x, bound)
                if status != 0:
                    break
            while isamp < nts and ts[isamp] - t0 <= tl * (1.0 + 1e-14) and tl < d:
                samples[isamp, :] = x
                isamp += 1
        if status != 0:
            break
        t0 = t0 + d
        while isamp < nts and ts[isamp] <= t0 * (1.0 + 1e-14):
            samples[isamp, :] = x
            isamp += 1
    for k in range(N):
        xf[k] = x[k]
    info[0] = status
    info[1] = accepted
    info[2] = rejected
    info[3] = errsum


@njit(cache=True, parallel=True, error_model="numpy")
def integrate_batch(x0, durations, omegas, constant, cos, sin, ts, adaptive, nfixed,
                    rtol, atol, max_steps, min_step, bound, xf, samples, info):
    for b in prange(x0.shape[0]):
        _integrate_one(x0[b], durations[b], omegas[b], constant[b], cos[b], sin[b], ts,
                       adaptive, nfixed, rtol, atol, max_steps, min_step, bound,
                       xf[b], samples[b], info[b])

'''


def _constants(t: ButcherTableau) -> str:
    return "\n".join(
        [
            "",
            "",
            "# --- integrators (nilpotent.numeric.kernels) ---",
            f"STAGES = {t.stages}",
            f"ORDER = {t.error_order}",
            f"ERR_EXP = {-1.0 / (t.error_order + 1)!r}",
            "SAFETY = 0.9",
            "MIN_FACTOR = 0.2",
            "MAX_FACTOR = 10.0",
            "INF = math.inf",
            "",
            "",
        ]
    )


def integrator_source(n: int, m: int, tableau: ButcherTableau = DOP853) -> str:
    """Text of the integrator kernels for a system module with ``N = n``, ``M = m``.

    ``n`` and ``m`` are already defined in the module as ``N``/``M``; they are
    accepted here so the text can be checked against them.
    """
    return (
        _constants(tableau)
        + _step_source(tableau)
        + _DRIVER
        + f"\n\nassert N == {n} and M == {m}\n"
    )


#: Names the generated numba files: changes whenever the kernel text would.
KERNEL_VERSION = hashlib.sha256(
    (_DRIVER + _step_source(DOP853) + _constants(DOP853)).encode()
).hexdigest()[:10]
