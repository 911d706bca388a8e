"""Each benchmark runs once at its smallest size (no timing asserted), so none can rot."""


def test_derivation_benchmark_runs(capsys, load_script):
    bench = load_script("benchmarks/derivation.py")
    bench.main(sizes=(2,), skip_bgt=True, repeats=1)
    out = capsys.readouterr().out
    assert "states" in out and "    2 " in out


def test_sweep_scaling_benchmark_runs(capsys, load_script):
    bench = load_script("benchmarks/sweep_scaling.py")
    result = bench.main(runs=2, segment=0.3, workers=1, external=False, null_tasks=5, model_runs=4)
    assert [r["engine"] for r in result["rows"]] == ["serial", "local:1"] and result["rows"][1]["failed"] == 0
    assert [c["chunk_size"] for c in result["chunking"]] == [1, 1]     # 4 runs, 1 worker: one each
    assert "speed-up" in capsys.readouterr().out
