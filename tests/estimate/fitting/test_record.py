"""The fit record (estimate.fitting.record): one writer and reader of the fit JSON, its
provenance checked against the files and libraries themselves, AIC/BIC against a hand
computation, a record of the first layout still read, the Markdown report."""

import ast
import datetime
import hashlib
import json
import math
import re
from pathlib import Path

import casadi
import numpy as np
import pytest
import scipy

from estimate.cli import main
from estimate.fitting.record import SCHEMA, read_fit, read_params

ROOT = Path(__file__).resolve().parents[3]
A1 = ROOT / "examples" / "A1.toml"
PACKAGE = ROOT / "estimate"
#: Keys only a fit record has: no module outside estimate/fitting/record/ may write them.
RECORD_KEYS = ("derived_stderr", "covariance_gauss_newton", "newey_west_lags", "interval_95",
               "information_criteria", "model_spec_given")


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """``slosh fit`` of the bundled example with --json and --report FILE.md."""
    folder = tmp_path_factory.mktemp("record")
    before = datetime.datetime.now(datetime.timezone.utc)
    status = main(["fit", str(A1), "--model", "fixed,p1:nospring", "--json",
                   str(folder / "fit.json"), "--report", str(folder / "fit.md")])
    assert status == 0
    return folder, before


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_the_record_names_its_schema_files_versions_and_options(written):
    folder, before = written
    data = json.loads((folder / "fit.json").read_text())
    assert data["schema"] == SCHEMA == "slosh-analogs/fit/2"
    prov = data["provenance"]
    # each file's checksum, computed here from its bytes
    (entry,) = prov["files"]
    assert entry["case_sha256"] == _sha256(A1)
    assert entry["data_sha256"] == _sha256(ROOT / "examples" / "A1.csv")
    assert Path(entry["data_file"]).name == "A1.csv" and entry["id"] == "A1"
    versions = prov["versions"]
    assert versions["casadi"] == casadi.__version__ and versions["numpy"] == np.__version__
    assert versions["scipy"] == scipy.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", versions["ipopt"])
    created = datetime.datetime.fromisoformat(prov["created_utc"].replace("Z", "+00:00"))
    assert before - datetime.timedelta(seconds=1) <= created <= datetime.datetime.now(
        datetime.timezone.utc)
    assert prov["command"] == "slosh fit"
    assert prov["model_spec_given"] == "fixed,p1:nospring"
    assert prov["options"]["cost"] == "squared" and prov["options"]["report"].endswith("fit.md")
    assert data["model_spec"] == "fixed,p1:nospring"  # the model's own, not its names


def test_the_reader_gives_what_the_record_holds(written):
    folder, _ = written
    data = json.loads((folder / "fit.json").read_text())
    fit = read_fit(folder / "fit.json")
    assert fit.schema == 2 and fit.notes == () and fit.provenance == data["provenance"]
    for name, entry in data["parameters"].items():
        assert fit.values[name] == entry["value"]
        if entry["estimated"]:
            assert fit.intervals[name] == tuple(entry["interval_95"])
            lo, hi = entry["interval_95"]
            assert lo < entry["value"] < hi
    assert fit.derived["p1.frequency_hz"][0] == data["derived"]["p1.frequency_hz"]
    assert fit.converged is True and fit.model_spec == "fixed,p1:nospring"
    assert read_params(folder / "fit.json") == fit.values


def test_aic_and_bic_by_hand(written):
    folder, _ = written
    data = json.loads((folder / "fit.json").read_text())
    ic = data["information_criteria"]
    n, k = 3001, sum(1 for e in data["parameters"].values() if e["estimated"])
    assert (ic["samples"], ic["estimates"]) == (n, k) == (3001, 4)
    m2ll = ic["minus_two_log_likelihood"]
    assert ic["aic"] == pytest.approx(m2ll + 2 * k, rel=1e-12)
    assert ic["bic"] == pytest.approx(m2ll + k * math.log(n), rel=1e-12)
    # the residuals are in units of their noise figures (the estimated input): -2 log L is
    # then about the number of weighted residuals, force and displacement (2 x 3001)
    assert 0.9 * 2 * n < m2ll < 1.1 * 2 * n


def test_aic_bic_of_an_unweighted_fit_are_n_log_cost_over_n(sine_result):
    from estimate.fitting.record import information_criteria

    res = sine_result
    ic = information_criteria(res)
    n, k = res.n_samples, len(res.names)
    by_hand = n * math.log(res.cost / n)
    assert ic["aic"] == pytest.approx(by_hand + 2 * k, rel=1e-12)
    assert ic["bic"] == pytest.approx(by_hand + k * math.log(n), rel=1e-12)


