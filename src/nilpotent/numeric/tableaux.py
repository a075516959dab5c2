"""Butcher tableaux of the explicit Runge–Kutta methods, as class data.

A method is data (its coefficients) plus a name in :data:`TABLEAUX`; the
integrators (:mod:`nilpotent.numeric.integrate`) and the generated numba
kernels (:mod:`nilpotent.numeric.kernels`) read the coefficients from here.

Convention: for ``dx/dt = f(t, x)`` and a step ``h`` from ``(t, x)``,
``k_s = f(t + c_s h, x + h Σ_{j<s} a_{sj} k_j)`` for ``s = 0..stages−1``,
``x_new = x + h Σ_s b_s k_s``. The error estimators ``e3``, ``e5`` (combined as in
Hairer's DOP853) use the stages plus ``k_stages = f(t + h, x_new)``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ButcherTableau:
    """An explicit Runge–Kutta method with an embedded error estimator.

    Attributes
    ----------
    name:
        Registry name.
    order:
        Order of the propagated solution.
    error_order:
        Order of the embedded error estimator (the step-size exponent is
        ``-1/(error_order + 1)``).
    a:
        Lower-triangular coefficients; ``a[s]`` has ``s`` entries.
    b:
        Weights of the stages in the solution.
    c:
        Nodes; ``c[s] = Σ_j a[s][j]``.
    e3, e5:
        Error-estimator weights over the stages and ``f(t+h, x_new)``
        (``len = stages + 1``), combined as
        ``err = |h| ‖e5·k‖² / sqrt(‖e5·k‖² + 0.01 ‖e3·k‖²)`` (RMS norms of
        the scaled vectors).
    """

    name: str
    order: int
    error_order: int
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    c: tuple[float, ...]
    e3: tuple[float, ...]
    e5: tuple[float, ...]

    @property
    def stages(self) -> int:
        """Number of stages (right-hand-side evaluations per step)."""
        return len(self.b)


#: Dormand–Prince 8(5,3) (Hairer, Nørsett & Wanner, *Solving ODEs I*, code DOP853):
#: 12 stages, order 8, embedded 5th- and 3rd-order estimators.  The numbers are
#: those of Hairer's Fortran code, as also used by ``scipy.integrate.DOP853``.
DOP853 = ButcherTableau(
    name="dop853",
    order=8,
    error_order=7,
    a=(
        (),
        (
            0.05260015195876773,
        ),
        (
            0.0197250569845379, 0.0591751709536137,
        ),
        (
            0.02958758547680685, 0.0, 0.08876275643042054,
        ),
        (
            0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792,
        ),
        (
            0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242,
        ),
        (
            0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125,
        ),
        (
            0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
            -0.015319437748624402, 0.008273789163814023,
        ),
        (
            0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
            27.59209969944671, 20.154067550477894, -43.48988418106996,
        ),
        (
            0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
            21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627,
        ),
        (
            -0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
            -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523,
            -3.0467644718982196,
        ),
        (
            2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
            -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
            12.360567175794303, 0.6433927460157636,
        ),
    ),
    b=(
        0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
        -5.801203960010585, 0.3111643669578199, -0.1521609496625161, 0.20136540080403034,
        0.04471061572777259,
    ),
    c=(
        0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726,
        0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6,
        0.8571428571428571, 1.0,
    ),
    e3=(
        -0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409, 1.8915178993145003,
        -5.801203960010585, -0.4226823213237919, -0.1521609496625161, 0.20136540080403034,
        0.02265179219836082, 0.0,
    ),
    e5=(
        0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044, -0.4957589496572502,
        1.6643771824549864, -0.35032884874997366, 0.3341791187130175, 0.08192320648511571,
        -0.022355307863886294, 0.0,
    ),
)

#: Registry of the tableaux by name.
TABLEAUX: dict[str, ButcherTableau] = {DOP853.name: DOP853}
