"""Models of the problem files in this folder, as a model file of the user's own.

A problem file names a model of its own with ``[model] file = "rigs.py"`` and
``class = "DCMotorRig"`` (the path is relative to the problem file; nothing needs to be
on the import path). Run as a script, it prints the rigs' parameters.
"""

from mechatron.estimation.bench import DCMotorRig
from mechatron.models.dc_motor_control import DCMotorSpeedPIVoltage

__all__ = ["DCMotorRig", "DCMotorSpeedPIVoltage"]

if __name__ == "__main__":
    import mechatron as mt
    for cls in (DCMotorRig, DCMotorSpeedPIVoltage):
        cm = mt.compile_model(cls())
        print(cls.__name__, ", ".join(cm.param_names))
