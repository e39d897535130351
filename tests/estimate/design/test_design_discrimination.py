"""``slosh design --discriminate``: two models that explain the first record equally (a
pendulum with a weak hinge spring, and a shorter pendulum without one: below resonance the
force depends on the frequency alone) are told apart by the recommended record.

The diagnosis file holds the two fits in the keys ``slosh diagnose --json`` writes
(``baseline``, ``final``: their parameters). The recommended drive is run on the truth
(the reference simulator, the spring model) and both models are fitted to both records:
the wrong one is left with a chi-square larger by more than 25 (rejected at five standard
deviations), as the design predicted. The size of the gap is not compared: the design
predicts it at the first fit's split of length and spring, which that record leaves
undetermined (its spring carries more of the stiffness than the truth's tenth, so the
predicted gap is larger). Slow (four fits).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import reference_models as ref
from design_helpers import FromCSV, G, fit_json, lateral_record, truth_pendulum

from estimate.cli import main

pytestmark = pytest.mark.slow


def test_discrimination_tells_spring_from_shorter_pendulum(tmp_path):
    m, L = 1.30, 0.0553
    k = 0.1 * m * G * L  # a tenth of the restoring stiffness: the shorter pendulum fits too
    truth = truth_pendulum(stiffness=k)
    f1 = ref.natural_frequency(truth, G) / (2 * np.pi)
    first, _ = lateral_record(tmp_path, "A", ref.Ramped(ref.Sine(0.004, 0.5 * f1), 1.5),
                              truth=truth, seed=21, diaphragm=True)
    base_path, base = fit_json(tmp_path, "base", [first], "fixed,p1:nospring")
    final_path, final = fit_json(tmp_path, "final", [first], "fixed,p1",
                                 initial={"p1.stiffness": 0.05})
    # both explain the first record: residual variances within 2 % of each other
    assert base.residual_variance == pytest.approx(final.residual_variance, rel=0.02)
    diag = tmp_path / "diag.json"
    diag.write_text(json.dumps({
        "baseline": {"parameters": json.loads(base_path.read_text())["parameters"]},
        "final": {"parameters": json.loads(final_path.read_text())["parameters"]}}))
    out = tmp_path / "disc.json"
    assert main(["design", str(final_path), str(first.path), "--discriminate", str(diag),
                 "--json", str(out), "--plot", str(tmp_path / "disc.png")]) == 0
    d = json.loads(out.read_text())
    assert d["models"] == {"baseline": "fixed,p1:nospring", "final": "fixed,p1"}
    predicted = d["recommended"]["lack_of_fit_chi2"]
    assert all(v <= 1.0 for v in d["recommended"]["limit_ratios"].values())
    second, _ = lateral_record(tmp_path, "B", FromCSV(d["drive_file"]), truth=truth, seed=22,
                               diaphragm=True)
    _, wrong = fit_json(tmp_path, "base_AB", [first, second], "fixed,p1:nospring")
    _, right = fit_json(tmp_path, "final_AB", [first, second], "fixed,p1",
                        initial={n: final.value(n) for n in final.names})
    # objectives are chi-squares (residuals over their noise levels)
    gap = wrong.objective - right.objective
    print(f"\npredicted lack of fit {predicted}, achieved chi-square gap {gap:.4g}")
    assert predicted["baseline"] >= 25 and gap >= 25
    assert d["recommended"]["counted"] == ["baseline"]
