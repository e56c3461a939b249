"""Code generation for real time: standalone C99 and FMUs from the fixed-step step
function that the desktop fixed-step run evaluates (docs/realtime.md).

- :func:`generate_c` writes the C files; :func:`build` compiles the host harness;
  :func:`run_harness` runs it and reads its CSV back as a SimResult.
- :func:`export_fmu` writes an FMI 2.0 (co-simulation or model exchange) or FMI 3.0
  (co-simulation) FMU with sources and a binary for this platform.
"""

from mechatron.codegen._common import CodegenError
from mechatron.codegen.c import (CModel, build, cross_compile, generate_c,
                                 measure_ns_per_step, run_harness)

__all__ = ["CodegenError", "CModel", "generate_c", "build", "run_harness",
           "measure_ns_per_step", "cross_compile", "export_fmu", "demo_run"]


def export_fmu(*args, **kwargs):
    """See :func:`mechatron.codegen.fmu.export_fmu`."""
    from mechatron.codegen.fmu import export_fmu as _export
    return _export(*args, **kwargs)


def demo_run(out_dir) -> dict:
    """See :func:`mechatron.codegen.demo.demo_run`."""
    from mechatron.codegen.demo import demo_run as _demo
    return _demo(out_dir)
