"""Where on a model a correction is attached: a junction, an input, an output or a law."""
from __future__ import annotations

from dataclasses import dataclass
from .errors import DiagnosisError

__all__ = ["Place", "PLACE_KINDS"]

#: ``junction``: an extra effort at a 1-junction or an extra flow at a 0-junction;
#: ``input``: the recorded input is transformed before it reaches the model (actuator effects);
#: ``output``: the model output is transformed before it is compared (sensor effects);
#: ``law``: an element's constitutive law whose bond ends at no junction, corrected in series
#: (effort) or beside it (flow) (:mod:`diagnosis.law_places`).
PLACE_KINDS = ("junction", "input", "output", "law")


@dataclass(frozen=True)
class Place:
    """A place on a model.

    Parameters
    ----------
    kind : {"junction", "input", "output", "law"}
    name : str
        The junction's element name, the input's / output's name, or the element owning the law.
    bond : str, optional
        For a junction, the bond the correction is thought to act on (reporting only); for a
        law, the law's bond.

    Examples
    --------
    >>> str(Place("junction", "v_mass"))
    'junction v_mass'
    """

    kind: str
    name: str
    bond: str | None = None

    def __post_init__(self):
        if self.kind not in PLACE_KINDS:
            raise DiagnosisError(f"place kind {self.kind!r} is not one of {PLACE_KINDS}")
        if not isinstance(self.name, str) or not self.name:
            raise DiagnosisError(f"place name must be a non-empty string, got {self.name!r}")

    def __str__(self) -> str:
        return f"{self.kind} {self.name}"
