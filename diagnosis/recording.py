"""Recordings (a time column and named signals) and their binding to a model.

:class:`Recording` holds a CSV's columns as they are (any sample rate, uneven
sampling allowed) and reports NaN gaps and constant columns by name and rows;
:func:`bind` picks the columns that drive the model's inputs and those that
measure its outputs, converts them to the model's units and returns an
:class:`Experiment`.  Nothing is dropped silently: a bound column with a gap,
a constant measured output, a non-numeric cell or a time that does not
increase is refused with the column and the rows.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, field

import numpy as np


from .errors import RecordingError, UnitError, UnknownColumnError, UnknownNameError
from .units import convert, parse_unit

__all__ = ["Recording", "Binding", "Experiment", "InputHistory", "bind", "TIME_NAMES"]

#: Column names taken as time when none is given (else the first column).
TIME_NAMES = ("t", "time", "t_s")


def _runs(rows: np.ndarray) -> list[tuple[int, int]]:
    """Consecutive runs ``(first, last)`` of sorted row indices."""
    if rows.size == 0:
        return []
    cuts = np.flatnonzero(np.diff(rows) > 1)
    starts = np.r_[rows[0], rows[cuts + 1]]
    ends = np.r_[rows[cuts], rows[-1]]
    return [(int(a), int(b)) for a, b in zip(starts, ends)]


def _rows_text(runs) -> str:
    parts = [f"{a}" if a == b else f"{a}-{b}" for a, b in runs[:5]]
    return ", ".join(parts) + (", ..." if len(runs) > 5 else "")


class Recording:
    """Recorded signals against time, as read (no unit conversion).

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times, s (strictly increasing, finite).
    columns : dict str -> array_like, shape (n,)
        Signals by column name; NaN marks a gap.
    source : str
        Where the data came from (file path or ``"arrays"``).

    Attributes
    ----------
    gaps : dict str -> list of (int, int)
        NaN runs per column, as 0-based data rows ``(first, last)``.
    constant : list of str
        Columns whose finite values are all equal.

    Raises
    ------
    RecordingError
        Non-increasing or non-finite time, or a column of the wrong length.
    """

    def __init__(self, t, columns: dict, source: str = "arrays", *, time_name: str = "t"):
        self.source = str(source)
        self.time_name = time_name
        self.t = np.asarray(t, dtype=float).reshape(-1)
        if self.t.size < 2:
            raise RecordingError(f"{self.source}: need at least 2 samples; found {self.t.size}",
                                 source=self.source, column=time_name)
        bad = np.flatnonzero(~np.isfinite(self.t))
        if bad.size:
            raise RecordingError(f"{self.source}: time column {time_name!r} has non-finite values "
                                 f"at rows {_rows_text(_runs(bad))}", source=self.source,
                                 column=time_name, rows=bad)
        back = np.flatnonzero(np.diff(self.t) <= 0) + 1
        if back.size:
            k = int(back[0])
            raise RecordingError(
                f"{self.source}: time column {time_name!r} does not increase at row(s) "
                f"{_rows_text(_runs(back))} (row {k}: {self.t[k]!r} s after {self.t[k - 1]!r} s); "
                "sort the recording or remove repeated samples", source=self.source,
                column=time_name, rows=back)
        self.columns: dict[str, np.ndarray] = {}
        for name, values in columns.items():
            v = np.asarray(values, dtype=float).reshape(-1)
            if v.shape != self.t.shape:
                raise RecordingError(f"{self.source}: column {name!r} has {v.size} values for "
                                     f"{self.t.size} times", source=self.source, column=name)
            self.columns[str(name)] = v
        self.gaps = {n: _runs(np.flatnonzero(np.isnan(v))) for n, v in self.columns.items()}
        self.gaps = {n: r for n, r in self.gaps.items() if r}
        self.constant = [n for n, v in self.columns.items()
                         if np.isfinite(v).any() and np.nanmax(v) == np.nanmin(v)]

    @classmethod
    def from_arrays(cls, t, columns: dict, source: str = "arrays") -> "Recording":
        """A recording from arrays (see the class parameters)."""
        return cls(t, columns, source)

    @classmethod
    def from_csv(cls, path, *, time: str | None = None) -> "Recording":
        """Read a CSV file with a header row.

        Parameters
        ----------
        path : str or path-like
            The file.  Empty cells and ``nan`` are gaps.
        time : str, optional
            Time column, optionally ``"COLUMN:UNIT"`` (e.g. ``"t_ms:ms"``);
            default the first of ``t``, ``time``, ``t_s`` present, else the
            first column.

        Returns
        -------
        Recording

        Raises
        ------
        RecordingError
            Missing, empty or duplicate column names, a missing time column,
            a ragged row, a non-numeric cell (column and row named),
            non-increasing time.
        """
        source = str(path)
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        rows = [r for r in rows if any(c.strip() for c in r)]
        if len(rows) < 2:
            raise RecordingError(f"{source}: need a header row and data rows; found {len(rows)} "
                                 "non-empty line(s)", source=source)
        header = [h.strip() for h in rows[0]]
        empty = [i + 1 for i, h in enumerate(header) if not h]
        if empty:
            raise RecordingError(f"{source}: header has empty column name(s) at position(s) "
                                 f"{', '.join(map(str, empty))}", source=source)
        dup = sorted({h for h in header if header.count(h) > 1})
        if dup:
            raise RecordingError(f"{source}: duplicate column name(s) {', '.join(map(repr, dup))}",
                                 source=source, column=dup[0])
        data = np.full((len(rows) - 1, len(header)), np.nan)
        for i, row in enumerate(rows[1:]):
            if len(row) != len(header):
                raise RecordingError(f"{source}: data row {i} has {len(row)} cells, the header "
                                     f"{len(header)}", source=source, rows=[i])
            for j, cell in enumerate(row):
                cell = cell.strip()
                if cell:
                    try:
                        data[i, j] = float(cell)
                    except ValueError:
                        raise RecordingError(f"{source}: column {header[j]!r}, data row {i}: "
                                             f"{cell!r} is not a number", source=source,
                                             column=header[j], rows=[i]) from None
        time_name, time_unit = _time_column(header, time, source)
        k = header.index(time_name)
        t = data[:, k] if time_unit is None else convert(data[:, k], time_unit, "s")
        columns = {h: data[:, j] for j, h in enumerate(header) if j != k}
        return cls(t, columns, source, time_name=time_name)

    def column(self, name: str) -> np.ndarray:
        """The values of column `name` (raises :class:`UnknownColumnError` listing the columns)."""
        if name not in self.columns:
            raise UnknownColumnError(name, self.columns, self.source)
        return self.columns[name]

    def notes(self) -> list[str]:
        """Plain-language notes on gaps and constant columns (empty when clean)."""
        out = [f"column {n!r} has NaN gaps at rows {_rows_text(r)}" for n, r in self.gaps.items()]
        out += [f"column {n!r} is constant" for n in self.constant]
        return out


def _time_column(header, time, source):
    if time is None:
        name = next((h for h in TIME_NAMES if h in header), header[0])
        return name, None
    name, _, unit = time.partition(":")
    name = name.strip()
    if name not in header:
        raise UnknownColumnError(name, header, source, "time")
    if unit.strip():
        parse_unit(unit.strip())
        return name, unit.strip()
    return name, None


@dataclass(frozen=True)
class Binding:
    """A model input or output bound to a recording column.

    Parameters
    ----------
    name : str
        Model input or output name.
    column : str
        Recording column.
    unit : str, optional
        The column's unit; converted to the model's unit.  None: already in it.
    """

    name: str
    column: str
    unit: str | None = None

    @classmethod
    def parse(cls, text: str) -> "Binding":
        """Parse ``"NAME=COLUMN[:UNIT]"`` (e.g. ``"psi=angle:rad"``).

        Raises
        ------
        RecordingError
            If the text is not of that form.
        """
        name, sep, rest = str(text).partition("=")
        column, _, unit = rest.partition(":")
        if not sep or not name.strip() or not column.strip():
            raise RecordingError(f"binding {text!r} is not NAME=COLUMN[:UNIT]", column=str(text))
        return cls(name.strip(), column.strip(), unit.strip() or None)


@dataclass(frozen=True)
class InputHistory:
    """The inputs recorded before a part of an experiment: what a delayed input reads there
    (:mod:`bondgraph.numerics.input_delays`) while its delay reaches back before the part.

    Parameters
    ----------
    t : ndarray, shape (m,)
        Sample times, s, all before the part's first.
    inputs : dict str -> ndarray, shape (m,)
        The experiment's inputs at those times.
    """

    t: np.ndarray
    inputs: dict

    def then(self, t, inputs) -> "InputHistory":
        """This history followed by the samples (`t`, `inputs`)."""
        return InputHistory(np.concatenate([self.t, t]), {k: np.concatenate([self.inputs[k], inputs[k]])
                                                          for k in inputs})


@dataclass
class Experiment:
    """Recorded inputs and outputs in the model's units, on one time grid.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times, s (absolute: a split keeps them).
    inputs, outputs : dict str -> ndarray, shape (n,)
        By model input / output name, in the model's units.
    units : dict str -> str
        The model's unit of each input and output.
    source : str
        The recording's source.
    substeps : int
        Fewest RK4 sub-steps per sample interval a simulation on this recording takes
        (:func:`diagnosis.residuals.settle_substeps` raises it where the model's own step rule
        leaves an integration error above the noise); parts of the experiment keep it.
    history : InputHistory, optional
        The inputs recorded before `t[0]`, where this is a part of a longer record (its parts,
        :meth:`samples`, :meth:`window` and :meth:`split`, keep what came before them): a delayed
        input reads them.  None at a record's start.
    """

    t: np.ndarray
    inputs: dict
    outputs: dict
    units: dict = field(default_factory=dict)
    source: str = "arrays"
    substeps: int = 1
    history: InputHistory | None = None

    @property
    def span(self) -> tuple[float, float]:
        """``(t0, t1)``, s."""
        return float(self.t[0]), float(self.t[-1])

    def _select(self, mask) -> "Experiment":
        if mask.sum() < 2:
            raise RecordingError(f"{self.source}: a part of the experiment with fewer than 2 "
                                 "samples", source=self.source)
        where = np.flatnonzero(mask)
        if where[-1] - where[0] + 1 == where.size:          # one run of samples: it has a history
            return self.samples(int(where[0]), int(where[-1]) + 1)
        return Experiment(self.t[mask], {k: v[mask] for k, v in self.inputs.items()},
                          {k: v[mask] for k, v in self.outputs.items()}, dict(self.units),
                          self.source, self.substeps)

    def samples(self, a: int, b: int) -> "Experiment":
        """The samples ``a`` to ``b - 1`` (indices, as a Python slice), with the inputs before them
        as their :attr:`history`."""
        a = slice(a, b).indices(self.t.size)[0]
        return Experiment(self.t[a:b], {k: v[a:b] for k, v in self.inputs.items()},
                          {k: v[a:b] for k, v in self.outputs.items()}, dict(self.units), self.source,
                          self.substeps, self.history_until(a))

    def history_until(self, a: int) -> InputHistory | None:
        """The inputs recorded before sample `a` (this experiment's history, then its first `a`
        samples); None when there are none."""
        if a <= 0:
            return self.history
        first = {k: v[:a] for k, v in self.inputs.items()}
        return InputHistory(self.t[:a], first) if self.history is None else self.history.then(self.t[:a], first)

    def window(self, t0: float, t1: float) -> "Experiment":
        """The samples with ``t0 <= t <= t1`` (times in s)."""
        return self._select((self.t >= t0) & (self.t <= t1))

    def split(self, holdout: float) -> tuple["Experiment", "Experiment"]:
        """``(train, held_out)``: the last `holdout` fraction of the time span held out.

        Raises
        ------
        RecordingError
            If `holdout` is not in (0, 1).
        """
        if not (0.0 < float(holdout) < 1.0):
            raise RecordingError(f"holdout must be a fraction in (0, 1); found {holdout!r}",
                                 source=self.source)
        t0, t1 = self.span
        cut = t1 - float(holdout) * (t1 - t0)
        return self._select(self.t < cut), self._select(self.t >= cut)


def _bindings(spec, what):
    if spec is None:
        return []
    if isinstance(spec, dict):
        return [Binding.parse(f"{k}={v}") for k, v in spec.items()]
    if isinstance(spec, (str, Binding)):
        spec = [spec]
    return [b if isinstance(b, Binding) else Binding.parse(b) for b in spec]


def _values(recording, b, model_unit, kind, model_name):
    if b.column not in recording.columns:
        raise UnknownColumnError(b.column, recording.columns, recording.source,
                                 f"model {kind} {b.name!r}")
    v = recording.columns[b.column]
    if b.column in recording.gaps:
        raise RecordingError(
            f"{recording.source}: column {b.column!r} (model {kind} {b.name!r}) has NaN gaps at "
            f"data rows {_rows_text(recording.gaps[b.column])}; fill or cut them (nothing is "
            "dropped silently)", source=recording.source, column=b.column,
            rows=[r for a, z in recording.gaps[b.column] for r in range(a, z + 1)])
    if b.unit is None:
        return v.copy()
    try:
        return convert(v, b.unit, model_unit or "1")
    except UnitError as exc:
        raise UnitError(f"column {b.column!r} for model {kind} {b.name!r} of {model_name!r} (unit "
                        f"{model_unit or '1'!r}): {exc}", b.unit, model_unit) from None


def bind(recording: Recording, model, inputs, outputs) -> Experiment:
    """Bind recording columns to a model's inputs and outputs.

    Parameters
    ----------
    recording : Recording
    model : BondGraph or StateEquations
    inputs, outputs : iterable of Binding or str, or dict str -> str
        ``"NAME=COLUMN[:UNIT]"`` strings, :class:`Binding` objects, or a dict
        ``NAME -> "COLUMN[:UNIT]"``.  Model inputs not bound keep their defaults.

    Returns
    -------
    Experiment
        Arrays in the model's units.

    Raises
    ------
    UnknownNameError
        A model input/output name the model does not have, or a column the
        recording does not have (lists the known ones).
    RecordingError
        A bound column with NaN gaps,
        a constant measured output (its NRMSE would be undefined), no output.
    UnitError
        A unit that does not convert to the model's unit.
    """
    from bondgraph.system import StateEquations

    eqs = model if isinstance(model, StateEquations) else model.equations()
    out_b, in_b = _bindings(outputs, "outputs"), _bindings(inputs, "inputs")
    if not out_b:
        raise RecordingError(f"{recording.source}: bind at least one model output to a column; "
                             f"model outputs are {', '.join(eqs.outputs)}", source=recording.source)
    result = {}
    for kind, bindings, known in (("input", in_b, eqs.input_names), ("output", out_b, eqs.outputs)):
        result[kind] = {}
        for b in bindings:
            if b.name not in known:
                raise UnknownNameError(kind, b.name, known, eqs.name)
            unit = eqs.units.get(b.name, "")
            result[kind][b.name] = _values(recording, b, unit, kind, eqs.name)
            if kind == "output" and b.column in recording.constant:
                raise RecordingError(
                    f"{recording.source}: column {b.column!r} bound to output {b.name!r} is "
                    "constant; a measured output must vary (its NRMSE divides by its spread)",
                    source=recording.source, column=b.column)
    units = {n: eqs.units.get(n, "") for n in [*result["input"], *result["output"]]}
    return Experiment(recording.t.copy(), result["input"], result["output"], units,
                      recording.source)
