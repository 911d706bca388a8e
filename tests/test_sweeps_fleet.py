"""The fleet summary counts recordings per kind, keeps every effect's parameters (one kind
found at two places in one recording included) and each recording's improvement once per kind."""
import json

import pandas as pd
import pytest

from sweeps.fleet import fleet_summary


def _row(kinds, places, parameters, improvement, status="ok"):
    return {"run_id": 0, "status": status, "error": "", "param.recording": "r.csv",
            "metric.kinds": kinds, "metric.places": places, "metric.parameters": json.dumps(parameters),
            "metric.improvement.x": improvement}


def test_one_kind_at_two_places_keeps_both_effects_and_counts_one_recording():
    table = pd.DataFrame([
        _row("coulomb_friction;coulomb_friction", "junction v_1;junction v_2",
             [{"Fc_v_1": 0.03}, {"Fc_v_2": 0.5}], 0.8),
        _row("coulomb_friction", "junction v_1", [{"Fc_v_1": 0.05}], 0.6),
        _row("none", "", [], float("nan")),
    ])
    summary = fleet_summary(table)
    assert summary["kinds"] == {"coulomb_friction": 2, "none": 1}
    assert summary["places"] == {"coulomb_friction": {"junction v_1": 2, "junction v_2": 1}}
    fitted = summary["parameters"]["coulomb_friction"]
    assert fitted["Fc_v_1"]["n"] == 2 and fitted["Fc_v_1"]["median"] == pytest.approx(0.04)
    assert fitted["Fc_v_2"] == {"n": 1, "median": 0.5, "q05": 0.5, "q95": 0.5}
    assert summary["improvement_by_kind"]["coulomb_friction"]["n"] == 2
    assert summary["improvement_by_kind"]["coulomb_friction"]["median"] == pytest.approx(0.7)


def test_rows_of_the_older_form_one_dict_per_kind_still_read():
    summary = fleet_summary(pd.DataFrame([_row("coulomb_friction", "junction v_1",
                                               {"coulomb_friction": {"Fc_v_1": 0.03}}, 0.8)]))
    assert summary["parameters"]["coulomb_friction"]["Fc_v_1"]["median"] == 0.03
