"""The compiler: model instance -> :class:`CompiledModel` (docs/compiler.md).

`compile_model` is imported when first read: loading and simulating a compiled model
needs `CompiledModel` alone, not the passes (nor the unit registry they build)."""

from mechatron.compiler.compiled import CompiledModel

TYPE_CHECKING = False       # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:           # for type checkers and the API reference
    from mechatron.compiler.pipeline import compile_model

__all__ = ["compile_model", "CompiledModel"]


def __getattr__(name: str):
    if name == "compile_model":
        from mechatron.compiler.pipeline import compile_model
        globals()[name] = compile_model     # later reads are plain attribute lookups
        return compile_model
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
