"""Simulation results: named time signals with units, CSV and plots.

CSV format
----------
One header row, then one row per time point, comma-separated::

    time [s],q [m],p [N s],y
    0,0.01,0,0.02
    0.001,0.0099995,-0.0049,0.019999

The first column is time in seconds; every other header cell is
``name [unit]``, or just ``name`` for a signal without unit.  Values are
written with 17 significant digits, so :meth:`SimulationResult.from_csv`
reads back exactly the numbers, names and units that
:meth:`SimulationResult.to_csv` wrote (the signal *kinds* are not stored; they
read back as ``"signal"``).  A single header row keeps the file readable by
spreadsheets and ``pandas.read_csv`` alike.
"""
from __future__ import annotations

import csv
import re
from types import MappingProxyType
from typing import Mapping

import numpy as np

from ..errors import ArgumentError, UnknownSignalError

__all__ = ["SimulationResult", "KINDS"]

#: Signal kinds a result may hold, in the order they are listed.
KINDS = ("state", "algebraic", "held", "input", "output", "signal")

_HEADER = re.compile(r"^(?P<name>.*?)\s*\[(?P<unit>[^\[\]]*)\]$")


class SimulationResult:
    """Time signals of one simulation, indexed by name (immutable).

    Parameters
    ----------
    t : array_like, shape (n_times,)
        Time points, s, non-decreasing.
    signals : mapping str -> array_like, shape (n_times,)
        Signal values in SI units, in the order to list them.
    units : mapping str -> str, optional
        Unit of each signal (missing: ``""``).
    kinds : mapping str -> str, optional
        One of :data:`KINDS` per signal (missing: ``"signal"``).
    info : mapping, optional
        How the result was made (solver, step, evaluation counts...).

    Attributes
    ----------
    t : ndarray, shape (n_times,)
        Time, s (read-only).
    names : tuple of str
        Signal names in order.
    units, kinds : mapping str -> str
    info : mapping

    Examples
    --------
    >>> r = SimulationResult([0.0, 1.0], {"q": [0.0, 0.5]}, units={"q": "m"})
    >>> r["q"]
    array([0. , 0.5])
    >>> r.units["q"]
    'm'
    """

    __slots__ = ("_t", "_data", "_units", "_kinds", "info")

    def __init__(self, t, signals: Mapping, *, units: Mapping | None = None,
                 kinds: Mapping | None = None, info: Mapping | None = None):
        t = np.array(t, dtype=float).reshape(-1)
        if t.size > 1 and np.any(np.diff(t) < 0):
            raise ArgumentError("t: time points must be non-decreasing")
        t.flags.writeable = False
        data = {}
        for name, values in signals.items():
            if not isinstance(name, str) or not name:
                raise ArgumentError(f"signal names must be non-empty strings; found {name!r}")
            a = np.array(values, dtype=float).reshape(-1)
            if a.shape != t.shape:
                raise ArgumentError(f"signal {name!r}: expected shape {t.shape} (one value per time "
                                 f"point); found {np.shape(values)}")
            a.flags.writeable = False
            data[name] = a
        units, kinds = dict(units or {}), dict(kinds or {})
        for label, mapping in (("units", units), ("kinds", kinds)):
            extra = sorted(set(mapping) - set(data))
            if extra:
                raise ArgumentError(f"{label} given for unknown signal(s) {', '.join(extra)}; "
                                 f"signals are {', '.join(data)}")
        bad = sorted(k for k, v in kinds.items() if v not in KINDS)
        if bad:
            raise ArgumentError(f"kind of {', '.join(bad)} must be one of {', '.join(KINDS)}")
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_data", data)
        object.__setattr__(self, "_units", MappingProxyType({k: str(units.get(k, "")) for k in data}))
        object.__setattr__(self, "_kinds", MappingProxyType({k: kinds.get(k, "signal") for k in data}))
        object.__setattr__(self, "info", MappingProxyType(dict(info or {})))

    def __setattr__(self, name, value):
        raise AttributeError(f"SimulationResult is immutable (cannot set {name!r})")

    # -- access ------------------------------------------------------------------
    @property
    def t(self) -> np.ndarray:
        return self._t

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self._data)

    @property
    def units(self) -> Mapping[str, str]:
        return self._units

    @property
    def kinds(self) -> Mapping[str, str]:
        return self._kinds

    def names_of(self, kind: str) -> tuple[str, ...]:
        """Names of the signals of one kind (``"state"``, ``"output"``...)."""
        if kind not in KINDS:
            raise ArgumentError(f"kind must be one of {', '.join(KINDS)}; found {kind!r}")
        return tuple(n for n, k in self._kinds.items() if k == kind)

    def __getitem__(self, name: str) -> np.ndarray:
        """Values of signal `name`, shape (n_times,), read-only."""
        try:
            return self._data[name]
        except (KeyError, TypeError):
            raise UnknownSignalError(name, list(self._data),
                                     f"no signal {name!r}; signals are {', '.join(self._data) or '(none)'}"
                                     " (time is .t)") from None

    def __contains__(self, name) -> bool:
        return name in self._data

    def __iter__(self):
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    def __repr__(self) -> str:
        span = f"{self._t[0]:g}..{self._t[-1]:g} s" if self._t.size else "empty"
        return f"<SimulationResult {self._t.size} points, {span}: {', '.join(self._data)}>"

    # -- CSV ---------------------------------------------------------------------
    def to_csv(self, path) -> None:
        """Write the result as CSV (format in the module docstring).

        Parameters
        ----------
        path : str or os.PathLike
        """
        header = ["time [s]"] + [f"{n} [{self._units[n]}]" if self._units[n] else n
                                 for n in self._data]
        table = np.column_stack([self._t, *self._data.values()]) if self._t.size else np.empty((0, 1))
        with open(path, "w", newline="") as fh:
            csv.writer(fh).writerow(header)
            np.savetxt(fh, table, fmt="%.17g", delimiter=",")

    @classmethod
    def from_csv(cls, path) -> "SimulationResult":
        """Read a CSV written by :meth:`to_csv` (or any file in that format).

        Parameters
        ----------
        path : str or os.PathLike

        Returns
        -------
        SimulationResult
            Kinds are ``"signal"``.

        Raises
        ------
        ValueError
            If the first column is not time (``time [s]`` or ``time``), a
            name repeats, or a row has the wrong number of values.
        """
        with open(path, newline="") as fh:
            header = next(csv.reader(fh), None)
            if not header:
                raise ArgumentError(f"{path}: empty file, expected a header row 'time [s],name [unit],...'")
            names, units = [], {}
            for cell in header:
                m = _HEADER.match(cell.strip())
                name, unit = (m["name"], m["unit"]) if m else (cell.strip(), "")
                names.append(name)
                units[name] = unit
            if names[0] != "time" or units[names[0]] not in ("s", ""):
                raise ArgumentError(f"{path}: first column must be 'time [s]'; found {header[0]!r}")
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise ArgumentError(f"{path}: repeated column name(s) {', '.join(dup)}")
            try:
                table = np.loadtxt(fh, delimiter=",", ndmin=2)
            except ValueError as exc:
                raise ArgumentError(f"{path}: cannot read the values: {exc}") from None
        if table.size == 0:
            table = np.empty((0, len(names)))
        if table.shape[1] != len(names):
            raise ArgumentError(f"{path}: header has {len(names)} columns but rows have {table.shape[1]}")
        signals = {n: table[:, i + 1] for i, n in enumerate(names[1:])}
        return cls(table[:, 0], signals, units={n: units[n] for n in names[1:]})

    # -- plot --------------------------------------------------------------------
    def to_pandas(self):
        """A ``pandas.DataFrame`` (index ``t``, s) with units in ``attrs`` (see :func:`bondgraph.numerics.results_export.to_pandas`)."""
        from .results_export import to_pandas
        return to_pandas(self)

    def to_xarray(self):
        """An ``xarray.Dataset`` with a ``units`` attribute per variable (see :func:`bondgraph.numerics.results_export.to_xarray`)."""
        from .results_export import to_xarray
        return to_xarray(self)

    def plot(self, names=None, *, ax=None):
        """Plot signals against time, one subplot per unit.

        Parameters
        ----------
        names : sequence of str, optional
            Signals to plot; default all.
        ax : matplotlib Axes or sequence of Axes, optional
            One Axes: every signal goes on it.  A sequence: one Axes per unit
            group (in order of first appearance).  Default: a new figure.

        Returns
        -------
        matplotlib.figure.Figure
            Lines are labelled ``name [unit]`` (``[-]`` without unit); the
            time axis is ``t [s]``.
        """
        import matplotlib.pyplot as plt   # imported here: keeps `import bondgraph` fast

        names = list(self._data) if names is None else [names] if isinstance(names, str) else list(names)
        for n in names:
            self[n]   # KeyError naming the unknown signal
        groups: dict[str, list[str]] = {}
        for n in names:
            groups.setdefault(self._units[n], []).append(n)
        if ax is None:
            fig, axes = plt.subplots(max(1, len(groups)), 1, sharex=True, squeeze=False,
                                     figsize=(7, 1.5 + 2.0 * max(1, len(groups))))
            axes = list(axes[:, 0])
        elif hasattr(ax, "plot"):
            axes, fig = [ax] * max(1, len(groups)), ax.figure
        else:
            axes = list(ax)
            if len(axes) != len(groups):
                raise ArgumentError(f"ax: expected {len(groups)} Axes (one per unit: "
                                 f"{', '.join(u or '-' for u in groups)}); found {len(axes)}")
            fig = axes[0].figure
        for a, (unit, members) in zip(axes, groups.items()):
            for n in members:
                a.plot(self._t, self._data[n], label=f"{n} [{unit or '-'}]")
            a.set_ylabel(f"[{unit or '-'}]")
            a.legend(loc="best", fontsize="small")
            a.grid(True, alpha=0.3)
        axes[-1].set_xlabel("t [s]")
        return fig
