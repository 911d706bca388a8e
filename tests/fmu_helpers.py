"""A small version-neutral driver of a Co-Simulation FMU through fmpy, for tests.

It uses fmpy's own classes (FMU2Slave / FMU3Slave), not our co-simulation
master, so the exported FMUs are checked by an importer we did not write.
Log messages are collected in ``messages`` instead of printed.
"""
from __future__ import annotations

import contextlib
import shutil

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, defaultCallbacks
from fmpy.fmi3 import FMU3Slave


class Slave:
    def __init__(self, path):
        self.md = read_model_description(str(path))
        self.version = 2 if self.md.fmiVersion.startswith("2") else 3
        self.dir = extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []
        cls = FMU2Slave if self.version == 2 else FMU3Slave
        # fmpy passes FMI 3.0's instantiationToken as ``guid`` too
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.dir,
                       modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="test")
        if self.version == 2:
            def logger(env, name, status, category, message):
                self.messages.append(message.decode())
            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(logger)
            cb.allocateMemory = defaultCallbacks.allocateMemory
            cb.freeMemory = defaultCallbacks.freeMemory
            self._cb = cb
            self.fmu.instantiate(callbacks=cb)
            self.fmu.setupExperiment(startTime=0.0)
        else:
            def log3(env, status, category, message):
                self.messages.append(message.decode())
            self.fmu.instantiate(logMessage=log3)

    def start(self, values=None):
        if values:
            self.set(list(values), list(values.values()))
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def set(self, names, values):
        vrs = [self.vr[n] for n in names]
        (self.fmu.setReal if self.version == 2 else self.fmu.setFloat64)(vrs, list(values))

    def get(self, names):
        vrs = [self.vr[n] for n in names]
        return list((self.fmu.getReal if self.version == 2 else self.fmu.getFloat64)(vrs))

    def do_step(self, t, dt):
        self.fmu.doStep(t, dt)

    def get_state(self):
        return self.fmu.getFMUState() if self.version == 3 else self.fmu.getFMUstate()

    def set_state(self, state):
        (self.fmu.setFMUState if self.version == 3 else self.fmu.setFMUstate)(state)

    def free_state(self, state):
        (self.fmu.freeFMUState if self.version == 3 else self.fmu.freeFMUstate)(state)

    def serialize(self, state):
        return (self.fmu.serializeFMUState if self.version == 3 else self.fmu.serializeFMUstate)(state)

    def deserialize(self, blob):
        return (self.fmu.deserializeFMUState if self.version == 3 else self.fmu.deSerializeFMUstate)(blob)

    def close(self):
        with contextlib.suppress(Exception):
            self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


@contextlib.contextmanager
def open_slave(path, start_values=None):
    """An initialised Slave of the FMU at `path` (inputs/parameters in `start_values`)."""
    slave = Slave(path)
    try:
        slave.start(start_values)
        yield slave
    finally:
        slave.close()


class Model:
    """A Model Exchange instance through fmpy's FMU2Model / FMU3Model, in continuous-time
    mode after :meth:`start`; states, derivatives and event indicators as numpy arrays."""

    def __init__(self, path):
        import numpy as np
        from fmpy.fmi2 import FMU2Model
        from fmpy.fmi3 import FMU3Model
        self.np = np
        self.md = read_model_description(str(path))
        self.version = 2 if self.md.fmiVersion.startswith("2") else 3
        self.dir = extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []
        self.nx = len(self.md.derivatives)
        self.state_names = [d.variable.derivative.name for d in self.md.derivatives]
        self.nz = self.md.numberOfEventIndicators
        cls = FMU2Model if self.version == 2 else FMU3Model
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.dir,
                       modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName="test")
        if self.version == 2:
            def logger(env, name, status, category, message):
                self.messages.append(message.decode())
            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(logger)
            cb.allocateMemory = defaultCallbacks.allocateMemory
            cb.freeMemory = defaultCallbacks.freeMemory
            self._cb = cb
            self.fmu.instantiate(callbacks=cb)
            self.fmu.setupExperiment(startTime=0.0)
        else:
            def log3(env, status, category, message):
                self.messages.append(message.decode())
            self.fmu.instantiate(logMessage=log3)

    def start(self, values=None):
        if values:
            self.set(list(values), list(values.values()))
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        if self.version == 2:
            self.fmu.newDiscreteStates()
        else:
            self.fmu.updateDiscreteStates()
        self.fmu.enterContinuousTimeMode()

    def set(self, names, values):
        vrs = [self.vr[n] for n in names]
        (self.fmu.setReal if self.version == 2 else self.fmu.setFloat64)(vrs, list(values))

    def get(self, names):
        vrs = [self.vr[n] for n in names]
        return list((self.fmu.getReal if self.version == 2 else self.fmu.getFloat64)(vrs))

    def _array(self, n):
        return self.np.zeros(max(n, 1))

    def x(self):
        x = self._array(self.nx)
        self.fmu.getContinuousStates(self.np.ctypeslib.as_ctypes(x), self.nx)
        return x[:self.nx]

    def set_x(self, x, t=None):
        if t is not None:
            self.fmu.setTime(t)
        x = self.np.ascontiguousarray(x, dtype=float)
        self.fmu.setContinuousStates(self.np.ctypeslib.as_ctypes(x), self.nx)

    def dx(self):
        dx = self._array(self.nx)
        (self.fmu.getDerivatives if self.version == 2 else self.fmu.getContinuousStateDerivatives)(
            self.np.ctypeslib.as_ctypes(dx), self.nx)
        return dx[:self.nx]

    def z(self):
        z = self._array(self.nz)
        self.fmu.getEventIndicators(self.np.ctypeslib.as_ctypes(z), self.nz)
        return z[:self.nz]

    def completed(self):
        """``(enterEventMode, terminateSimulation)``."""
        out = self.fmu.completedIntegratorStep()
        return tuple(out) if isinstance(out, (tuple, list)) else (out, False)

    def directional(self, unknowns, knowns, seed):
        u = [self.vr[n] for n in unknowns]
        k = [self.vr[n] for n in knowns]
        return self.np.array(self.fmu.getDirectionalDerivative(u, k, list(seed)))

    def close(self):
        with contextlib.suppress(Exception):
            self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)
