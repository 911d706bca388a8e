"""A :class:`~bondgraph.numerics.results.SimulationResult` as a pandas DataFrame or an xarray Dataset.

Both carry the units as metadata (the project's rule: SI inside, each signal
with its ``unit``).  pandas and xarray are optional: each function imports its
library when called and says how to install it when it is missing.
"""
from __future__ import annotations

import importlib

from ..errors import OptionalDependencyError

__all__ = ["to_pandas", "to_xarray"]


def _require(package: str, what: str):
    try:
        return importlib.import_module(package)
    except ImportError:
        raise OptionalDependencyError(
            f"{what} needs {package}, which is not installed: pip install {package} "
            "(or install bondcosim with its 'data' extra)", package=package) from None


def _plain(info) -> dict:
    """`info` with values that are not numbers or strings written as text (attrs stay portable)."""
    return {str(k): v if isinstance(v, (int, float, str, bool)) else str(v) for k, v in dict(info).items()}


def to_pandas(result):
    """The result as a ``pandas.DataFrame``: index ``t`` (s), one column per signal.

    ``df.attrs["units"]`` maps each column (and ``"t"``) to its unit,
    ``df.attrs["kinds"]`` to its kind (state, input, output...), and
    ``df.attrs["info"]`` holds how the result was made.

    Raises
    ------
    OptionalDependencyError
        pandas is not installed.
    """
    pd = _require("pandas", "SimulationResult.to_pandas()")
    frame = pd.DataFrame({name: result[name] for name in result.names},
                         index=pd.Index(result.t, name="t"))
    frame.attrs["units"] = {"t": "s", **dict(result.units)}
    frame.attrs["kinds"] = dict(result.kinds)
    frame.attrs["info"] = _plain(result.info)
    return frame


def to_xarray(result):
    """The result as an ``xarray.Dataset`` over the coordinate ``t`` (s).

    Each data variable has ``attrs["units"]`` (its unit, "" when
    dimensionless) and ``attrs["kind"]``; the dataset's attrs hold ``info``.

    Raises
    ------
    OptionalDependencyError
        xarray is not installed.
    """
    xr = _require("xarray", "SimulationResult.to_xarray()")
    data = {name: ("t", result[name], {"units": result.units.get(name, ""), "kind": result.kinds.get(name, "")})
            for name in result.names}
    return xr.Dataset(data, coords={"t": ("t", result.t, {"units": "s", "long_name": "time"})},
                      attrs=_plain(result.info))
