"""diagnosis: mismatch location, missing-physics catalogue, refit and report.

Layer 5 of the design.  Arrives with the diagnosis issue.
"""
__all__: list[str] = []
