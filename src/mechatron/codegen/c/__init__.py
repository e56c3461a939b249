"""Standalone C99 of the fixed-step step function: generation, build, run, measurement."""

from mechatron.codegen.c.build import (build, cross_compile, measure_ns_per_step,
                                       run_harness)
from mechatron.codegen.c.generator import CModel, generate_c

__all__ = ["CModel", "generate_c", "build", "run_harness", "measure_ns_per_step",
           "cross_compile"]
