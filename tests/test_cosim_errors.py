"""Bad co-simulation input: each a clear error naming the culprit."""
from __future__ import annotations

import zipfile

import pytest

from bondgraph.errors import (AlgebraicLoopError, CosimError, FMUError, SimulationError,
                              UnknownNameError)
from cosim import PI, CoSimulation, Constant, FMUComponent, Function, Step
from cosim_helpers import handwritten_msd
from fmus.loading import find_variable, read_fmu


@pytest.fixture(scope="session")
def msd_fmu(tmp_path_factory):
    return handwritten_msd(tmp_path_factory)


def test_missing_fmu_file(tmp_path):
    path = tmp_path / "nowhere.fmu"
    with pytest.raises(FMUError, match="nowhere.fmu.*does not exist") as info:
        FMUComponent(path)
    assert info.value.path == str(path)


def test_corrupt_fmu_files(tmp_path):
    garbage = tmp_path / "x.fmu"
    garbage.write_bytes(b"\x00garbage, not a zip archive" * 10)
    with pytest.raises(FMUError, match="x.fmu.*not a zip archive"):
        FMUComponent(garbage)
    empty = tmp_path / "empty.fmu"
    with zipfile.ZipFile(empty, "w") as zf:
        zf.writestr("binaries/readme.txt", "no model description")
    with pytest.raises(FMUError, match="empty.fmu.*no modelDescription.xml.*binaries/readme.txt"):
        read_fmu(empty)
    broken = tmp_path / "broken.fmu"
    with zipfile.ZipFile(broken, "w") as zf:
        zf.writestr("modelDescription.xml", "<fmiModelDescription fmiVersion='2.0'")
    with pytest.raises(FMUError, match="broken.fmu.*modelDescription.xml"):
        read_fmu(broken)


def test_unknown_fmu_variables_list_the_known_ones(msd_fmu):
    with pytest.raises(UnknownNameError, match="unknown FMU output 'z'.*known FMU outputs are x, v"):
        FMUComponent(msd_fmu, outputs=["z"])
    with pytest.raises(UnknownNameError, match="unknown FMU input 'x'") as info:
        FMUComponent(msd_fmu, inputs=["x"])          # exists, but is an output
    assert info.value.known == ["F"]
    with pytest.raises(UnknownNameError, match="unknown FMU parameter 'mass'.*m, k, c, x0, v0"):
        FMUComponent(msd_fmu, parameters={"mass": 1.0})
    with pytest.raises(UnknownNameError, match="unknown FMU variable 'x1'"):
        FMUComponent(msd_fmu, start_values={"x1": 1.0})
    with pytest.raises(UnknownNameError) as info:
        find_variable(read_fmu(msd_fmu), "q", path=msd_fmu)
    assert info.value.name == "q" and "handwritten_msd" in str(info.value)


def test_fmu_failure_names_component_function_and_log(msd_fmu):
    plant = FMUComponent(msd_fmu, name="plant", parameters={"m": 0.0})
    sim = CoSimulation([plant], [], step=0.01)
    with pytest.raises(FMUError, match="'plant'.*initialisation failed at t = 0 s.*m must be "
                                       "positive"):
        sim.run(0.1)


def test_unit_mismatch_names_both_ends(msd_fmu):
    plant = FMUComponent(msd_fmu, name="plant")
    pi = PI("pi", kp=1.0, ki=0.0, unit_in="rad", unit_out="N")
    with pytest.raises(CosimError, match=r"unit mismatch: 'plant.x' \[m\] -> 'pi.y_m' \[rad\]") \
            as info:
        CoSimulation([plant, pi], [("plant.x", "pi.y_m"), ("pi.u", "plant.F")], step=1e-3)
    assert info.value.ports == ("plant.x", "pi.y_m")
    # "" is unspecified and connects to anything
    CoSimulation([plant, PI("p2", kp=1.0, ki=0.0)], [("plant.x", "p2.y_m")], step=1e-3)


