"""Linearisation of state equations at an operating point.

:func:`linearize` turns :class:`~bondgraph.system.StateEquations` into a
:class:`LinearModel` ``(A, B, C, D)`` for small deviations
:math:`\\delta x = x - x_0`, :math:`\\delta u = u - u_0`,
:math:`\\delta y = y - y_0` about the point :math:`(x_0, u_0)`:

.. math::

    \\delta\\dot x = A\\,\\delta x + B\\,\\delta u + \\dot x_0, \\qquad
    \\delta y = C\\,\\delta x + D\\,\\delta u,

where :math:`\\dot x_0 = f(t, x_0, u_0, z_0, d_0, p)` is zero at an
equilibrium.  Held (discrete) variables ``d`` are constants of the
linearisation, and time ``t`` is frozen at the given value.

How each column is obtained (``LinearModel.derivatives`` says which, per
state and input):

* **symbolic** (default, ``method="auto"``): Jacobians are taken symbolically,
  switches (``sign``, ``Abs``, ``Heaviside``) frozen as locally constant
  (:func:`bondgraph.derivatives.diff_almost_everywhere`, no ``simplify``),
  and evaluated numerically at the point.  This is the derivative wherever
  the law is differentiable.
* **one-sided numerical**, for the variables on which a switch sits exactly
  on its switching surface at the point (``sign(P_1 - P_out)`` with
  :math:`P_1 = P_{out}`, a clipped valve voltage at 0 V; listed in
  ``LinearModel.kinks``), or whose symbolic derivative is not finite there
  (:math:`\\sqrt{|h_1 - h_2|}` at equal levels): the right-sided
  second-order difference

  .. math::

      \\frac{\\partial F}{\\partial v_j} \\approx
      \\frac{-3 F(v) + 4 F(v + \\epsilon_j e_j) - F(v + 2 \\epsilon_j e_j)}{2 \\epsilon_j},
      \\qquad \\epsilon_j = 6\\cdot 10^{-6} \\max(1, |v_j|)

  of :math:`F = (f, h)` (algebraic unknowns re-solved at each point), i.e.
  the derivative for a small *increase* of the variable (a valve opening, a
  muscle above atmospheric pressure).  :math:`6\\cdot 10^{-6} \\approx
  \\epsilon_{mach}^{1/3}` balances the :math:`O(\\epsilon^2)` truncation
  against rounding.
  A column whose estimate does not converge (the estimates with steps
  :math:`\\epsilon_j` and :math:`4\\epsilon_j` differ by more than 0.1 %) has an
  unbounded one-sided derivative -- the orifice law's
  :math:`\\sqrt{P - P_{out}}` at zero pressure difference -- and gets the
  secant :math:`(F(v + \\Delta_j e_j) - F(v))/\\Delta_j` over
  :math:`\\Delta_j = 10^{-3} \\max(1, |v_j|)` instead, said so in
  ``derivatives``.  A law that *jumps* at the point (``sign(v)`` at
  :math:`v = 0`) has no derivative at all: :class:`DerivationError`.
* ``method="numerical"``: every column that way; ``method="symbolic"``:
  never (a non-finite derivative is an error).

Algebraic unknowns ``z`` defined implicitly by :math:`0 = r(t, x, u, z, d, p)`
are first solved numerically at the point; their sensitivities follow from
the implicit-function theorem [2]_ (a linear solve, never an inverse):

.. math::

    \\frac{\\partial z}{\\partial x} = -r_z^{-1} r_x, \\qquad
    \\frac{\\partial z}{\\partial u} = -r_z^{-1} r_u, \\qquad
    A = f_x + f_z \\frac{\\partial z}{\\partial x}, \\quad
    B = f_u + f_z \\frac{\\partial z}{\\partial u}, \\quad
    C = h_x + h_z \\frac{\\partial z}{\\partial x}, \\quad
    D = h_u + h_z \\frac{\\partial z}{\\partial u}.

References
----------
.. [1] H. K. Khalil, *Nonlinear Systems*, 3rd ed., Prentice Hall, 2002,
   ch. 4 (linearisation and Lyapunov's indirect method).
.. [2] S. G. Krantz and H. R. Parks, *The Implicit Function Theorem:
   History, Theory, and Applications*, Birkhäuser, 2002.
"""
from __future__ import annotations

