"""What a real acquisition does to a lateral record, and what the loader and the fit make of
it: a time column written in ms, a force transducer mounted backwards, a CSV column in mm or
kN, a saturated force channel, electrical spikes. Each was fitted before without a word
(a traceback for the ms record; 300-600 iterations of nonsense for the backwards force and
the mm displacement; "converged" with a 95 % interval excluding the true slosh mass for the
clipped force). The records are the bundled A1 (synthetic, the reference simulator; truth
in ``examples/A1_truth.json``) with one defect each."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from estimate import FitProblem, fit, model_from_spec
from estimate.data import CaseError, load_case
from estimate.data.bad_samples import BadSamples, bad_samples
from estimate.data.plausible_units import ImplausibleUnit

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
TRUTH = json.loads((EXAMPLES / "A1_truth.json").read_text())["parameters"]
DATA = np.loadtxt(EXAMPLES / "A1.csv", delimiter=",", skiprows=1)


def _a1(folder: Path, name: str, data: np.ndarray, *, drop_prediction: bool = False) -> Path:
    np.savetxt(folder / f"{name}.csv", data, delimiter=",", header="time,displacement,force",
               comments="", fmt="%.12g")
    text = (EXAMPLES / "A1.toml").read_text().replace('data = "A1.csv"', f'data = "{name}.csv"')
    if drop_prediction:
        text = text[:text.index("\n[prediction]")]
    (folder / f"{name}.toml").write_text(text)
    return folder / f"{name}.toml"


def _loaded(path: Path) -> tuple[object, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        case = load_case(path)
    return case, [str(w.message) for w in caught if issubclass(w.category, ImplausibleUnit)]


def _problems(path: Path) -> list[str]:
    with pytest.raises(CaseError) as info:
        load_case(path)
    return info.value.problems


@pytest.mark.parametrize("drop_prediction", [False, True], ids=["prediction", "tank"])
def test_times_in_ms_are_refused_naming_the_unit(tmp_path, drop_prediction):
    # 100 Hz samples written in ms: a step of 10 "s" cannot hold a 2.1 Hz mode (the fit
    # raised from SciPy's least_squares: bounds crossed); the first mode comes from
    # [prediction] (2.09 Hz) or, without it, the tank's modal analysis (2.09 Hz too)
    d = DATA.copy()
    d[:, 0] *= 1e3
    found = _problems(_a1(tmp_path, "ms", d, drop_prediction=drop_prediction))
    assert len(found) == 1 and found[0].startswith("ms.csv: column `time`: a step of 10 s")
    assert "2.09 Hz predicted" in found[0] and "look like ms" in found[0]


def test_a_slow_but_sufficient_record_is_read(tmp_path):
    # 10 Hz (every 10th sample): 4.8 samples per period of the 2.09 Hz mode, enough
    case, _ = _loaded(_a1(tmp_path, "slow", DATA[::10]))
    assert case.n_samples == 301


def test_a_backwards_force_is_refused_naming_the_column(tmp_path):
    d = DATA.copy()
    d[:, 2] *= -1
    found = _problems(_a1(tmp_path, "flip", d))
    assert len(found) == 1 and found[0].startswith("flip.toml: column `force`: the force has the "
                                                   "opposite sign of mass x acceleration")
    # it reads minus the rigid and slosh masses with the container: 1.2 + 1.5 + 1.3 kg
    mass = float(found[0].split("it reads ")[1].split(" kg")[0])
    assert -4.4 < mass < -2.5


def test_a_drive_above_resonance_is_not_taken_for_a_backwards_force(tmp_path):
    # a steady sine at 1.15 f1: once the liquid swings, the force is in antiphase with the
    # acceleration (rigid 2.7 kg minus 3.1 times the 1.3 kg slosh mass); the check's slosh
    # term must read it as a positive mass
    import reference_models as ref
    from synthetic_cases import rig_record

    case, _, _ = rig_record(tmp_path, "above", lambda f1: ref.Sine(0.002, 1.15 * f1), seed=3,
                            ramp=2.0)
    assert _loaded(case.path)[1] == []


def test_csv_columns_in_other_units_are_named(tmp_path):
    mm = DATA.copy()
    mm[:, 1] *= 1e3
    kn = DATA.copy()
    kn[:, 2] *= 1e-3
    found_mm = _loaded(_a1(tmp_path, "mm", mm))[1]
    found_kn = _loaded(_a1(tmp_path, "kn", kn))[1]
    assert len(found_mm) == 1 and "column `displacement` (a CSV's columns are SI)" in found_mm[0]
    assert "looks like mm (12 mm); write it in m" in found_mm[0]
    assert len(found_kn) == 1 and "column `force`" in found_kn[0]
    assert "looks like kN; write it in N" in found_kn[0]
    assert _loaded(EXAMPLES / "A1.toml")[1] == []


def test_a_clipped_displacement_is_refused(tmp_path):
    # an LVDT channel saturating at 80 % of the stroke (40 % of the samples): fitted, the
    # fixed mass went to its bound 0 and the slosh mass to 1.76 kg, its interval
    # [1.47, 1.97] excluding the truth 1.30, "converged"
    d = DATA.copy()
    lim = 0.8 * np.abs(d[:, 1]).max()
    d[:, 1] = np.clip(d[:, 1], -lim, lim)
    found = _problems(_a1(tmp_path, "dclip", d))
    assert len(found) == 1 and found[0].startswith("dclip.csv: column `displacement`: 1205 "
                                                   "samples (40 %) read exactly")
    assert "the carriage motion is unknown where it is clipped" in found[0]


def test_a_quantised_displacement_is_no_clipped_one(tmp_path):
    # an encoder of 5 um steps: every peak of a steady sine reads the same top step for a
    # few samples; and a force quantised to 5 mN
    d = DATA.copy()
    d[:, 1] = np.round(d[:, 1] / 5e-6) * 5e-6
    d[:, 2] = np.round(d[:, 2] / 5e-3) * 5e-3
    case, _ = _loaded(_a1(tmp_path, "quantised", d))
    assert bad_samples(case)[1] == []


def _fit(path: Path):
    case = load_case(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        problem = FitProblem.build(case, model_from_spec("fixed,p1", case))
    result = fit(problem, progress=False)
    return result, [str(w.message) for w in caught if issubclass(w.category, BadSamples)]


def _covers(result, name: str) -> bool:
    lo, hi = result.interval(name)
    return lo <= TRUTH[name] <= hi


def test_a_clipped_force_is_left_out_and_the_intervals_cover_the_truth(tmp_path):
    # a +-6 N full scale: a third of A1's samples (its peaks reach 9 N) read exactly 6 N.
    # Fitted as measurements: slosh mass 1.098 kg (truth 1.30), its 95 % interval
    # [0.94, 1.26]; left out: both masses within their intervals
    d = DATA.copy()
    d[:, 2] = np.clip(d[:, 2], -6.0, 6.0)
    result, found = _fit(_a1(tmp_path, "clip", d))
    assert len(found) == 1
    assert found[0].startswith("A1: column `force`: 967 samples (32 %) read exactly -6 and +6")
    assert _covers(result, "p1.mass") and _covers(result, "fixed.mass")
    assert abs(result.value("p1.mass") / TRUTH["p1.mass"] - 1) < 0.01


def test_spikes_are_left_out(tmp_path):
    # two glitches of +80 N and -60 N (the noise is 0.07 N): fitted, they ended the fit on
    # the liquid-mass bound with a residual 6.8 times the noise
    d = DATA.copy()
    d[1200, 2] += 80.0
    d[2200, 2] -= 60.0
    result, found = _fit(_a1(tmp_path, "spike", d))
    assert len(found) == 1 and found[0].startswith("A1: column `force`: 2 samples")
    assert "(at 12 s)" in found[0]
    assert _covers(result, "p1.mass") and _covers(result, "fixed.mass")
    assert result.rms_residual < 1.1 * 0.0712  # A1's own residual


def test_records_as_rigs_write_them_flag_nothing():
    # every bundled record (sines, sweeps, a crank, two modes) and a 500 Hz transducer
    # record (internal filter, quantisation, lines) with a fast transport move
    import tempfile

    import transport_cases as tc

    paths = sorted(EXAMPLES.glob("*.toml")) + sorted((EXAMPLES / "campaign").glob("F*.toml"))
    cases = [load_case(p) for p in paths if p.stem != "spacecraft"]
    with tempfile.TemporaryDirectory() as folder:
        for planned in (False, True):
            cases.append(tc.transport_record(Path(folder), tc.sphere_8in(), planned=planned,
                                             decay=6.0, seed=3).case)
        found = {c.test.id: bad_samples(c)[1] for c in cases}
    assert all(not f for f in found.values()), found


def test_a_clipped_record_is_diagnosed_on_its_measurements(tmp_path):
    # the diagnosis scores candidates on held-out blocks (weight 0 in its fits): the
    # clipped samples, weight 0 as well, must not count as held out (their residual is the
    # clipping's, 30 times the noise), nor be drawn as residuals
    from estimate.diagnosis import diagnose

    d = DATA.copy()
    d[:, 2] = np.clip(d[:, 2], -6.0, 6.0)
    case = load_case(_a1(tmp_path, "clip", d))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BadSamples)
        dg = diagnose(case)
    assert dg.findings == ()
    left = dg.baseline.problem.left_out[0]
    held = dg.baseline.problem.held_out(0, dg.baseline.weights[0])
    assert left.sum() == 967 and not (held & ~(dg.baseline.weights[0] == 0)).any()
    # three held-out blocks of 3 s, whole: the clipped runs inside them belong to them
    edges = np.flatnonzero(np.diff(np.r_[0, held.astype(int), 0]))
    assert len(edges) == 6 and all(b - a > 290 for a, b in zip(edges[::2], edges[1::2]))
    assert dg.final.rms_residual < 1.05 * 0.0712
