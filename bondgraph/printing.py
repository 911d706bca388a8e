"""Readable text and LaTeX renderings of :class:`~bondgraph.system.StateEquations`."""
from __future__ import annotations

import sympy as sp

__all__ = ["pretty", "latex", "equations_to_dict"]


def _fmt_unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def _fmt_value(value: float) -> str:
    return f"{value:.6g}"


def _forms(eqs, flat: bool):
    """(assignments, f, h, held_update) to show: the short forms, or the flat ones."""
    if flat:
        return (), eqs.f, eqs.h, eqs.held_update
    return eqs.assignments, eqs.f_short, eqs.h_short, eqs.held_update_short


def pretty(eqs, *, simplify: bool = False, flat: bool = False) -> str:
    """Explicit state equations as plain text, one per line, with units.

    By default the ordered causal assignments (named intermediates such as
    ``valve1.alpha``, :attr:`StateEquations.assignments`) come first, in
    evaluation order, and the state equations use them; ``flat=True`` shows
    every right-hand side fully substituted.

    Parameters
    ----------
    eqs : StateEquations
    simplify : bool
        Apply ``sympy.simplify`` to each right-hand side for display only
        (slow on large models).
    flat : bool
        Substitute the assignments (one long expression per state).

    Returns
    -------
    str
    """
    show = (lambda e: sp.simplify(e)) if simplify else (lambda e: e)
    assignments, f, h, held_update = _forms(eqs, flat)
    u = eqs.units
    lines = [f"{eqs.name}: {len(eqs.states)} state(s), {len(eqs.inputs)} input(s), "
             f"{len(eqs.outputs)} output(s)"]
    lines.append("  states:  " + ", ".join(f"{s}{_fmt_unit(u.get(s.name, ''))}" for s in eqs.states))
    if eqs.inputs:
        lines.append("  inputs:  " + ", ".join(f"{s}{_fmt_unit(u.get(s.name, ''))}" for s in eqs.inputs))
    if eqs.held:
        lines.append("  held:    " + ", ".join(f"{s}{_fmt_unit(u.get(s.name, ''))}" for s in eqs.held)
                     + f"  (fixed step {eqs.fixed_step:g} s)")
    width = max([len(s.name) for s in eqs.states] + [len(o) for o in eqs.outputs] + [1])
    if assignments:
        lines.append("")
        lines.append("  assignments, in evaluation order:")
        a_width = max(len(a.name) for a, _ in assignments)
        for a, expr in assignments:
            lines.append(f"  {a.name:<{max(a_width, width + 4)}} = {show(expr)}")
    lines.append("")
    for s, rhs in zip(eqs.states, f):
        lines.append(f"  {'d' + s.name + '/dt':<{width + 4}} = {show(rhs)}")
    for z, r in zip(eqs.algebraic, eqs.residuals):
        lines.append(f"  0 = {show(r)}    (algebraic, solves {z})")
    for d, upd in zip(eqs.held, held_update):
        lines.append(f"  {d.name} <- {upd}    (each sub-step)")
    if eqs.outputs:
        lines.append("")
    for name, expr in zip(eqs.outputs, h):
        lines.append(f"  {name:<{width + 4}} = {show(expr)}{_fmt_unit(u.get(name, ''))}")
    if eqs.params:
        lines.append("")
        lines.append("  parameters: " + ", ".join(
            f"{p} = {_fmt_value(eqs.param_values[p.name])}{(' ' + u[p.name]) if u.get(p.name) else ''}"
            for p in eqs.params))
    report = str(eqs.report)
    lines.append("  causality: " + report.replace("\n", "\n             "))
    return "\n".join(lines)


def _latex_name(symbol) -> str:
    """``valve1.alpha`` -> ``\\mathrm{valve1}.\\alpha``; other names as sympy prints them."""
    element, dot, local = symbol.name.partition(".")
    if not dot:
        return sp.latex(symbol)
    return rf"\mathrm{{{element}}}.{sp.latex(sp.Symbol(local))}"


def latex(eqs, *, flat: bool = False) -> str:
    """The assignments (unless `flat`), state and output equations as a LaTeX ``aligned`` block."""
    assignments, f, h, _ = _forms(eqs, flat)
    names = {a: sp.Symbol(_latex_name(a)) for a, _ in assignments}

    def tex(expr):
        return sp.latex(expr.xreplace(names) if names else expr)

    rows = [rf"{_latex_name(a)} &:= {tex(expr)}" for a, expr in assignments]
    for s, rhs in zip(eqs.states, f):
        rows.append(rf"\dot{{{sp.latex(s)}}} &= {tex(rhs)}")
    for z, r in zip(eqs.algebraic, eqs.residuals):
        rows.append(rf"0 &= {sp.latex(r)}")
    for name, expr in zip(eqs.outputs, h):
        rows.append(rf"{sp.latex(sp.Symbol(name))} &= {tex(expr)}")
    return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"


def equations_to_dict(eqs) -> dict:
    """JSON-ready summary: names, parameter values, right-hand sides as strings.

    ``f``/``h`` are the flat (substituted) forms; ``assignments`` is the
    ordered list of ``{"name", "expression"}`` intermediates and
    ``f_short``/``h_short`` use them."""
    return {
        "name": eqs.name,
        "states": list(eqs.state_names),
        "inputs": list(eqs.input_names),
        "outputs": list(eqs.outputs),
        "parameters": {p.name: eqs.param_values[p.name] for p in eqs.params},
        "units": dict(eqs.units),
        "f": [str(e) for e in eqs.f],
        "h": [str(e) for e in eqs.h],
        "assignments": [{"name": a.name, "expression": str(e)} for a, e in eqs.assignments],
        "f_short": [str(e) for e in eqs.f_short],
        "h_short": [str(e) for e in eqs.h_short],
        "algebraic": [str(z) for z in eqs.algebraic],
        "residuals": [str(r) for r in eqs.residuals],
        "held": list(eqs.held_names),
        "held_update": [str(e) for e in eqs.held_update],
        "fixed_step": eqs.fixed_step,
        "causality": str(eqs.report),
    }
