"""C code for state equations: batch evaluators, compiled once and cached.

This module is the low layer of the compiled backend (the Pythonic layer is
:class:`bondgraph.evaluate.CompiledModel`): :func:`generate_source` writes C
for a :class:`~bondgraph.system.StateEquations`, :func:`compile_source` turns
it into a shared library with the system compiler (cached by the sha256 of
source and flags), :func:`build_library` does both (skipping generation too
when the same equations were built before), and :class:`CLibrary` is a 1:1
ctypes binding of the functions below.

C contract
----------
Every function evaluates a whole batch of ``n`` rows in one call.  Arrays are
row-major ``double``; the arrays marked *broadcastable* come with a stride
(``0`` = one row shared by the batch, row length = one row per batch row)::

    void bc_dims(int *dims)   /* NX NU NP NZ ND NY */
    void bc_<name>(int n,
                   const double *t, int st,    /* (n,) or (1,), s; st = 1 or 0      */
                   const double *x,            /* (n, NX) states                    */
                   const double *u, int su,    /* (n, NU) or (1, NU) inputs         */
                   const double *z,            /* (n, NZ) algebraic unknowns        */
                   const double *d, int sd,    /* (n, ND) or (1, ND) held variables */
                   const double *p, int sp,    /* (n, NP) or (1, NP) parameters     */
                   double step,                /* sub-step for held_update, s       */
                   double *out)

with ``<name>`` and ``out`` shape:

=================  ==============  =============================================
``f``              (n, NX)         :math:`\\dot x = f`
``h``              (n, NY)         outputs
``held_update``    (n, ND)         new held values
``residuals``      (n, NZ)         :math:`r`, zero at a solution
``jac_fx``         (n, NX, NX)     :math:`\\partial f / \\partial x`
``jac_fz``         (n, NX, NZ)     :math:`\\partial f / \\partial z`
``jac_rx``         (n, NZ, NX)     :math:`\\partial r / \\partial x`
``jac_rz``         (n, NZ, NZ)     :math:`\\partial r / \\partial z`
=================  ==============  =============================================

and the Newton solver of the algebraic loops, ``z`` in/out (warm start)::

    int bc_solve(int n, <t, x, u as above>, double *z, <d, p, step as above>,
                 int *status)   /* returns the number of failed rows */

``status[i]`` is :data:`NEWTON_OK` or one of the failure codes in
:data:`NEWTON_STATUS`.  Fixed-step integration over one output interval::

    int bc_rk4(int n, double t0, double h, int m,
               double *x,                 /* (n, NX) in/out                      */
               const double *u, int su,   /* held constant over the m sub-steps  */
               double *z,                 /* (n, NZ) in/out, warm start          */
               const double *zinit,       /* (NZ,) Newton restart point          */
               double *d,                 /* (n, ND) in/out held values          */
               const double *p, int sp, int *status)

runs ``m`` classic RK4 sub-steps of length ``h`` from ``t0``; at each sub-step
start ``d = held_update(t, x, u, z, d, p, h)``; ``z`` is solved at every
stage (from the last solution, then from ``zinit`` if that fails).  Returns
the number of rows stopped by a Newton failure (their ``status``).

Code shape
----------
Expressions go through :func:`sympy.cse`; temporaries are ``const double``
locals.  A block with more than :data:`SPLIT_STATEMENTS` statements is split
into several ``noinline`` functions sharing a scratch array (compile time of
one huge function grows super-linearly).  The SLP vectoriser is switched off
(``-fno-tree-slp-vectorize``): on straight-line generated code it dominated
compile time and gains nothing.
"""
from __future__ import annotations

import ctypes
import hashlib
import math
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import sympy as sp
from sympy.printing.c import C99CodePrinter

from .errors import CompilationError

