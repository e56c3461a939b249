"""FMU instances stepped over communication intervals, through FMPy.

:class:`CoSimulationSlave` calls the FMU's own ``doStep``. :class:`ModelExchangeSlave`
integrates a model-exchange FMU over each interval with FMPy's CVODE (BDF, the solver FMPy
uses for model exchange), handling the FMU's time, state and step events as FMPy's own
``simulate_fmu`` does. Both take their inputs before a step and hold them over it.
"""

from __future__ import annotations

import shutil
import tempfile

import numpy as np

from mechatron.errors import SimulationError

__all__ = ["open_slave", "CoSimulationSlave", "ModelExchangeSlave"]


class _NoInput:
    """FMPy's solver re-applies table inputs at each root evaluation; ours are set by the
    co-simulation before each step."""

    def apply(self, *args, **kwargs):
        pass


class _Slave:
    """Common part: unzip, instantiate, set parameters, initialize; get and set reals."""

    def __init__(self, block: dict, fmi_type: str, t0: float, parameters: dict,
                 inputs: dict):
        from fmpy import extract, read_model_description
        from fmpy.simulation import instantiate_fmu
        self.block = block
        self.where = f"FMU '{block['path']}' ({block['file']})"
        self.md = read_model_description(block["file"], validate=False)
        self.fmi3 = self.md.fmiVersion.startswith("3.")
        self._dir = tempfile.mkdtemp(prefix="mechatron_fmu_import_")
        try:
            extract(block["file"], self._dir)
            self.fmu = instantiate_fmu(self._dir, self.md, fmi_type)
        except Exception as exc:
            self.close()
            raise SimulationError(f"{self.where}: cannot be instantiated on this machine "
                                  f"({exc}). Is there a binary for this platform?",
                                  path=block["path"]) from None
        self.in_vr = [vr for _, _, vr in block["inputs"]]
        self.out_vr = [vr for _, _, vr in block["outputs"]]
        self.t = t0
        self._call("setting up", self._initialize, t0, parameters, inputs)

    def _call(self, what, fn, *args):
        try:
            return fn(*args)
        except SimulationError:
            raise
        except Exception as exc:
            raise SimulationError(f"{self.where}: {what} failed at t = {self.t:.9g} s "
                                  f"({exc}).", path=self.block["path"]) from None

    def _set_parameters(self, parameters: dict) -> None:
        if parameters:
            self.set(list(parameters), list(parameters.values()))

    def set(self, vrs, values) -> None:
        if not vrs:
            return
        values = [float(v) for v in values]
        if self.fmi3:
            self.fmu.setFloat64(vrs, values)
        else:
            self.fmu.setReal(vrs, values)

    def get(self, vrs) -> np.ndarray:
        if not vrs:
            return np.zeros(0)
        vals = self.fmu.getFloat64(vrs) if self.fmi3 else self.fmu.getReal(vrs)
        return np.asarray(vals, dtype=float)

    def outputs(self) -> np.ndarray:
        """The FMU's outputs now."""
        return self._call("reading the outputs", self.get, self.out_vr)

    def set_inputs(self, values) -> None:
        self._call("setting the inputs", self.set, self.in_vr, values)

    def close(self) -> None:
        fmu = getattr(self, "fmu", None)
        if fmu is not None:
            try:
                fmu.terminate()
            except Exception:
                pass
            try:
                fmu.freeInstance()
            except Exception:
                pass
            self.fmu = None
        shutil.rmtree(self._dir, ignore_errors=True)


class CoSimulationSlave(_Slave):
    """A co-simulation FMU: ``doStep`` over each communication interval."""

    def __init__(self, block, t0, parameters, inputs, **_):
        super().__init__(block, "CoSimulation", t0, parameters, inputs)

    def _initialize(self, t0, parameters, inputs):
        fmu = self.fmu
        fmu.instantiate()
        self._set_parameters(parameters)
        if self.fmi3:
            fmu.enterInitializationMode(startTime=t0)
        else:
            fmu.setupExperiment(startTime=t0)
            fmu.enterInitializationMode()
        if inputs is not None:
            self.set(self.in_vr, inputs)
        fmu.exitInitializationMode()

    def step(self, h: float) -> None:
        """Advance from the current communication point by ``h``."""
        def go():
            out = self.fmu.doStep(self.t, h)
            if self.fmi3 and out is not None and out[1]:
                raise SimulationError(f"{self.where}: the FMU asked to terminate at "
                                      f"t = {self.t:.9g} s.", path=self.block["path"])
        self._call("doStep", go)
        self.t += h


