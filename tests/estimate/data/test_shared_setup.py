"""Cases fitted with shared parameters must describe one tank, fill and liquid: a 40 % and an
80 % fill in one `slosh fit` are refused before any fitting, in one line naming both files
and the key that differs (new-user report, defect 8)."""

import shutil
from pathlib import Path

import pytest

from estimate.cli import main
from estimate.data import load_case
from estimate.data.case import CaseError
from estimate.data.records import refuse_mixed, setup_differences

CAMPAIGN = Path(__file__).resolve().parents[3] / "examples" / "campaign"


def test_a_40_and_an_80_percent_fill_in_one_fit_are_refused_in_one_line(capsys):
    status = main(["fit", str(CAMPAIGN / "F40_sine_3mm.toml"), str(CAMPAIGN / "F80_sine_3mm.toml"),
                   "--model", "fixed,p1:nospring"])
    assert status == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    assert err.startswith("slosh fit: error: F80_sine_3mm.toml: [tank] fill_fraction = 0.8, but "
                          "F40_sine_3mm.toml has 0.4")
    assert "slosh campaign" in err


def test_the_same_fill_fits_together_and_every_differing_key_is_named(tmp_path):
    a = load_case(CAMPAIGN / "F40_sine_3mm.toml")
    b = load_case(CAMPAIGN / "F40_sine_1.5mm.toml")
    refuse_mixed([a, b])  # two drives of one fill: accepted
    assert setup_differences(a, b) == []
    # another liquid in a copy of the record
    text = (CAMPAIGN / "F40_sine_1.5mm.toml").read_text()
    shutil.copy(CAMPAIGN / "F40_sine_1.5mm.csv", tmp_path / "F40_sine_1.5mm.csv")
    assert "density = 998.2 " in text
    (tmp_path / "oil.toml").write_text(text.replace("density = 998.2 ", "density = 870.0 "))
    c = load_case(tmp_path / "oil.toml")
    assert setup_differences(c, a) == [("[liquid] density", "870", "998.2")]
    with pytest.raises(CaseError, match=r"^oil\.toml: \[liquid\] density = 870, but "
                                        r"F40_sine_3mm\.toml has 998\.2: "):
        refuse_mixed([a, c])
