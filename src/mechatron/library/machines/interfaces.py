"""What every machine shares: the structural options (back-EMF shape, heat port) and the
heat port that takes the losses (MSL's ``useThermalPort``)."""

from __future__ import annotations

from mechatron.library._options import OptionDispatch
from mechatron.library.thermal.interfaces import HeatPort

__all__ = ["MachineOptions", "HeatPortLosses", "thermal_variant"]


class MachineOptions(OptionDispatch):
    """Constructor option ``use_heat_port`` (default False): with True the machine is built
    as its heat-port variant (registered by :func:`thermal_variant`), whose ``heat_port``
    takes all its losses; without it the losses stay inside (no port, no equation).
    Subclasses with more options extend ``_options`` and ``_variant``."""

    _options = {"use_heat_port": False}
    _thermal: type | None = None        # the heat-port variant, set by thermal_variant
    _plain: type | None = None          # the variant without, set by thermal_variant

    @classmethod
    def _variant(cls, options, kwargs):
        if options["use_heat_port"]:
            return cls._thermal or cls
        return cls._plain or cls

    def _loss_power(self):
        """The machine's total losses (an expression of its parts' variables, W)."""
        raise NotImplementedError


class HeatPortLosses:
    """Mixin of the heat-port variants: ``heat_port.Q == -P_loss`` (the losses leave the
    machine at its heat port; ``P_loss`` from the machine's ``_losses``)."""

    heat_port = HeatPort(doc="Heat port taking the machine's losses (copper, friction)")

    def equations(self):
        return [self.heat_port.Q == -self._loss_power()]


def thermal_variant(cls: type, losses: str) -> type:
    """Make and register the heat-port variant of the machine class ``cls``: a subclass
    named ``<cls>WithHeatPort`` in ``cls``'s module, selected by ``use_heat_port=True``.
    ``losses`` describes ``P_loss`` for its docstring."""
    name = f"{cls.__name__}WithHeatPort"
    doc = (f"{cls.__name__} with a heat port (``use_heat_port=True``; MSL's "
           f"``useThermalPort``): as :class:`{cls.__name__}`, and the losses leave at "
           "``heat_port``::\n\n"
           f"        heat_port.Q == -P_loss,  P_loss = {losses}\n\n"
           "    The machine's parameters do not depend on the port's temperature (no "
           "temperature coefficient of the resistances).\n    ")
    variant = type(name, (HeatPortLosses, cls), {
        "__module__": cls.__module__, "__qualname__": name, "__doc__": doc,
        "_options": {**cls._options, "use_heat_port": True}})
    cls._thermal = variant
    cls._plain = cls
    variant._thermal = variant
    variant._plain = cls
    return variant
