"""A record fitted decimated (``[test] decimate``) gives the estimates and standard errors of
its fit at the full rate (issue 27)."""

from __future__ import annotations

import numpy as np
from synthetic_cases import sweep_record

from estimate import FitProblem, fit, load_case, model_from_spec


def test_a_decimated_fit_keeps_the_estimates_and_their_standard_errors(tmp_path):
    """The 6 s, 500 Hz sweep of ``benchmarks/bench_length.py`` from rest (white force noise
    1.3 %, displacement noise 20 um), ``fixed,p1`` with the carriage motion estimated, at
    500 Hz and decimated by 5 to 100 Hz. Measured: the estimates move by under 0.6 of a
    standard error, the robust standard errors by under 3 %, and they stay within 1.21 times
    the Gauss-Newton ones (before the spectral middle read the noise only where the
    anti-alias filter leaves it: 2.6 times, the masses' intervals twice as wide)."""
    case, p = sweep_record(tmp_path, "S", 6.0, seed=4)
    toml = tmp_path / "S.toml"
    (tmp_path / "D.toml").write_text(toml.read_text().replace("[test]\n", "[test]\ndecimate = 5\n"))
    decimated = load_case(tmp_path / "D.toml")
    assert decimated.time.size == 601
    full = fit(FitProblem.build(case, model_from_spec("fixed,p1", case)), progress=False)
    dec = fit(FitProblem.build(decimated, model_from_spec("fixed,p1", decimated)), progress=False)
    assert full.converged and dec.converged
    truth = {"fixed.mass": 1.5, "p1.mass": p.mass, "p1.length": p.length}
    for k, v in truth.items():
        i, j = full.names.index(k), dec.names.index(k)
        se, se_dec = full.stderr[i], dec.stderr[j]
        assert abs(dec.value(k) - full.value(k)) < 1.0 * se, (k, dec.value(k), full.value(k), se)
        assert abs(se_dec / se - 1) < 0.10, (k, se_dec, se)
        gn = float(np.sqrt(dec.gauss_newton_covariance[j, j]))
        assert se_dec < 1.35 * gn, (k, se_dec, gn)
        lo, hi = dec.interval(k)
        assert lo <= v <= hi, (k, lo, v, hi)


def test_a_long_fast_record_is_told_how_to_decimate(tmp_path):
    """20 s at 500 Hz from rest (10,001 samples, the reference simulator): the fit's notes
    propose ``[test] decimate = 5``; with ``decimate = 1`` (every sample asked for) nothing
    is said, nor for a record at 100 Hz (A1)."""
    from dataclasses import replace
    from pathlib import Path

    fast, _ = sweep_record(tmp_path, "F", 20.0, seed=5)
    kept = replace(fast, test=replace(fast.test, decimate=1))
    a1 = load_case(Path(__file__).resolve().parents[3] / "examples" / "A1.toml")
    hint = ("F.csv: 10001 samples at 500 Hz, far above the slosh band: `[test] decimate = 5` "
            "(or --decimate 5) fits them at 100 Hz")
    model = model_from_spec("fixed,p1", fast)
    assert any(hint in n for n in FitProblem.build(fast, model, first_stage=False).notes)
    for case in (kept, a1):
        notes = FitProblem.build(case, model, first_stage=False).notes
        assert not any("far above the slosh band" in n for n in notes)
