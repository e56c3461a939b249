"""Structural algorithms on the equation–variable bipartite graph.

Everything here works on integers, without symbols, so that each pass can be tested on
tiny hand-made systems. A system of ``n_eq`` equations in ``n_var`` variables is given
by its incidence ``adj``: ``adj[e]`` lists the variables (``0 .. n_var - 1``) appearing
in equation ``e``. Links between a variable and its time derivative are a list
``var_to_diff``: ``var_to_diff[x] == dx`` when variable ``dx`` stands for ``der(x)``,
-1 when ``der(x)`` does not appear; ``eq_to_diff`` does the same for equations.
"Unmatched" is -1 everywhere.

The passes, in the order a compiler runs them:

- `maximum_matching`: pair equations with the variables they are solved for.
- `pantelides`: differentiate the equations of a high-index DAE until its highest
  derivatives can be matched (`IndexReduction`).
- `dummy_derivatives` and `state_selection`: choose which derivatives become algebraic
  and which variables stay states.
- `block_lower_triangular` (on `strongly_connected_components`): order the matched
  equations into blocks solvable one after another; `block_order` gives them as
  arrays (`BlockOrder`).
- `tear`: reduce each algebraic loop to a few tearing variables and residuals.

Every pass is iterative (no recursion) and runs in near-linear time, so systems of
100,000 equations are routine.
"""

from .blt import (Block, BlockOrder, block_lower_triangular, block_order,
                  strongly_connected_components)
from .dummy import dummy_derivatives, state_selection
from .matching import UNMATCHED, Matching, maximum_matching
from .pantelides import IndexReduction, derivative_chains, pantelides
from .tearing import Tearing, tear

__all__ = [
    "UNMATCHED",
    "Matching",
    "maximum_matching",
    "IndexReduction",
    "pantelides",
    "derivative_chains",
    "dummy_derivatives",
    "state_selection",
    "Block",
    "strongly_connected_components",
    "block_lower_triangular",
    "BlockOrder",
    "block_order",
    "Tearing",
    "tear",
]
