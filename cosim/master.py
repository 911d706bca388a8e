"""The co-simulation master: fixed communication step, ordered by feedthrough.

Scheme
------
At each communication point :math:`t_k = t_0 + k\\,h` (computed by
multiplication, so no drift accumulates):

1. components run :meth:`~cosim.Component.output` in *execution order*; just
   before, a component with direct feedthrough gathers its connected inputs
   from the signal buffer, so a chain of feedthrough blocks has no delay;
2. every input is gathered (all outputs are now at :math:`t_k`) and the
   whole buffer is logged as row ``k``;
3. (``k < n``) every component advances from :math:`t_k` to
   :math:`t_{k+1}` with its inputs held.

An input that no connection drives keeps its port's start value.

Execution order
---------------
Components run in topological order of the feedthrough graph; a cycle of
feedthrough ports is an algebraic loop (:mod:`cosim.ordering` explains both).

Units
-----
A connection carries the value from the source's unit into the destination's
through :func:`bondgraph.units.convert` when the two differ but have the same
dimension (``deg`` -> ``rad``, ``bar`` -> ``Pa``, ``N.m`` -> ``N m``):
:math:`v_{dst} = (s_{src} v + o_{src} - o_{dst}) / s_{dst}` with each unit's
scale and offset to SI, applied when the inputs are gathered (the log shows
each input in its own unit).  ``""`` (unspecified) matches anything without
conversion.  Different dimensions, or texts that do not parse and differ, are
a :class:`CosimError`.  A third connection element overrides this for
third-party FMUs that declare no or a wrong unit: ``("src.y", "dst.u",
{"unit": "N"})`` states the source's unit (then converts if needed),
``{"convert": False}`` passes the raw number.
"""
from __future__ import annotations

import sys
import time as _time

import numpy as np

from cosim.errors import BondcosimError, CosimError, SimulationError, UnitError
from bondgraph.numerics.progress import Progress
from bondgraph.numerics.results import SimulationResult
from bondgraph.units import parse_unit

from .component import Component, PythonBlock
from .ordering import execution_plan

__all__ = ["CoSimulation", "CosimResult"]

_PROGRESS_STEPS = 200_000   # runs longer than this (about 2 s) show progress by default


class CosimResult(SimulationResult):
    """Result of :meth:`CoSimulation.run`: signals ``"component.port"``.

    Outputs have kind ``"output"``, inputs ``"input"``; ``info`` holds
    ``step`` (s), ``n_steps``, ``t0``, ``t_end`` (s), ``wall_time`` (s),
    ``order`` (component names in execution order, repeats for passes) and
    ``connections``.  CSV and plotting as :class:`~bondgraph.numerics.results.SimulationResult`.
    """

    __slots__ = ()

    def plot(self, names=None, *, ax=None):
        """Plot signals, one subplot per unit, on a new :class:`matplotlib.figure.Figure`.

        Parameters
        ----------
        names : sequence of str, optional
            Signals to plot (default all).
        ax : matplotlib Axes or sequence of Axes, optional
            Draw there instead (see :meth:`SimulationResult.plot`).

        Returns
        -------
        matplotlib.figure.Figure
        """
        if ax is not None:
            return super().plot(names, ax=ax)
        from matplotlib.figure import Figure   # no pyplot: no global figure state
        names = list(self.names) if names is None else [names] if isinstance(names, str) \
            else list(names)
        for n in names:
            self[n]   # KeyError naming an unknown signal
        n_units = max(1, len(dict.fromkeys(self.units[n] for n in names)))
        fig = Figure(figsize=(7, 1.5 + 2.0 * n_units))
        axes = fig.subplots(n_units, 1, sharex=True, squeeze=False)[:, 0]
        return super().plot(names, ax=list(axes))


def _split(signal, what: str) -> tuple[str, str]:
    comp, sep, port = str(signal).partition(".")
    if not (isinstance(signal, str) and sep and comp and port):
        raise CosimError(f"{what} {signal!r}: expected 'component.port'")
    return comp, port