__all__ = [
    "generate_source", "compile_source", "build_library", "find_compiler", "cache_dir",
    "jacobian_entries", "prepare_expression", "symbol_names",
    "CLibrary",
    "NEWTON_OK", "NEWTON_STATUS", "NEWTON_MAX_ITER", "NEWTON_RTOL", "NEWTON_ATOL",
    "SPLIT_STATEMENTS", "CFLAGS", "PARTS",
]

#: Relative / absolute step tolerance of the Newton iteration:
#: converged when :math:`|\\Delta z_i| \\le 10^{-12} |z_i| + 10^{-14}` for all i.
NEWTON_RTOL = 1e-12
NEWTON_ATOL = 1e-14
#: Most Newton iterations per row.
NEWTON_MAX_ITER = 50
#: Status codes of :func:`bc_solve` rows.
NEWTON_OK = 0
NEWTON_STATUS = {
    1: f"no convergence in {NEWTON_MAX_ITER} Newton iterations",
    2: "singular Jacobian dr/dz",
    3: "residual is not finite (NaN or inf)",
}
#: Statements above which a block is split into several functions.
SPLIT_STATEMENTS = 400
#: Compiler flags (besides ``-o``, source and ``-lm``).
CFLAGS = ("-O2", "-fno-tree-slp-vectorize", "-shared", "-fPIC")
#: Batch kernels of each generated library (``main`` also has ``bc_solve``).
PARTS = {
    "main": ("f", "h", "held_update", "residuals", "jac_rz"),
    "jacobian": ("jac_fx", "jac_fz", "jac_rx"),
}

_ROW_ARGS = ("double t, const double *x, const double *u, const double *z, "
             "const double *d, const double *p, double step")
_ROW_CALL = "t, x, u, z, d, p, step"
_BATCH_HEAD = ("int n, const double *t, int st, const double *x, const double *u, int su, "
               "{zc}double *z, const double *d, int sd, const double *p, int sp, double step")
_GENERATOR_VERSION = "bondcosim-codegen-c 1"


class _Printer(C99CodePrinter):
    """C99 printer that maps model symbols to array elements and prints constants
    as literals (no ``M_PI``, which needs a feature macro)."""

    def __init__(self, names: dict):
        super().__init__({"precision": 17})
        self._names = names

    def _print_Symbol(self, expr):
        try:
            return self._names[expr]
        except KeyError:
            raise CompilationError(f"internal error: symbol {expr} has no C name") from None

    def _print_Pi(self, expr):
        return repr(math.pi)

    def _print_Exp1(self, expr):
        return repr(math.e)

    def _print_Heaviside(self, expr):
        # H(0) = 1/2 unless given, as sympy and numpy.heaviside(x, 0.5).
        return self._print(expr.rewrite(sp.Piecewise))


def prepare_expression(expr) -> sp.Expr:
    """Give every Piecewise a default branch (NaN) so C always has a value."""
    expr = sp.sympify(expr)

    def fix(pw):
        if pw.args and pw.args[-1].cond == sp.true:
            return pw
        return sp.Piecewise(*pw.args, (sp.nan, True))

    if expr.has(sp.Piecewise):
        expr = expr.replace(lambda e: isinstance(e, sp.Piecewise), fix)
    return expr


def symbol_names(eqs) -> dict:
    """C text of every model symbol: ``x[i]``, ``u[i]``, ``p[i]``, ``z[i]``, ``d[i]``."""
    names = {eqs.t: "t", eqs.step: "step"}
    for arr, syms in (("x", eqs.states), ("u", eqs.inputs), ("p", eqs.params),
                      ("z", eqs.algebraic), ("d", eqs.held)):
        for i, s in enumerate(syms):
            names[s] = f"{arr}[{i}]"
    return names


# -- blocks of assignments ---------------------------------------------------

