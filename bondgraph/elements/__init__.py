"""Bond-graph elements.

Sources ``Se, Sf, MSe, MSf``; storage ``I, C``; ``R``; two-ports ``TF, GY,
MTF, MGY``; junctions ``Zero`` (0) and ``One`` (1); multiport fields
``CField, IField``; the pneumatic chamber ``PneumaticChamber`` (a two-port C-field);
:class:`EquationElement` for pseudo-bond graphs and
sampled/switched laws.
"""
from .base import ELEMENT_KINDS, EFFORT, FLOW, Element
from .equation import EquationElement
from .fields import CField, IField
from .junctions import One, Zero
from .pneumatic import PneumaticChamber
from .resistor import R
from .sources import MSe, MSf, Se, Sf
from .storage import C, I
from .twoports import GY, MGY, MTF, TF

__all__ = ["Element", "ELEMENT_KINDS", "EFFORT", "FLOW", "Se", "Sf", "MSe", "MSf", "I", "C", "R",
           "TF", "GY", "MTF", "MGY", "Zero", "One", "CField", "IField", "EquationElement",
           "PneumaticChamber", "SOURCE_KINDS", "TWO_PORT_KINDS"]

#: the kinds of the sources (an imposed effort or flow, constant or modulated)
SOURCE_KINDS = frozenset(c.kind for c in (Se, Sf, MSe, MSf))
#: the kinds of the power-conserving two-ports (transformers and gyrators, constant or modulated)
TWO_PORT_KINDS = frozenset(c.kind for c in (TF, MTF, GY, MGY))
