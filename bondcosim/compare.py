"""``bondcosim compare``: a seed plant's bond graph against its block-diagram twin."""
from __future__ import annotations

from pathlib import Path

__all__ = ["compare", "MODELS"]

#: Models that have a block-diagram twin.
MODELS = ("exoskeleton", "pam")

#: Largest relative matrix difference that counts as equal.
MATRIX_RTOL = 1e-9


def _exoskeleton(plot_dir):
    from plants.blockdiagram import exoskeleton as bd

    run = bd.compare_section_5_1()
    if plot_dir is not None:
        run.plot(Path(plot_dir) / "exoskeleton_section_5_1.png")
    return run.max_abs_error, run.rms_error, bd.matrix_difference({"b_f": 0.0}) <= MATRIX_RTOL


def _pam(plot_dir):
    from plants.blockdiagram.pam_compare import compare_fig8

    run = compare_fig8(variant="full", duration=20.0)
    if plot_dir is not None:
        run.plot(Path(plot_dir) / "pam_fig8.png")
    return run.max_abs_error, run.rms_error, None   # nonlinear: no matrices to compare


def compare(model: str, *, plot_dir=None) -> dict:
    """Run the comparison of `model` and return its summary.

    Returns
    -------
    dict
        ``{"max_abs_error": {signal: value}, "rms_error": {signal: value},
        "matrices_equal": bool or None}`` (None where the model is nonlinear).
    """
    from bondgraph.errors import GraphError

    runners = {"exoskeleton": _exoskeleton, "pam": _pam}
    if model not in runners:
        raise GraphError(f"no block-diagram twin for {model!r}; compare one of {', '.join(MODELS)}")
    if plot_dir is not None:
        Path(plot_dir).mkdir(parents=True, exist_ok=True)
    max_abs, rms, equal = runners[model](plot_dir)
    return {"max_abs_error": dict(max_abs), "rms_error": dict(rms), "matrices_equal": equal}
