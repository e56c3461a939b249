"""The compiler: model instance -> :class:`CompiledModel` (DESIGN.md §4)."""

from mechatron.compiler.compiled import CompiledModel
from mechatron.compiler.pipeline import compile_model

__all__ = ["compile_model", "CompiledModel"]
