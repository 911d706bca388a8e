"""The benchmark's truth plants by name."""
from __future__ import annotations

from . import plants_textbook as _tb

__all__ = ["PLANTS", "plant"]

PLANTS = {
    "msd": _tb.mass_spring_damper,
    "dc-motor": _tb.dc_motor,
    "rlc": _tb.rlc,
    "tanks": _tb.coupled_tanks,
    "geared-inertias": _tb.geared_inertias,
}


def plant(name: str):
    """A fresh truth plant `name`."""
    try:
        return PLANTS[name]()
    except KeyError:
        raise KeyError(f"no benchmark plant {name!r}; known: {', '.join(PLANTS)}") from None
