"""The compiler: model instance -> :class:`CompiledModel` (docs/compiler.md)."""

from mechatron.compiler.compiled import CompiledModel
from mechatron.compiler.pipeline import compile_model

__all__ = ["compile_model", "CompiledModel"]
