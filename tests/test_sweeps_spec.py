"""Sweep specs: laws and grids from text, spec files (TOML/YAML), the run plan, and their errors."""
import numpy as np
import pytest

from sweeps import DistributionError, SpecError, load_spec, montecarlo_spec, parse_law, spec_from_dict
from sweeps.runners import flatten, make_runner, plan_runs


@pytest.mark.parametrize("text, kind, args, relative", [
    ("normal(1, 0.1)*nominal", "normal", (1.0, 0.1), True),
    ("nominal * uniform(0.8,1.2)", "uniform", (0.8, 1.2), True),
    ("lognormal(0, 0.25)", "lognormal", (0.0, 0.25), False),
    ("uniform(-1e-3, 2E-3)", "uniform", (-1e-3, 2e-3), False),
])
def test_random_laws_parse(text, kind, args, relative):
    law = parse_law("p", text)
    assert (law.kind, law.args, law.relative) == (kind, args, relative)


def test_grids_parse_to_their_values():
    assert parse_law("p", "linspace(0.8, 1.2, 3)*nominal").values(nominal=10.0) == pytest.approx((8.0, 10.0, 12.0))
    assert parse_law("p", "geomspace(1, 100, 3)").values(nominal=5.0) == pytest.approx((1.0, 10.0, 100.0))
    assert parse_law("p", "grid(1, 2.5)").values(nominal=5.0) == (1.0, 2.5)
    assert parse_law("p", [3, 4]).values(nominal=0.0) == (3.0, 4.0)
    assert parse_law("p", parse_law("p", [3, 4]).text).values(nominal=0.0) == (3.0, 4.0)   # round trip
    assert parse_law("p", "1.1*nominal").values(nominal=2.0) == pytest.approx((2.2,))


def test_draws_follow_the_law():
    rng = np.random.default_rng(0)
    law = parse_law("A1", "normal(1, 0.1)*nominal")
    x = np.array([law.sample(rng, nominal=5.0) for _ in range(4000)])
    # mean 5, std 0.5 (10 % of the nominal); 4000 draws: standard error of the mean 0.008
    assert x.mean() == pytest.approx(5.0, abs=0.03) and x.std() == pytest.approx(0.5, rel=0.05)


@pytest.mark.parametrize("text, needle", [
    ("normal(1)", "normal takes 2 arguments"),
    ("gauss(1, 2)", "unknown law 'gauss'"),
    ("uniform(2, 1)", "LOW < HIGH"),
    ("normal(1, x)", "'x' is not a number"),
    ("normal(1, -0.1)", "spread >= 0"),
    ("linspace(0, 1, 2.5)", "whole N"),
    ("normal(1,0.1)*nomnal", "not LAW(ARGS)"),
])
def test_bad_law_text_is_named(text, needle):
    with pytest.raises(DistributionError, match="parameter 'A1'") as err:
        parse_law("A1", text)
    assert needle in str(err.value) and err.value.text == text


