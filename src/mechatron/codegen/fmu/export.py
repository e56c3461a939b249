"""Export a model as an FMU (Functional Mock-up Unit).

Co-simulation FMUs (FMI 2.0 and 3.0) carry the fixed-step solver: ``doStep`` runs the
generated C step function (:mod:`mechatron.codegen.c`) over the communication step, which
must be a whole number of solver steps; the FMU then agrees with Mechatron's desktop
fixed-step run to rounding. Model-exchange FMUs (FMI 2.0) give the importer the state
derivatives ``der(x)`` and the logged variables; the importer integrates.

Variables: every parameter (``causality="parameter"``, tunable, start = default), every
external input of the model (``causality="input"``, see below), every other logged
variable by instance path (``causality="output"``); model exchange adds the continuous
states (as outputs when they are logged, else local) and their derivatives. The FMU holds
its C sources (``sources/``; FMI 3.0 also ``buildDescription.xml``) and a shared library
for the build platform, compiled at export and linked only against the C library and libm.

Inputs: the signal inputs of the model's root component (``CompiledModel.input_names``,
:mod:`mechatron.solvers.inputs`) are FMI inputs, ``variability="continuous"``, with their
unit, description and a start value (the declared start, 0 when there is none: FMI
requires one; ``params={...}`` overrides it). Each is a slot of the parameter vector ``p``
of the generated C, so ``fmi2SetReal``/``fmi3SetFloat64`` write that slot at any time.
Co-simulation holds the value set before ``doStep`` over the whole communication step
(zero-order hold, as Mechatron's fixed-step run holds an input over each solver step): with
a communication step equal to the solver step, an FMU fed with a table's values at the
communication points reproduces ``mt.simulate(..., solver=, dt=, inputs={...})`` to
rounding. Model exchange evaluates ``der(x)`` with the input last set, so an importer that
interpolates the input continuously matches a variable-step run. The logged copy of the
input (equation ``u == p_u``) is the input variable itself, not a second output; outputs
list no dependencies (they may depend on every input) and the FMU cannot interpolate
inputs (``canInterpolateInputs`` is false).

Limitations: model exchange of models with event relations is refused (export
co-simulation, which handles their modes as the fixed-step solver does); FMU states,
directional derivatives, input derivatives and FMI 3.0 model exchange are not provided.
"""

from __future__ import annotations

import hashlib
import platform
import shutil
import subprocess
import tempfile
import uuid
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

import mechatron
from mechatron._io import atomic_path
from mechatron.codegen._common import CodegenError, c_array, render
from mechatron.codegen.c.generator import Prepared, prepare, template_values, write_c

__all__ = ["export_fmu", "fmi_platform", "FMU_C_FLAGS"]

#: Flags of the FMU's shared library.
FMU_C_FLAGS = ["-std=c99", "-O2", "-fPIC", "-shared", "-Wall", "-Wextra", "-pedantic",
               "-Werror", "-ffp-contract=off"]

#: Kind of each value reference in the C wrapper; an input is a slot of ``p`` and is read
#: and written as a parameter.
_KIND = {"parameter": 0, "input": 0, "output": 1, "state": 2, "derivative": 3, "time": 4}


def fmi_platform(fmi: int) -> tuple[str, str]:
    """The binaries folder of this platform for FMI ``fmi`` and the library suffix."""
    system, machine = platform.system(), platform.machine().lower()
    arch = {"amd64": "x86_64", "x86_64": "x86_64", "arm64": "aarch64",
            "aarch64": "aarch64"}.get(machine)
    if system not in ("Linux", "Darwin") or arch is None:
        raise CodegenError(f"FMU export: no binary for {system} {machine}; Mechatron builds "
                           "FMU binaries on Linux and macOS (x86_64, aarch64).")
    suffix = ".so" if system == "Linux" else ".dylib"
    if fmi == 2:
        if arch != "x86_64":
            raise CodegenError(f"FMI 2.0 defines no platform name for {system} {arch}; "
                               "export FMI 3.0 (--fmi 3).")
        return ("linux64" if system == "Linux" else "darwin64"), suffix
    return f"{arch}-{'linux' if system == 'Linux' else 'darwin'}", suffix