def _emit_block(fname: str, targets: list, printer: _Printer, n_out: int) -> list[str]:
    """C lines of a row function ``fname`` writing ``out[k] = expr`` for
    ``targets = [(k, expr), ...]``; other entries of ``out[:n_out]`` are 0."""
    lines: list[str] = []
    zero = f"  memset(out, 0, sizeof(double) * {n_out});" if n_out > len(targets) else None
    if not targets:
        lines.append(f"static void {fname}({_ROW_ARGS}, double *out) {{")
        if n_out:
            lines.append(f"  memset(out, 0, sizeof(double) * {n_out});")
        lines.append("}")
        return lines
    exprs = [prepare_expression(e) for _, e in targets]
    used = set().union(*(e.free_symbols for e in exprs))
    temps = sp.numbered_symbols("w", exclude=used)
    replacements, reduced = sp.cse(exprs, symbols=temps, order="none")
    statements = len(replacements) + len(reduced)
    if statements <= SPLIT_STATEMENTS:
        # One function, const double locals.
        for sym, _ in replacements:
            printer._names[sym] = sym.name
        lines.append(f"static void {fname}({_ROW_ARGS}, double *out) {{")
        if zero:
            lines.append(zero)
        for sym, e in replacements:
            lines.append(f"  const double {sym.name} = {printer.doprint(e)};")
        for (k, _), e in zip(targets, reduced):
            lines.append(f"  out[{k}] = {printer.doprint(e)};")
        lines.append("}")
        return lines
    # Split: temporaries live in a scratch array w[], parts run in sequence.
    for i, (sym, _) in enumerate(replacements):
        printer._names[sym] = f"w[{i}]"
    stmts = [f"  w[{i}] = {printer.doprint(e)};" for i, (_, e) in enumerate(replacements)]
    stmts += [f"  out[{k}] = {printer.doprint(e)};" for (k, _), e in zip(targets, reduced)]
    parts = []
    for start in range(0, len(stmts), SPLIT_STATEMENTS):
        pname = f"{fname}_part{len(parts)}"
        parts.append(pname)
        lines.append(f"__attribute__((noinline)) static void {pname}({_ROW_ARGS}, "
                     "double *w, double *out) {")
        lines.extend(stmts[start:start + SPLIT_STATEMENTS])
        lines.append("}")
    n_w = max(1, len(replacements))
    lines.append(f"static void {fname}({_ROW_ARGS}, double *out) {{")
    lines.append(f"  double *w = (double *)malloc(sizeof(double) * {n_w});")
    if zero:
        lines.append(zero)
    lines.append("  if (!w) { for (int k = 0; k < %d; ++k) out[k] = NAN; return; }" % n_out)
    lines.extend(f"  {pname}({_ROW_CALL}, w, out);" for pname in parts)
    lines.append("  free(w);")
    lines.append("}")
    return lines


def _batch_function(name: str, row: str, n_out: int, dims: dict) -> list[str]:
    head = _BATCH_HEAD.format(zc="const ")
    nx, nz = dims["NX"], dims["NZ"]
    return [
        f"void bc_{name}({head}, double *out) {{",
        "  for (int i = 0; i < n; ++i) {",
        f"    {row}(t[(size_t)i * st], x + (size_t)i * {nx}, u + (size_t)i * su, "
        f"z + (size_t)i * {nz}, d + (size_t)i * sd, p + (size_t)i * sp, step, "
        f"out + (size_t)i * {n_out});",
        "  }",
        "}",
    ]


_SWITCHES = (sp.sign, sp.Heaviside, sp.floor, sp.ceiling)


