"""The ``bondcosim`` console script: one subcommand per library call.

Examples
--------
  bondcosim list
  bondcosim equations mass-spring-damper
  bondcosim equations my_graph.json --json
  bondcosim draw dc-motor -o dc_motor.png
  bondcosim simulate rlc --stop-time 0.2 --input "V=sin(100*t)" -o rlc.csv --plot rlc.png
  bondcosim compare exoskeleton --json --plot figures
  bondcosim export-fmu pam -o pam.fmu --fmi 3
  bondcosim export-fmu exoskeleton -o exo.fmu --solver dopri --tolerance 1e-6 --max-substeps 1e4
  bondcosim fmu-info pam.fmu
  bondcosim cosim pam-pi --json --plot figures
  bondcosim diagnose mass-spring-damper rec.csv --input F=force:N --output x=pos:mm --report out --json
  bondcosim montecarlo pam-ukf --samples 200 --vary "A1=normal(1,0.1)*nominal" --quick --out mc/
  bondcosim sweep examples/sweep_exo_grid.toml --out exo-grid/ --workers 2
  bondcosim diagnose-batch pam 'recordings/*.csv' --input u1=u1 --input u2=u2 --output psi=psi --out fleet/
  bondcosim demo
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import sys

from bondgraph.errors import BondcosimError, ExpressionError, ParameterError

from . import __version__

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (``bondcosim simulate: error: ...``), exit status 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bondcosim", description="Bond-graph modelling, FMU export and co-simulation.",
        epilog=__doc__.split("Examples\n--------\n", 1)[1]
        + f"\nbondcosim {__version__}, Python {platform.python_version()} on {platform.platform()}",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"bondcosim {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)

    sub.add_parser("list", help="name the built-in models, one line each")

    p = sub.add_parser("equations", help="derive and print the state equations of MODEL")
    p.add_argument("model", help="built-in name, graph .json file, or .py file with build()")
    fmt = p.add_mutually_exclusive_group()
    fmt.add_argument("--json", action="store_true",
                     help="print states, inputs, outputs, parameters, f, h and A-D (linearised at the "
                          "model's default operating point) as JSON")
    fmt.add_argument("--latex", action="store_true", help="print a LaTeX aligned block")
    p.add_argument("--at", action="append", default=[], metavar="NAME=VALUE",
                   help="with --json: linearise at this state/input value (SI; repeatable) instead of "
                        "the model's default operating point")
    p.add_argument("--flat", action="store_true",
                   help="print every right-hand side fully substituted (default: the ordered causal "
                        "assignments, named intermediates such as valve1.alpha, then the state equations)")

    p = sub.add_parser("draw", help="draw MODEL with power half-arrows and causal strokes")
    p.add_argument("model")
    p.add_argument("-o", "--output", required=True, help="output file (.png, .svg or .pdf)")

    p = sub.add_parser("simulate", help="simulate MODEL and write a CSV (and optionally a plot)")
    p.add_argument("model")
    p.add_argument("--stop-time", type=float, required=True, help="end time, s")
    p.add_argument("--start-time", type=float, default=0.0, help="start time, s (default 0)")
    p.add_argument("--input", action="append", default=[], metavar="NAME=EXPR",
                   help="input as a number or an expression of t, e.g. 'V=12*Heaviside(t-0.1)' (repeatable)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter value, SI units (repeatable)")
    p.add_argument("--output-interval", type=float, default=None, help="sample interval of the results, s")
    p.add_argument("-o", "--output", required=True, help="results CSV file")
    p.add_argument("--plot", default=None, help="also save a plot (.png/.svg/.pdf)")
    p.add_argument("--stream", action="store_true",
                   help="write the CSV segment by segment as the simulation runs (bounded memory, for runs "
                        "too long to hold; needs --output-interval, not --plot)")

    p = sub.add_parser("compare", help="a seed plant's bond graph against its block-diagram model")
    p.add_argument("model", choices=["exoskeleton", "pam"])
    p.add_argument("--json", action="store_true",
                   help="print max_abs_error, rms_error per signal and matrices_equal as JSON")
    p.add_argument("--plot", default=None, metavar="DIR", help="save the overlay/difference plots in DIR")

    p = sub.add_parser("export-fmu", help="export MODEL as a binary FMU (Co-Simulation, and "
                       "Model Exchange for smooth models)")
    p.add_argument("model")
    p.add_argument("-o", "--output", required=True, help="output .fmu file")
    p.add_argument("--fmi", type=int, choices=[2, 3], default=2, help="FMI version (default 2)")
    p.add_argument("--solver", choices=["rk4", "dopri"], default="rk4",
                   help="Co-Simulation solver the FMU starts with: fixed-step RK4 or variable-step "
                        "Dormand-Prince 5(4) (models without held variables); an importer may change "
                        "its 'solver' parameter (default rk4)")
    p.add_argument("--solver-step", type=float, default=None, metavar="S",
                   help="largest internal RK4 sub-step (Dormand-Prince: first step tried), s "
                        "(default from the model)")
    p.add_argument("--tolerance", type=float, default=1e-8,
                   help="relative tolerance of Dormand-Prince (default 1e-8)")
    p.add_argument("--max-substeps", type=float, default=1e6, metavar="N",
                   help="most internal sub-steps one doStep may take before it returns Discard "
                        "(default 1e6)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="parameter start value (repeatable)")
    p.add_argument("--stop-time", type=float, default=None, metavar="S",
                   help="DefaultExperiment stop time, s (default from the model's time constants)")
    p.add_argument("--step-size", type=float, default=None, metavar="S",
                   help="DefaultExperiment communication step, s (default stop time / 1000)")
    p.add_argument("--identifier", default=None, help="modelIdentifier (default from the model name)")
    p.add_argument("--description", default=None, help="model description text")
    for flag, default, what in (("--author", "bondcosim", "author"), ("--fmu-version", "1.0", "version"),
                                ("--license", "MIT", "license"), ("--copyright", "", "copyright")):
        p.add_argument(flag, default=default, help=f"{what} written into modelDescription.xml "
                       f"(default {default!r}; empty: left out)")

    p = sub.add_parser("fmu-info", help="list an FMU's variables with causality, units and start values")
    p.add_argument("fmu", help=".fmu file (any FMI 2.0/3.0 FMU)")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")

    p = sub.add_parser("cosim", help="run a closed-loop scenario: plant FMU, estimators and "
                       "controllers in the co-simulation master")
    p.add_argument("scenario", help="scenario name (bondcosim cosim --list)", nargs="?")
    p.add_argument("--list", action="store_true", help="list the scenarios")
    p.add_argument("--json", action="store_true", help="print the numbers as JSON")
    p.add_argument("--plot", default=None, metavar="DIR", help="save the scenario's plots in DIR")

    p = sub.add_parser("diagnose", help="locate and name what MODEL leaves out of a recording; "
                       "fit it and show the held-out fit improve")
    p.add_argument("model", help="built-in name, graph .json file, or .py file with build()")
    p.add_argument("recording", help="CSV file: a time column and named signals")
    p.add_argument("--input", action="append", default=[], metavar="NAME=COLUMN[:UNIT]",
                   help="model input driven by a recorded column, converted from UNIT (repeatable)")
    p.add_argument("--output", action="append", default=[], required=True, metavar="NAME=COLUMN[:UNIT]",
                   help="model output measured by a recorded column, converted from UNIT (repeatable)")
    p.add_argument("--time", default=None, metavar="COLUMN[:UNIT]",
                   help="time column (default t, time, t_s or the first column)")
    p.add_argument("--holdout", type=float, default=0.3,
                   help="fraction of the recording, at its end, held out of fitting (default 0.3)")
    p.add_argument("--uncertain", action="append", default=[], metavar="PARAM",
                   help="nominal parameter to refit alongside (repeatable)")
    p.add_argument("--top", type=int, default=3, help="graph places whose candidates are fitted (default 3)")
    p.add_argument("--max-effects", type=int, default=2, metavar="N",
                   help="most missing effects to find, one per round (default 2)")
    p.add_argument("--noise", action="append", default=[], metavar="NAME=SIGMA[:UNIT]",
                   help="known noise standard deviation of a measured output (default: estimated)")
    p.add_argument("--keep-spikes", action="store_true",
                   help="use every sample as recorded (default: a single sample that stands out of its neighbours "
                        "by over 10 noise standard deviations where nothing else does is replaced, and named)")
    p.add_argument("--report", default=None, metavar="DIR",
                   help="write diagnosis.json, diagnosis.txt, plots and improved_model.json in DIR")
    p.add_argument("--json", action="store_true", help="print the result as JSON (issue 6 schema)")

    from .cli_sweeps import add_parsers
    add_parsers(sub)

    p = sub.add_parser("demo", help="the main job on built-in defaults: equations, drawings, a simulation")
    p.add_argument("--output-dir", default="demo-output", help="where figures and CSVs go (default demo-output)")
    p.add_argument("--quick", action="store_true", help="shortened closed-loop scenarios (for tests)")
    return parser


def _pairs(items, what: str) -> dict[str, str]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name or not value.strip():
            raise ExpressionError(f"{what} {item!r} is not NAME=VALUE", owner=what, expression=item)
        out[name] = value.strip()
    return out


def _cmd_list(args) -> int:
    from plants import library
    width = max(len(n) for n in library.names())
    for name in library.names():
        print(f"{name:<{width}}  {library.describe(name)}")
    return 0


def _cmd_equations(args) -> int:
    from plants import load as load_model
    if args.at and not args.json:
        raise ParameterError("--at sets the linearisation point, which only --json prints", name="--at")
    at = _numbers(args.at, "--at")
    eqs = load_model(args.model).equations()
    if args.latex:
        print(eqs.latex(flat=args.flat))
    elif args.json:
        data = eqs.to_dict()
        lin = eqs.linearize(at or None)
        result = {key: data[key] for key in ("states", "inputs", "outputs", "parameters", "f", "h",
                                             "assignments", "f_short", "h_short")}
        result.update({k: getattr(lin, k).tolist() for k in ("A", "B", "C", "D")})
        result["linearisation"] = {
            "operating_point": dict(lin.operating_point), "equilibrium": lin.is_equilibrium,
            "derivatives": dict(lin.derivatives), "kinks": list(lin.kinks)}
        print(json.dumps(result, indent=2))
    else:
        print(eqs.pretty(flat=args.flat))
    return 0


def _cmd_draw(args) -> int:
    from plants import load as load_model
    load_model(args.model).draw(args.output)
    print(f"wrote {args.output}")
    return 0


def _numbers(items, what: str = "--param") -> dict[str, float]:
    params = {}
    for name, text in _pairs(items, what).items():
        try:
            params[name] = float(text)
        except ValueError:
            raise ParameterError(f"{what} {name}={text!r}: not a number", name=name) from None
    return params


def _cmd_simulate(args) -> int:
    from bondgraph.numerics.simulation import simulate
    from plants import load as load_model
    graph = load_model(args.model)
    params = _numbers(args.param)
    inputs = {}
    for name, text in _pairs(args.input, "--input").items():
        try:
            inputs[name] = float(text)
        except ValueError:
            inputs[name] = text
    if args.stream:
        from bondgraph.numerics.simulation_stream import simulate_to_csv
        if args.output_interval is None or args.plot:
            raise ParameterError("--stream needs --output-interval and cannot --plot (the result is never "
                                 "all in memory)", name="--stream")
        done = simulate_to_csv(graph, (args.start_time, args.stop_time), args.output, inputs=inputs,
                               params=params or None, output_interval=args.output_interval,
                               progress=sys.stderr.isatty())
        print(f"wrote {args.output} ({done['samples']} samples, {done['segments']} segments)")
        return 0
    result = simulate(graph, (args.start_time, args.stop_time), inputs=inputs, params=params or None,
                      output_interval=args.output_interval, progress=sys.stderr.isatty())
    result.to_csv(args.output)
    print(f"wrote {args.output} ({len(result.t)} samples)")
    if args.plot:
        result.plot().savefig(args.plot, dpi=150)
        print(f"wrote {args.plot}")
    return 0


def _cmd_compare(args) -> int:
    from .compare import compare
    result = compare(args.model, plot_dir=args.plot)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"{args.model}: bond graph vs block diagram")
    for name, value in result["max_abs_error"].items():
        print(f"  {name:<8} max |error| {value:.3g}   rms {result['rms_error'][name]:.3g}")
    equal = result["matrices_equal"]
    print("  matrices: " + ("n/a (nonlinear model)" if equal is None else "equal" if equal else "DIFFERENT"))
    if args.plot:
        print(f"  plots in {args.plot}")
    return 0


def _cmd_export_fmu(args) -> int:
    from fmus import export
    from fmus.info import fmu_info
    from plants import load as load_model
    path = export(load_model(args.model), args.output, fmi_version=args.fmi, solver=args.solver,
                  solver_step=args.solver_step, tolerance=args.tolerance,
                  max_substeps=args.max_substeps, params=_numbers(args.param) or None,
                  stop_time=args.stop_time, step_size=args.step_size, identifier=args.identifier,
                  description=args.description, author=args.author, version=args.fmu_version,
                  license=args.license, copyright=args.copyright)
    info = fmu_info(path)
    print(f"wrote {path} (FMI {info['fmi_version']}: {', '.join(info['interfaces'])}; "
          f"{len(info['variables'])} variables)")
    return 0


def _cmd_fmu_info(args) -> int:
    from fmus.info import fmu_info, format_fmu_info
    info = fmu_info(args.fmu)
    print(json.dumps(info, indent=2) if args.json else format_fmu_info(info))
    return 0


def _cmd_cosim(args) -> int:
    import reproductions as scenarios
    if args.list or not args.scenario:
        width = max(len(n) for n in scenarios.names())
        for name in scenarios.names():
            print(f"{name:<{width}}  {scenarios.describe(name)}")
        return 0
    result = scenarios.run(args.scenario, args.plot)
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"{args.scenario}: {scenarios.describe(args.scenario)}")
    for key, value in _flatten(result):
        print(f"  {key}: {value:.4g}" if isinstance(value, float) else f"  {key}: {value}")
    if args.plot:
        print(f"  plots in {args.plot}")
    return 0


def _flatten(data, prefix=""):
    for key, value in data.items():
        if isinstance(value, dict):
            yield from _flatten(value, f"{prefix}{key}.")
        else:
            yield f"{prefix}{key}", value


def _cmd_diagnose(args) -> int:
    from diagnosis.diagnose import diagnose
    from plants import load as load_model
    report = diagnose(load_model(args.model), args.recording, inputs=args.input, outputs=args.output,
                      time=args.time, holdout=args.holdout, uncertain=args.uncertain, top=args.top,
                      progress=True, max_effects=args.max_effects, noise=args.noise,
                      spikes="keep" if args.keep_spikes else "repair")
    if args.report:
        paths = report.save(args.report)
        print(f"wrote {', '.join(paths.values())}", file=sys.stderr)
    print(json.dumps(report.to_json(), indent=2) if args.json else report.text)
    return 0


def _cmd_demo(args) -> int:
    from .demo import run_demo
    run_demo(args.output_dir, quick=args.quick)
    return 0


def _sweep_command(name):
    def run(args):
        from .cli_sweeps import COMMANDS
        return COMMANDS[name](args)
    return run


_COMMANDS = {"list": _cmd_list, "equations": _cmd_equations, "draw": _cmd_draw,
             "simulate": _cmd_simulate, "compare": _cmd_compare, "export-fmu": _cmd_export_fmu,
             "fmu-info": _cmd_fmu_info, "cosim": _cmd_cosim, "diagnose": _cmd_diagnose,
             "demo": _cmd_demo, **{n: _sweep_command(n) for n in ("sweep", "montecarlo", "diagnose-batch")}}


def _one_line(exc: BaseException) -> str:
    """The message of `exc` on one line (a multi-line message, e.g. every causal conflict, joined by '; ')."""
    text = str(exc) or type(exc).__name__
    return "; ".join(re.sub(r"^\s*-\s+", "", part).strip() for part in text.splitlines() if part.strip())


def _quiet_stdout() -> None:
    """After the reader of our stdout went away (``bondcosim ... | head``): send what is
    still buffered to /dev/null, so neither this process nor Python's exit reports it."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):   # no real file descriptor (captured in tests)
        pass


def main(argv=None) -> int:
    """Run the console script; returns the exit status.

    0 on success; 1 on a reported error (one line on stderr naming the culprit, never a
    traceback); 2 on a usage error (argparse); 130 when interrupted; 141 (128 + SIGPIPE,
    as the shell's own tools) when the reader of stdout closed it early, quietly.
    """
    args = _parser().parse_args(argv)
    where = f"bondcosim {args.command}"
    try:
        status = _COMMANDS[args.command](args)
        sys.stdout.flush()   # a closed pipe shows here, not at interpreter exit
        return status
    except BrokenPipeError:
        _quiet_stdout()
        return 141
    except BondcosimError as exc:
        print(f"{where}: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except OSError as exc:   # a file we were asked to read or write
        print(f"{where}: error: {_one_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{where}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 -- the last line of defence: one line, never a traceback
        print(f"{where}: internal error: {type(exc).__name__}: {_one_line(exc)} "
              "(please report it with the command line)", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
