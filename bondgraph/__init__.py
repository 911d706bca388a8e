"""bondgraph: the modelling language of bondcosim.

Build a :class:`BondGraph` from elements (``Se, Sf, MSe, MSf, I, C, R, TF,
GY, MTF, MGY, Zero, One, CField, IField, PneumaticChamber, EquationElement``), connect them with
bonds, state physical-domain conditions with :class:`Guard`, and derive explicit state equations with :meth:`BondGraph.equations`
(a :class:`StateEquations`), and linearise them (``linearize``, a :class:`LinearModel`).
The numerics (C generation, compiled evaluation, ``simulate``, results) are in
:mod:`bondgraph.numerics`, which imports this language and is never imported by it.
"""
from .elements import (C, CField, EquationElement, GY, I, IField, MGY, MSe, MSf, MTF, One, PneumaticChamber, R,
                       Se, Sf, TF, Zero, Element, ELEMENT_KINDS)
from .errors import (BondcosimError, CausalityError, DerivationError, DuplicateNameError, ExpressionError,
                     DomainError, GraphError, JunctionError, ParameterError, PortError, SchemaError,
                     UnknownElementKindError, UnknownNameError)
from .graph import Bond, BondGraph, Output, Port
from .guards import Guard
from .params import DOMAINS, Param
from .system import CausalityReport, StateEquations

__all__ = [
    "BondGraph", "Bond", "Port", "Output", "Param", "DOMAINS", "StateEquations", "CausalityReport",
    "Element", "ELEMENT_KINDS", "Se", "Sf", "MSe", "MSf", "I", "C", "R", "TF", "GY", "MTF", "MGY",
    "Zero", "One", "CField", "IField", "EquationElement", "PneumaticChamber", "Guard", "DomainError",
    "BondcosimError", "GraphError", "CausalityError", "DerivationError", "DuplicateNameError",
    "ExpressionError", "JunctionError", "ParameterError", "PortError", "SchemaError",
    "UnknownElementKindError", "UnknownNameError", "linearize", "LinearModel",
]


_LAZY = {  # imported on first use: fast CLI start
    "linearize": ("linearization", "linearize"),
    "LinearModel": ("linear_model", "LinearModel"),
}


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module 'bondgraph' has no attribute {name!r}")
    import importlib
    module, attr = _LAZY[name]
    value = getattr(importlib.import_module(f".{module}", __name__), attr)
    globals()[name] = value
    return value
