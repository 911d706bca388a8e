"""fmus: bond graph -> FMU (generated C, compiled) and FMU loading helpers.

Layer 2 of the design (imports only ``bondgraph``).  Its export arrives with the FMU issue.
"""
__all__: list[str] = []
