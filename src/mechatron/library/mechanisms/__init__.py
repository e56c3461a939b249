"""Mechanisms: converters between the rotational and translational domains.

Every converter has a rotational flange ``R`` (across ``w`` in rad/s, through ``tau`` in
N*m) and a translational flange ``T`` (across ``v`` in m/s, through ``f`` in N); its case
is grounded (the reactions go to the implicit reference). Through variables are positive
into the converter, as everywhere. Kinematics ``T.v = m R.w`` with the transmission ``m``
(m/rad); power flowing in at ``R`` (``R.tau R.w >= 0``) drives the translational side with
efficiency ``eta``, power flowing in at ``T`` drives the rotational side with
``eta_back``; the loss ``P_loss = R.tau R.w + T.f T.v`` is never negative.
"""

from mechatron.library.mechanisms.converters import (LeadScrew, RackAndPinion,
                                                     RotTransConverter, WheelAndAxle)

__all__ = ["RotTransConverter", "LeadScrew", "RackAndPinion", "WheelAndAxle"]
