"""Model documents: schematics (:mod:`~mechatron.report.diagram`) and the HTML report of a
database model (:mod:`~mechatron.report.html`)."""

from mechatron.report.diagram import Diagram, diagram_dot, write_diagram

__all__ = ["Diagram", "diagram_dot", "write_diagram"]
