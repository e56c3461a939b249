"""Generate and compile the C of the HIL processes (a small adapter around CasADi).

The plant and controller step functions of :mod:`mechatron.realtime.loop` are emitted
with ``casadi.CodeGenerator`` as ``plant_model.c/.h`` (``plant_out``, ``plant_step``,
``plant_x0``) and ``ctrl_model.c/.h`` (``ctrl_step``, ``ctrl_x0``), in CasADi's calling
convention (``f(arg, res, iw, w, mem)``). The hand-written C of this package
(``templates/c/``: runner, bridge, controller core; ``templates/firmware/``) calls them through
``templates/c/mt_casadi.h``. This is the interim generator named in the HIL issue: when
``mechatron.codegen`` offers the same functions, this module is the one place to switch.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from importlib import resources
from pathlib import Path

import casadi as ca

from mechatron.errors import SimulationError
from mechatron.realtime.loop import LoopFunctions

__all__ = ["C_DIR", "FIRMWARE_DIR", "generate_sources", "build_host", "build_firmware",
           "find_tool"]

C_DIR = Path(str(resources.files("mechatron.realtime") / "templates" / "c"))
FIRMWARE_DIR = Path(str(resources.files("mechatron.realtime") / "templates" / "firmware"))
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra"]
#: Warnings that CasADi's generated code triggers; our own sources build with -Werror.
GENERATED_CFLAGS = ["-Wno-unused-parameter", "-Wno-unused-variable",
                    "-Wno-unused-function", "-Wno-unused-but-set-variable"]
OPTS = {"with_header": True, "casadi_int": "int", "casadi_real": "double"}


def find_tool(name: str) -> str | None:
    """Path of an executable on PATH, or None."""
    return shutil.which(name)


def _gen(name: str, funcs: list[ca.Function], out: Path) -> None:
    cg = ca.CodeGenerator(f"{name}.c", OPTS)
    for f in funcs:
        cg.add(f)
    cg.generate(str(out) + os.sep)


def generate_sources(loop: LoopFunctions, out: Path) -> Path:
    """Write the generated model C and copy the hand-written sources into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    _gen("plant_model", [loop.plant_out, loop.plant_step, loop.plant_x0], out)
    _gen("ctrl_model", [loop.ctrl_step, loop.ctrl_x0], out)
    for src in C_DIR.iterdir():
        if src.suffix in (".c", ".h"):
            shutil.copy(src, out / src.name)
    return out


def _run(cmd: list[str], cwd: Path, what: str) -> None:
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SimulationError(f"hil: building {what} failed ({' '.join(cmd[:1])} exit "
                              f"{proc.returncode}): {proc.stderr.strip()[:2000]}")


def build_host(loop: LoopFunctions, out: Path, cc: str | None = None) -> dict[str, Path]:
    """Generate and compile ``mt_plant`` (runner + plant) and ``mt_controller``.

    Returns the paths of the two executables.
    """
    cc = cc or os.environ.get("CC") or find_tool("cc") or find_tool("gcc")
    if not cc:
        raise SimulationError("hil: no C compiler found (looked for $CC, cc, gcc). Install "
                              "gcc (apt-get install gcc) or set CC.")
    out = generate_sources(loop, out)
    objs = []
    for src, gen in (("plant_model.c", True), ("ctrl_model.c", True),
                     ("mt_packet.c", False), ("mt_transport.c", False),
                     ("ctrl_core.c", False), ("plant_runner.c", False),
                     ("controller_main.c", False)):
        obj = src[:-2] + ".o"
        flags = CFLAGS + (GENERATED_CFLAGS if gen else ["-Werror", "-D_GNU_SOURCE"])
        _run([cc, *flags, "-c", src, "-o", obj], out, src)
        objs.append(obj)
    plant = out / "mt_plant"
    ctrl = out / "mt_controller"
    _run([cc, "-o", plant.name, "plant_runner.o", "plant_model.o", "mt_packet.o",
          "mt_transport.o", "-lm"], out, "mt_plant")
    _run([cc, "-o", ctrl.name, "controller_main.o", "ctrl_core.o", "ctrl_model.o",
          "mt_packet.o", "mt_transport.o", "-lm"], out, "mt_controller")
    return {"plant": plant, "controller": ctrl}


def build_firmware(loop: LoopFunctions, out: Path, cc: str | None = None) -> Path:
    """Cross-compile the controller firmware for the LM3S6965 (Cortex-M3) board.

    Needs ``arm-none-eabi-gcc`` with newlib (Debian: ``gcc-arm-none-eabi``,
    ``libnewlib-arm-none-eabi``). Returns the ELF file.
    """
    cc = cc or find_tool("arm-none-eabi-gcc")
    if not cc:
        raise SimulationError("hil --mode pil: arm-none-eabi-gcc not found. Install it "
                              "(apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi).")
    out = generate_sources(loop, out)
    for src in FIRMWARE_DIR.iterdir():
        shutil.copy(src, out / src.name)
    arch = ["-mcpu=cortex-m3", "-mthumb", "-O2", "-std=c99", "-ffunction-sections",
            "-fdata-sections"]
    srcs = [("ctrl_model.c", True), ("ctrl_core.c", False), ("mt_packet.c", False),
            ("fw_main.c", False), ("startup_lm3s6965.c", False)]
    objs = []
    for src, gen in srcs:
        obj = "fw_" + src[:-2] + ".o"
        flags = arch + ["-Wall", "-Wextra"] + (GENERATED_CFLAGS if gen else ["-Werror"])
        _run([cc, *flags, "-c", src, "-o", obj], out, f"firmware {src}")
        objs.append(obj)
    elf = out / "mt_firmware.elf"
    _run([cc, *arch, "-nostartfiles", "-T", "lm3s6965.ld", "--specs=nano.specs",
          "--specs=nosys.specs", "-Wl,--gc-sections", "-o", elf.name, *objs, "-lm"],
         out, "firmware link")
    return elf
