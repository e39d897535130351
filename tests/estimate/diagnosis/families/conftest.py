"""Clean short records for the per-family tests: the same drives as the records with an
effect, no effect (the family must not be proposed on them)."""

import pytest
import reference_diagnosis_records as R


@pytest.fixture(scope="session")
def clean_sweep(tmp_path_factory):
    """15 s chirp 1-4.5 Hz (3 mm), first mode only."""
    return R.write(R.short("clean sweep", R.SHORT_SWEEP, seed=61), tmp_path_factory.mktemp("c"),
                   "clean_sweep")[0]


@pytest.fixture(scope="session")
def clean_steps(tmp_path_factory):
    """15 s of 1, 2 and 4 mm at 1.9 Hz, first mode only."""
    return R.write(R.short("clean steps", R.SHORT_STEPS, seed=62), tmp_path_factory.mktemp("c"),
                   "clean_steps")[0]
