"""The progress line of a step without a known total (``slosh diagnose``): the count in its
unit, the elapsed time and the stage; no inverted rate ("1.61s/ fits")."""

import re

from estimate._progress import progress


def test_a_bar_without_a_total_counts_in_its_unit_with_the_time_and_the_stage():
    with progress(total=None, desc="diagnose", unit=" fits", enabled=True) as bar:
        bar.update()
        bar.update()
        bar.set_postfix_str("round 1: candidates")
        line = str(bar)
    assert re.fullmatch(r"diagnose: 2 fits \[00:0\d, round 1: candidates\]", line), line


def test_a_bar_with_a_total_keeps_tqdm_s_line():
    with progress(total=4, desc="NTC", unit="stage", enabled=True) as bar:
        bar.update()
        line = str(bar)
    assert line.startswith("NTC:  25%|") and "1/4" in line, line