import math
import weakref
from typing import TYPE_CHECKING, Mapping

import numpy as np
import sympy as sp

from .derivatives import NotDifferentiable, diff_almost_everywhere
from .errors import DerivationError, ParameterError
from .linear_model import EQUILIBRIUM_ATOL, LinearModel
from .linearization_numeric import kinks_at, not_finite_columns, one_sided_column, set_column, solve_algebraic

if TYPE_CHECKING:   # annotations only: system.py imports this module (StateEquations.linearize)
    from .system import StateEquations

__all__ = ["linearize", "LinearModel"]


# Symbolic Jacobians, compiled once per StateEquations
# ---------------------------------------------------------------------------
#: the first index of :class:`_Jacobians`' real dummies (far above sympy's own counter)
_DUMMY_BASE = 10**12


class _Jacobians:
    """Lambdified f, h, r and their Jacobians w.r.t. x, u, z of one StateEquations."""

    def __init__(self, eqs: StateEquations):
        declared = (eqs.t, *eqs.states, *eqs.inputs, *eqs.algebraic, *eqs.held, *eqs.params)
        # Real dummies: differentiation of Abs/sign stays real-valued even when the
        # caller built the equations with assumption-free symbols.  Numbered by position, the same
        # equations of another build get equal dummies, and their derivatives are remembered
        # (:func:`~bondgraph.derivatives.diff_almost_everywhere`)
        real = {s: sp.Dummy(s.name, real=True, dummy_index=_DUMMY_BASE + i) for i, s in enumerate(declared)}
        self.args = [real[s] for s in declared]
        groups = (("f", eqs.state_names, eqs.f), ("h", eqs.outputs, eqs.h),
                  ("r", tuple(z.name for z in eqs.algebraic), eqs.residuals))
        problems = []
        for kind, names, exprs in groups:
            for name, expr in zip(names, exprs):
                extra = sorted(s.name for s in sp.sympify(expr).free_symbols if s not in real)
                if extra:
                    problems.append(f"{kind}[{name}] uses undeclared symbol(s) {', '.join(extra)}")
        if problems:
            raise DerivationError(
                f"{eqs.name}: " + "; ".join(problems) + "; declared symbols are "
                + ", ".join(s.name for s in declared))
        F, H, R = (sp.Matrix([sp.sympify(e).xreplace(real) for e in exprs]) for _, _, exprs in groups)
        X, U, Z = ([real[s] for s in group] for group in (eqs.states, eqs.inputs, eqs.algebraic))
        self.value_names = ("f", "h", "r")
        jac = {}
        for (kind, names, _), M in zip(groups, (F, H, R)):
            for wrt, syms, wrt_names in (("x", X, eqs.state_names), ("u", U, eqs.input_names),
                                         ("z", Z, tuple(z.name for z in eqs.algebraic))):
                J = sp.zeros(len(M), len(syms))
                for a in range(len(M)):
                    present = M[a].free_symbols
                    for b, s in enumerate(syms):
                        if s not in present:
                            continue
                        try:   # the derivative off the switching surfaces (see kinks below)
                            J[a, b] = diff_almost_everywhere(M[a], s)
                        except NotDifferentiable:
                            raise DerivationError(
                                f"{eqs.name}: {kind}[{names[a]}] has no symbolic derivative with respect "
                                f"to {wrt_names[b]}; rewrite it with differentiable functions") from None
                jac[kind + "_" + wrt] = J
        self.all = _compile(self.args, {"f": F, "h": H, "r": R, **jac})
        self.residual = _compile(self.args, {"r": R, "r_z": jac["r_z"]})