def _diff_almost_everywhere(expr, var):
    """:math:`\\partial expr / \\partial var` where every switch is locally constant.

    ``sign``, ``Heaviside``, ``floor`` and ``ceiling`` are frozen as constants
    and ``Abs(g)`` is differentiated as ``sign(g) g``: the derivative that holds
    everywhere except on the switching surfaces, which is what a Newton or
    implicit-solver step needs.  (Plain ``sympy.diff`` leaves ``Derivative(sign(g))``
    unevaluated when it cannot prove ``g`` finite, and yields ``DiracDelta`` otherwise.)
    """
    frozen: dict = {}

    def freeze(node):
        if isinstance(node, sp.Abs):
            g = node.args[0]
            return g * frozen.setdefault(sp.sign(g), sp.Dummy("s"))
        return frozen.setdefault(node, sp.Dummy("s"))

    work = (expr.replace(lambda a: isinstance(a, (*_SWITCHES, sp.Abs)), freeze)
            if expr.has(*_SWITCHES, sp.Abs) else expr)
    de = sp.diff(work, var)
    back = {d: k for k, d in frozen.items()}
    for _ in range(len(back) + 1):   # keys may hold other frozen switches (nesting)
        if not (de.free_symbols & back.keys()):
            break
        de = de.xreplace(back)
    if de.has(sp.DiracDelta):
        de = de.replace(lambda a: isinstance(a, sp.DiracDelta), lambda a: sp.S.Zero)
    if de.has(sp.Derivative):
        raise CompilationError(f"cannot differentiate {expr} with respect to {var}: sympy "
                               f"leaves {de.atoms(sp.Derivative).pop()} unevaluated")
    return de


def jacobian_entries(exprs, wrt) -> list:
    """Nonzero entries ``(i * len(wrt) + j, d expr_i / d wrt_j)`` (almost everywhere, see
    :func:`_diff_almost_everywhere`), differentiating only by the symbols each
    expression contains (sparse, so 600 states stay cheap)."""
    index = {s: j for j, s in enumerate(wrt)}
    n = len(wrt)
    targets = []
    for i, e in enumerate(exprs):
        e = sp.sympify(e)
        for s in sorted(e.free_symbols & index.keys(), key=lambda s: index[s]):
            de = _diff_almost_everywhere(e, s)
            if de != 0:
                targets.append((i * n + index[s], de))
    return targets


# -- Newton ------------------------------------------------------------------

_NEWTON_TEMPLATE = r"""
/* Solve A y = b in place (A: m x m row-major, overwritten) by Gaussian
   elimination with partial pivoting.  Returns 1 when A is singular. */
static int bc_gauss(int m, double *A, double *b) {
  for (int k = 0; k < m; ++k) {
    int piv = k;
    double amax = fabs(A[k * m + k]);
    for (int i = k + 1; i < m; ++i) {
      double a = fabs(A[i * m + k]);
      if (a > amax) { amax = a; piv = i; }
    }
    if (!(amax > 1e-300) || !isfinite(amax)) return 1;
    if (piv != k) {
      for (int j = 0; j < m; ++j) { double s = A[k * m + j]; A[k * m + j] = A[piv * m + j]; A[piv * m + j] = s; }
      double s = b[k]; b[k] = b[piv]; b[piv] = s;
    }
    for (int i = k + 1; i < m; ++i) {
      double l = A[i * m + k] / A[k * m + k];
      if (l == 0.0) continue;
      for (int j = k; j < m; ++j) A[i * m + j] -= l * A[k * m + j];
      b[i] -= l * b[k];
    }
  }
  for (int k = m - 1; k >= 0; --k) {
    double s = b[k];
    for (int j = k + 1; j < m; ++j) s -= A[k * m + j] * b[j];
    b[k] = s / A[k * m + k];
  }
  return 0;
}

static double bc_norm2(int m, const double *r) {
  double s = 0.0;
  for (int k = 0; k < m; ++k) s += r[k] * r[k];
  return s;
}

static int bc_newton_iterate(double t, const double *x, const double *u, double *z,
                             const double *d, const double *p, double step, double *r,
                             double nr, double *J, double *dz, double *zt, double *rt);

/* Newton iteration for 0 = r(z) on one row, z warm-started in place.
   Step: J dz = -r with J = dr/dz; full step unless it increases |r|^2, then
   halve it (at most 10 times).  Converged when every |dz_k| <= RTOL |z_k| + ATOL. */
static int bc_newton_row(double t, const double *x, const double *u, double *z,
                         const double *d, const double *p, double step) {
  WORKSPACE_
  residuals_row(t, x, u, z, d, p, step, r);
  double nr = bc_norm2(NZ_, r);
  int status = 1;
  if (!isfinite(nr)) status = 3;
  else if (nr == 0.0) status = 0;
  else status = bc_newton_iterate(t, x, u, z, d, p, step, r, nr, J, dz, zt, rt);
  RELEASE_
  return status;
}

static int bc_newton_iterate(double t, const double *x, const double *u, double *z,
                             const double *d, const double *p, double step, double *r,
                             double nr, double *J, double *dz, double *zt, double *rt) {
  for (int it = 0; it < MAXIT_; ++it) {
    jac_rz_row(t, x, u, z, d, p, step, J);
    for (int k = 0; k < NZ_; ++k) dz[k] = -r[k];
    if (bc_gauss(NZ_, J, dz)) return 2;
    int small = 1;
    for (int k = 0; k < NZ_; ++k) {
      if (!isfinite(dz[k])) return 2;
      if (fabs(dz[k]) > RTOL_ * fabs(z[k]) + ATOL_) small = 0;
    }
    double lam = 1.0, nrt = 0.0;
    for (int ls = 0; ls <= 10; ++ls) {
      for (int k = 0; k < NZ_; ++k) zt[k] = z[k] + lam * dz[k];
      residuals_row(t, x, u, zt, d, p, step, rt);
      nrt = bc_norm2(NZ_, rt);
      if (isfinite(nrt) && (nrt <= nr || small)) break;
      lam *= 0.5;
    }
    if (!isfinite(nrt)) return 3;
    for (int k = 0; k < NZ_; ++k) { z[k] = zt[k]; r[k] = rt[k]; }
    nr = nrt;
    if ((small && lam == 1.0) || nr == 0.0) return 0;
  }
  return 1;
}
"""