def test_toml_and_yaml_specs_read_the_same(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text('scenario = "pam-ukf"\nquick = true\nsamples = 3\nseed = 7\nmetrics = ["ukf.angle.I"]\n'
                    '[vary]\nA1 = "normal(1, 0.1)*nominal"\n[fixed]\nsegment_s = 0.3\n')
    yaml = tmp_path / "s.yaml"
    yaml.write_text('scenario: pam-ukf\nquick: true\nsamples: 3\nseed: 7\nmetrics: [ukf.angle.I]\n'
                    'vary:\n  A1: "normal(1, 0.1)*nominal"\nfixed:\n  segment_s: 0.3\n')
    a, b = load_spec(toml), load_spec(yaml)
    assert a.to_dict() == b.to_dict()
    assert a.samples == 3 and a.target.name == "pam-ukf" and a.target.quick and dict(a.fixed) == {"segment_s": 0.3}


def test_a_bad_spec_file_lists_every_problem(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('scenario = "pam-ukf"\nsampels = 3\nsamples = -1\n[vary]\nA1 = "normal(1)"\n')
    with pytest.raises(SpecError) as err:
        load_spec(path)
    text = str(err.value)
    assert str(path) in text and "3 problem(s)" in text
    assert "unknown key 'sampels'" in text and "samples: -1 must be > 0" in text and "vary.A1" in text
    broken = tmp_path / "broken.toml"
    broken.write_text("samples = = 3\n")
    with pytest.raises(SpecError, match="not valid TOML"):
        load_spec(broken)
    with pytest.raises(SpecError, match="unknown spec format '.ini'"):
        load_spec(tmp_path / "x.ini")


def test_unknown_parameters_and_metrics_are_named_before_anything_runs():
    spec = spec_from_dict({"scenario": "pam-ukf", "vary": {"A9": "uniform(0, 1)"}, "fixed": {"segmnt_s": 1.0}})
    with pytest.raises(SpecError) as err:
        make_runner(spec)
    assert "vary.A9: scenario 'pam-ukf' has no parameter 'A9'" in str(err.value)
    assert "fixed.segmnt_s" in str(err.value) and "A1" in str(err.value)
    with pytest.raises(SpecError, match="'kpid' takes no parameters.*pam-ukf, exo-lqi"):
        make_runner(spec_from_dict({"scenario": "kpid", "samples": 2}))
    spec = spec_from_dict({"model": {"name": "mass-spring-damper", "stop_time": 1.0, "outputs": ["y"]},
                           "metrics": ["x.median"]})
    with pytest.raises(SpecError) as err:
        make_runner(spec)
    assert "no output 'y'" in str(err.value) and "no metric 'x.median'" in str(err.value)


def test_the_plan_is_the_grid_times_the_samples_and_depends_on_seed_and_index_only():
    spec = spec_from_dict({"model": {"name": "mass-spring-damper", "stop_time": 1.0},
                           "vary": {"k": "grid(1, 2, 3)", "b": "uniform(0.1, 0.5)"}, "samples": 4, "seed": 3})
    runs = plan_runs(spec, {"k": 4.0, "b": 0.4, "m": 1.0})
    assert len(runs) == 12 and [r.params["k"] for r in runs[:5]] == [1.0, 1.0, 1.0, 1.0, 2.0]
    assert all(0.1 <= r.params["b"] <= 0.5 for r in runs) and len({r.seed for r in runs}) == 12
    again = plan_runs(spec, {"k": 4.0, "b": 0.4, "m": 1.0})
    assert [r.params for r in again] == [r.params for r in runs]
    other = plan_runs(spec_from_dict({**spec.to_dict(), "seed": 4}), {"k": 4.0, "b": 0.4, "m": 1.0})
    assert other[0].params["b"] != runs[0].params["b"]


def test_montecarlo_spec_from_command_line_pairs():
    spec = montecarlo_spec("pam-ukf", samples=5, vary=["A1=normal(1,0.1)*nominal"], seed=2)
    assert spec.samples == 5 and spec.vary["A1"].kind == "normal" and spec.seed == 2
    with pytest.raises(SpecError, match="not NAME=LAW"):
        montecarlo_spec("pam-ukf", samples=5, vary=["A1"])
    with pytest.raises(DistributionError, match="Monte-Carlo draws"):
        montecarlo_spec("pam-ukf", samples=5, vary=["A1=grid(1, 2)"])


def test_flatten_keeps_numeric_leaves_only():
    assert flatten({"a": {"b": 1, "c": "text"}, "d": [1.0], "e": False}) == {"a.b": 1.0, "e": False}


@pytest.mark.parametrize("name", ["sweep_exo_grid.toml", "montecarlo_pam_ukf.yaml"])
def test_example_specs_load_and_name_only_known_parameters(name):
    from pathlib import Path
    spec = load_spec(Path(__file__).resolve().parent.parent / "examples" / name)
    runner = make_runner(spec)                 # checks every parameter name against the scenario
    runs = plan_runs(spec, runner.nominal)
    assert len(runs) == {"sweep_exo_grid.toml": 25, "montecarlo_pam_ukf.yaml": 200}[name]
