"""Numerical parts of linearisation: the algebraic-loop solve at the point, kinks at
the point, and one-sided differences (see :mod:`bondgraph.linearization` for the maths)."""
from __future__ import annotations

import numpy as np

from .derivatives import Kink, kinks
from .errors import DerivationError, SimulationError

__all__ = ["solve_algebraic", "kinks_at", "not_finite_columns", "one_sided_column", "set_column",
           "ONE_SIDED_STEP", "SECANT_STEP"]


def solve_algebraic(eqs, jac, vector: np.ndarray, sl: slice) -> None:
    """Solve 0 = r(..., z, ...) for z in place (MINPACK hybrd, then Newton polish)."""
    from scipy.optimize import root

    def fun(z):
        vector[sl] = z
        return jac.residual(vector)["r"].reshape(-1).real

    def fjac(z):
        vector[sl] = z
        return jac.residual(vector)["r_z"].real

    guess = vector[sl].copy()
    r0 = fun(guess)
    with np.errstate(all="ignore"):
        sol = root(fun, guess, jac=fjac, method="hybr", options={"xtol": 1e-13})
    z = sol.x
    for _ in range(3):  # Newton polish: z <- z - r_z^{-1} r, kept only while |r| falls
        r = fun(z)
        try:
            step = np.linalg.solve(fjac(z), r)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.isfinite(step)) or np.linalg.norm(fun(z - step)) >= np.linalg.norm(r):
            break
        z = z - step
    r = fun(z)
    tol = 1e-9 * (1.0 + np.max(np.abs(r0), initial=0.0)) if np.all(np.isfinite(r0)) else 1e-9
    if not np.all(np.isfinite(r)) or np.max(np.abs(r)) > tol:
        names = ", ".join(s.name for s in eqs.algebraic)
        raise SimulationError(
            f"{eqs.name}: cannot solve the algebraic loop for {names} at the operating point "
            f"(residuals {np.array2string(r, precision=3)} from guess {np.array2string(guess)}; "
            f"solver: {sol.message.strip()}); give a better guess for {names} in operating_point")
    vector[sl] = z


#: Relative step of the one-sided differences (about the cube root of the machine epsilon).
ONE_SIDED_STEP = 6e-6
#: Relative step of the secant used where the one-sided derivative is unbounded.
SECANT_STEP = 1e-3


def set_column(M, j, col):
    M = np.array(M, dtype=float, copy=True)
    M[:, j] = col
    return M


def kinks_at(eqs, vector) -> list:
    """Switches of f, h, r on their switching surface at the point (see bondgraph.derivatives).

    Searched in the ordered assignments and the short forms (so a kink reads
    ``Abs(valve1.net)``, not a page of substituted text); each kink's
    variables are traced back through the assignments to states and inputs."""
    symbols = (eqs.t, *eqs.states, *eqs.inputs, *eqs.algebraic, *eqs.held, *eqs.params)
    point = {s: float(v) for s, v in zip(symbols, vector)}
    closure = {}
    for a, body in eqs.assignments:
        try:
            point[a] = complex(body.xreplace(point))
        except (TypeError, ValueError):
            point[a] = complex("nan")
        closure[a] = set().union(*[closure.get(s, {s}) for s in body.free_symbols]) if body.free_symbols else set()
    found = kinks([*(b for _, b in eqs.assignments), *eqs.f_short, *eqs.h_short, *eqs.residuals], point)
    return [Kink(k.switch, frozenset().union(*[closure.get(s, {s}) for s in k.symbols])) for k in found]


def not_finite_columns(eqs, m: dict) -> set:
    """State/input names whose symbolic column has a non-finite or complex entry."""
    out = set()
    for key, names in (("f_x", eqs.state_names), ("h_x", eqs.state_names),
                       ("f_u", eqs.input_names), ("h_u", eqs.input_names)):
        bad = ~np.isfinite(m[key]) | (np.abs(np.imag(m[key])) > 1e-12 * np.maximum(1.0, np.abs(np.real(m[key]))))
        out |= {names[j] for j in np.nonzero(bad.any(axis=0))[0]} if m[key].size else set()
    return out


def _values(eqs, jac, vector, z_slice) -> np.ndarray:
    """(f, h) at `vector`, the algebraic unknowns re-solved from the vector's guess."""
    if z_slice.stop > z_slice.start:
        solve_algebraic(eqs, jac, vector, z_slice)
    m = jac.all(vector)
    return np.concatenate([m["f"].reshape(-1), m["h"].reshape(-1)])


def one_sided_column(eqs, jac, vector, index, z_slice):
    """Right-sided derivative of (f, h) in vector[index] (module docstring): returns the column, and
    how it was obtained."""
    v0 = float(vector[index])
    eps = ONE_SIDED_STEP * max(1.0, abs(v0))

    def at(step):
        v = vector.copy()
        v[index] += step
        return _values(eqs, jac, v, z_slice)

    F = {k: at(k * eps) for k in (0, 1, 2, 4, 8)}
    name = ([*eqs.state_names, *eqs.input_names])[index - 1]
    rows = [*(f"f[{n}]" for n in eqs.state_names), *(f"h[{n}]" for n in eqs.outputs)]
    if not all(np.all(np.isfinite(x)) for x in F.values()):
        raise DerivationError(f"{eqs.name}: (f, h) is not finite just above {name} = {v0:.6g}, so no "
                              "one-sided derivative exists there")
    F = {k: x.real for k, x in F.items()}
    # A jump (sign(v) at v = 0) is no kink: the first step changes F by far more than the second.
    d1, d2 = F[1] - F[0], F[2] - F[1]
    jumps = np.abs(d1) > 100.0 * np.abs(d2) + 1e-9 * np.maximum(1.0, np.abs(F[0]))
    if np.any(jumps):
        a = int(np.argmax(jumps))
        raise DerivationError(
            f"{eqs.name}: d {rows[a]} / d {name} does not exist at the operating point: {rows[a]} jumps by "
            f"{d1[a]:.6g} there (a discontinuous law such as sign); linearise at a nearby point")
    col = (-3.0 * F[0] + 4.0 * F[1] - F[2]) / (2.0 * eps)
    coarse = (-3.0 * F[0] + 4.0 * F[4] - F[8]) / (8.0 * eps)
    floor = 1e-8 * np.maximum(1.0, np.abs(F[0])) / eps
    if np.all(np.abs(col - coarse) <= 1e-3 * np.maximum(np.abs(col), np.abs(coarse)) + floor):
        return col, f"one-sided numerical (right, step {eps:.3g})"
    # The estimates grow as the step shrinks: an unbounded one-sided derivative (an orifice's
    # sqrt(P - P_out) at zero pressure difference).  Give the secant over a stated finite step.
    delta = SECANT_STEP * max(1.0, abs(v0))
    secant = (at(delta).real - F[0]) / delta
    unbounded = [rows[a] for a in np.nonzero(np.abs(col - coarse) > 1e-3 * np.maximum(np.abs(col), np.abs(coarse))
                                             + floor)[0]]
    return secant, (f"one-sided numerical (secant over {delta:.3g}: the one-sided derivative of "
                    f"{', '.join(unbounded)} is unbounded)")
