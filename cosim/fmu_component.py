"""Any FMI 2.0 / 3.0 Co-Simulation FMU as a co-simulation component.

Set-up (instantiation, parameters, initialisation) goes through fmpy's
Python classes; the per-step calls go straight to the C functions fmpy
loaded (``fmi2SetReal``/``fmi2GetReal``/``fmi2DoStep``, ``fmi3SetFloat64``/
``fmi3GetFloat64``/``fmi3DoStep``), with the value-reference arrays built
once and the master's buffer passed by pointer: one step is about three C
calls, with no Python lists or ctypes arrays made per step.
"""
from __future__ import annotations

import contextlib
import functools
import os
import weakref
from collections import deque
from ctypes import POINTER, byref, c_bool, c_double, c_int, c_uint, c_void_p, cast, pointer
from pathlib import Path

import numpy as np

from cosim.errors import CosimError, FMUError, FMUStepDiscarded, UnknownNameError
from fmus.loading import extract_fmu, find_variable, read_fmu, remove_extracted, variable_unit

from .component import Port
from .fmu_fastpath import advance_function

__all__ = ["FMUComponent"]

_STATUS = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")
_TERMINATE = 100   # pseudo status: fmi3DoStep asked to terminate the simulation


def _setter(v3: bool, vtype: str) -> tuple[str, type]:
    """fmpy set-method name and Python type for a variable type."""
    if vtype in ("Real", "Float64", "Float32"):
        return ("setFloat64" if vtype == "Float64" else f"set{vtype}") if v3 else "setReal", float
    if vtype == "Boolean":
        return "setBoolean", bool
    if vtype == "String":
        return "setString", str
    if vtype == "Enumeration":
        return ("setInt64" if v3 else "setInteger"), int
    return (f"set{vtype}" if v3 else "setInteger"), int


