"""``modelDescription.xml`` of an exported FMU, FMI 2.0 or 3.0, from its variable layout.

Both versions list the same variables (:func:`fmus.layout.variable_layout`);
they differ in spelling: FMI 2.0 has ``ScalarVariable``/``Real`` elements and
refers to variables by 1-based index in the ModelStructure, FMI 3.0 has
``Float64`` elements, a ``time`` variable and refers to value references.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET
from datetime import datetime, timezone

from fmus.errors import UnitError
from bondgraph.units import BASE_UNITS, base_unit

__all__ = ["model_description_xml", "generation_tool"]


def generation_tool() -> str:
    """``"bondcosim <version>"`` (the installed distribution's version)."""
    try:
        from importlib.metadata import version
        return f"bondcosim {version('bondcosim')}"
    except Exception:   # noqa: BLE001 -- not installed: the name alone
        return "bondcosim"


def _num(x: float) -> str:
    return repr(float(x))


def _common_root(version: int, name: str, token: str, description: str, date: str | None,
                 meta: dict, n_indicators: int) -> ET.Element:
    attrs = {"fmiVersion": "2.0" if version == 2 else "3.0", "modelName": name}
    attrs["guid" if version == 2 else "instantiationToken"] = token
    attrs["description"] = description
    attrs.update({k: str(meta[k]) for k in ("author", "version", "copyright", "license") if meta.get(k)})
    attrs.update({"generationTool": generation_tool(),
                  "generationDateAndTime": date or datetime.now(timezone.utc)
                  .replace(microsecond=0).isoformat().replace("+00:00", "Z"),
                  "variableNamingConvention": "flat"})
    if version == 2:
        attrs["numberOfEventIndicators"] = str(n_indicators)
    return ET.Element("fmiModelDescription", attrs)


def _interfaces(root, version: int, identifier: str, model_exchange: bool, sources: list,
                directional: bool) -> None:
    state = "canGetAndSetFMUstate" if version == 2 else "canGetAndSetFMUState"
    serial = "canSerializeFMUstate" if version == 2 else "canSerializeFMUState"
    flags = {state: "true", serial: "true"}
    if directional:
        flags["providesDirectionalDerivative" if version == 2 else "providesDirectionalDerivatives"] = "true"
    if version == 2:
        flags["canNotUseMemoryManagementFunctions"] = "true"
    elements = []
    if model_exchange:
        elements.append(ET.SubElement(root, "ModelExchange", {"modelIdentifier": identifier, **flags}))
    elements.append(ET.SubElement(root, "CoSimulation", {
        "modelIdentifier": identifier, "canHandleVariableCommunicationStepSize": "true", **flags}))
    if version == 2 and sources:   # FMI 3.0 lists them in sources/buildDescription.xml
        for el in elements:
            files = ET.SubElement(el, "SourceFiles")
            for name in sources:
                ET.SubElement(files, "File", {"name": name})


def _base_unit_attrs(unit: str) -> dict:
    """BaseUnit attributes of `unit`: SI exponents, then factor and offset (when not 1, 0)."""
    exps, factor, offset = base_unit(unit)
    attrs = {b: str(exps[b]) for b in BASE_UNITS if b in exps}
    if factor != 1.0:
        attrs["factor"] = _num(factor)
    if offset != 0.0:
        attrs["offset"] = _num(offset)
    return attrs


def _units_and_categories(root, variables, experiment: dict) -> None:
    units = sorted({v.unit for v in variables if v.unit})
    if units:
        defs = ET.SubElement(root, "UnitDefinitions")
        for u in units:
            unit = ET.SubElement(defs, "Unit", {"name": u})
            try:
                ET.SubElement(unit, "BaseUnit", _base_unit_attrs(u))
            except UnitError:   # a unit text the grammar does not know: declared, no BaseUnit
                pass
    cats = ET.SubElement(root, "LogCategories")
    for c in ("logStatusWarning", "logStatusDiscard", "logStatusError"):
        ET.SubElement(cats, "Category", {"name": c})
    ET.SubElement(root, "DefaultExperiment", {k: _num(experiment[k]) for k in
                                              ("startTime", "stopTime", "stepSize") if k in experiment})


def _common_attrs(v) -> dict:
    """Attributes every FMI version writes the same way, in the standard's order."""
    attrs = {"name": v.name, "valueReference": str(v.vr)}
    if v.description:
        attrs["description"] = v.description
    attrs.update({"causality": v.causality, "variability": v.variability})
    if v.initial:
        attrs["initial"] = v.initial
    return attrs


def _range(v) -> dict:
    """``min``, ``max``, ``nominal`` attributes of a variable that has them."""
    out = {}
    for key in ("min", "max", "nominal"):
        if getattr(v, key) is not None:
            out[key] = _num(getattr(v, key))
    return out


def _fmi2_variables(root, variables) -> dict[int, int]:
    """Write the ScalarVariables; return value reference -> 1-based index."""
    mv = ET.SubElement(root, "ModelVariables")
    index = {}
    for k, v in enumerate(variables, start=1):
        index[v.vr] = k
        sv = ET.SubElement(mv, "ScalarVariable", _common_attrs(v))
        real = {}
        if v.state_vr is not None:
            real["derivative"] = str(index[v.state_vr])
        if v.unit:
            real["unit"] = v.unit
        real.update(_range(v))
        if v.start is not None:
            real["start"] = _num(v.start)
        ET.SubElement(sv, "Real", real)
    return index


def _fmi2_structure(root, variables, index) -> None:
    ms = ET.SubElement(root, "ModelStructure")
    outputs = [v for v in variables if v.causality == "output"]
    if outputs:
        el = ET.SubElement(ms, "Outputs")
        for v in outputs:
            ET.SubElement(el, "Unknown", {"index": str(index[v.vr]),
                                          "dependencies": " ".join(str(index[d]) for d in v.dependencies)})
    derivatives = [v for v in variables if v.kind == "derivative"]
    if derivatives:
        el = ET.SubElement(ms, "Derivatives")
        for v in derivatives:
            attrs = {"index": str(index[v.vr])}
            if v.dependencies is not None:
                attrs["dependencies"] = " ".join(str(index[d]) for d in v.dependencies)
            ET.SubElement(el, "Unknown", attrs)
    initial = sorted(index[v.vr] for v in variables
                     if v.initial == "calculated" and v.kind in ("output", "derivative"))
    if initial:
        el = ET.SubElement(ms, "InitialUnknowns")
        for k in initial:
            ET.SubElement(el, "Unknown", {"index": str(k)})


def _fmi3_variables(root, variables) -> None:
    mv = ET.SubElement(root, "ModelVariables")
    time = [v for v in variables if v.kind == "time"]
    for v in time + [v for v in variables if v.kind != "time"]:
        attrs = _common_attrs(v)
        if v.state_vr is not None:
            attrs["derivative"] = str(v.state_vr)
        if v.unit:
            attrs["unit"] = v.unit
        attrs.update(_range(v))
        if v.start is not None:
            attrs["start"] = _num(v.start)
        ET.SubElement(mv, "Float64", attrs)


def _fmi3_structure(root, variables) -> None:
    ms = ET.SubElement(root, "ModelStructure")
    for v in variables:
        if v.causality == "output":
            ET.SubElement(ms, "Output", {"valueReference": str(v.vr),
                                         "dependencies": " ".join(map(str, v.dependencies))})
    for v in variables:
        if v.kind == "derivative":
            attrs = {"valueReference": str(v.vr)}
            if v.dependencies is not None:
                attrs["dependencies"] = " ".join(map(str, v.dependencies))
            ET.SubElement(ms, "ContinuousStateDerivative", attrs)
    for v in variables:
        if v.initial == "calculated" and v.kind in ("output", "derivative"):
            ET.SubElement(ms, "InitialUnknown", {"valueReference": str(v.vr)})
    for v in variables:
        if v.kind == "indicator":
            ET.SubElement(ms, "EventIndicator", {"valueReference": str(v.vr)})


def model_description_xml(variables, *, version: int, name: str, identifier: str, token: str,
                          description: str = "", model_exchange: bool = True,
                          date: str | None = None, experiment: dict | None = None,
                          meta: dict | None = None, sources: list | None = None,
                          n_indicators: int = 0, directional: bool = False) -> str:
    """The ``modelDescription.xml`` text.

    Parameters
    ----------
    variables : list of FmuVariable
        From :func:`fmus.layout.variable_layout` (with the same `version`).
    version : {2, 3}
    name, identifier : str
        Model name and ``modelIdentifier`` (the shared library's name).
    token : str
        GUID (2.0) / instantiation token (3.0); the binary checks it.
    description : str
    model_exchange : bool
        Offer Model Exchange besides Co-Simulation.
    date : str, optional
        ``generationDateAndTime`` (ISO 8601); default now.  Fix it for
        reproducible files.
    experiment : dict, optional
        ``DefaultExperiment`` attributes ``startTime``, ``stopTime``,
        ``stepSize`` (s); default ``startTime`` 0 only.
    meta : dict, optional
        ``author``, ``version``, ``copyright``, ``license`` (written when not empty).
    sources : list of str, optional
        C files under ``sources/`` to list in FMI 2.0's ``<SourceFiles>``.
    n_indicators : int
        Event indicators of Model Exchange (FMI 2.0's ``numberOfEventIndicators``;
        FMI 3.0 lists the ``indicator`` variables of `variables` instead).
    directional : bool
        Declare ``providesDirectionalDerivative(s)``.

    Returns
    -------
    str
    """
    root = _common_root(version, name, token, description, date, meta or {}, n_indicators)
    _interfaces(root, version, identifier, model_exchange, sources or [], directional)
    _units_and_categories(root, variables, experiment or {"startTime": 0.0})
    if version == 2:
        _fmi2_structure(root, variables, _fmi2_variables(root, variables))
    else:
        _fmi3_variables(root, variables)
        _fmi3_structure(root, variables)
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