class CoSimulation:
    """A co-simulation of components connected output -> input.

    Parameters
    ----------
    components : sequence of Component
        FMU components, Python blocks...; names unique and without ``"."``.
    connections : iterable of (str, str)
        ``(source, destination)`` pairs in signal direction, each
        ``"component.port"``: an output drives an input.
    step : float, s
        Communication step, > 0.

    Attributes
    ----------
    components : dict str -> Component
    connections : tuple of (str, str)
    conversions : dict str -> (str, str, float, float)
        Destination input -> (source unit, destination unit, scale, shift):
        the input receives ``scale * value + shift``.
    step : float
    order : tuple of str
        Component names in execution order (a group evaluated in several
        passes appears several times).

    Raises
    ------
    CosimError
        Every set-up problem found, named: non-positive step, duplicate or bad
        component names, unknown component or port (with the known ones),
        connection the wrong way round, input driven twice, unit mismatch.
    AlgebraicLoopError
        Feedthrough ports in a loop; ``.ports`` lists the loop in signal order.

    Examples
    --------
    >>> from cosim import CoSimulation, Step, PI, Constant
    >>> sim = CoSimulation([Step("r", 0.0), Constant("m", 0.25), PI("c", kp=2.0, ki=0.0)],
    ...                    [("r.y", "c.r"), ("m.y", "c.y_m")], step=0.1)
    >>> float(sim.run(0.2)["c.u"][-1])
    1.5
    """

    def __init__(self, components, connections, step: float):
        try:
            self.step = float(step)
        except (TypeError, ValueError):
            raise CosimError(f"step must be a number of seconds; found {step!r}") from None
        if not (np.isfinite(self.step) and self.step > 0):
            raise CosimError(f"step must be positive and finite (s); found {step!r}")
        self.components = self._check_components(list(components))
        self.conversions: dict[str, tuple] = {}
        self.connections = self._check_connections(list(connections))
        self._layout()
        self._order = [self.components[n] for n in execution_plan(
            list(self.components.values()), self.connections)]
        self.order = tuple(c.name for c in self._order)

    # -- validation --------------------------------------------------------------------------
    @staticmethod
    def _check_components(components) -> dict:
        found, problems = {}, []
        for i, c in enumerate(components):
            if not isinstance(c, Component):
                missing = [a for a in ("name", "inputs", "outputs", "feedthrough", "bind",
                                       "start", "output", "advance", "stop") if not hasattr(c, a)]
                problems.append(f"components[{i}] = {c!r} is not a component (lacks "
                                f"{', '.join(missing)})")
            elif not isinstance(c.name, str) or not c.name or "." in c.name:
                problems.append(f"components[{i}]: name {c.name!r} must be a non-empty str "
                                "without '.'")
            elif c.name in found:
                problems.append(f"duplicate component name {c.name!r} (components "
                                f"{list(found).index(c.name)} and {i})")
            else:
                names = [p.name for p in (*c.inputs, *c.outputs)]
                dup = sorted({n for n in names if names.count(n) > 1})
                if dup:
                    problems.append(f"component {c.name!r}: port name(s) {', '.join(dup)} used "
                                    "more than once among its inputs and outputs")
                ins, outs = {p.name for p in c.inputs}, {p.name for p in c.outputs}
                bad = sorted(f"({i!r}, {o!r})" for i, o in c.feedthrough
                             if i not in ins or o not in outs)
                if bad:
                    problems.append(f"component {c.name!r}: feedthrough {', '.join(bad)} names "
                                    "ports it does not have")
                found[c.name] = c
        if problems:
            raise CosimError(_joined(problems))
        return found

    def _port(self, signal: str, want: str, problems: list):
        comp, port = _split(signal, want)
        c = self.components.get(comp)
        if c is None:
            problems.append(f"{want} {signal!r}: unknown component {comp!r}; components are "
                            f"{', '.join(self.components) or '(none)'}")
            return None
        ports = {p.name: p for p in (c.outputs if want == "source" else c.inputs)}
        if port in ports:
            return ports[port]
        kind = "output" if want == "source" else "input"
        other = {p.name for p in (c.inputs if want == "source" else c.outputs)}
        hint = (f" ({port!r} is an {'input' if kind == 'output' else 'output'}; connections go "
                "output -> input)") if port in other else ""
        problems.append(f"{want} {signal!r}: component {comp!r} has no {kind} {port!r}{hint}; its "
                        f"{kind}s are {', '.join(ports) or '(none)'}")
        return None

    def _check_connections(self, connections) -> tuple:
        problems, culprits, driven = [], [], {}
        pairs = []
        for j, pair in enumerate(connections):
            if isinstance(pair, str) or not hasattr(pair, "__len__") or len(pair) not in (2, 3):
                raise CosimError(f"connections[{j}] = {pair!r}: expected a (source, destination) "
                                 "pair of 'component.port' names, optionally with a dict of "
                                 "options (unit, convert)")
            src, dst = pair[0], pair[1]
            options = _options(pair, j, problems)
            ps, pd = self._port(src, "source", problems), self._port(dst, "destination", problems)
            if ps is None or pd is None or options is None:
                culprits.append(src if ps is None else dst)
                continue
            if dst in driven:
                problems.append(f"input {dst!r} is driven twice: by {driven[dst]!r} and {src!r}")
                culprits.append(dst)
            elif options.get("convert", True):
                unit = options.get("unit", ps.unit)
                conversion = _conversion(src, unit, dst, pd.unit, problems)
                if conversion is False:
                    culprits.extend((src, dst))
                elif conversion is not None:
                    self.conversions[dst] = conversion
            driven.setdefault(dst, src)
            pairs.append((src, dst))
        if problems:
            raise CosimError(_joined(problems), ports=culprits)
        return tuple(pairs)

    # -- layout and order --------------------------------------------------------------------
    def _layout(self) -> None:
        """Positions in the signal buffer: all outputs, then all inputs, in component order."""
        comps = list(self.components.values())
        outs = [f"{c.name}.{p.name}" for c in comps for p in c.outputs]
        ins = [f"{c.name}.{p.name}" for c in comps for p in c.inputs]
        self._signals = outs + ins
        self._n_out = len(outs)
        self._pos = {s: i for i, s in enumerate(self._signals)}
        self._start = np.array([p.start for c in comps for p in c.outputs] +
                               [p.start for c in comps for p in c.inputs], dtype=float)
        self._source = dict((dst, src) for src, dst in self.connections)
        # gather index: an input reads its source output, an unconnected one itself
        self._gather = np.array([self._pos[self._source.get(s, s)] for s in ins], dtype=np.intp)
        # unit conversions: positions among the inputs, scale and shift
        conv = [(k, *self.conversions[s][2:]) for k, s in enumerate(ins) if s in self.conversions]
        self._conv = (np.array([c[0] for c in conv], dtype=np.intp),
                      np.array([c[1] for c in conv]), np.array([c[2] for c in conv]))

    # -- run ---------------------------------------------------------------------------------
    def run(self, t_end: float, t0: float = 0.0, *, progress=None) -> CosimResult:
        """Simulate from ``t0`` to ``t_end``.

        Parameters
        ----------
        t_end : float, s
            ``t_end - t0`` must be a whole number of steps (to 1e-9 relative).
        t0 : float, s, optional
        progress : bool or None, optional
            Show a progress bar on stderr.  None: only for runs of more than
            200 000 steps (about two seconds and up).

        Returns
        -------
        CosimResult
            ``n_steps + 1`` points ``t0 + k * step``.

        Raises
        ------
        CosimError
            ``t_end < t0`` or not on the step grid.
        FMUError, SimulationError
            A component failed; the message names it and the time.
        """
        t0, t_end = float(t0), float(t_end)
        if not (np.isfinite(t0) and np.isfinite(t_end)) or t_end < t0:
            raise CosimError(f"need finite t0 <= t_end; found t0 = {t0!r} s, t_end = {t_end!r} s")
        ratio = (t_end - t0) / self.step
        n = int(round(ratio))
        if abs(ratio - n) > 1e-9 * max(1.0, ratio):
            raise CosimError(f"t_end - t0 = {t_end - t0!r} s is not a multiple of step "
                             f"{self.step!r} s; nearest: t_end = {t0 + n * self.step!r} or "
                             f"{t0 + (n + 1) * self.step!r} s")
        show = n > _PROGRESS_STEPS if progress is None else bool(progress)
        wall = _time.perf_counter()
        log = self._execute(t0, n, show)
        wall = _time.perf_counter() - wall
        comps = list(self.components.values())
        units = {f"{c.name}.{p.name}": p.unit for c in comps for p in c.outputs}
        units.update({f"{c.name}.{p.name}": p.unit for c in comps for p in c.inputs})
        kinds = {s: "output" if i < self._n_out else "input" for i, s in enumerate(self._signals)}
        info = {"step": self.step, "n_steps": n, "t0": t0, "t_end": t0 + n * self.step,
                "wall_time": wall, "order": self.order,
                "connections": tuple(f"{a} -> {b}" + (f" [{self.conversions[b][0]} -> "
                                                      f"{self.conversions[b][1]}]"
                                                      if b in self.conversions else "")
                                     for a, b in self.connections)}
        return CosimResult(t0 + np.arange(n + 1) * self.step,
                           {s: log[:, i] for i, s in enumerate(self._signals)},
                           units=units, kinds=kinds, info=info)

    def _execute(self, t0: float, n: int, show: bool) -> np.ndarray:
        comps = list(self.components.values())
        sig = self._start.copy()                          # outputs, then inputs
        n_out, sig_in, gather = self._n_out, sig[self._n_out:], self._gather
        log = np.empty((n + 1, sig.size))
        views, o, i = {}, 0, n_out
        for c in comps:
            views[c.name] = (sig[i:i + len(c.inputs)], sig[o:o + len(c.outputs)],
                             gather[i - n_out:i - n_out + len(c.inputs)])
            o, i = o + len(c.outputs), i + len(c.inputs)
        calls = []
        conv_pos, conv_a, conv_b = self._conv
        first = 0
        for c in comps:   # each component's converted inputs, as positions in its u
            sel = (conv_pos >= first) & (conv_pos < first + len(c.inputs))
            views[c.name] += ((conv_pos[sel] - first, conv_a[sel], conv_b[sel]),)
            first += len(c.inputs)
        for c in self._order:
            u, _, idx, cv = views[c.name]
            has_ft = bool(c.feedthrough) and any(self._source.get(f"{c.name}.{p.name}")
                                                  for p in c.inputs)
            calls.append((c.output, idx if has_ft else None, u, cv if cv[0].size else None))
        # a Python block without state has nothing to advance
        advances = [c.advance for c in comps if getattr(type(c), "advance", None)
                    is not PythonBlock.advance]
        take = sig.take   # bound method: no per-call dispatch (np.take costs 3x more)
        has_conv = bool(conv_pos.size)
        step, started, t = self.step, [], t0
        bar = Progress(max(n, 1), fmt="co-simulation [{bar:40}] {percentage:3.0f}%", enabled=show)
        try:
            for c in comps:
                u, y, _, _ = views[c.name]
                c.bind(u, y)
            for c in {c.name: c for c in self._order}.values():   # first pass, in order
                u, _, idx, cv = views[c.name]
                take(idx, out=u, mode="clip")   # u holds the inputs at t0
                if cv[0].size:
                    u[cv[0]] = cv[1] * u[cv[0]] + cv[2]
                started.append(c)                # stop() is safe after a failed start
                c.start(t0)
                c.output(t0)
            chunk = max(1, n // 100) if show else max(n, 1)
            for k0 in range(0, n + 1, chunk):
                for k in range(k0, min(k0 + chunk, n + 1)):
                    t = t0 + k * step
                    for out, idx, u, cv in calls:
                        if idx is not None:
                            take(idx, out=u, mode="clip")
                            if cv is not None:   # unit conversion of this block's inputs
                                u[cv[0]] = cv[1] * u[cv[0]] + cv[2]
                        out(t)
                    take(gather, out=sig_in, mode="clip")
                    if has_conv:
                        sig_in[conv_pos] = conv_a * sig_in[conv_pos] + conv_b
                    log[k] = sig
                    if k < n:   # the last point is only observed
                        for adv in advances:
                            adv(t, step)
                bar.update_to(min(k0 + chunk, n))
        except BondcosimError:
            raise
        except Exception as exc:
            raise SimulationError(f"{_culprit(exc, comps)} raised {type(exc).__name__} at "
                                  f"t = {t:.12g} s: {exc}", time=t) from exc
        finally:
            bar.close()
            _stop_all(started, sys.exc_info()[0] is not None)
        return log


def _culprit(exc: BaseException, comps) -> str:
    """'component NAME (in output)' from the traceback frame of the failing component method."""
    tb = exc.__traceback__
    while tb is not None:
        owner = tb.tb_frame.f_locals.get("self")
        if any(owner is c for c in comps):
            return f"component {owner.name!r} (in {tb.tb_frame.f_code.co_name})"
        tb = tb.tb_next
    return "a component"


def _stop_all(started, failing: bool) -> None:
    errors = []
    for c in reversed(started):
        try:
            c.stop()
        except Exception as exc:   # stop every component before reporting
            errors.append(exc)
    if errors and not failing:
        raise errors[0]


_OPTIONS = ("unit", "convert")


def _options(pair, j: int, problems: list) -> dict | None:
    """The override dict of connection `j` (empty for a pair); None (and a problem) if bad."""
    if len(pair) == 2:
        return {}
    options = pair[2]
    if not isinstance(options, dict):
        problems.append(f"connections[{j}]: the third element must be a dict of options "
                        f"({', '.join(_OPTIONS)}); found {options!r}")
        return None
    unknown = sorted(set(options) - set(_OPTIONS))
    if unknown:
        problems.append(f"connections[{j}]: unknown option(s) {', '.join(map(repr, unknown))}; "
                        f"expected {', '.join(_OPTIONS)}")
        return None
    if "unit" in options and not isinstance(options["unit"], str):
        problems.append(f"connections[{j}]: unit must be a str; found {options['unit']!r}")
        return None
    return options


def _conversion(src: str, unit_from: str, dst: str, unit_to: str, problems: list):
    """(unit_from, unit_to, scale, shift) of a connection needing one; None when the value
    passes unchanged; False (and a problem naming both ends) when the units do not match."""
    if not unit_from or not unit_to or unit_from == unit_to:
        return None
    hint = (f"; if {src!r} is really in {unit_to}, say so: ({src!r}, {dst!r}, "
            f"{{'unit': {unit_to!r}}}), or pass raw numbers with {{'convert': False}}")
    try:
        a, b = parse_unit(unit_from), parse_unit(unit_to)
    except UnitError as exc:
        problems.append(f"unit mismatch: {src!r} [{unit_from}] -> {dst!r} [{unit_to}] ({exc}){hint}")
        return False
    if a.dimension != b.dimension:
        problems.append(f"unit mismatch: {src!r} [{unit_from}] -> {dst!r} [{unit_to}]: "
                        f"dimensions {a.describe_dimension()} and {b.describe_dimension()}{hint}")
        return False
    if a.scale == b.scale and a.offset == b.offset:
        return None
    # v_dst = (s_a v + o_a - o_b) / s_b
    return (unit_from, unit_to, a.scale / b.scale, (a.offset - b.offset) / b.scale)


def _joined(problems: list[str]) -> str:
    if len(problems) == 1:
        return problems[0]
    return f"{len(problems)} problems:\n" + "\n".join(f"  - {p}" for p in problems)
