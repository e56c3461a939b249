"""The domains of the foundation library (docs/modeling.md; the seed thesis's table of
across and through variables). Colours follow Simscape's connection lines."""

from mechatron.core.domain import Domain

__all__ = ["ELECTRICAL", "ROTATIONAL", "TRANSLATIONAL", "THERMAL", "MAGNETIC", "HYDRAULIC",
           "SIGNAL"]

ELECTRICAL = Domain("electrical", "voltage v (V)", "current i (A)", color="#1f5fbf",
                    needs_reference=True,
                    hint="Is an electrical reference missing, or a pin left unconnected?")
ROTATIONAL = Domain("rotational", "angular velocity w (rad/s)", "torque tau (N*m)",
                    color="#2e8b3a",
                    hint="Is a rotational reference missing, or a flange left unconnected?")
TRANSLATIONAL = Domain("translational", "velocity v (m/s)", "force f (N)", color="#6cc04a",
                       hint="Is a translational reference missing, or a flange left "
                            "unconnected?")
THERMAL = Domain("thermal", "temperature T (K)", "heat flow Q (W)", color="#e07b00",
                 needs_reference=False,
                 hint="Is a thermal port left unconnected?")
MAGNETIC = Domain("magnetic", "magnetomotive force mmf (A)", "flux phi (Wb)",
                  color="#c0262d", needs_reference=True,
                  hint="Is a magnetic reference missing, or a port left unconnected?")
HYDRAULIC = Domain("hydraulic", "pressure p (Pa)", "volumetric flow rate q (m^3/s)",
                   color="#8b5a2b", needs_reference=True,
                   hint="Is a hydraulic reference (reservoir) missing, or a port left "
                        "unconnected?")
SIGNAL = Domain("signal", "value", "(none: causal)", color="#000000")
