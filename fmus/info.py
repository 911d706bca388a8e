"""What an FMU offers: interfaces and variables with causality, units and start values."""
from __future__ import annotations

__all__ = ["fmu_info", "format_fmu_info"]

_CAUSALITY_ORDER = ("input", "output", "parameter", "calculatedParameter", "local",
                    "independent", "structuralParameter")


def fmu_info(path) -> dict:
    """Summary of the FMU at `path` (any FMU fmpy can read, ours or not).

    Returns
    -------
    dict
        ``name``, ``fmi_version``, ``interfaces`` (list of ``"ModelExchange"`` /
        ``"CoSimulation"``), ``generation_tool``, ``description`` and
        ``variables``: a list of dicts with ``name``, ``causality``,
        ``variability``, ``type``, ``unit``, ``start`` (None if calculated),
        ``description``, ``value_reference``; inputs first, then outputs,
        parameters, locals.

    Raises
    ------
    FMUError
        Missing file, not a zip, no or unreadable ``modelDescription.xml``.
    """
    from .loading import read_fmu, variable_unit
    md = read_fmu(path)
    interfaces = [name for name, attr in (("ModelExchange", "modelExchange"),
                                          ("CoSimulation", "coSimulation")) if getattr(md, attr)]
    rank = {c: i for i, c in enumerate(_CAUSALITY_ORDER)}
    variables = [{
        "name": v.name, "causality": v.causality, "variability": v.variability, "type": v.type,
        "unit": variable_unit(v), "start": None if v.start is None else v.start,
        "description": v.description or "", "value_reference": v.valueReference,
    } for v in md.modelVariables]
    variables.sort(key=lambda v: rank.get(v["causality"], len(rank)))
    return {"name": md.modelName, "fmi_version": md.fmiVersion, "interfaces": interfaces,
            "generation_tool": md.generationTool or "", "description": md.description or "",
            "variables": variables}


def format_fmu_info(info: dict) -> str:
    """`info` from :func:`fmu_info` as an aligned text table."""
    lines = [f"{info['name']}  (FMI {info['fmi_version']}; {', '.join(info['interfaces'])}"
             + (f"; made by {info['generation_tool']}" if info["generation_tool"] else "") + ")"]
    if info["description"]:
        lines.append(info["description"])
    rows = [("name", "causality", "variability", "unit", "start", "description")]
    for v in info["variables"]:
        rows.append((v["name"], v["causality"], v["variability"], v["unit"] or "-",
                     "" if v["start"] is None else str(v["start"]), v["description"]))
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    for r in rows:
        lines.append("  ".join(c.ljust(w) for c, w in zip(r[:5], widths)) + "  " + r[5])
    return "\n".join(line.rstrip() for line in lines)
