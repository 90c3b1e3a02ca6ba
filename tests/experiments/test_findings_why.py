"""A finding that does not agree says why, in plain words read from the same numbers."""

from __future__ import annotations

import math

import pandas as pd

from echocal.experiments._findings import fewest_measurements

INF = math.inf
THESIS = ("gradient", "momentum", "nesterov", "spsa", "newton", "quasi-newton")


def _summary(to90_iter, to90_meas, final, beyond=()):
    """Rows as summarize_configs makes them: the six thesis methods, then `beyond` ones."""
    rows = [
        {
            "label": m,
            "method": m,
            "beyond_thesis": False,
            "initial_error_deg": 6.0,
            "final_error_deg": f,
            "n_measurements": 270.0 if m == "newton" else 120.0,
            "iterations_to_90pct": i,
            "measurements_to_90pct": n,
        }
        for m, i, n, f in zip(THESIS, to90_iter, to90_meas, final, strict=True)
    ]
    rows += [
        {
            "label": f"{m} (beyond the thesis)",
            "method": m,
            "beyond_thesis": True,
            "initial_error_deg": 6.0,
            "final_error_deg": 0.05,
            "n_measurements": 36.0,
            "iterations_to_90pct": 7.0,
            "measurements_to_90pct": n,
        }
        for m, n in beyond
    ]
    return pd.DataFrame(rows)


def _check(summary, gains="the thesis's gains"):
    return fewest_measurements(summary, claim="c", group="g", method="spsa", gains=gains)


def test_no_method_reaching_90_percent_is_explained_by_how_little_the_estimates_moved():
    finals = (5.4, 4.4, 4.4, 5.8, 2.2, 3.2)
    summary = _summary([INF] * 6, [INF] * 6, finals, beyond=[("model-based", 13.0)])
    finding = _check(summary)
    assert not finding.agrees
    why = finding.why
    assert "None of the 6 thesis methods reached 90 %" in why
    assert "with the thesis's gains" in why
    assert "Starting 6.0° from the optimum" in why
    assert "2.2° (newton)" in why and "5.8° (spsa)" in why  # the range, from the table
    assert "model-based (beyond the thesis) reached it after 13 measurements" in why
    assert finding.to_dict()["why"] == why


def test_a_slower_spsa_is_explained_by_its_iterations_against_the_fastest():
    iters = (10.0, 10.0, 5.0, 26.0, 5.0, 7.0)
    meas = (40.0, 40.0, 20.0, 60.0, 45.0, 28.0)
    finding = _check(_summary(iters, meas, (1.5,) * 6), gains="automatic gains")
    assert not finding.agrees
    assert "2 instead of 4" in finding.why
    assert "needed 26 iterations (60 measurements)" in finding.why
    assert "5.2× the 5 iterations (20 measurements) of nesterov" in finding.why


def test_spsa_that_never_gets_there_while_another_does():
    iters = (10.0, 10.0, 5.0, INF, 5.0, 7.0)
    meas = (40.0, 40.0, 20.0, INF, 45.0, 28.0)
    finding = _check(_summary(iters, meas, (1.5, 1.5, 1.5, 4.0, 1.5, 1.5)))
    assert "spsa never reached 90 %" in finding.why
    assert "median final error 4.0°" in finding.why
    assert "nesterov did after 20 measurements" in finding.why


def test_an_agreeing_finding_has_no_explanation():
    iters = (10.0, 10.0, 5.0, 4.0, 5.0, 7.0)
    meas = (40.0, 40.0, 20.0, 10.0, 45.0, 28.0)
    finding = _check(_summary(iters, meas, (0.1,) * 6))
    assert finding.agrees and finding.why == ""
