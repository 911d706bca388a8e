"""Derivation of explicit state equations along causal paths.

After SCAP every bond variable is *defined* by exactly one element (the one
that sets it), as an expression of other bond variables, states, inputs and
parameters.  The derivation

1. collects these definitions and the state rates from every element;
2. orders the bond variables by their dependencies (strongly connected
   components of the dependency graph, in topological order) and
   substitutes along that order -- one ``xreplace`` per variable, no global
   ``simplify``, so the cost grows linearly with the graph;
3. solves each *algebraic loop* (a strongly connected component with more
   than one variable): a few *tear* variables are chosen until the rest is
   acyclic; if the tear residuals are linear in the tears they are solved
   symbolically, otherwise the tears stay as algebraic unknowns with their
   residuals, solved numerically at each evaluation;
4. eliminates storage in *derivative causality*: its effort (I) or flow (C)
   is ``d/dt S(x)`` with ``S`` its energy variable through the inverse law,
   i.e. ``sum_j dS/dx_j * xdot_j``; with ``xdot`` depending on these
   unknowns this is a linear system, solved symbolically.  The dependent
   element's state disappears from the ODE (the reduction of Karnopp,
   Margolis & Rosenberg, *System Dynamics*, sec. 7.3).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import networkx as nx
import sympy as sp
from sympy.solvers.solveset import NonlinearError

from .assignments import readable_form
from .causality import assign_causality
from .elements.base import PortVars
from .errors import DerivationError, ExpressionError
from .guards import DerivedGuard
from .symbols import STEP, TIME, as_expression, sym
from .system import CausalityReport, StateEquations

if TYPE_CHECKING:   # annotations only: graph.py imports this module (BondGraph.equations)
    from .graph import BondGraph

__all__ = ["derive"]


def derive(graph: BondGraph) -> StateEquations:
    """Derive the state equations of `graph` (see the module docstring)."""
    graph.validate()
    names = graph.names()
    graph.prepare_expressions(names)
    assignment = assign_causality(graph)

    defs: dict[sp.Symbol, sp.Expr] = {}
    local_symbols: set = set()
    state_decls, derivative_decls, held_decls = [], [], []
    for element in graph.elements.values():
        ports = _port_vars(graph, element, assignment, names)
        contribution = element.contribute(ports, names)
        for var, expr in contribution.defs:
            if var in defs:  # pragma: no cover - SCAP guarantees one setter per variable
                raise DerivationError(f"{var} is set twice (second time by {element.name})", element=element.name)
            defs[var] = expr
        for var, expr in contribution.locals:
            defs[var] = expr
            local_symbols.add(var)
        state_decls += contribution.states
        derivative_decls += contribution.derivative
        held_decls += contribution.held

    dependent = {}  # symbol of d(S)/dt -> DerivativeDecl
    for decl in derivative_decls:
        rate_symbol = sym(f"der_{decl.state_name}")
        dependent[rate_symbol] = decl
        defs[decl.output] = decl.factor * rate_symbol

    resolver = _Resolver(defs)
    resolver.run()

    x = [s.symbol for s in state_decls]
    rates = [resolver.substitute(s.rate) for s in state_decls]
    stored = {}
    if dependent:
        rates, stored, solution = _eliminate_dependent(dependent, resolver, x, rates, names, graph)
        resolver.apply(solution)

    outputs, h, out_units, out_desc, h_raw = _outputs(graph, names, resolver, stored, state_decls)
    held_update = [resolver.substitute(d.update) for d in held_decls]
    final = {v: resolver.resolved[v] for loop in resolver.loops for v in loop}
    final.update({d.output: resolver.resolved[d.output] for d in dependent.values()})
    readable = readable_form(defs, resolver.order, local_symbols, final, names,
                             [s.rate for s in state_decls], h_raw, [d.update for d in held_decls])

    inputs = graph.inputs()
    params = graph.parameters()
    algebraic = tuple(resolver.algebraic)
    residuals = tuple(resolver.residuals)
    allowed = set(x) | {names[i.name] for i in inputs} | {names[p] for p in params} | set(algebraic) \
        | {d.symbol for d in held_decls} | {TIME}
    _check_free_symbols(graph, rates, h, residuals, allowed, state_decls, outputs)

    units = {s.symbol.name: s.unit for s in state_decls}
    units.update({i.name: i.unit for i in inputs})
    units.update({p.name: p.unit for p in params.values()})
    units.update({d.symbol.name: d.unit for d in held_decls})
    units.update(out_units)
    descriptions = {s.symbol.name: s.description for s in state_decls}
    descriptions.update({i.name: i.description for i in inputs})
    descriptions.update({p.name: p.description for p in params.values()})
    descriptions.update({d.symbol.name: d.description for d in held_decls})
    descriptions.update(out_desc)
    owners = {s.symbol.name: s.owner for s in state_decls}
    owners.update({i.name: i.owner for i in inputs})
    owners.update({d.symbol.name: d.owner for d in held_decls})
    for e in graph.elements.values():
        for p in e.parameters():
            owners.setdefault(p.name, (e.name, "parameter"))
    input_functions = {}
    for i in inputs:
        if i.function is not None:
            table = {"t": TIME, **{p: names[p] for p in params}}
            input_functions[i.name] = as_expression(i.function, table, owner=f"input {i.name} (function of t)")
    input_delays = _input_delays(graph, inputs, params)
    guards = _derived_guards(graph, names, resolver, allowed - set(algebraic))
    steps = [e.fixed_step for e in graph.elements.values() if e.fixed_step is not None]
    op = graph.operating_point
    report = CausalityReport(
        derivative_storage=tuple(assignment.derivative),
        algebraic_loops=tuple(_bonds_of(loop) for loop in resolver.loops),
        loops_solved_symbolically=tuple(resolver.loop_linear),
        arbitrary=tuple(assignment.arbitrary),
    )
    return StateEquations(
        name=graph.name, t=TIME, states=tuple(x), inputs=tuple(names[i.name] for i in inputs),
        params=tuple(names[p] for p in params), outputs=tuple(outputs), f=tuple(rates), h=tuple(h),
        algebraic=algebraic, residuals=residuals,
        held=tuple(d.symbol for d in held_decls), held_update=tuple(held_update),
        step=STEP, fixed_step=min(steps) if steps else None,
        param_values={p.name: p.value for p in params.values()},
        initial_state={s.symbol.name: op.get(s.symbol.name, s.initial) for s in state_decls},
        input_defaults={i.name: op.get(i.name, i.default) for i in inputs},
        held_initial={d.symbol.name: op.get(d.symbol.name, d.initial) for d in held_decls},
        units=units, descriptions=descriptions, owners=owners, input_functions=input_functions,
        input_delays=input_delays,
        report=report, assignments=readable.assignments, f_short=readable.f, h_short=readable.h,
        held_update_short=readable.held_update, guards=guards,
        param_bounds={p.name: (p.min, p.max) for p in params.values()
                      if p.min is not None or p.max is not None},
    )


def _input_delays(graph, inputs, params) -> dict:
    """Name -> :class:`~bondgraph.elements.base.InputDelay` of the delayed inputs, each checked:
    its source an input that is not itself delayed, its delay (and a `before` given by name) a
    parameter of the graph."""
    by_name = {i.name: i for i in inputs}
    delays = {}
    for i in inputs:
        if i.delay is None:
            continue
        source, time = i.delay.source, i.delay.time
        if source not in by_name:
            raise DerivationError(f"input {i.name!r} delays input {source!r}, which model {graph.name!r} does "
                                  f"not have; its inputs are {', '.join(sorted(by_name))}")
        if by_name[source].delay is not None:
            raise DerivationError(f"input {i.name!r} delays input {source!r}, itself a delayed input: delay "
                                  f"{by_name[source].delay.source!r} by the sum instead")
        if time not in params:
            raise DerivationError(f"input {i.name!r}: its delay {time!r} is not a parameter of model "
                                  f"{graph.name!r} (declare it with add_parameter)")
        before = i.delay.before
        if isinstance(before, str) and before not in params:
            raise DerivationError(f"input {i.name!r}: its value before the run, {before!r}, is not a parameter "
                                  f"of model {graph.name!r} (declare it with add_parameter)")
        delays[i.name] = i.delay
    return delays


def _derived_guards(graph, names, resolver, allowed) -> tuple:
    """The graph's guards with their expressions in the model's symbols (bond
    variables resolved); a guard on anything else is an ExpressionError naming it."""
    out = []
    for owner, g in graph.guards():
        what = f"guard {g.name!r} of {owner}"
        expr = resolver.substitute(as_expression(g.expression, names, owner=what))
        extra = sorted(str(s) for s in expr.free_symbols - allowed)
        if extra:
            raise ExpressionError(f"{what}: {expr} depends on {', '.join(extra)}; a guard may use "
                                  "only time, states, inputs, parameters and held variables",
                                  owner=what, expression=str(g.expression), unknown=extra)
        out.append(DerivedGuard(g, expr, owner))
    return tuple(out)


def _port_vars(graph, element, assignment, names) -> dict[str, PortVars]:
    ports = {}
    for bond, end in graph.bonds_of(element.name):
        port = bond.tail.port if end == "tail" else bond.head.port
        key = bond.name if element.ports is None else port
        natural = element.direction(port) if element.ports is not None else "in"
        sign = 1 if (natural == "in") == (end == "head") else -1
        ports[key] = PortVars(bond.name, names[f"e_{bond.name}"], names[f"f_{bond.name}"], sign,
                              assignment.role(bond, end))
    return ports


class _Resolver:
    """Substitutes bond-variable definitions along their dependency order."""

    def __init__(self, defs):
        self.defs = defs
        self.resolved: dict[sp.Symbol, sp.Expr] = {}
        self.algebraic: list[sp.Symbol] = []
        self.residuals: list[sp.Expr] = []
        self.loops: list[list[sp.Symbol]] = []
        self.loop_linear: list[bool] = []
        self.order: list[sp.Symbol] = []   # every variable, dependencies first
        self.deps = {v: [s for s in e.free_symbols if s in defs] for v, e in defs.items()}

    def _resolve_one(self, var, table):
        deps = self.deps[var]
        expr = self.defs[var]
        return expr.xreplace({d: table[d] for d in deps}) if deps else expr

    def run(self):
        graph = nx.DiGraph()
        graph.add_nodes_from(self.defs)
        graph.add_edges_from((d, v) for v, ds in self.deps.items() for d in ds)
        condensed = nx.condensation(graph)
        for component in nx.topological_sort(condensed):
            members = condensed.nodes[component]["members"]
            if len(members) == 1:
                (var,) = members
                if var not in self.deps[var]:
                    self.resolved[var] = self._resolve_one(var, self.resolved)
                    self.order.append(var)
                    continue
            self._solve_loop(graph.subgraph(members).copy())

    def _solve_loop(self, loop: nx.DiGraph):
        members = sorted(loop.nodes, key=str)
        tears = []
        while not nx.is_directed_acyclic_graph(loop):
            var = max(sorted(loop.nodes, key=str),
                      key=lambda n: (loop.in_degree(n) * loop.out_degree(n) + (2 if loop.has_edge(n, n) else 0)))
            tears.append(var)
            loop.remove_node(var)
        order = list(nx.topological_sort(loop))
        self.order += tears + order
        table = dict(self.resolved)
        table.update({t: t for t in tears})
        for var in order:
            table[var] = self._resolve_one(var, table)
        residuals = [t - self._resolve_one(t, table) for t in tears]
        self.loops.append(members)
        try:
            A, b = sp.linear_eq_to_matrix(residuals, tears)
            linear = not any(A.has(t) or b.has(t) for t in tears)
        except (NonlinearError, ValueError):
            linear = False
        self.loop_linear.append(linear)
        if linear:
            if len(tears) == 1:
                if A[0, 0] == 0:
                    raise DerivationError(f"algebraic loop through {', '.join(map(str, members))} is singular")
                solution = {tears[0]: b[0] / A[0, 0]}
            else:
                try:
                    values = A.LUsolve(b)
                except (ValueError, ZeroDivisionError) as exc:
                    raise DerivationError(f"algebraic loop through {', '.join(map(str, members))} is singular "
                                          f"({exc})") from None
                solution = dict(zip(tears, values))
            for t in tears:
                self.resolved[t] = solution[t]
            for var in order:
                self.resolved[var] = table[var].xreplace(solution)
        else:
            self.algebraic += tears
            self.residuals += residuals
            for t in tears:
                self.resolved[t] = t
            for var in order:
                self.resolved[var] = table[var]

    def substitute(self, expr: sp.Expr) -> sp.Expr:
        mapping = {s: self.resolved[s] for s in expr.free_symbols if s in self.resolved}
        return expr.xreplace(mapping) if mapping else expr

    def apply(self, solution):
        """Replace symbols (dependent-storage rates) everywhere."""
        for var in self.resolved:
            self.resolved[var] = self.resolved[var].xreplace(solution)
        self.residuals = [r.xreplace(solution) for r in self.residuals]


def _eliminate_dependent(dependent, resolver, x, rates, names, graph):
    """Solve for the rates of storage in derivative causality (module docstring, step 4)."""
    input_symbols = {names[i.name]: i.name for i in graph.inputs()}
    stored_exprs = {}
    equations = []
    for rate_symbol, decl in dependent.items():
        S = resolver.substitute(decl.stored)
        bad_inputs = [input_symbols[s] for s in S.free_symbols if s in input_symbols]
        if bad_inputs:
            raise DerivationError(
                f"{decl.element} is in derivative causality (bond {decl.bond}) and its "
                f"{'momentum' if decl.state_name.startswith('p') else 'state'} follows input(s) "
                f"{', '.join(bad_inputs)} directly, which would need their time derivative; "
                "add compliance or resistance between the source and the element", element=decl.element)
        dependent_states = {names[d.state_name] for d in dependent.values()}
        unsupported = [s for s in S.free_symbols
                       if s in dependent or s in dependent_states or s in set(resolver.algebraic)]
        if unsupported:
            raise DerivationError(
                f"{decl.element} is in derivative causality (bond {decl.bond}) and its stored quantity "
                f"depends on {', '.join(sorted(map(str, unsupported)))}, an eliminated state or an algebraic "
                "unknown; this structure is not supported", element=decl.element)
        stored_exprs[decl.state_name] = S
        rhs = sum((sp.diff(S, xj) * fj for xj, fj in zip(x, rates) if S.has(xj)), sp.Integer(0))
        rhs += sp.diff(S, TIME)
        equations.append(rate_symbol - rhs)
    unknowns = list(dependent)
    try:
        A, b = sp.linear_eq_to_matrix(equations, unknowns)
        linear = not any(A.has(u) or b.has(u) for u in unknowns)
    except (NonlinearError, ValueError):
        linear = False
    if not linear:
        resolver.algebraic += unknowns
        resolver.residuals += equations
        return rates, stored_exprs, {}
    values = [b[0] / A[0, 0]] if len(unknowns) == 1 else list(A.LUsolve(b))
    solution = {u: _rational(sp.together, v) for u, v in zip(unknowns, values)}
    rates = [_tidy(r.xreplace(solution)) if r.has(*unknowns) else r for r in rates]
    return rates, stored_exprs, solution


def _tidy(expr: sp.Expr, max_ops: int = 200) -> sp.Expr:
    """Cancel a small rational expression (a local, bounded simplification;
    the reduced rate of dependent storage reads ``(tau - b w)/(J1 + n^2 J2)``
    instead of a difference of fractions).  Large expressions are left alone."""
    if sp.count_ops(expr) > max_ops:
        return expr
    return _rational(lambda e: sp.factor_terms(sp.cancel(e)), expr)


def _rational(operation, expr: sp.Expr) -> sp.Expr:
    """``operation(expr)`` (a rational simplification: together, cancel) with every function
    application (exp, tanh, ...) held as an opaque symbol.  Otherwise the common denominator takes
    ``exp(-u)`` as ``1/exp(u)`` and multiplies the other terms by ``exp(u)``: a Stribeck law's
    ``exp(-(v/v_s)^2)`` in a gear's reduced inertia became ``(... exp(+(v/v_s)^2))/exp(+(v/v_s)^2)``,
    which overflows to inf/inf = NaN once the speed passes about 27 v_s.  The calls are numbered
    in sympy's sort order, so the result is the same in every process."""
    calls = expr.atoms(sp.Function)
    if not calls:
        return operation(expr)
    held = {call: sp.Dummy(f"call{i}") for i, call in enumerate(sorted(calls, key=sp.default_sort_key))}
    back = {d: call for call, d in held.items()}
    return operation(expr.xreplace(held)).xreplace(back)


