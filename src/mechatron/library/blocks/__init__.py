"""Causal signal blocks (the Simulink side).

Outputs are ``y``, inputs ``u`` (``u1``, ``u2``, ... for several). Modules: sources, math,
continuous, discrete (sampled, with sample times and offsets), nonlinear, logic and
routing (including lookup tables), and converters to physical quantities with units.
Every name is importable from ``mechatron.library.blocks``.
"""

from mechatron.library.blocks.continuous import *  # noqa: F401,F403
from mechatron.library.blocks.continuous import __all__ as _continuous
from mechatron.library.blocks.discrete import *  # noqa: F401,F403
from mechatron.library.blocks.discrete import __all__ as _discrete
from mechatron.library.blocks.logic import *  # noqa: F401,F403
from mechatron.library.blocks.logic import __all__ as _logic
from mechatron.library.blocks.math import *  # noqa: F401,F403
from mechatron.library.blocks.math import __all__ as _math
from mechatron.library.blocks.nonlinear import *  # noqa: F401,F403
from mechatron.library.blocks.nonlinear import __all__ as _nonlinear
from mechatron.library.blocks.sources import *  # noqa: F401,F403
from mechatron.library.blocks.sources import __all__ as _sources

__all__ = [*_sources, *_math, *_continuous, *_discrete, *_nonlinear, *_logic]