def _compile(args, matrices: dict):
    """Lambdify a dict of matrices into one numpy function of the flat argument vector."""
    shapes = {k: M.shape for k, M in matrices.items()}
    live = [k for k, M in matrices.items() if 0 not in M.shape]
    fn = sp.lambdify(args, [matrices[k] for k in live], modules="numpy", cse=True) if live else None

    def evaluate(vector) -> dict:
        out = {k: np.zeros(s) for k, s in shapes.items()}
        if fn is not None:
            with np.errstate(all="ignore"):  # non-finite results are reported by the caller
                got = fn(*vector)
            for k, value in zip(live, got):
                out[k] = np.asarray(value, dtype=complex).reshape(shapes[k])
        return out

    return evaluate


_CACHE: "weakref.WeakKeyDictionary[StateEquations, _Jacobians]" = weakref.WeakKeyDictionary()


def _jacobians(eqs: StateEquations) -> _Jacobians:
    if eqs not in _CACHE:
        _CACHE[eqs] = _Jacobians(eqs)
    return _CACHE[eqs]


# ---------------------------------------------------------------------------
# Operating point
# ---------------------------------------------------------------------------
def _number(value) -> float | None:
    if isinstance(value, bool):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _resolve(eqs: StateEquations, operating_point, params, t: float):
    """Numbers for every symbol; raises one ParameterError listing every problem."""
    given = dict(operating_point or {})
    overrides = dict(params or {})
    kinds = {"state": eqs.state_names, "input": eqs.input_names,
             "held": eqs.held_names, "algebraic": tuple(z.name for z in eqs.algebraic)}
    known = {n for names in kinds.values() for n in names}
    problems, bad = [], []
    for key in given:
        if key not in known:
            bad.append(str(key))
            problems.append(f"operating point names unknown variable {key!r}")
    for key in overrides:
        if key not in eqs.param_names:
            bad.append(str(key))
            problems.append(f"params names unknown parameter {key!r}")
    param_values = {n: overrides.get(n, eqs.param_values.get(n)) for n in eqs.param_names}
    sources = {"state": eqs.initial_state, "held": eqs.held_initial, "algebraic": {}}
    values = {}
    for kind, names in kinds.items():
        for n in names:
            if n in given:
                values[n] = given[n]
            elif kind == "input" and n in eqs.input_functions:
                values[n] = sp.sympify(eqs.input_functions[n]).xreplace(
                    {eqs.t: t, **{p: param_values[p.name] for p in eqs.params if param_values[p.name] is not None}})
            elif kind == "input":
                values[n] = eqs.input_defaults.get(n)
            elif kind == "algebraic":
                values[n] = 0.0  # starting guess of the root solve
            else:
                values[n] = sources[kind].get(n)
    for n, v in [*values.items(), *param_values.items()]:
        if v is None:
            bad.append(n)
            problems.append(f"no value for {n!r}: give it in operating_point/params or as a default")
        elif _number(v) is None:
            bad.append(n)
            problems.append(f"value of {n!r} is {v!r}, not a finite real number")
    if problems:
        expected = "; ".join(f"{k}s: {', '.join(v) or '(none)'}" for k, v in kinds.items())
        raise ParameterError(
            f"cannot linearise {eqs.name!r}: " + "; ".join(problems)
            + f". Known names -- {expected}; params: {', '.join(eqs.param_names) or '(none)'}",
            name=bad[0])
    return {n: float(v) for n, v in values.items()}, {n: float(v) for n, v in param_values.items()}


