"""Results that lose nothing: one Parquet part file per finished chunk, consolidated at the end.

Layout of a sweep directory::

    DIR/sweep.json            the spec (to check --resume) and the number of runs
    DIR/parts/part-*.parquet  one file per finished chunk, written atomically (temporary
                              file, then rename): a killed sweep leaves only whole parts
    DIR/runs.parquet          every row, sorted by run_id (rewritten at the end of each sweep)

Why Parquet and not Zarr: a run is a row of mixed columns -- the parameters,
its seed, its status and error *text*, its metrics, optionally its output
time series as lists -- i.e. a table, which Parquet stores natively (typed,
compressed, read by pandas, pyarrow, polars, DuckDB, Spark).  Zarr (via xarray)
suits dense N-d arrays on a known grid; a Monte-Carlo with failed runs and
strings fits it poorly, and appending rows from many writers needs region
writes coordinated on one array.  With immutable part files appends need no
coordination at all: each finished chunk is its own file.
"""
from __future__ import annotations

import json
import os
import uuid
from pathlib import Path

from .errors import StoreError

__all__ = ["RunStore"]

_VERSION = 1


class RunStore:
    """The results directory of one sweep.

    Parameters
    ----------
    directory : path-like
    spec : dict
        The sweep's :meth:`SweepSpec.to_dict` (or another JSON-ready description).
    n_runs : int
    resume : bool
        Continue a sweep already in `directory`; it must have the same spec.

    Raises
    ------
    StoreError
        `directory` holds results and `resume` is false; or `resume` and its
        sweep differs (the message names the keys that differ).
    """

    def __init__(self, directory, spec: dict, n_runs: int, *, resume: bool = False):
        self.directory = Path(directory)
        self.parts = self.directory / "parts"
        meta_path = self.directory / "sweep.json"
        meta = {"version": _VERSION, "n_runs": int(n_runs), "spec": spec}
        if meta_path.exists() or (self.parts.exists() and any(self.parts.glob("*.parquet"))):
            if not resume:
                raise StoreError(self.directory, "holds results of a sweep already; pass --resume (resume=True) "
                                                 "to continue it, or choose another output directory")
            try:
                old = json.loads(meta_path.read_text())
            except (OSError, ValueError) as exc:
                raise StoreError(self.directory, f"sweep.json is unreadable ({exc}); not a sweep directory") from None
            new = json.loads(json.dumps(meta))
            if old != new:
                differ = sorted(k for k in set(old.get("spec", {})) | set(spec)
                                if old.get("spec", {}).get(k) != new["spec"].get(k))
                raise StoreError(self.directory, "--resume needs the same sweep; these keys differ: "
                                                 f"{', '.join(differ) or 'n_runs/version'}")
            if list(old.get("spec", {}).get("vary", {})) != list(new["spec"].get("vary", {})):
                # the order numbers the grid points and orders each run's draws: equal laws in another
                # order would give other values to the run ids still missing
                raise StoreError(self.directory, "--resume needs the same sweep; the varied parameters are in "
                                                 f"another order ({', '.join(old['spec']['vary'])} before, "
                                                 f"{', '.join(new['spec']['vary'])} now)")
        self.parts.mkdir(parents=True, exist_ok=True)
        _atomic_write(meta_path, json.dumps(meta, indent=1).encode())

    def done(self) -> set:
        """Run ids with a row (finished, ok or failed)."""
        import pyarrow.parquet as pq
        ids = set()
        for part in sorted(self.parts.glob("part-*.parquet")):
            ids.update(pq.read_table(part, columns=["run_id"]).column("run_id").to_pylist())
        return ids

    def write(self, rows: list) -> Path:
        """Write `rows` (dicts) as one part file, atomically; returns its path."""
        import pandas as pd
        frame = pd.DataFrame(rows)
        name = f"part-{int(frame['run_id'].min()):07d}-{uuid.uuid4().hex[:8]}.parquet"
        target = self.parts / name
        tmp = self.parts / f".{name}.tmp"
        frame.to_parquet(tmp, index=False)
        os.replace(tmp, target)
        return target

    def read(self):
        """Every row written, one per run id (the last written if a run was written twice), by run_id.

        Returns
        -------
        pandas.DataFrame
        """
        import pandas as pd
        frames = [pd.read_parquet(p) for p in sorted(self.parts.glob("part-*.parquet"))]
        frames = [f for f in frames if len(f)]
        if not frames:
            return pd.DataFrame(columns=["run_id", "status", "error", "seed", "started", "duration_s", "worker"])
        table = pd.concat(frames, ignore_index=True, sort=False)
        table = table.drop_duplicates("run_id", keep="last").sort_values("run_id").reset_index(drop=True)
        return table

    def consolidate(self) -> Path:
        """Write ``runs.parquet`` (every row by run_id), atomically; returns its path."""
        path = self.directory / "runs.parquet"
        tmp = self.directory / ".runs.parquet.tmp"
        self.read().to_parquet(tmp, index=False)
        os.replace(tmp, path)
        return path


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)
