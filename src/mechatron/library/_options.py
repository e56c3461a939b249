"""Structural options: constructor keywords that choose a variant class (Modelica's
conditional declarations, ``parameter Boolean useHeatPort`` with ``HeatPort heatPort if
useHeatPort``).

A variant declares more (a heat port, an angle state) or other equations (a trapezoidal
back EMF); choosing it when the part is built keeps the compiled size of the models that do
not ask for it unchanged. Every variant is a named, module-level class (documented and
checked for balance like any other part); the option only picks it::

    class Inertia(OptionDispatch, Component):
        _options = {"use_phi": False}          # option keywords and their defaults

        @classmethod
        def _variant(cls, options, kwargs):    # options merged over the defaults
            return InertiaWithAngle if options["use_phi"] or "phi" in kwargs else cls
"""

from __future__ import annotations

__all__ = ["OptionDispatch"]


class OptionDispatch:
    """Mixin (before :class:`~mechatron.Component` in the bases): the constructor keywords
    listed in ``_options`` (name -> default) are taken off and passed to ``_variant``,
    which returns the class to instantiate (``cls``, a subclass or a sibling class whose
    own ``_options`` defaults select itself)."""

    _options: dict[str, object] = {}

    def __new__(cls, *args, **kwargs):
        options = {k: kwargs[k] for k in cls._options if k in kwargs}
        target = cls._variant({**cls._options, **options}, kwargs)
        if issubclass(target, cls):
            return object.__new__(target)      # Python calls its __init__ next
        # a sibling class (PMSM(emf="trapezoidal") is a TrapezoidalPMSM): built here, as
        # Python calls __init__ only on instances of cls
        return target(*args, **kwargs)

    def __init__(self, **kwargs):
        for key in type(self)._options:
            kwargs.pop(key, None)
        super().__init__(**kwargs)

    @classmethod
    def _variant(cls, options: dict, kwargs: dict) -> type:
        return cls