@pytest.fixture(scope="module")
def sine_result():
    """A fit with the filtered input: residuals in newtons, not divided by a noise."""
    from estimate import FitProblem, fit, load_case, model_from_spec

    case = load_case(A1)
    problem = FitProblem.build([case], model_from_spec("fixed,p1:nospring", case),
                               input="filtered")
    assert all(n is None for n in (problem.noise or [None]))
    return fit(problem, progress=False)


def test_the_diagnosis_bic_is_the_record_bic(sine_result):
    from estimate.diagnosis.scoring import bic
    from estimate.fitting.record import information_criteria

    assert information_criteria(sine_result)["bic"] == pytest.approx(bic(sine_result), rel=1e-12)


def test_the_markdown_report_holds_the_estimates_and_the_provenance(written):
    folder, _ = written
    text = (folder / "fit.md").read_text()
    data = json.loads((folder / "fit.json").read_text())
    assert text.startswith("# Fit of A1: fixed,p1:nospring")
    assert _sha256(ROOT / "examples" / "A1.csv") in text
    row = next(line for line in text.splitlines() if line.startswith("| p1.mass |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert float(cells[1]) == pytest.approx(data["parameters"]["p1.mass"]["value"], rel=1e-5)
    lo, hi = data["parameters"]["p1.mass"]["interval_95"]
    assert cells[5] == f"[{lo:.6g}, {hi:.6g}]"
    assert "| AIC |" in text and "| BIC |" in text and "## Provenance" in text


def test_the_text_report_columns_line_up(sine_result):
    text = sine_result.report()
    rows = [line for line in text.splitlines() if "95%: [" in line]
    assert len(rows) == 4
    for mark in ("=", "+/-", "95%:", "(init"):
        assert len({row.index(mark) for row in rows}) == 1, (mark, rows)
    assert re.search(r"^    AIC +=", text, re.M) and re.search(r"^    BIC +=", text, re.M)


def _old_layout(data: dict) -> dict:
    """The record as versions before the schema wrote it."""
    old = {k: v for k, v in data.items() if k not in ("schema", "provenance",
                                                     "information_criteria", "transcription",
                                                     "cost_kind")}
    old["parameters"] = {n: {k: v for k, v in e.items() if k != "interval_95"}
                         for n, e in data["parameters"].items()}
    return old


def test_a_record_without_provenance_still_reads_with_a_note(written, tmp_path, capsys):
    folder, _ = written
    data = json.loads((folder / "fit.json").read_text())
    old = tmp_path / "old_fit.json"
    old.write_text(json.dumps(_old_layout(data)))
    fit = read_fit(old)
    assert fit.schema == 1 and fit.provenance is None
    assert "before records carried their provenance" in fit.notes[0] and str(old) in fit.notes[0]
    entry = data["parameters"]["p1.mass"]
    # an old record holds no interval: the normal one, by hand
    assert fit.intervals["p1.mass"] == pytest.approx(
        (entry["value"] - 1.959964 * entry["stderr"], entry["value"] + 1.959964 * entry["stderr"]),
        rel=1e-9)
    assert fit.values == read_fit(folder / "fit.json").values
    # and a command that takes a fit uses it, saying so
    assert main(["simulate", str(A1), "--params", str(old), "--out", str(tmp_path / "s.csv"),
                 "--model", "fixed,p1:nospring"]) == 0
    err = capsys.readouterr().err
    assert "old_fit.json: a fit record written before records carried their provenance" in err


def test_a_record_of_another_kind_is_refused_naming_the_key(written, tmp_path):
    from analogs.errors import InputError

    folder, _ = written
    data = json.loads((folder / "fit.json").read_text())
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data | {"schema": "other-tool/fit/7"}))
    with pytest.raises(InputError, match=r"bad\.json: `schema`: expected \"slosh-analogs/fit/2\""):
        read_fit(bad)
    bad.write_text(json.dumps(data | {"parameters": {"p1.mass": {"value": 1.0, "estimated": True,
                                                                   "interval_95": [1.0]}}}))
    with pytest.raises(InputError, match=r"`parameters.p1.mass.interval_95`: expected \[lower, "):
        read_fit(bad)


def test_report_option_refuses_a_case_file_as_its_name(tmp_path, capsys):
    assert main(["fit", "--report", str(A1), str(A1)]) == 2
    assert "--report" in capsys.readouterr().err


def test_no_module_but_the_record_writes_a_fit_record():
    """Every command writes and reads a fit through estimate.fitting.record: the keys only a
    fit record has appear nowhere else in the package's code."""
    found = []
    for path in PACKAGE.rglob("*.py"):
        if path.parent == PACKAGE / "fitting" / "record":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Constant) and node.value in RECORD_KEYS:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.value!r}")
    assert not found, found
