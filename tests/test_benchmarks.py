"""Each benchmark runs once at its smallest size (no timing asserted), so none can rot."""


def test_derivation_benchmark_runs(capsys, load_script):
    bench = load_script("benchmarks/derivation.py")
    bench.main(sizes=(2,), skip_bgt=True, repeats=1)
    out = capsys.readouterr().out
    assert "states" in out and "    2 " in out


def test_codegen_benchmark_runs(capsys, load_script):
    from bondgraph.numerics.c_build import find_compiler
    if find_compiler() is None:
        import pytest
        pytest.skip("no C compiler")
    from plants.library.chain import mass_spring_chain
    bench = load_script("benchmarks/codegen.py")
    rows = bench.main({"chain2": mass_spring_chain(2)})
    assert rows[0]["model"] == "chain2" and rows[0]["assignments"][2] > 0
    assert "ratio" in capsys.readouterr().out


def test_sweep_scaling_benchmark_runs(capsys, load_script):
    # shipping (f) compiles the pam-ukf kernels in a fresh process with an empty cache (a minute);
    # tests/test_sweeps_shipping.py runs shipped runners on workers without a compiler
    bench = load_script("benchmarks/sweep_scaling.py")
    result = bench.main(runs=2, segment=0.3, workers=1, external=False, null_tasks=5, model_runs=4, ship=False)
    assert [r["engine"] for r in result["rows"]] == ["serial", "local:1"] and result["rows"][1]["failed"] == 0
    assert [c["chunk_size"] for c in result["chunking"]] == [1, 1]     # 4 runs, 1 worker: one each
    assert "speed-up" in capsys.readouterr().out and result["shipping"] is None


def test_fmu_solvers_benchmark_runs(capsys, load_script):
    bench = load_script("benchmarks/fmu_solvers.py")
    rows = bench.main(["--horizon", "0.005", "--models", "pam-locked"])
    assert {r["run"] for r in rows} == {"CS RK4", "CS DoPri", "ME CVode"}
    # the finest RK4 and the tightest tolerances agree with the DOP853 reference
    assert min(r["error"] for r in rows if r["run"] == "CS RK4") < 1e-9
    assert "rel. error" in capsys.readouterr().out
