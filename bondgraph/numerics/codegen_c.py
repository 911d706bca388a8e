"""C code for state equations: sympy expressions to batch evaluators.

This module is the low layer of the compiled backend (the Pythonic layer is
:class:`bondgraph.numerics.evaluate.CompiledModel`): :func:`generate_source` writes C
for a :class:`~bondgraph.system.StateEquations`, one row function per kernel
from the model's expressions plus the fixed Newton solver and RK4 driver of
:mod:`bondgraph.numerics.codegen_c_templates`.  Compiling, caching and loading are in
:mod:`bondgraph.numerics.c_build`, re-exported here: :func:`compile_source` turns
the source into a shared library with the system compiler (cached by the
sha256 of source and flags), :func:`build_library` does both (skipping
generation too when the same equations were built before), and
:class:`CLibrary` is a 1:1 ctypes binding of the functions below.

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
``bc_rk4_every(n, t0, h, m, every, <the rest as bc_rk4>)`` updates the held
values only at every ``every``-th sub-step start, over ``every h``: finer RK4
steps nested in a discrete law's interval (``bc_rk4`` is it with ``every = 1``).

Code shape
----------
``f``, ``h`` and ``held_update`` are generated from the model's ordered causal
assignments (:attr:`~bondgraph.system.StateEquations.assignments`), each a
``const double`` local computed once; every block then goes through
:func:`sympy.cse`, whose temporaries are ``const double`` locals too.  A block with more than :data:`SPLIT_STATEMENTS` statements is split
into several ``noinline`` functions sharing a scratch array (compile time of
one huge function grows super-linearly).  The compiler flags (:data:`CFLAGS`)
are explained in :mod:`bondgraph.numerics.c_build`.
"""
from __future__ import annotations

import math

import sympy as sp
from sympy.printing.c import C99CodePrinter

from ..assignments import needed_assignments
from .codegen_c_templates import BATCH_HEAD, newton_source, rk4_source
from ..derivatives import NotDifferentiable, diff_almost_everywhere
from ..errors import ArgumentError, CompilationError

__all__ = ["generate_source", "jacobian_entries", "prepare_expression", "symbol_names",
           "SPLIT_STATEMENTS", "PARTS", "GENERATOR_VERSION", "guard_source", "indicator_source",
           "partials_source"]

#: Statements above which a block is split into several functions.
SPLIT_STATEMENTS = 400
#: Batch kernels of each generated library (``main`` also has ``bc_solve``).
PARTS = {
    "main": ("f", "h", "held_update", "residuals", "jac_rz"),
    "jacobian": ("jac_fx", "jac_fz", "jac_rx"),
}

_ROW_ARGS = ("double t, const double *x, const double *u, const double *z, "
             "const double *d, const double *p, double step")
_ROW_CALL = "t, x, u, z, d, p, step"
GENERATOR_VERSION = "bondcosim-codegen-c 4"   # 3: bc_rk4_every; 4: Newton stops at the rounding floor


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

def _statements(targets: list, prelude) -> tuple[list, list]:
    """cse over `targets` (and the `prelude` assignments they need): returns
    ``(statements, reduced)``, the temporaries and assignments as ``(symbol,
    expr)`` in an evaluation order, and each target over them."""
    from graphlib import TopologicalSorter

    pre = needed_assignments(prelude, [e for _, e in targets])
    exprs = [prepare_expression(e) for _, e in pre] + [prepare_expression(e) for _, e in targets]
    used = set().union(*(e.free_symbols for e in exprs))
    temps = sp.numbered_symbols("w", exclude=used)
    replacements, reduced = sp.cse(exprs, symbols=temps, order="none")
    if not pre:
        return list(replacements), reduced
    statements = dict(replacements)
    statements.update(zip((s for s, _ in pre), reduced[:len(pre)]))
    graph = {s: [d for d in e.free_symbols if d in statements] for s, e in statements.items()}
    order = TopologicalSorter(graph).static_order()
    return [(s, statements[s]) for s in order], reduced[len(pre):]


def _emit_block(fname: str, targets: list, printer: _Printer, n_out: int, prelude=()) -> list[str]:
    """C lines of a row function ``fname`` writing ``out[k] = expr`` for
    ``targets = [(k, expr), ...]``; other entries of ``out[:n_out]`` are 0.
    `prelude` is ordered ``(symbol, expr)`` assignments the targets may use
    (the model's causal assignments), each computed once as a local."""
    lines: list[str] = []
    zero = f"  memset(out, 0, sizeof(double) * {n_out});" if n_out > len(targets) else None
    if not targets:
        lines.append(f"static void {fname}({_ROW_ARGS}, double *out) {{")
        if n_out:
            lines.append(f"  memset(out, 0, sizeof(double) * {n_out});")
        lines.append("}")
        return lines
    replacements, reduced = _statements(targets, prelude)
    statements = len(replacements) + len(reduced)
    prelude_names = {s: f"a{i}" for i, (s, _) in enumerate(prelude)}
    if statements <= SPLIT_STATEMENTS:
        # One function, const double locals.
        for sym, _ in replacements:
            printer._names[sym] = prelude_names.get(sym, sym.name)
        lines.append(f"static void {fname}({_ROW_ARGS}, double *out) {{")
        if zero:
            lines.append(zero)
        for sym, e in replacements:
            lines.append(f"  const double {printer._names[sym]} = {printer.doprint(e)};")
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
    head = BATCH_HEAD.format(zc="const ")
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


