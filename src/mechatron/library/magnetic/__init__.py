"""Magnetic domain: across = magnetomotive force (magnetic potential) mmf (A), through =
magnetic flux phi (Wb).

Sign rules: flux is positive when it flows **into** the component at the port. Two-port
components have ports ``A`` and ``B``: ``mmf = A.mmf - B.mmf`` and ``phi`` flows from A
to B through the component. Power is ``mmf * dphi/dt`` (not ``mmf * phi``): a reluctance
stores ``R phi^2 / 2``, an eddy-current element dissipates ``G (dphi/dt)^2``. Sources are
written like the electrical ones: ``MmfSource`` raises ``B`` by ``F`` over ``A``, a
``FluxSource`` pushes ``Phi`` out of ``B``. One-port components (reference) have a single
port ``port``. Every magnetic network needs a ``MagneticReference``.

Flux tubes from geometry and material (saturating soft iron after MSL's approximation or
a B(H) table, permanent magnets, leakage, air gaps that move and pull) are in
:mod:`~mechatron.library.magnetic.fluxtubes`.

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
from mechatron.library.magnetic.fluxtubes import (HARD_MAGNETIC, LEAKAGE_SHAPES,
                                                  SOFT_MAGNETIC, Cuboid,
                                                  CuboidOrthogonalFluxForce,
                                                  CuboidParallelFluxForce, FluxTube,
                                                  HardMagnetic, HollowCylinderAxialFlux,
                                                  HollowCylinderAxialFluxForce,
                                                  HollowCylinderRadialFlux, Leakage,
                                                  PermanentMagnet, SaturatingReluctance,
                                                  SoftMagnetic)
from mechatron.library.magnetic.interfaces import MagneticPort, TwoPort

__all__ = ["MU0", "MagneticPort", "TwoPort", "Reluctance", "AirGapReluctance",
           "VariableAirGapReluctance", "EddyCurrent", "MmfSource", "ControlledMmfSource",
           "FluxSource", "ControlledFluxSource", "MagneticReference", "FluxSensor",
           "MmfSensor", "ElectromagneticConverter", "ReluctanceForceActuator",
           "FluxTube", "SaturatingReluctance", "Cuboid", "HollowCylinderAxialFlux",
           "HollowCylinderRadialFlux", "PermanentMagnet", "Leakage",
           "CuboidParallelFluxForce", "CuboidOrthogonalFluxForce",
           "HollowCylinderAxialFluxForce", "SoftMagnetic", "HardMagnetic", "SOFT_MAGNETIC",
           "HARD_MAGNETIC", "LEAKAGE_SHAPES"]