def _newton_source(dims: dict) -> list[str]:
    nz, nx = dims["NZ"], dims["NX"]
    head = _BATCH_HEAD.format(zc="")
    lines = [f"int bc_solve({head}, int *status) {{", "  int bad = 0;"]
    if nz:
        if nz <= 64:   # workspace on the stack (<= 34 kB)
            work = (f"double r[{nz}], J[{nz * nz}], dz[{nz}], zt[{nz}], rt[{nz}];", "")
        else:
            work = (f"double *r = (double *)malloc(sizeof(double) * {nz * nz + 4 * nz});\n"
                    "  if (!r) return 2;\n"
                    f"  double *J = r + {nz}, *dz = J + {nz * nz}, *zt = dz + {nz}, *rt = zt + {nz};",
                    "free(r);")
        body = (_NEWTON_TEMPLATE.replace("WORKSPACE_", work[0]).replace("RELEASE_", work[1])
                .replace("NZ_", str(nz)).replace("MAXIT_", str(NEWTON_MAX_ITER))
                .replace("RTOL_", repr(NEWTON_RTOL)).replace("ATOL_", repr(NEWTON_ATOL)))
        lines = body.splitlines() + lines
        lines += [
            "  for (int i = 0; i < n; ++i) {",
            f"    status[i] = bc_newton_row(t[(size_t)i * st], x + (size_t)i * {nx}, "
            f"u + (size_t)i * su, z + (size_t)i * {nz}, d + (size_t)i * sd, "
            "p + (size_t)i * sp, step);",
            "    if (status[i]) ++bad;",
            "  }",
        ]
    else:
        lines.append("  for (int i = 0; i < n; ++i) status[i] = 0;")
    lines += ["  return bad;", "}"]
    return lines