class FMUComponent:
    """A Co-Simulation FMU (FMI 2.0 or 3.0, ours or anybody's) as a component.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.fmu`` file.
    name : str, optional
        Component name (default: the file name without ``.fmu``).
    inputs, outputs : sequence of str, optional
        FMU variables to expose as ports, in order.  Default: every scalar
        Real (FMI 2.0) / Float64 (FMI 3.0) variable of causality ``input`` /
        ``output``.  Ports carry the variable's unit (its own or its declared
        type's), description and start value.
    parameters : mapping str -> value, optional
        Values for variables of causality ``parameter``, set before
        initialisation.
    start_values : mapping str -> value, optional
        Start values of any other variables (e.g. states, inputs), set before
        initialisation; an input's start value also becomes its port start.
    feedthrough : iterable of (str, str), optional
        ``(input, output)`` pairs with direct feedthrough, overriding the
        FMU's ``ModelStructure``.  By default an output feeds through the
        inputs listed in its ``dependencies``; an output without a
        ``dependencies`` attribute depends on every input (FMI 2.0 and 3.0).

    Attributes
    ----------
    path : pathlib.Path
    model_description : fmpy.model_description.ModelDescription
    messages : collections.deque of str
        The FMU's last 50 log messages.

    Raises
    ------
    FMUError
        Unreadable FMU, no Co-Simulation interface, FMI 1.0, or no binary for
        this platform.
    UnknownNameError
        An input, output, parameter or start value the FMU does not have.

    Notes
    -----
    :meth:`advance` calls ``doStep`` with ``noSetFMUStatePriorToCurrentPoint``
    false, so :meth:`set_state` may roll back to any saved state.
    """

    def __init__(self, path, name=None, *, inputs=None, outputs=None, parameters=None,
                 start_values=None, feedthrough=None):
        self.path = Path(os.fspath(path))
        md = self.model_description = read_fmu(self.path)
        self.name = self.path.stem if name is None else str(name)
        major = (md.fmiVersion or "?").split(".")[0]
        if major not in ("2", "3"):
            raise FMUError(f"{self._who}: FMI {md.fmiVersion} is not supported (FMI 2.0 and 3.0 "
                           "are)", self.path)
        if md.coSimulation is None:
            raise FMUError(f"{self._who}: the FMU offers no Co-Simulation interface (only Model "
                           "Exchange)", self.path)
        self._v3 = major == "3"
        self._fmu = None
        self._failed = False
        self.messages = deque(maxlen=50)
        real = "Float64" if self._v3 else "Real"
        by_causality = {c: [v for v in md.modelVariables if v.causality == c and v.type == real
                            and not v.dimensions] for c in ("input", "output")}
        start_values = dict(start_values or {})
        self._vars = {}
        self._presets = self._check_presets(dict(parameters or {}), start_values)
        self.inputs = self._ports(by_causality["input"], inputs, "input", start_values)
        self.outputs = self._ports(by_causality["output"], outputs, "output", {})
        self.feedthrough = self._feedthrough(feedthrough)
        self._vr_in = (c_uint * len(self.inputs))(*[self._vars[p.name].valueReference
                                                     for p in self.inputs])
        self._vr_out = (c_uint * len(self.outputs))(*[self._vars[p.name].valueReference
                                                       for p in self.outputs])
        self._ft_any = bool(self.feedthrough)
        self._set_u = self._get_y = self._do_step = self._not_started
        self._dir = extract_fmu(self.path)
        weakref.finalize(self, remove_extracted, self._dir)
        self._check_binary()

    # -- set-up ------------------------------------------------------------------------------
    @property
    def _who(self) -> str:
        return f"FMU component {self.name!r} ({self.path})"

    def _ports(self, candidates, names, kind, starts):
        known = {v.name: v for v in candidates}
        chosen = list(known) if names is None else [str(n) for n in names]
        ports = []
        for n in chosen:
            if n not in known:
                scalar = "Float64" if self._v3 else "Real"
                raise UnknownNameError(f"FMU {kind}", n, list(known),
                                       f"{self.model_description.modelName} ({self.path}; scalar "
                                       f"{scalar} variables of causality {kind})")
            v = self._vars[n] = known[n]
            start = starts.get(n, v.start)
            ports.append(Port(n, variable_unit(v), v.description or "",
                              float(start) if start is not None else 0.0))
        if len(set(chosen)) != len(chosen):
            raise CosimError(f"{self._who}: an {kind} is listed twice in {chosen}")
        return tuple(ports)

    def _check_presets(self, parameters, start_values):
        md = self.model_description
        params = [v.name for v in md.modelVariables if v.causality == "parameter"]
        presets = []
        for n, value in parameters.items():
            if n not in params:
                raise UnknownNameError("FMU parameter", n, params, f"{md.modelName} ({self.path})")
            presets.append((find_variable(md, n, path=self.path), value))
        for n, value in start_values.items():
            presets.append((find_variable(md, n, path=self.path), value))
        for v, value in presets:
            method, pytype = _setter(self._v3, v.type)
            try:
                pytype(value)
            except (TypeError, ValueError):
                raise CosimError(f"{self._who}: value {value!r} for {v.type} variable "
                                 f"{v.name!r} is not a {pytype.__name__}") from None
        return presets

    def _feedthrough(self, override):
        ins = [p.name for p in self.inputs]
        outs = [p.name for p in self.outputs]
        if override is not None:
            pairs = frozenset((str(i), str(o)) for i, o in override)
            for i, o in pairs:
                if i not in ins:
                    raise UnknownNameError("input", i, ins, self.name)
                if o not in outs:
                    raise UnknownNameError("output", o, outs, self.name)
            return pairs
        deps = {u.variable.name: u.dependencies for u in self.model_description.outputs}
        pairs = set()
        for o in outs:
            d = deps.get(o)
            listed = set(ins) if d is None else {v.name for v in d}   # None: depends on all
            pairs.update((i, o) for i in ins if i in listed)
        return frozenset(pairs)

    def _check_binary(self):
        import fmpy
        platform = fmpy.platform_tuple if self._v3 else fmpy.platform
        mid = self.model_description.coSimulation.modelIdentifier
        lib = self._dir / "binaries" / platform / (mid + fmpy.sharedLibraryExtension)
        if not lib.is_file():
            have = sorted(p.name for p in (self._dir / "binaries").glob("*")) \
                if (self._dir / "binaries").is_dir() else []
            raise FMUError(f"{self._who}: no binary binaries/{platform}/{lib.name} for this "
                           f"platform; the FMU has binaries for {', '.join(have) or 'no platform'}"
                           " (a source-code FMU must be compiled first)", self.path)

    # -- component protocol ------------------------------------------------------------------
    def bind(self, u: np.ndarray, y: np.ndarray) -> None:
        """Keep the master's views and their C pointers (see :class:`~cosim.Component`)."""
        for label, a, n in (("u", u, len(self.inputs)), ("y", y, len(self.outputs))):
            if a.dtype != np.float64 or not a.flags.c_contiguous or a.shape != (n,):
                raise CosimError(f"{self._who}: bind needs a C-contiguous float64 {label} of "
                                 f"shape ({n},); found {a.dtype} {a.shape}")
        self.u, self.y = u, y
        self._u_ptr = u.ctypes.data_as(POINTER(c_double))
        self._y_ptr = y.ctypes.data_as(POINTER(c_double))

    def start(self, t0: float) -> None:
        """Load, instantiate, set parameters and start values, initialise at ``t0`` (s)."""
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave
        self.stop()
        if not hasattr(self, "_u_ptr"):
            raise FMUError(f"{self._who}: call bind(u, y) before start", self.path)
        md, self._failed = self.model_description, False
        cls = FMU3Slave if self._v3 else FMU2Slave
        with self._calls("loading the binary", t0):
            fmu = cls(unzipDirectory=str(self._dir), instanceName=self.name,
                      modelIdentifier=md.coSimulation.modelIdentifier,
                      guid=md.guid)   # fmpy: the FMI 3.0 instantiationToken, too
        try:
            with self._calls("instantiate", t0):
                if self._v3:
                    fmu.instantiate(logMessage=self._log3)
                else:
                    fmu.instantiate(callbacks=self._callbacks2())
        except FMUError:
            with contextlib.suppress(Exception):
                fmu.freeLibrary()
            raise
        self._fmu = fmu
        with self._calls("initialisation", t0):
            if not self._v3:
                fmu.setupExperiment(startTime=t0)
            for v, value in self._presets:
                method, pytype = _setter(self._v3, v.type)
                getattr(fmu, method)([v.valueReference], [pytype(value)])
            if self._v3:
                fmu.enterInitializationMode(startTime=t0)
            else:
                fmu.enterInitializationMode()
            if self.inputs:
                getattr(fmu, "setFloat64" if self._v3 else "setReal")(list(self._vr_in),
                                                                       self.u.tolist())
            fmu.exitInitializationMode()
        self._prepare_raw(fmu)

    def _prepare_raw(self, fmu) -> None:
        """Precompute the hot-path calls on the raw C functions fmpy loaded."""
        dll, comp = fmu.dll, c_void_p(fmu.component)
        vr_in, vr_out = cast(self._vr_in, POINTER(c_uint)), cast(self._vr_out, POINTER(c_uint))
        n_in, n_out = len(self.inputs), len(self.outputs)
        if self._v3:
            self._set_u = functools.partial(dll.fmi3SetFloat64, comp, vr_in, n_in, self._u_ptr, n_in)
            self._get_y = functools.partial(dll.fmi3GetFloat64, comp, vr_out, n_out, self._y_ptr,
                                            n_out)
            raw_step = dll.fmi3DoStep
            flags = [c_bool(), c_bool(), c_bool()]
            last = c_double()
            p_event, p_term, p_early, p_last = (pointer(flags[0]), pointer(flags[1]),
                                                pointer(flags[2]), pointer(last))

            def do_step(t, dt, _no_set_prior):
                status = raw_step(comp, t, dt, False, p_event, p_term, p_early, p_last)
                return _TERMINATE if status <= 1 and flags[1].value else status
            self._do_step = do_step
        else:
            self._set_u = functools.partial(dll.fmi2SetReal, comp, vr_in, n_in, self._u_ptr)
            self._get_y = functools.partial(dll.fmi2GetReal, comp, vr_out, n_out, self._y_ptr)
            self._do_step = functools.partial(dll.fmi2DoStep, comp)
        # Without feedthrough the outputs at t + dt are known after doStep: one C call
        # sets the inputs, steps and fetches them (cosim.fmu_fastpath), output() is then free.
        self._which = c_int()
        self._fast = None if self._ft_any else advance_function(
            dll, comp.value, 3 if self._v3 else 2, self._vr_in, n_in, self._u_ptr,
            self._vr_out, n_out, self._y_ptr, self._which)
        self._y_fresh = False
        self._set_name = "fmi3SetFloat64" if self._v3 else "fmi2SetReal"
        self._get_name = "fmi3GetFloat64" if self._v3 else "fmi2GetReal"
        self._step_name = "fmi3DoStep" if self._v3 else "fmi2DoStep"

    def output(self, t: float) -> None:
        """Outputs at ``t`` (s) into ``y``: set the inputs first if any feeds through."""
        if self._y_fresh:   # the fast path fetched them at the end of the last step
            self._y_fresh = False
            return
        if self._ft_any:
            status = self._set_u()
            if status > 1:
                raise self._status_error(self._set_name, t, status)
        status = self._get_y()
        if status > 1:
            raise self._status_error(self._get_name, t, status)

    def advance(self, t: float, dt: float) -> None:
        """Set the inputs and ``doStep(t, dt)`` (s); without feedthrough, also fetch the
        outputs at ``t + dt`` in the same C call."""
        if self._fast is not None:
            status = self._fast(t, dt)
            if status:
                raise self._fast_error(t, status, dt)
            self._y_fresh = True
            return
        if self.inputs:
            status = self._set_u()
            if status > 1:
                raise self._status_error(self._set_name, t, status)
        status = self._do_step(t, dt, 0)
        if status > 1:
            raise self._status_error(self._step_name, t, status, dt)

    def stop(self) -> None:
        """Terminate and free the instance (no-op if not started or already stopped)."""
        fmu, self._fmu = self._fmu, None
        if fmu is None:
            return
        self._set_u = self._get_y = self._do_step = self._not_started   # library is unloaded
        problem = None
        try:
            fmu.terminate()
        except Exception as exc:   # an FMU that failed may refuse; free it anyway
            problem = exc
        fmu.freeInstance()
        if problem is not None and not self._failed:
            raise FMUError(f"{self._who}: terminate failed: {problem}{self._log_tail()}",
                           self.path)

    # -- rollback ----------------------------------------------------------------------------
    def get_state(self):
        """Save the FMU's complete state (``getFMUstate``); returns an opaque handle."""
        self._need_state_support("get_state")
        with self._calls("getFMUstate"):
            return self._fmu.getFMUState()

    def set_state(self, state) -> None:
        """Restore a state saved by :meth:`get_state` (``setFMUstate``).

        ``y`` is updated at the next :meth:`output`.
        """
        self._need_state_support("set_state")
        with self._calls("setFMUstate"):
            self._fmu.setFMUState(state)
        self._y_fresh = False

    def free_state(self, state) -> None:
        """Release a state saved by :meth:`get_state` (``freeFMUstate``)."""
        if self._fmu is not None:
            with self._calls("freeFMUstate"):
                self._fmu.freeFMUState(state)

    def _need_state_support(self, what):
        if self._fmu is None:
            raise FMUError(f"{self._who}: {what} needs a started FMU (call start first)", self.path)
        if not self.model_description.coSimulation.canGetAndSetFMUstate:
            raise FMUError(f"{self._who}: the FMU cannot get and set its state "
                           "(canGetAndSetFMUstate is false)", self.path)

    def _not_started(self, *args):
        raise FMUError(f"{self._who}: the FMU is not started (call start first)", self.path)

    # -- errors and logging ------------------------------------------------------------------
    def _log_tail(self) -> str:
        return ("; the FMU logged: " + " | ".join(list(self.messages)[-3:])) if self.messages else ""

    def _fast_error(self, t: float, status: int, dt: float | None = None) -> FMUError:
        which = self._which.value
        if which == 3:
            return self._status_error(self._step_name, t, _TERMINATE)
        name = (self._set_name, self._step_name, self._get_name)[which]
        return self._status_error(name, t, status, dt if which == 1 else None)

    def _status_error(self, function: str, t: float, status: int, dt: float | None = None) -> FMUError:
        self._failed = True
        if status == 2 and dt is not None:   # doStep Discard: the FMU could not take this step
            reason = self.messages[-1] if self.messages else ""
            return FMUStepDiscarded(
                f"{self._who}: {function} discarded the step from t = {t:.12g} s to "
                f"{t + dt:.12g} s{self._log_tail()}", component=self.name, time=t, step=dt,
                reason=reason, path=self.path)
        if status == _TERMINATE:
            what = "asked to terminate the simulation"
        else:
            what = f"returned {_STATUS[status] if 0 <= status < 6 else status}"
        return FMUError(f"{self._who}: {function} {what} at t = {t:.12g} s{self._log_tail()}",
                        self.path)

    @contextlib.contextmanager
    def _calls(self, what: str, t: float | None = None):
        try:
            yield
        except FMUError:
            raise
        except Exception as exc:   # fmpy raises FMICallException or bare Exception
            self._failed = True
            at = f" at t = {t:.12g} s" if t is not None else ""
            raise FMUError(f"{self._who}: {what} failed{at}: {exc}{self._log_tail()}",
                           self.path) from None

    def _log(self, status: int, message: bytes | None) -> None:
        label = _STATUS[status] if 0 <= status < 6 else str(status)
        self.messages.append(f"[{label}] {(message or b'').decode('utf-8', 'replace')}")

    def _log3(self, env, status, category, message):
        self._log(status, message)

    def _callbacks2(self):
        from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(lambda env, inst, status, cat, msg:
                                           self._log(status, msg))
        cb.allocateMemory = defaultCallbacks.allocateMemory
        cb.freeMemory = defaultCallbacks.freeMemory
        with contextlib.suppress(Exception):   # printf-style formatting of the messages
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(byref(cb))
        self._cb2 = cb   # kept alive as long as the instance
        return cb

    def __repr__(self) -> str:
        return (f"<FMUComponent {self.name!r} {self.path.name}: "
                f"({', '.join(p.name for p in self.inputs)}) -> "
                f"({', '.join(p.name for p in self.outputs)})>")

