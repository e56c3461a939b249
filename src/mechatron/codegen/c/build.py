"""Build and run generated C: the host harness, its timing, and a Cortex-M4 image."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

from mechatron.codegen._common import CodegenError
from mechatron.codegen.c.generator import CModel
from mechatron.results import SimResult

__all__ = ["build", "run_harness", "measure_ns_per_step", "cross_compile",
           "have_cross_compiler", "C_FLAGS"]

#: The flags of the generated Makefile (the issue's strictness, plus no FMA contraction
#: so that the C rounds as CasADi's virtual machine does).
C_FLAGS = "-std=c99 -O2 -Wall -Wextra -Werror -pedantic -ffp-contract=off"
TIMEOUT = 600


def _make() -> str:
    make = shutil.which("make")
    if make is None:
        raise CodegenError("building generated C needs `make`; install it (Debian: "
                           "apt-get install make).")
    return make


def _run(cmd: list[str], cwd: Path, what: str) -> subprocess.CompletedProcess:
    try:
        proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT)
    except FileNotFoundError as exc:
        raise CodegenError(f"{what}: {exc.filename} not found; install a C compiler "
                           "(Debian: apt-get install gcc make).") from exc
    except subprocess.TimeoutExpired as exc:
        raise CodegenError(f"{what}: no result after {TIMEOUT} s.") from exc
    if proc.returncode != 0:
        tail = "\n".join((proc.stderr or proc.stdout).strip().splitlines()[-12:])
        raise CodegenError(f"{what} failed (exit {proc.returncode}) in {cwd}: {tail}",
                           path=str(cwd))
    return proc


def build(code: CModel, *, cc: str | None = None) -> Path:
    """Compile the host harness with the generated Makefile (``-std=c99 -Wall -Wextra
    -Werror -pedantic``); returns its path."""
    cmd = [_make(), "--no-print-directory", f"{code.name}_run"]
    env_cc = cc or os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if env_cc is None:
        raise CodegenError("no C compiler found (cc, gcc); install one (Debian: "
                           "apt-get install gcc) or set CC.")
    cmd.append(f"CC={env_cc}")
    _run(cmd, code.directory, f"building {code.name}_run")
    return code.harness


def run_harness(code: CModel, *, t_stop: float | None = None, params: dict | None = None,
                out: Path | None = None) -> SimResult:
    """Run the harness from t0 to ``t_stop`` (parameters by instance path, SI) and read
    its CSV back."""
    if not code.harness.exists():
        build(code)
    out = Path(out) if out is not None else code.directory / f"{code.name}_c.csv"
    cmd = [str(code.harness.resolve()), "--out", str(out.resolve())]
    if t_stop is not None:
        cmd += ["--t-stop", repr(float(t_stop))]
    for key, value in (params or {}).items():
        cmd += ["--set", f"{key}={float(value)!r}"]
    _run(cmd, code.directory, f"running {code.name}_run")
    return SimResult.load(out)


def measure_ns_per_step(code: CModel, steps: int = 1_000_000, repeats: int = 3) -> dict:
    """Time ``steps`` steps of the compiled harness, best of ``repeats``."""
    if not code.harness.exists():
        build(code)
    runs = []
    for _ in range(max(1, repeats)):
        proc = _run([str(code.harness.resolve()), "--bench", str(int(steps))],
                    code.directory, f"timing {code.name}_run")
        runs.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    best = min(runs, key=lambda r: r["ns_per_step"])
    return {"ns_per_step": best["ns_per_step"], "steps": best["steps"],
            "all_ns_per_step": [r["ns_per_step"] for r in runs],
            "finite": all(r["status"] == 0 for r in runs)}


def have_cross_compiler(prefix: str = "arm-none-eabi-") -> bool:
    """Whether the ARM bare-metal toolchain (gcc and size) is on the PATH."""
    return bool(shutil.which(prefix + "gcc") and shutil.which(prefix + "size"))


def cross_compile(code: CModel, *, prefix: str = "arm-none-eabi-") -> dict:
    """Build the Cortex-M4 image (``make arm``) and report its sizes.

    Returns ``flash_bytes`` (text + data: code, constants and initial values) and
    ``ram_bytes`` (data + bss: the static model instance and the C library's variables;
    the stack comes on top). The M4's FPU is single precision: the double-precision
    arithmetic of the model runs in software there.
    """
    if not have_cross_compiler(prefix):
        raise CodegenError(f"{prefix}gcc not found: cannot cross-compile for a Cortex-M4. "
                           "Install it (Debian: apt-get install gcc-arm-none-eabi "
                           "libnewlib-arm-none-eabi).")
    _run([_make(), "--no-print-directory", f"{code.name}_arm.elf",
          f"ARM_CC={prefix}gcc"], code.directory, f"cross-compiling {code.name}")
    elf = code.directory / f"{code.name}_arm.elf"
    # `size` runs in the code's folder: give it the name there, not a path relative to
    # the caller's folder (which a relative --out would be)
    proc = _run([prefix + "size", "-B", elf.name], code.directory, "arm size")
    text, data, bss = (int(v) for v in proc.stdout.strip().splitlines()[-1].split()[:3])
    return {"target": "cortex-m4 (thumb, fpv4-sp-d16 hard float)", "elf": str(elf),
            "text_bytes": text, "data_bytes": data, "bss_bytes": bss,
            "flash_bytes": text + data, "ram_bytes": data + bss}