def _rk4_source(dims: dict) -> list[str]:
    """``bc_rk4``: m classic RK4 sub-steps of length h per row, u constant,
    held values updated at each sub-step start, z solved at every stage."""
    nx, nz, nd = dims["NX"], dims["NZ"], dims["ND"]

    def solve(tt, xx, indent):
        if not nz:
            return []
        return [f"{indent}s = bc_newton_row({tt}, {xx}, ui, zi, di, pi, 0.0);",
                f"{indent}if (s) {{ for (int q = 0; q < {nz}; ++q) zi[q] = zinit[q];",
                f"{indent}  s = bc_newton_row({tt}, {xx}, ui, zi, di, pi, 0.0); }}",
                f"{indent}if (s) break;"]

    def stage(k, tt, xx):
        return solve(tt, xx, "      ") + [f"      f_row({tt}, {xx}, ui, zi, di, pi, 0.0, {k});"]

    lines = [
        "int bc_rk4(int n, double t0, double h, int m, double *x, const double *u, int su,",
        "           double *z, const double *zinit, double *d, const double *p, int sp,",
        "           int *status) {",
        f"  double *w = (double *)malloc(sizeof(double) * ({5 * nx + nd} + 1));",
        "  if (!w) return -1;",
        f"  double *k1 = w, *k2 = w + {nx}, *k3 = w + {2 * nx}, *k4 = w + {3 * nx};",
        f"  double *xt = w + {4 * nx}, *dn = w + {5 * nx};",
        "  (void)zinit; (void)dn;",
        "  int bad = 0;",
        "  for (int i = 0; i < n; ++i) {",
        f"    double *xi = x + (size_t)i * {nx}, *zi = z + (size_t)i * {nz}, *di = d + (size_t)i * {nd};",
        "    const double *ui = u + (size_t)i * su, *pi = p + (size_t)i * sp;",
        "    int s = 0;",
        "    for (int j = 0; j < m; ++j) {",
        "      double t = t0 + j * h;",
    ]
    if nd:
        lines += solve("t", "xi", "      ")
        lines += ["      held_update_row(t, xi, ui, zi, di, pi, h, dn);",
                  f"      for (int q = 0; q < {nd}; ++q) di[q] = dn[q];"]
    lines += stage("k1", "t", "xi")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + 0.5 * h * k1[q];"]
    lines += stage("k2", "t + 0.5 * h", "xt")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + 0.5 * h * k2[q];"]
    lines += stage("k3", "t + 0.5 * h", "xt")
    lines += [f"      for (int q = 0; q < {nx}; ++q) xt[q] = xi[q] + h * k3[q];"]
    lines += stage("k4", "t + h", "xt")
    lines += [
        f"      for (int q = 0; q < {nx}; ++q)",
        "        xi[q] += (h / 6.0) * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q]);",
        "    }",
        "    status[i] = s;",
        "    if (s) ++bad;",
        "  }",
        "  free(w);",
        "  return bad;",
        "}",
    ]
    return lines


# -- whole source --------------------------------------------------------------

