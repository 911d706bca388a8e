"""cosim: the co-simulation master for FMUs and Python components, and scenarios.

Layer 4 of the design.  Arrives with the FMU/co-simulation issue.
"""
__all__: list[str] = []
