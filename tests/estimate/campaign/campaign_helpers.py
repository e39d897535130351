"""Mini campaigns for the tests: records of the bundled SYNTHETIC campaign
(``examples/campaign``, made by the independent reference simulator) copied into a folder,
and the generator's truth to compare with."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import tolerances as tol

ROOT = Path(__file__).resolve().parents[3]
BUNDLED = ROOT / "examples" / "campaign"
TRUTH = json.loads((BUNDLED / "campaign_truth.json").read_text())

#: Relative tolerance of a group fit per quantity (reasons in tests/tolerances.py).
TOLERANCES = {"fixed.mass": tol.CAMPAIGN_MASS, "p1.mass": tol.CAMPAIGN_MASS,
              "p1.frequency_hz": tol.CAMPAIGN_FREQUENCY,
              "p1.damping_ratio": tol.CAMPAIGN_DAMPING}
RECORD_SIGMAS = tol.CAMPAIGN_RECORD_SIGMAS
#: A record fitted alone on the free-surface model (no hinge spring), as campaign.toml does.
MODEL = "fixed,p1:nospring"


def copy_records(folder: Path, names, *, campaign_toml: str | None = None) -> Path:
    """Copy bundled records (case file and CSV) into ``folder``; optionally write a
    ``campaign.toml``. Returns ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        for ext in ("toml", "csv"):
            shutil.copy(BUNDLED / f"{name}.{ext}", folder / f"{name}.{ext}")
    if campaign_toml is not None:
        (folder / "campaign.toml").write_text(campaign_toml)
    return folder


def corrupt(folder: Path, name: str, line: int = 500) -> None:
    """Replace one data row of ``name``'s CSV with text, as a damaged transfer might."""
    path = folder / f"{name}.csv"
    rows = path.read_text().splitlines()
    rows[line] = "12.34,not a number,##"
    path.write_text("\n".join(rows) + "\n")


def read_csv(path: Path) -> list[dict[str, str]]:
    import csv

    with path.open() as fh:
        return list(csv.DictReader(fh))


def case_toml(folder: Path, name: str, *, fill=0.6, density=998.2, radius=0.1016,
              rig="lateral", data=True) -> Path:
    """A case file with what discovery reads, and a stand-in data file (not a valid case:
    loading it fails, which some tests want)."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.toml"
    path.write_text(f'[test]\nid = "{name}"\nrig = "{rig}"\ndata = "{name}.csv"\n'
                    f'excitation = "measured"\n[tank]\nshape = "sphere"\nradius = {radius}\n'
                    f"fill_fraction = {fill}\ndiaphragm = false\n[liquid]\ndensity = {density}\n"
                    "kinematic_viscosity = 1.004e-6\n[rig]\ndry_mass = 1.2\ngravity = 9.80665\n")
    if data:
        (folder / f"{name}.csv").write_text(f"time,displacement,force\n0,0,{fill}\n")
    return path