def generate_source(eqs, *, part: str = "main") -> str:
    """C source of one group of batch kernels of `eqs` (see the module docstring).

    Parameters
    ----------
    eqs : StateEquations
        Equations to translate; every free symbol must be one of its ``t``,
        ``step``, states, inputs, params, algebraic or held symbols.
    part : {"main", "jacobian"}
        ``"main"``: ``f``, ``h``, ``held_update``, ``residuals``, ``jac_rz`` and
        ``solve`` -- everything simulation needs.  ``"jacobian"``: ``jac_fx``,
        ``jac_fz``, ``jac_rx``, for implicit solvers and linearisation.  Kept
        apart because symbolic differentiation of a large model costs more
        than the rest of code generation; a caller builds it on first use.

    Returns
    -------
    str
        A self-contained C99 translation unit (includes only ``math.h``,
        ``stdlib.h``, ``string.h``).

    Raises
    ------
    CompilationError
        If an expression contains a symbol the equations do not declare.
    ValueError
        If `part` is not one of the above.
    """
    if part not in PARTS:
        raise ValueError(f"part must be one of {', '.join(PARTS)}; found {part!r}")
    printer = _Printer(symbol_names(eqs))
    dims = {"NX": len(eqs.states), "NU": len(eqs.inputs), "NP": len(eqs.params),
            "NZ": len(eqs.algebraic), "ND": len(eqs.held), "NY": len(eqs.h)}
    nx, nz = dims["NX"], dims["NZ"]
    blocks = {
        "f": lambda: (list(enumerate(eqs.f)), nx),
        "h": lambda: (list(enumerate(eqs.h)), dims["NY"]),
        "held_update": lambda: (list(enumerate(eqs.held_update)), dims["ND"]),
        "residuals": lambda: (list(enumerate(eqs.residuals)), nz),
        "jac_rz": lambda: (jacobian_entries(eqs.residuals, eqs.algebraic), nz * nz),
        "jac_fx": lambda: (jacobian_entries(eqs.f, eqs.states), nx * nx),
        "jac_fz": lambda: (jacobian_entries(eqs.f, eqs.algebraic), nx * nz),
        "jac_rx": lambda: (jacobian_entries(eqs.residuals, eqs.states), nz * nx),
    }
    lines = [
        f"/* Generated by {_GENERATOR_VERSION} for model {eqs.name!r} ({part}); do not edit. */",
        "#include <math.h>", "#include <stdlib.h>", "#include <string.h>", "",
        "void bc_dims(int *dims) {",
        *(f"  dims[{i}] = {dims[k]};" for i, k in enumerate(("NX", "NU", "NP", "NZ", "ND", "NY"))),
        "}", "",
    ]
    for name in PARTS[part]:
        targets, n_out = blocks[name]()
        lines += _emit_block(f"{name}_row", targets, printer, n_out)
        lines += _batch_function(name, f"{name}_row", n_out, dims)
        lines.append("")
    if part == "main":
        lines += _newton_source(dims)
        lines += _rk4_source(dims)
    return "\n".join(lines) + "\n"


# -- compiling and caching -----------------------------------------------------

def find_compiler() -> str | None:
    """Path of the C compiler: ``$CC`` if set, else the first of cc, gcc, clang on PATH."""
    for name in ([os.environ["CC"]] if os.environ.get("CC") else []) + ["cc", "gcc", "clang"]:
        path = shutil.which(name)
        if path:
            return path
    return None


def cache_dir() -> Path:
    """Directory of compiled libraries: ``$BONDCOSIM_CACHE``, else ``~/.cache/bondcosim``."""
    env = os.environ.get("BONDCOSIM_CACHE")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "bondcosim"


def compile_source(source: str, *, compiler: str | None = None) -> Path:
    """Compile C source to a shared library, or reuse the cached one.

    The library is ``<cache>/bc_<sha256>.so``, where the hash covers the
    source, compiler path and flags.  It is built in a temporary file of the
    cache directory and renamed into place (atomic on POSIX), so concurrent
    processes compiling the same model never load a half-written file.

    Parameters
    ----------
    source : str
        C translation unit.
    compiler : str, optional
        Compiler executable; default :func:`find_compiler`.

    Returns
    -------
    pathlib.Path
        Path of the shared library.

    Raises
    ------
    CompilationError
        No compiler found, or it failed (its output is in ``.output``).
    """
    compiler = compiler or find_compiler()
    if compiler is None:
        raise CompilationError("no C compiler found: set $CC or put cc/gcc/clang on PATH "
                               "(or use backend='numpy')")
    key = hashlib.sha256("\0".join([source, compiler, *CFLAGS]).encode()).hexdigest()
    directory = cache_dir()
    target = directory / f"bc_{key[:40]}.so"
    if target.exists():
        return target
    directory.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=directory, prefix=".build-") as tmp:
        src = Path(tmp) / f"bc_{key[:40]}.c"
        src.write_text(source)
        lib = Path(tmp) / "lib.so"
        cmd = [compiler, *CFLAGS, "-o", str(lib), str(src), "-lm"]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise CompilationError(f"could not run {' '.join(cmd)}: {exc}") from None
        if proc.returncode != 0:
            raise CompilationError(
                f"C compiler failed (exit {proc.returncode}): {' '.join(cmd)}",
                output=(proc.stdout + proc.stderr).strip())
        os.replace(src, directory / src.name)   # keep the source next to the library
        os.replace(lib, target)
    return target