class ModelExchangeSlave(_Slave):
    """A model-exchange FMU integrated by FMPy's CVODE between communication points."""

    def __init__(self, block, t0, parameters, inputs, rtol=1e-6, max_step=None):
        self.rtol = rtol
        self.max_step = max_step
        super().__init__(block, "ModelExchange", t0, parameters, inputs)

    def _event_update(self):
        fmu = self.fmu
        more, terminate = True, False
        nxt = None
        while more and not terminate:
            res = fmu.updateDiscreteStates() if self.fmi3 else fmu.newDiscreteStates()
            more, terminate = res[0], res[1]
            nxt = res[5] if res[4] else None
        if terminate:
            raise SimulationError(f"{self.where}: the FMU asked to terminate at "
                                  f"t = {self.t:.9g} s.", path=self.block["path"])
        self.next_event = nxt

    def _initialize(self, t0, parameters, inputs):
        from fmpy.sundials import CVodeSolver
        fmu, md = self.fmu, self.md
        fmu.instantiate()
        self._set_parameters(parameters)
        if self.fmi3:
            fmu.enterInitializationMode(startTime=t0)
        else:
            fmu.setupExperiment(startTime=t0)
            fmu.enterInitializationMode()
        if inputs is not None:
            self.set(self.in_vr, inputs)
        fmu.exitInitializationMode()
        self._event_update()
        fmu.enterContinuousTimeMode()
        nx = md.numberOfContinuousStates
        self.step_event = bool(md.modelExchange.needsCompletedIntegratorStep)
        self.solver = CVodeSolver(
            nx=nx, nz=md.numberOfEventIndicators,
            get_x=fmu.getContinuousStates, set_x=fmu.setContinuousStates,
            get_dx=fmu.getContinuousStateDerivatives if self.fmi3 else fmu.getDerivatives,
            get_z=fmu.getEventIndicators,
            get_nominals=fmu.getNominalsOfContinuousStates, set_time=fmu.setTime,
            input=_NoInput(), startTime=t0,
            maxStep=self.max_step if self.max_step else float("inf"),
            relativeTolerance=self.rtol, maxNumSteps=100_000)

    def set_inputs(self, values) -> None:
        super().set_inputs(values)
        # the right-hand side changed: CVODE restarts from the current point
        self._call("restarting CVODE", self.solver.reset, self.t)

    def step(self, h: float) -> None:
        self._call("integrating", self._integrate, self.t + h)

    def _integrate(self, t_end: float) -> None:
        fmu, t = self.fmu, self.t
        tol = 1e-12 * max(1.0, abs(t_end))
        while t < t_end - tol:
            target = t_end
            time_event = self.next_event is not None and self.next_event < t_end - tol
            if time_event:
                target = self.next_event
            state_event, _, t = self.solver.step(t, target)
            fmu.setTime(t)
            step_event = False
            if self.step_event:
                step_event, terminate = fmu.completedIntegratorStep()[:2]
                if terminate:
                    raise SimulationError(f"{self.where}: the FMU asked to terminate at "
                                          f"t = {t:.9g} s.", path=self.block["path"])
            if state_event or step_event or (time_event and abs(t - target) <= tol):
                fmu.enterEventMode()
                self.t = t
                self._event_update()
                fmu.enterContinuousTimeMode()
                self.solver.reset(t)
        self.t = t_end


def open_slave(block: dict, t0: float, parameters: dict, inputs, *, rtol: float,
               max_step: float | None):
    """An initialized slave for ``block`` (see :meth:`FMUComponent.external_block`):
    ``parameters`` maps value references to values, ``inputs`` gives the inputs' values
    at ``t0``."""
    cls = CoSimulationSlave if block["kind"] == "cs" else ModelExchangeSlave
    return cls(block, t0, parameters, inputs, rtol=rtol, max_step=max_step)