def _variables(prep: Prepared, fmi: int, kind: str) -> list[dict]:
    """The model variables in value-reference order, with what each maps to."""
    cm = prep.cm
    out: list[dict] = []
    if fmi == 3:
        out.append(dict(name="time", causality="independent", variability="continuous",
                        kind="time", index=0, unit="s"))
    slots = set(cm.input_index)
    for i, name in enumerate(cm.param_names):
        if i in slots:
            continue
        out.append(dict(name=name, causality="parameter", variability="tunable",
                        initial="exact", start=float(prep.p[i]), kind="parameter", index=i,
                        unit=cm.param_units[i], description=None))
    for k, (name, slot) in enumerate(zip(cm.input_names, cm.input_index)):
        start = float(prep.p[slot])
        out.append(dict(name=name, causality="input", variability="continuous",
                        start=start if np.isfinite(start) else 0.0, kind="input",
                        index=int(slot), unit=cm.input_units[k],
                        description=cm.input_docs[k] or None))
    inputs = set(cm.input_names)
    logged = {n: j for j, n in enumerate(cm.names)}
    me = kind == "me"
    states = set(cm.state_names) if me else set()
    for j, name in enumerate(cm.names):
        if name in inputs:       # its logged copy (u == p_u) is the input variable
            continue
        v = dict(name=name, causality="output", variability="continuous", kind="output",
                 index=j, unit=cm.units[j], description=cm.docs[j] or None)
        if name in states:
            k = cm.state_names.index(name)
            v.update(initial="exact", start=float(prep.x_start[k]))
        out.append(v)
    if me:
        taken = {v["name"] for v in out}
        for k, name in enumerate(cm.state_names):
            if name not in logged:
                out.append(dict(name=name, causality="local", variability="continuous",
                                initial="exact", start=float(prep.x_start[k]), kind="state",
                                index=k, unit=_state_unit(cm, name)))
                taken.add(name)
        for k, name in enumerate(cm.state_names):
            dname, n = f"der({name})", 2
            while dname in taken:
                dname, n = f"der({name})_{n}", n + 1
            taken.add(dname)
            out.append(dict(name=dname, causality="local", variability="continuous",
                            kind="derivative", index=k, state=name,
                            unit=_derivative_unit(_state_unit(cm, name))))
    for vr, v in enumerate(out):
        v["vr"] = vr
    return out


def _state_unit(cm, name: str) -> str:
    return cm.units[cm.names.index(name)] if name in cm.names else ""


def _derivative_unit(unit: str) -> str:
    if not unit or unit == "1":
        return "1/s"
    return f"({unit})/s" if any(c in unit for c in "*/") else f"{unit}/s"


def _fmt(x: float) -> str:
    return repr(float(x))


