"""Errors that name the culprit: every bondcosim error is a BondcosimError and a builtin.

Run:  python examples/errors.py
"""
from plants import library
from bondgraph.numerics import simulate
from bondgraph.errors import BondcosimError


def main():
    graph = library.build("rlc")
    messages = {}
    attempts = {
        "negative span": lambda: simulate(graph, (0.0, -1.0)),
        "unknown input": lambda: simulate(graph, (0.0, 1.0), inputs={"Q": 1.0}),
        "too many samples": lambda: simulate(graph, (0.0, 1e9), output_interval=1e-6),
    }
    for label, attempt in attempts.items():
        try:
            attempt()
        except BondcosimError as exc:          # also a ValueError / MemoryError / ...
            builtin = next(b.__name__ for b in type(exc).__mro__ if b.__module__ == "builtins")
            messages[label] = (type(exc).__name__, builtin, str(exc))
            print(f"{label}: {type(exc).__name__} ({builtin}): {exc}")
    return messages


if __name__ == "__main__":
    main()
