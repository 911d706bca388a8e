"""The UKF step as one compiled C call: the fast engine of a model-based filter.

:class:`CEngine` generates (:func:`estimators.ukf_c_source.ukf_source`),
compiles and caches (:func:`bondgraph.numerics.c_build.compile_source`) and loads the
step kernel of one model and filter configuration (or loads the library
shipped in under :func:`kernel_key`, :mod:`bondgraph.numerics.c_shipped`, generating
and compiling nothing), owns its workspace (one
``double`` array whose numpy views are the filter's state), and calls
``bc_ukf_predict`` / ``bc_ukf_update`` / ``bc_ukf_run`` through ctypes with
pointers computed once.  It has the attributes and methods of the numpy
reference engine of :mod:`estimators.ukf`; failures come back as status codes
and are raised as :class:`~bondgraph.errors.EstimatorError` naming the step,
the time and the matrix.
"""
from __future__ import annotations

import ctypes
import functools
import hashlib
import weakref
from pathlib import Path

import numpy as np

from bondgraph.numerics import c_shipped
from bondgraph.numerics.c_build import c_available, compile_source, equations_key
from bondgraph.numerics.codegen_c import generate_source
from estimators.errors import EstimatorError

from . import ukf_c_source
from .ukf_c_source import STATUS, layout, ukf_source

__all__ = ["CEngine", "c_engine_available", "kernel_key"]

# generate_source per equations object (sympy cse is the slow part; equations are immutable)
_MODEL_SOURCE: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def c_engine_available(model) -> str | None:
    """None when the C engine can run `model`, else the reason it cannot."""
    if not c_available():
        return "no C compiler found ($CC, cc, gcc, clang) and no compiled library shipped in"
    if model.algebraic_names:
        return (f"model {model.equations.name!r} has algebraic unknowns "
                f"({', '.join(model.algebraic_names)}), which the C kernel does not solve")
    return None


def _model_source(eqs) -> str:
    src = _MODEL_SOURCE.get(eqs)
    if src is None:
        src = _MODEL_SOURCE[eqs] = generate_source(eqs, part="main")
    return src


@functools.cache
def _template_hash() -> str:
    return hashlib.sha256(Path(ukf_c_source.__file__).read_bytes()).hexdigest()


def kernel_key(eqs, dims: dict, output_index, redraw: bool, has_map: bool) -> str:
    """Compiler-independent lookup key of one UKF kernel (:mod:`bondgraph.numerics.c_shipped`).

    Everything the source depends on, without generating it: the model's
    :func:`~bondgraph.numerics.c_build.equations_key`, the template module's text, the
    sizes and options.
    """
    text = "\0".join([equations_key(eqs, "main"), _template_hash(), repr(sorted(dims.items())),
                      repr(tuple(int(i) for i in output_index)), repr(bool(redraw)), repr(bool(has_map))])
    return "ukf:" + hashlib.sha256(text.encode()).hexdigest()[:40]


def _library(eqs, dims, output_index, redraw, has_map):
    """The UKF kernel's library: shipped in under :func:`kernel_key`, else generated and compiled."""
    key = kernel_key(eqs, dims, output_index, redraw, has_map)
    path = c_shipped.lookup(key)
    if path is None:
        path = compile_source(ukf_source(_model_source(eqs), **dims, output_index=output_index,
                                         redraw=bool(redraw), has_map=has_map))
    c_shipped.note(key, path)
    return ctypes.CDLL(str(path))