def _diff_almost_everywhere(expr, var):
    """:func:`bondgraph.derivatives.diff_almost_everywhere`, failures as CompilationError."""
    try:
        return diff_almost_everywhere(expr, var)
    except NotDifferentiable as exc:
        raise CompilationError(str(exc)) from None


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
        raise ArgumentError(f"part must be one of {', '.join(PARTS)}; found {part!r}")
    printer = _Printer(symbol_names(eqs))
    dims = {"NX": len(eqs.states), "NU": len(eqs.inputs), "NP": len(eqs.params),
            "NZ": len(eqs.algebraic), "ND": len(eqs.held), "NY": len(eqs.h)}
    nx, nz = dims["NX"], dims["NZ"]
    # f, h and held_update over the causal assignments: each intermediate (a valve's
    # table, a muscle's force) is computed once instead of once per use
    blocks = {
        "f": lambda: (list(enumerate(eqs.f_short)), nx),
        "h": lambda: (list(enumerate(eqs.h_short)), dims["NY"]),
        "held_update": lambda: (list(enumerate(eqs.held_update_short)), dims["ND"]),
        "residuals": lambda: (list(enumerate(eqs.residuals)), nz),
        "jac_rz": lambda: (jacobian_entries(eqs.residuals, eqs.algebraic), nz * nz),
        "jac_fx": lambda: (jacobian_entries(eqs.f, eqs.states), nx * nx),
        "jac_fz": lambda: (jacobian_entries(eqs.f, eqs.algebraic), nx * nz),
        "jac_rx": lambda: (jacobian_entries(eqs.residuals, eqs.states), nz * nx),
    }
    lines = [
        f"/* Generated by {GENERATOR_VERSION} for model {eqs.name!r} ({part}); do not edit. */",
        "#include <math.h>", "#include <stdlib.h>", "#include <string.h>", "",
        "void bc_dims(int *dims) {",
        *(f"  dims[{i}] = {dims[k]};" for i, k in enumerate(("NX", "NU", "NP", "NZ", "ND", "NY"))),
        "}", "",
    ]
    for name in PARTS[part]:
        targets, n_out = blocks[name]()
        prelude = eqs.assignments if name in ("f", "h", "held_update") else ()
        lines += _emit_block(f"{name}_row", targets, printer, n_out, prelude)
        lines += _batch_function(name, f"{name}_row", n_out, dims)
        lines.append("")
    if part == "main":
        lines += newton_source(dims)
        lines += rk4_source(dims)
    return "\n".join(lines) + "\n"


def guard_source(eqs) -> str:
    """C text of ``static void guard_row(t, x, u, z, d, p, step, out)``: the value of
    every guard of `eqs` (:attr:`StateEquations.guards`, in order) at one point, for
    code that checks the physical domain (the FMU core).  Compiled together with
    the ``main`` part (it uses the same helpers and ``math.h``).

    Returns
    -------
    str
    """
    printer = _Printer(symbol_names(eqs))
    targets = list(enumerate(g.expr for g in eqs.guards))
    return "\n".join(_emit_block("guard_row", targets, printer, max(1, len(targets)))) + "\n"


def indicator_source(eqs, surfaces) -> str:
    """C text of ``static void indicator_row(t, x, u, z, d, p, step, out)``: the value of
    each switching function in `surfaces` (expressions over the symbols of `eqs` and its
    assignment names, e.g. from :func:`bondgraph.derivatives.switching_surfaces`) at one
    point -- a Model Exchange FMU's event indicators.

    Returns
    -------
    str
    """
    printer = _Printer(symbol_names(eqs))
    targets = list(enumerate(surfaces))
    return "\n".join(_emit_block("indicator_row", targets, printer, max(1, len(targets)),
                                 eqs.assignments)) + "\n"


def partials_source(eqs) -> str:
    """C text of the two row functions partial derivatives are assembled from, over
    :math:`w = (x, u, z)` (states, inputs, algebraic unknowns):

    * ``partials_F_row(t, x, u, z, d, p, step, out)``: :math:`\\partial (f, h) / \\partial w`,
      ``out`` of shape ``(NX + NY, NX + NU + NZ)`` row-major;
    * ``partials_r_row(...)``: :math:`\\partial r / \\partial w`, shape ``(NZ, NX + NU + NZ)``,

    each entry the derivative almost everywhere (switches frozen,
    :func:`bondgraph.derivatives.diff_almost_everywhere`).  Eliminating ``z`` by the
    implicit-function theorem (:mod:`bondgraph.linearization`) gives the Jacobian of the
    derivatives and outputs with respect to states and inputs.

    Raises
    ------
    CompilationError
        An expression sympy cannot differentiate.
    """
    printer = _Printer(symbol_names(eqs))
    wrt = [*eqs.states, *eqs.inputs, *eqs.algebraic]
    n_f = len(eqs.f) + len(eqs.h)
    lines = _emit_block("partials_F_row", jacobian_entries([*eqs.f, *eqs.h], wrt), printer,
                        max(1, n_f * len(wrt)))
    lines += _emit_block("partials_r_row", jacobian_entries(eqs.residuals, wrt), printer,
                         max(1, len(eqs.residuals) * len(wrt)))
    return "\n".join(lines) + "\n"
