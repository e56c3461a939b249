"""Physical signals: unit-carrying signals, their math, and converters to and from causal
signals.

A physical signal is a directed (causal) connection ``Output -> Input`` whose value is an
SI float and whose declarations carry a unit. Connecting an output to an input of another
dimension is a :class:`~mechatron.errors.UnitError` when the model compiles; dimensionless
signals (``"1"``, the plain causal signals of :mod:`mechatron.library.blocks`) connect to
anything. ``SignalToPhysical(unit=...)`` gives a plain signal its unit (scaling ``mV``,
``rpm``, ``bar`` to SI), ``PhysicalToSignal(unit=...)`` reads one back as a number in a
chosen unit. Ports: inputs ``u`` (``u1``, ``u2``), output ``y``; units are constructor
keywords (``unit``, ``unit_in``/``unit_out``, ``unit1``/``unit2``). There are no
conserving ports, hence no across/through pair and no reference in this domain.
"""

from mechatron.library.physical_signals.blocks import (PhysicalToSignal, PSAdd,
                                                       PSConstant, PSGain, PSIntegrator,
                                                       PSProduct, PSSaturation,
                                                       PSSubtract, SignalToPhysical)
from mechatron.library.physical_signals.interfaces import UnitBlock, si_factor, unit_expr

__all__ = ["UnitBlock", "unit_expr", "si_factor", "SignalToPhysical", "PhysicalToSignal",
           "PSConstant", "PSGain", "PSAdd", "PSSubtract", "PSProduct", "PSSaturation",
           "PSIntegrator"]
