"""``slosh fit`` on records as labs write them: receive-time stamps (``[test] resample_hz``,
said in the output and the JSON) and ``--motion-band``."""

from __future__ import annotations

import json

import numpy as np
import pytest
import reference_models as ref
import reference_rig_records as rig

from estimate.cli import main
from estimate.data import write_case
from estimate.data.case import Liquid, Rig, Tank, TestInfo
from estimate.fitting.carriage import KNOTS_PER_PERIOD


@pytest.fixture(scope="module")
def jittered(tmp_path_factory):
    """A 12 s sine test from rest at 100 Hz whose timestamps jitter by +/- 2 ms."""
    folder = tmp_path_factory.mktemp("lab")
    t = np.arange(1201) / 100.0
    p = ref.Pendulum(1.3, 0.0553, 0.0, ref.hinge_damping(1.3, 0.0553, 0.01))
    sim = ref.simulate_lateral(t, ref.Ramped(ref.Sine(0.002, 1.8), 2.0), pendulums=[p],
                               fixed_mass=1.5, dry_mass=1.2, noise=0.01,
                               displacement_noise=2e-5, seed=2)
    stamps = rig.receive_times(t, jitter=2e-3, rng=np.random.default_rng(2))
    write_case(folder / "j.toml", test=TestInfo("j", "lateral", "j.csv", "measured",
                                                resample_hz=100.0),
               tank=Tank("sphere", 0.1016, 0.6, False), liquid=Liquid(998.2, 1.004e-6),
               rig=Rig(1.2, 9.80665), time=stamps, force=sim["force"],
               displacement=sim["displacement"])
    return folder / "j.toml"


def test_fit_says_what_was_done_to_the_timestamps(jittered, tmp_path, capsys):
    out = tmp_path / "fit.json"
    assert main(["fit", str(jittered), "--json", str(out), "--motion-band", "3"]) == 0
    printed = capsys.readouterr().out
    assert "note: j.csv: [test] resample_hz = 100: timestamps jitter by up to 2" in printed
    data = json.loads(out.read_text())
    assert any("receive times of uniformly taken samples" in n for n in data["notes"])
    # --motion-band 3 Hz: knots at most 1 / (KNOTS_PER_PERIOD x 3 Hz) apart, the record cut
    # in equal parts
    top = 1 / (KNOTS_PER_PERIOD * 3.0)
    assert 0.99 * top < data["noise"][0]["knot_spacing_s"] <= top


@pytest.mark.parametrize("value", ["0", "-2", "fast", "nan"])
def test_a_bad_motion_band_is_refused(jittered, capsys, value):
    with pytest.raises(SystemExit) as info:
        main(["fit", str(jittered), f"--motion-band={value}"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--motion-band" in err and "expected a positive frequency in Hz" in err \
        or "expected a frequency in Hz" in err
