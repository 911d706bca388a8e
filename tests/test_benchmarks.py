"""Each benchmark runs once at its smallest size (no timing asserted), so none can rot."""


def test_derivation_benchmark_runs(capsys, load_script):
    bench = load_script("benchmarks/derivation.py")
    bench.main(sizes=(2,), skip_bgt=True, repeats=1)
    out = capsys.readouterr().out
    assert "states" in out and "    2 " in out
