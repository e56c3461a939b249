"""The modeling language: domains, connectors, declarations, components, equations."""

from mechatron.core.component import Component, Connect, Connector, Element, System
from mechatron.core.context import connect, der, if_else, logic_and, logic_not, logic_or
from mechatron.core.declarations import (Across, Discrete, Input, Output, Parameter,
                                         ParameterExpression, Start, Through, Variable)
from mechatron.core.domain import Domain
from mechatron.core.events import (Clock, EventAction, initial, pre, reinit, sample,
                                   steady_state, terminal, when)

__all__ = ["Component", "Connector", "Element", "System", "Connect", "connect", "der",
           "if_else", "Across", "Through", "Input", "Output", "Parameter",
           "ParameterExpression", "Variable", "Start", "Domain", "Clock", "EventAction",
           "sample", "when", "Discrete", "pre", "initial", "terminal", "reinit",
           "steady_state", "logic_and", "logic_or", "logic_not"]