def _bonds_of(variables) -> tuple[str, ...]:
    """Bond names of bond variables (``e_b3`` -> ``b3``), sorted and unique."""
    return tuple(sorted({str(v)[2:] for v in variables}))


def _outputs(graph, names, resolver, stored, state_decls):
    if not graph.outputs:
        outs = [s.symbol.name for s in state_decls]
        return outs, [s.symbol for s in state_decls], {}, {}, [s.symbol for s in state_decls]
    table = dict(names)
    outs, h, units, desc, raw = [], [], {}, {}, []
    dependent_states = {names[k]: v for k, v in stored.items()}
    for out in graph.outputs.values():
        expr = as_expression(out.expression, table, owner=f"output {out.name!r}")
        raw.append(expr.xreplace(dependent_states))
        expr = resolver.substitute(raw[-1])
        outs.append(out.name)
        h.append(expr)
        unit = out.unit
        if not unit and isinstance(out.expression, str):
            match = [s for s in state_decls if s.symbol.name == out.expression.strip()]
            unit = match[0].unit if match else ""
        units[out.name] = unit
        desc[out.name] = out.description
    return outs, h, units, desc, raw


def _check_free_symbols(graph, rates, h, residuals, allowed, state_decls, outputs):
    problems = []
    for decl, rate in zip(state_decls, rates):
        extra = rate.free_symbols - allowed
        if extra:
            problems.append(f"rate of {decl.symbol} still depends on {', '.join(sorted(map(str, extra)))}")
    for name, expr in zip(outputs, h):
        extra = expr.free_symbols - allowed
        if extra:
            problems.append(f"output {name} depends on {', '.join(sorted(map(str, extra)))}, which the "
                            "derivation does not determine (a state eliminated by derivative causality?)")
    if problems:
        raise DerivationError(f"graph {graph.name!r}: " + "; ".join(problems))


