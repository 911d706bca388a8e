"""``python -m diagnosis.cases OUTDIR [CASE ...]``: regenerate the recordings and ``cases.json``."""
from __future__ import annotations

import sys


def main(argv=None) -> int:
    """Write every case (or the named ones) into OUTDIR; print one line per case."""
    from .definitions import CASES, case
    from .generate import write_all
    args = list(sys.argv[1:] if argv is None else argv)
    if not args or args[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if args else 2
    chosen = tuple(case(n) for n in args[1:]) or CASES
    manifest = write_all(args[0], chosen, progress=True)
    for e in manifest["cases"]:
        print(f"{e['name']:24s} {e['kind']:28s} effect/noise = {e.get('effect_to_noise', '-')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
