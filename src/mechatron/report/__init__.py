"""Model documents: schematics (:mod:`~mechatron.report.diagram`) and the HTML report of a
database model (:mod:`~mechatron.report.html`).

The names are imported when first read: the command line imports this package to add
its subcommands, and the diagram module brings the compiler with it."""

__all__ = ["Diagram", "diagram_dot", "write_diagram"]

TYPE_CHECKING = False       # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:           # for type checkers and the API reference
    from mechatron.report.diagram import Diagram, diagram_dot, write_diagram


def __getattr__(name: str):
    if name in __all__:
        from mechatron.report import diagram
        value = globals()[name] = getattr(diagram, name)
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
