"""Test-session set-up shared by tests/ and the packages' doctests.

Single-threaded BLAS/OpenMP: the suite's many small matrix operations only
fight over the cores when numpy's maths runs threads (measured: one diagnosis
test file took 2 min wall-clock multi-threaded on a loaded 2-core machine, 12 s
single-threaded).  Set before numpy is first imported; an explicit setting in
the environment wins.
"""
import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