# ---------------------------------------------------------------------------
# Public entry point
# ---------------------------------------------------------------------------
def linearize(eqs: StateEquations, operating_point: Mapping[str, float] | None = None, *,
              params: Mapping[str, float] | None = None, t: float = 0.0,
              equilibrium_atol: float = EQUILIBRIUM_ATOL, method: str = "auto") -> LinearModel:
    """Linearise state equations at an operating point (see the module docstring for the equations).

    Parameters
    ----------
    eqs : StateEquations
        The model; its Jacobians are derived once and cached for this object.
    operating_point : mapping str -> float, optional
        Values (SI) of states, inputs and held variables by name.  Missing
        states come from ``eqs.initial_state``, missing inputs from
        ``eqs.input_functions`` evaluated at `t`, else ``eqs.input_defaults``,
        missing held variables from ``eqs.held_initial``.  Values given for
        algebraic unknowns are starting guesses of the root solve (default 0).
    params : mapping str -> float, optional
        Parameter values overriding ``eqs.param_values``.
    t : float, s, optional
        Time at which a time-varying model is frozen (default 0).
    equilibrium_atol : float, optional
        Tolerance on :math:`\\lVert f \\rVert_2` for :attr:`LinearModel.is_equilibrium`.
    method : {"auto", "symbolic", "numerical"}
        How the columns of A-D are obtained (module docstring): ``"auto"``
        symbolic where the model is differentiable at the point, one-sided
        numerical for the variables where it is not.

    Returns
    -------
    LinearModel
        ``A``, ``B``, ``C``, ``D`` at the point; a point that is not an
        equilibrium is still linearised, and ``xdot``/``equilibrium_residual``
        say how far from one it is.

    Raises
    ------
    ParameterError
        Unknown names, missing or non-finite values (all listed at once).
    SimulationError
        The algebraic loop cannot be solved at the point.
    DerivationError
        Undeclared symbols, a function sympy cannot differentiate, a
        derivative that is not finite at the point, or a singular
        :math:`\\partial r/\\partial z` (implicit-function theorem fails).

    Examples
    --------
    Mass-spring-damper, momentum ``p`` and spring displacement ``q``:

    >>> import sympy as sp
    >>> from bondgraph.system import StateEquations
    >>> q, p, F, m, k, b = sp.symbols("q p F m k b", real=True)
    >>> eqs = StateEquations(name="msd", t=sp.Symbol("t", real=True), states=(q, p),
    ...     inputs=(F,), params=(m, k, b), outputs=("v",), f=(p / m, F - k * q - b * p / m),
    ...     h=(p / m,), param_values={"m": 2.0, "k": 8.0, "b": 1.0},
    ...     initial_state={"q": 0.0, "p": 0.0}, input_defaults={"F": 0.0})
    >>> lin = linearize(eqs)
    >>> lin.A.tolist(), lin.B.tolist(), lin.C.tolist(), lin.is_equilibrium
    ([[0.0, 0.5], [-8.0, -0.5]], [[0.0], [1.0]], [[0.0, 0.5]], True)
    """
    if not all(hasattr(eqs, a) for a in ("f", "h", "states", "inputs", "params")):   # duck-typed: system.py
        raise ParameterError(f"linearize expects StateEquations, got {type(eqs).__name__}", name="eqs")
    if _number(t) is None:
        raise ParameterError(f"t must be a finite time in s, got {t!r}", name="t")
    if method not in METHODS:
        raise ParameterError(f"method must be one of {', '.join(map(repr, METHODS))}; found {method!r}",
                             name="method")
    values, param_values = _resolve(eqs, operating_point, params, float(t))
    jac = _jacobians(eqs)

    # Flat argument vector in the order of _Jacobians.args: t, x, u, z, d, p.
    names = [*eqs.state_names, *eqs.input_names, *(z.name for z in eqs.algebraic), *eqs.held_names]
    vector = np.array([float(t), *(values[n] for n in names),
                       *(param_values[n] for n in eqs.param_names)], dtype=float)
    nx, nu, nz = len(eqs.states), len(eqs.inputs), len(eqs.algebraic)
    z_slice = slice(1 + nx + nu, 1 + nx + nu + nz)
    if nz:
        solve_algebraic(eqs, jac, vector, z_slice)
        values.update(zip((z.name for z in eqs.algebraic), vector[z_slice]))
    m = jac.all(vector)
    columns = [*eqs.state_names, *eqs.input_names]
    found = kinks_at(eqs, vector) if method == "auto" else []
    numeric = set(columns) if method == "numerical" else {s.name for k in found for s in k.symbols} & set(columns)
    if method == "auto":
        numeric |= not_finite_columns(eqs, m) & set(columns)
        if nz and numeric:
            numeric = set(columns)   # a one-sided step re-solves z, so do every column alike
    _check_finite(eqs, m, skip=numeric if method != "symbolic" else set(), values_only=method == "numerical")
    m = {k: v.real for k, v in m.items()}

    A, B, C, D = m["f_x"], m["f_u"], m["h_x"], m["h_u"]
    if nz and len(numeric) < len(columns):
        # Implicit-function theorem [2]: dz/d[x u] = -r_z^{-1} [r_x r_u], by a solve.
        r_z = m["r_z"]
        if np.linalg.cond(r_z) > 1.0 / np.finfo(float).eps:
            raise DerivationError(
                f"{eqs.name}: d r/d z is singular at the operating point (z = "
                f"{', '.join(f'{z.name} = {values[z.name]:.6g}' for z in eqs.algebraic)}); "
                "the algebraic unknowns are not locally determined, so the model cannot be linearised there")
        dz = -np.linalg.solve(r_z, np.hstack([m["r_x"], m["r_u"]]))
        dz_dx, dz_du = dz[:, :nx], dz[:, nx:]
        A, B = A + m["f_z"] @ dz_dx, B + m["f_z"] @ dz_du
        C, D = C + m["h_z"] @ dz_dx, D + m["h_z"] @ dz_du
    derivatives = {}
    for j, name in enumerate(columns):
        if name not in numeric:
            derivatives[name] = "symbolic"
            continue
        col, how = one_sided_column(eqs, jac, vector, 1 + j, z_slice)
        if not nz:   # rows that do not contain the variable have an exact zero (no difference noise)
            symbol = (*eqs.states, *eqs.inputs)[j]
            col = np.where([symbol in e.free_symbols for e in (*eqs.f, *eqs.h)], col, 0.0)
        if j < nx:
            A, C = set_column(A, j, col[:nx]), set_column(C, j, col[nx:])
        else:
            B, D = set_column(B, j - nx, col[:nx]), set_column(D, j - nx, col[nx:])
        derivatives[name] = how

    xdot = m["f"].reshape(-1)
    everything = (*eqs.state_names, *eqs.input_names, *eqs.outputs, *eqs.held_names,
                  *(z.name for z in eqs.algebraic))
    return LinearModel(
        name=eqs.name, A=A, B=B, C=C, D=D,
        states=eqs.state_names, inputs=eqs.input_names, outputs=eqs.outputs,
        units={n: eqs.units.get(n, "") for n in everything},
        operating_point=values, t=float(t), params=param_values,
        xdot=xdot, y=m["h"].reshape(-1),
        equilibrium_residual=float(np.linalg.norm(xdot)), equilibrium_atol=float(equilibrium_atol),
        derivatives=derivatives, kinks=tuple(str(k) for k in found))


