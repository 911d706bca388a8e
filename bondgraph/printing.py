"""Readable text and LaTeX renderings of :class:`~bondgraph.system.StateEquations`."""
from __future__ import annotations

import sympy as sp

__all__ = ["pretty", "latex", "equations_to_dict"]


def _fmt_unit(unit: str) -> str:
    return f" [{unit}]" if unit else ""


def _fmt_value(value: float) -> str:
    return f"{value:.6g}"


def pretty(eqs, *, simplify: bool = False) -> str:
    """Explicit state equations as plain text, one per line, with units.

    Parameters
    ----------
    eqs : StateEquations
    simplify : bool
        Apply ``sympy.simplify`` to each right-hand side for display only
        (slow on large models).

    Returns
    -------
    str
    """
    show = (lambda e: sp.simplify(e)) if simplify else (lambda e: e)
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
    lines.append("")
    for s, rhs in zip(eqs.states, eqs.f):
        lines.append(f"  {'d' + s.name + '/dt':<{width + 4}} = {show(rhs)}")
    for z, r in zip(eqs.algebraic, eqs.residuals):
        lines.append(f"  0 = {show(r)}    (algebraic, solves {z})")
    for d, upd in zip(eqs.held, eqs.held_update):
        lines.append(f"  {d.name} <- {upd}    (each sub-step)")
    if eqs.outputs:
        lines.append("")
    for name, expr in zip(eqs.outputs, eqs.h):
        lines.append(f"  {name:<{width + 4}} = {show(expr)}{_fmt_unit(u.get(name, ''))}")
    if eqs.params:
        lines.append("")
        lines.append("  parameters: " + ", ".join(
            f"{p} = {_fmt_value(eqs.param_values[p.name])}{(' ' + u[p.name]) if u.get(p.name) else ''}"
            for p in eqs.params))
    report = str(eqs.report)
    lines.append("  causality: " + report.replace("\n", "\n             "))
    return "\n".join(lines)


def latex(eqs) -> str:
    """The state and output equations as a LaTeX ``aligned`` block."""
    rows = []
    for s, rhs in zip(eqs.states, eqs.f):
        rows.append(rf"\dot{{{sp.latex(s)}}} &= {sp.latex(rhs)}")
    for z, r in zip(eqs.algebraic, eqs.residuals):
        rows.append(rf"0 &= {sp.latex(r)}")
    for name, expr in zip(eqs.outputs, eqs.h):
        rows.append(rf"{sp.latex(sp.Symbol(name))} &= {sp.latex(expr)}")
    return "\\begin{aligned}\n" + " \\\\\n".join(rows) + "\n\\end{aligned}"


def equations_to_dict(eqs) -> dict:
    """JSON-ready summary: names, parameter values, right-hand sides as strings."""
    return {
        "name": eqs.name,
        "states": list(eqs.state_names),
        "inputs": list(eqs.input_names),
        "outputs": list(eqs.outputs),
        "parameters": {p.name: eqs.param_values[p.name] for p in eqs.params},
        "units": dict(eqs.units),
        "f": [str(e) for e in eqs.f],
        "h": [str(e) for e in eqs.h],
        "algebraic": [str(z) for z in eqs.algebraic],
        "residuals": [str(r) for r in eqs.residuals],
        "held": list(eqs.held_names),
        "held_update": [str(e) for e in eqs.held_update],
        "fixed_step": eqs.fixed_step,
        "causality": str(eqs.report),
    }