def _equations_key(eqs, part: str, compiler: str) -> str:
    """sha256 of everything the generated source depends on (cheap: no cse)."""
    parts = [_GENERATOR_VERSION, part, compiler, *CFLAGS, str(SPLIT_STATEMENTS), eqs.name]
    for field in ("t", "step"):
        parts.append(sp.srepr(getattr(eqs, field)))
    for field in ("states", "inputs", "params", "algebraic", "held",
                  "f", "h", "residuals", "held_update"):
        parts.append("|".join(sp.srepr(e) for e in getattr(eqs, field)))
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()


def build_library(eqs, *, part: str = "main") -> "CLibrary":
    """Generate, compile (or reuse) and load one library of `eqs`.

    A small index file ``idx_<key>`` in the cache maps a hash of the
    equations themselves to the library, so a later process skips code
    generation as well as compilation.

    Parameters
    ----------
    eqs : StateEquations
    part : {"main", "jacobian"}
        See :func:`generate_source`.

    Returns
    -------
    CLibrary

    Raises
    ------
    CompilationError
        No compiler, or it failed.
    """
    compiler = find_compiler()
    if compiler is None:
        raise CompilationError("no C compiler found: set $CC or put cc/gcc/clang on PATH "
                               "(or use backend='numpy')")
    index = cache_dir() / f"idx_{_equations_key(eqs, part, compiler)[:40]}"
    try:
        cached = cache_dir() / index.read_text().strip()
        if cached.exists():
            return CLibrary(cached)
    except OSError:
        pass
    path = compile_source(generate_source(eqs, part=part), compiler=compiler)
    fd, tmp = tempfile.mkstemp(dir=index.parent, prefix=".idx-")
    with os.fdopen(fd, "w") as fh:
        fh.write(path.name)
    os.replace(tmp, index)
    return CLibrary(path)


class CLibrary:
    """1:1 ctypes binding of a library made by :func:`generate_source`.

    Attributes
    ----------
    path : pathlib.Path
    dims : dict str -> int
        ``NX NU NP NZ ND NY``.
    kernels : list of str
        Names of the ``bc_*`` functions the library holds; each is an attribute
        (``lib.f``, ``lib.jac_fx``, ``lib.solve``...) taking ``int``,
        ``c_void_p`` and ``double`` arguments as in the module docstring.
        ``solve`` returns the number of failed rows.
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        self._dll = ctypes.CDLL(str(self.path))
        dims = (ctypes.c_int * 6)()
        self._dll.bc_dims(dims)
        self.dims = dict(zip(("NX", "NU", "NP", "NZ", "ND", "NY"), list(dims)))
        vp, i, dbl = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
        batch = [i, vp, i, vp, vp, i, vp, vp, i, vp, i, dbl]
        self.kernels = []
        for name in (*PARTS["main"], *PARTS["jacobian"], "solve"):
            try:
                fn = getattr(self._dll, f"bc_{name}")
            except AttributeError:
                continue
            fn.argtypes = batch + [vp]
            fn.restype = ctypes.c_int if name == "solve" else None
            setattr(self, name, fn)
            self.kernels.append(name)
        if hasattr(self._dll, "bc_rk4"):
            self.rk4 = self._dll.bc_rk4
            self.rk4.argtypes = [i, dbl, dbl, i, vp, vp, i, vp, vp, vp, vp, i, vp]
            self.rk4.restype = ctypes.c_int
            self.kernels.append("rk4")