def test_algebraic_loop_lists_ports_in_signal_order():
    a, b = PI("a", kp=0.5, ki=0.0), PI("b", kp=0.5, ki=0.0)
    with pytest.raises(AlgebraicLoopError, match=r"a.u -> b.r -> b.u -> a.r -> a.u") as info:
        CoSimulation([a, b], [("a.u", "b.r"), ("b.u", "a.r")], step=0.1)
    assert info.value.ports == ("a.u", "b.r", "b.u", "a.r")
    # the listing starts at the output of the component given first
    with pytest.raises(AlgebraicLoopError) as info:
        CoSimulation([b, a], [("a.u", "b.r"), ("b.u", "a.r")], step=0.1)
    assert info.value.ports == ("b.u", "a.r", "a.u", "b.r")
    assert isinstance(info.value, CosimError)


def test_input_driven_twice():
    with pytest.raises(CosimError, match="input 'pi.r' is driven twice: by 's1.y' and 's2.y'"):
        CoSimulation([PI("pi", kp=1.0, ki=1.0), Step("s1", 0.0), Step("s2", 1.0)],
                     [("s1.y", "pi.r"), ("s2.y", "pi.r")], step=0.1)


def test_unknown_component_and_port():
    blocks = [PI("pi", kp=1.0, ki=1.0), Step("s", 0.0)]
    with pytest.raises(CosimError, match="unknown component 'plant'; components are pi, s"):
        CoSimulation(blocks, [("plant.x", "pi.y_m")], step=0.1)
    with pytest.raises(CosimError, match="component 's' has no output 'out'; its outputs are y"):
        CoSimulation(blocks, [("s.out", "pi.r")], step=0.1)
    with pytest.raises(CosimError, match="'r' is an input; connections go output -> input"):
        CoSimulation(blocks, [("pi.r", "s.y")], step=0.1)
    with pytest.raises(CosimError, match="expected 'component.port'"):
        CoSimulation(blocks, [("s", "pi.r")], step=0.1)
    with pytest.raises(CosimError, match="2 problems"):
        CoSimulation(blocks, [("s.y", "pi.q"), ("x.y", "pi.r")], step=0.1)


def test_component_set_up_errors():
    with pytest.raises(CosimError, match="duplicate component name 's'"):
        CoSimulation([Step("s", 0.0), Step("s", 1.0)], [], step=0.1)
    with pytest.raises(CosimError, match="'a.b' must be a non-empty str without '.'"):
        CoSimulation([Step("a.b", 0.0)], [], step=0.1)
    with pytest.raises(CosimError, match="is not a component.*lacks.*feedthrough"):
        CoSimulation([object()], [], step=0.1)
    with pytest.raises(CosimError, match="times must be strictly increasing"):
        from cosim import Table
        Table("tab", [0.0, 0.0], [1.0, 2.0])


def test_step_and_time_span_errors():
    blocks = [Constant("c", 1.0)]
    for bad in (0.0, -1e-3, float("nan"), "fast"):
        with pytest.raises(CosimError, match="step must be"):
            CoSimulation(blocks, [], step=bad)
    sim = CoSimulation(blocks, [], step=0.1)
    with pytest.raises(CosimError, match="t0 <= t_end"):
        sim.run(0.5, t0=1.0)
    with pytest.raises(CosimError, match="not a multiple of step 0.1 s; nearest: t_end = "):
        sim.run(0.55)


def test_python_block_failure_names_component_and_time():
    def boom(t):
        if t > 0.25:
            raise ZeroDivisionError("no")
        return 0.0
    sim = CoSimulation([Function("f", boom)], [], step=0.1)
    with pytest.raises(SimulationError, match=r"component 'f' \(in output\) raised "
                                              r"ZeroDivisionError at t = 0.3 s") as info:
        sim.run(1.0)
    assert info.value.time == pytest.approx(0.3)
