"""Magnetic domain: across = magnetomotive force (magnetic potential) mmf (A), through =
magnetic flux phi (Wb).

Sign rules: flux is positive when it flows **into** the component at the port. Two-port
components have ports ``A`` and ``B``: ``mmf = A.mmf - B.mmf`` and ``phi`` flows from A
to B through the component. Power is ``mmf * dphi/dt`` (not ``mmf * phi``): a reluctance
stores ``R phi^2 / 2``, an eddy-current element dissipates ``G (dphi/dt)^2``. Sources are
written like the electrical ones: ``MmfSource`` raises ``B`` by ``F`` over ``A``, a
``FluxSource`` pushes ``Phi`` out of ``B``. One-port components (reference) have a single
port ``port``. Every magnetic network needs a ``MagneticReference``.

The ``ElectromagneticConverter`` couples to electrical pins ``p``/``n``; the
``ReluctanceForceActuator`` to translational flanges ``rod``/``case``.
"""

from mechatron.library.magnetic.components import (MU0, AirGapReluctance,
                                                   ControlledFluxSource,
                                                   ControlledMmfSource, EddyCurrent,
                                                   FluxSensor, FluxSource,
                                                   MagneticReference, MmfSensor, MmfSource,
                                                   Reluctance, VariableAirGapReluctance)
from mechatron.library.magnetic.converters import (ElectromagneticConverter,
                                                   ReluctanceForceActuator)
from mechatron.library.magnetic.interfaces import MagneticPort, TwoPort

__all__ = ["MU0", "MagneticPort", "TwoPort", "Reluctance", "AirGapReluctance",
           "VariableAirGapReluctance", "EddyCurrent", "MmfSource", "ControlledMmfSource",
           "FluxSource", "ControlledFluxSource", "MagneticReference", "FluxSensor",
           "MmfSensor", "ElectromagneticConverter", "ReluctanceForceActuator"]