#: Accepted values of ``linearize(method=...)``.
METHODS = ("auto", "symbolic", "numerical")
def _check_finite(eqs: StateEquations, m: dict, *, skip=frozenset(), values_only: bool = False) -> None:
    """Every value and derivative at the point must be a finite real number
    (except derivatives by the variables in `skip`, or all when `values_only`)."""
    row_names = {"f": eqs.state_names, "h": eqs.outputs, "r": tuple(z.name for z in eqs.algebraic)}
    col_names = {"x": eqs.state_names, "u": eqs.input_names, "z": tuple(z.name for z in eqs.algebraic)}
    bad = []
    for key, value in m.items():
        kind, _, wrt = key.partition("_")
        if wrt and values_only:
            continue
        for (a, b), v in np.ndenumerate(value):
            if np.isfinite(v) and abs(v.imag) <= 1e-12 * max(1.0, abs(v.real)):
                continue
            if wrt and col_names[wrt][b] in skip:
                continue
            what = f"{kind}[{row_names[kind][a]}]"
            if wrt:
                what = f"d {what} / d {col_names[wrt][b]}"
            bad.append(f"{what} = {v.real if v.imag == 0 else v}")
    if bad:
        shown = "; ".join(bad[:10]) + (f"; ... ({len(bad) - 10} more)" if len(bad) > 10 else "")
        raise DerivationError(
            f"{eqs.name}: the model is not differentiable (or not real) at the operating point: {shown}")