def _model_description(prep: Prepared, variables, fmi: int, kind: str, guid: str,
                       sources: list[str]) -> bytes:
    cm = prep.cm
    root = ET.Element("fmiModelDescription")
    root.set("fmiVersion", "2.0" if fmi == 2 else "3.0")
    root.set("modelName", cm.name)
    root.set("guid" if fmi == 2 else "instantiationToken", guid)
    root.set("description", f"{cm.name}: generated by Mechatron "
             + (f"({prep.solver}, step {prep.dt:g} s)" if kind == "cs" else
                "(model exchange)"))
    root.set("generationTool", f"Mechatron {mechatron.__version__}")
    root.set("variableNamingConvention", "flat")
    if fmi == 2:
        root.set("numberOfEventIndicators", "0")
    iface = ET.SubElement(root, "CoSimulation" if kind == "cs" else "ModelExchange")
    iface.set("modelIdentifier", prep.name)
    if kind == "cs":
        iface.set("canHandleVariableCommunicationStepSize", "true")
        if fmi == 3:
            iface.set("fixedInternalStepSize", _fmt(prep.dt))
    if fmi == 2:
        files = ET.SubElement(iface, "SourceFiles")
        for s in sources:
            ET.SubElement(files, "File", name=s)
    units = sorted({v["unit"] for v in variables if v.get("unit")})
    if units:
        ud = ET.SubElement(root, "UnitDefinitions")
        for u in units:
            ET.SubElement(ud, "Unit", name=u)
    ET.SubElement(root, "DefaultExperiment", startTime=_fmt(prep.t0),
                  stopTime=_fmt(prep.t_stop),
                  stepSize=_fmt(prep.dt))
    mv = ET.SubElement(root, "ModelVariables")
    position = {}            # 1-based index in ModelVariables (FMI 2.0 ModelStructure)
    for k, v in enumerate(variables, 1):
        position[v["name"]] = k
        attrs = {"name": v["name"], "valueReference": str(v["vr"]),
                 "causality": v["causality"], "variability": v["variability"]}
        if v.get("initial"):
            attrs["initial"] = v["initial"]
        if v.get("description"):
            attrs["description"] = v["description"]
        typed = {}
        if v.get("unit"):
            typed["unit"] = v["unit"]
        if "start" in v:
            typed["start"] = _fmt(v["start"])
        if v["kind"] == "derivative":
            typed["derivative"] = str(position[v["state"]]) if fmi == 2 else str(
                next(w["vr"] for w in variables if w["name"] == v["state"]))
        if fmi == 2:
            sv = ET.SubElement(mv, "ScalarVariable", attrs)
            ET.SubElement(sv, "Real", typed)
        else:
            ET.SubElement(mv, "Float64", {**attrs, **typed})
    ms = ET.SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v["causality"] == "output"]
    derivs = [v for v in variables if v["kind"] == "derivative"]
    initial = [v for v in variables
               if (v["causality"] == "output" and v.get("initial") != "exact")
               or v["kind"] == "derivative"]
    if fmi == 2:
        for tag, group in (("Outputs", outputs), ("Derivatives", derivs),
                           ("InitialUnknowns", initial)):
            if group:
                el = ET.SubElement(ms, tag)
                for v in group:
                    ET.SubElement(el, "Unknown", index=str(position[v["name"]]))
    else:
        for v in outputs:
            ET.SubElement(ms, "Output", valueReference=str(v["vr"]))
        for v in derivs:
            ET.SubElement(ms, "ContinuousStateDerivative", valueReference=str(v["vr"]))
        for v in initial:
            ET.SubElement(ms, "InitialUnknown", valueReference=str(v["vr"]))
    ET.indent(root)
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _compile(src: Path, sources: list[str], library: Path) -> None:
    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        raise CodegenError("FMU export compiles a binary and needs a C compiler (cc, gcc, "
                           "clang); install one (Debian: apt-get install gcc).")
    library.parent.mkdir(parents=True, exist_ok=True)
    cmd = [cc, *FMU_C_FLAGS, "-o", str(library), *[str(src / s) for s in sources], "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-12:])
        raise CodegenError(f"compiling the FMU binary failed: {tail}")


def export_fmu(model, path, *, fmi: int = 2, kind: str = "cs", solver: str = "rk4",
               dt: float, iterations: int = 3, params: dict | None = None,
               t0: float = 0.0, t_stop: float | None = None,
               name: str | None = None) -> dict:
    """Write an FMU of ``model`` to ``path`` and return facts about it.

    Parameters
    ----------
    model : Component or CompiledModel
    path : path
        The ``.fmu`` file to write (replaced if it exists).
    fmi : {2, 3}
        FMI version; FMI 3.0 provides co-simulation only.
    kind : {"cs", "me"}
        Co-simulation (the fixed-step ``solver`` with step ``dt`` inside) or model
        exchange.
    solver, dt, iterations, params, t0, t_stop, name
        As for :func:`mechatron.codegen.generate_c`; ``dt`` is also the default
        experiment's step size.
    """
    if fmi not in (2, 3):
        raise CodegenError(f"FMI version must be 2 or 3, got {fmi!r}.")
    if kind not in ("cs", "me"):
        raise CodegenError(f"FMU kind must be 'cs' (co-simulation) or 'me' (model "
                           f"exchange), got {kind!r}.")
    if fmi == 3 and kind == "me":
        raise CodegenError("FMI 3.0 model exchange is not provided; export FMI 3.0 "
                           "co-simulation (--kind cs) or FMI 2.0 model exchange (--fmi 2).")
    prep = prepare(model, solver=solver, dt=dt, iterations=iterations, params=params, t0=t0,
                   t_stop=t_stop, name=name)
    cm = prep.cm
    if kind == "me" and cm.nr:
        owners = sorted({o for o, _ in cm.relations})
        raise CodegenError(f"model '{cm.name}': model exchange of models with event "
                           f"relations ({', '.join(owners[:5])}) is not provided; export "
                           "co-simulation (--kind cs) instead.", path=cm.name)
    binaries, suffix = fmi_platform(fmi)
    variables = _variables(prep, fmi, kind)
    with tempfile.TemporaryDirectory(prefix="mechatron_fmu_") as tmp:
        root = Path(tmp)
        src = root / "sources"
        code = write_c(prep, src)
        for extra in ("Makefile", f"{prep.name}_main.c", f"{prep.name}_arm.c"):
            code.files.pop(extra).unlink()
        digest = hashlib.sha256()
        for f in sorted(code.files):
            digest.update(code.files[f].read_bytes())
        digest.update(f"{fmi}{kind}".encode())
        guid = "{" + str(uuid.UUID(digest.hexdigest()[:32])) + "}"
        values = template_values(prep)
        values.update(guid=guid, nvr=len(variables), nvr_alloc=max(1, len(variables)),
                      vr_kind=c_array(str(_KIND[v["kind"]]) for v in variables),
                      vr_index=c_array(str(v["index"]) for v in variables))
        wrapper = "fmi2.c" if fmi == 2 else "fmi3.c"
        (src / "fmu_common.h").write_text(render("fmu/fmu_common.h.in", **values))
        (src / "fmu_common.c").write_text(render("fmu/fmu_common.c.in", **values))
        (src / wrapper).write_text(render(f"fmu/{wrapper}.in", **values))
        sources = [f"{prep.name}.c", f"{prep.name}_casadi.c", "fmu_common.c", wrapper]
        if fmi == 3:
            values["source_files"] = "\n".join(f'      <SourceFile name="{s}"/>'
                                               for s in sources)
            (src / "buildDescription.xml").write_text(
                render("fmu/buildDescription.xml.in", **values))
        (root / "modelDescription.xml").write_bytes(
            _model_description(prep, variables, fmi, kind, guid, sources))
        library = root / "binaries" / binaries / f"{prep.name}{suffix}"
        _compile(src, sources, library)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp_fmu, \
                zipfile.ZipFile(tmp_fmu, "w", zipfile.ZIP_DEFLATED) as zf:
            for f in sorted(root.rglob("*")):
                if f.is_file():
                    zf.write(f, f.relative_to(root).as_posix())
    return {"path": str(path), "fmi": f"{fmi}.0", "kind": kind, "guid": guid,
            "solver": prep.solver if kind == "cs" else None,
            "dt": prep.dt, "iterations": prep.iterations, "platform": binaries,
            "variables": len(variables),
            "parameters": len(cm.param_names) - len(cm.input_names),
            "inputs": list(cm.input_names),
            "outputs": len(cm.names) - len(set(cm.input_names) & set(cm.names)),
            "states": cm.nx,
            "sources": [f"sources/{s}" for s in sources]
            + (["sources/buildDescription.xml"] if fmi == 3 else [])}