class CEngine:
    """Compiled UKF engine of a model-based filter (see the module docstring).

    Parameters
    ----------
    functions : ModelFunctions
        Model, sample time, sub-steps, measured outputs, state map, parameters.
    points : SigmaPoints
    redraw : bool
    x0, P0, Q, R : ndarray
        Validated initial state and covariances (filter coordinates).
    t0 : float, s
    d0 : ndarray, shape (n_held,)

    Raises
    ------
    EstimatorError
        The model has algebraic unknowns, or there is no compiler (``name == "kernel"``).
    CompilationError
        The compiler failed.
    """

    kind = "c"

    def __init__(self, functions, points, redraw, x0, P0, Q, R, t0, d0):
        model = functions.model
        why = c_engine_available(model)
        if why:
            raise EstimatorError(f"UKF kernel 'c' unavailable: {why}; use kernel='numpy'", "kernel")
        eqs = model.equations
        nf, ny = x0.size, len(functions.output_index)
        dims = dict(nf=nf, nm=len(model.state_names), nu=len(model.input_names),
                    nd=len(model.held_names), npar=len(model.param_names),
                    nym_model=len(model.output_names))
        self._lib = _library(eqs, dims, functions.output_index, redraw, functions.state_map is not None)
        vp, ci = ctypes.c_void_p, ctypes.c_int
        for name in ("bc_ukf_predict", "bc_ukf_update", "bc_ukf_step"):
            getattr(self._lib, name).argtypes = [vp, vp]
            getattr(self._lib, name).restype = ci
        self._lib.bc_ukf_run.argtypes = [vp, ci, vp, vp, vp, vp, vp]
        self._lib.bc_ukf_run.restype = ci
        table = layout(dims["nf"], dims["nm"], ny, dims["nu"], dims["nd"], dims["npar"], dims["nym_model"])
        self._ws = np.zeros(table[-1][1] + table[-1][2])
        shapes = {"P": (nf, nf), "Q": (nf, nf), "R": (ny, ny), "P_prior": (nf, nf), "S": (ny, ny),
                  "K": (nf, ny), "T": (dims["nm"], nf), "Ti": (nf, dims["nm"]),
                  "sig": (2 * nf + 1, nf), "Xp": (2 * nf + 1, nf), "Y": (2 * nf + 1, ny)}
        self._v = {name: self._ws[off:off + size].reshape(shapes.get(name, (size,)))
                   for name, off, size in table}
        v = self._v
        v["x"][:], v["P"][:], v["Q"][:], v["R"][:] = x0, P0, Q, R
        v["Wm"][:], v["Wc"][:], v["sqrtc"][0] = points.Wm, points.Wc, np.sqrt(points.scale)
        if functions.state_map is not None:
            v["T"][:], v["Ti"][:] = functions.state_map.matrix, functions.state_map.inverse
        v["p"][:] = functions.p[0]
        v["d"][:] = d0
        v["t"][0], v["h"][0], v["m"][0], v["dt"][0] = t0, functions.h, functions.substeps, functions.dt
        self._info = np.zeros(4, dtype=np.intc)
        self._ws_p = ctypes.c_void_p(self._ws.ctypes.data)
        self._info_p = ctypes.c_void_p(self._info.ctypes.data)
        self._predict_fn, self._update_fn = self._lib.bc_ukf_predict, self._lib.bc_ukf_update
        self._step_fn = self._lib.bc_ukf_step
        self._u, self._y = v["u"], v["y"]
        self._u_prev = np.array(self._u)
        self.k = 0
        self.dt = functions.dt
        v["u"][:] = model.default_inputs

    # -- state (views into the workspace) ----------------------------------------------
    x = property(lambda self: self._v["x"])
    P = property(lambda self: self._v["P"])
    x_prior = property(lambda self: self._v["x_prior"])
    P_prior = property(lambda self: self._v["P_prior"])
    K = property(lambda self: self._v["K"])
    S = property(lambda self: self._v["S"])
    y_pred = property(lambda self: self._v["yhat"])
    innovation = property(lambda self: self._v["innov"])
    d = property(lambda self: self._v["d"])
    sigmas_f = property(lambda self: self._v["Xp"])
    t = property(lambda self: float(self._v["t"][0]))

    def set_state(self, x=None, P=None):
        if x is not None:
            self._v["x"][:] = x
        if P is not None:
            self._v["P"][:] = P

    def _raise(self, status, what):
        name, msg = STATUS.get(status, ("kernel", f"unknown status {status}"))
        msg = msg.format(row=int(self._info[1]))
        raise EstimatorError(f"UKF {what} at step {self.k} (t = {self.t:.9g} s): {msg}", name,
                             step=self.k, time=self.t)

    # -- steps (u None: keep the input in the workspace, the last one given) --------------
    def predict(self, u):
        if u is not None:
            self._u[:] = u
        status = self._predict_fn(self._ws_p, self._info_p)
        if status:
            self._raise(status, "predict")
        self.k += 1

    def update(self, z, u):
        self._y[:] = z
        if u is not None:   # for this update only; the last predict's input stays
            self._u_prev[:] = self._u
            self._u[:] = u
        status = self._update_fn(self._ws_p, self._info_p)
        if u is not None:
            self._u[:] = self._u_prev
        if status:
            self._raise(status, "update")

    def step(self, u, z) -> int:
        """Predict and update in one call, without raising for bad `u`, `z`: returns
        the status (6 / 9: non-finite `z` / `u`, nothing done); raises for the others."""
        self._y[:] = z
        if u is not None:
            self._u_prev[:] = self._u
            self._u[:] = u
        status = self._step_fn(self._ws_p, self._info_p)
        if status == 0:
            self.k += 1
        elif status in (6, 9):
            if u is not None:   # nothing done: keep the last input
                self._u[:] = self._u_prev
        else:
            if self._info[2]:
                self.k += 1
            self._raise(status, "step")
        return status

    def run(self, U, Z, X, P):
        """Steps ``k = 0..n-1``: predict with ``U[k]``, update with ``Z[k]``; posteriors
        into ``X[k]``, ``P[k]`` (all C-contiguous float64)."""
        status = self._lib.bc_ukf_run(self._ws_p, U.shape[0], U.ctypes.data, Z.ctypes.data,
                                      X.ctypes.data, P.ctypes.data, self._info_p)
        self.k += int(self._info[0])
        if status:
            if self._info[2]:   # the failing step's prediction was made
                self.k += 1
            self._raise(status, "step")
