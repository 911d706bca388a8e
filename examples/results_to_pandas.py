"""Simulation results in the data ecosystem: pandas and xarray, with units as metadata.

Run:  python examples/results_to_pandas.py [output_dir]     (needs pandas and xarray)
"""
import sys
from pathlib import Path

from plants import library
from bondgraph.numerics import simulate


def main(output_dir="."):
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    result = simulate(library.build("dc-motor"), (0.0, 0.5), output_interval=1e-3, progress=True)
    frame = result.to_pandas()                     # index t (s); frame.attrs["units"]
    print(frame.describe().T[["mean", "max"]])
    print("units:", frame.attrs["units"])
    data = result.to_xarray()                      # data.w_m.attrs["units"] == "rad/s"
    print(data)
    frame.to_csv(out / "dc_motor_pandas.csv")
    return {"frame": frame, "dataset": data}


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
