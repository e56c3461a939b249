"""Physical domains.

A domain is named by its across/through pair (docs/modeling.md) and carries what tools
need to know of it: the colour of its connection lines in diagrams, and whether every
network of it needs a reference (a ground). A connector class names its domain (``class
Pin(Connector, domain=ELECTRICAL)``); adding a domain means creating a :class:`Domain`
and a connector, without editing any base class.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Domain"]


@dataclass(frozen=True)
class Domain:
    """A physical domain, identified by name.

    Parameters
    ----------
    name : str
        Short name, e.g. ``"electrical"``.
    across, through : str
        Descriptions of the across and through quantities with their units, e.g.
        ``"voltage (V)"``; used in docs and diagnostics.
    color : str
        Connection line colour in diagrams (hex RGB).
    needs_reference : bool
        Whether a network of this domain without a reference component is an error
        (electrical: a ground is needed; rotational: inertias are referenced implicitly).
    hint : str
        What to try when a network of this domain is singular.
    """

    name: str
    across: str
    through: str
    color: str = "#000000"
    needs_reference: bool = False
    hint: str = ""

    def __str__(self) -> str:
        return self.name
