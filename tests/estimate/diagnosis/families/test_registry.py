"""The family registry (``estimate.diagnosis.families``): every family module contributes its
family, each names one cause, says what it is (its docstring), and the cause list the CLI,
the README and the search use is the registry's."""

import re
from pathlib import Path

from estimate.diagnosis.families import CAUSES, FAMILIES, family

ROOT = Path(__file__).resolve().parents[4]


def test_every_family_module_is_registered_once_with_a_description():
    import pkgutil

    import estimate.diagnosis.families as pkg

    modules = {m.name for m in pkgutil.iter_modules(pkg.__path__)} - {"base"}
    assert {type(f).__module__.rsplit(".", 1)[1] for f in FAMILIES} == modules
    assert len(CAUSES) == len(set(CAUSES))
    for fam in FAMILIES:
        assert family(fam.cause) is fam
        assert len(fam.description) > 40, fam.cause
        assert fam.rig in ("lateral", "spinning", "motion")


def test_the_readme_documents_exactly_the_registered_causes():
    text = (ROOT / "README.md").read_text()
    table = set(re.findall(r"^\s*\| `([a-z_]+)` \|", text, flags=re.M))
    assert set(CAUSES) <= table, set(CAUSES) - table


def test_the_cli_lists_the_registered_causes():
    import argparse

    from estimate.cli import diagnose

    parser = argparse.ArgumentParser()
    diagnose.add_parser(parser.add_subparsers())
    text = parser._subparsers._group_actions[0].choices["diagnose"].format_help()
    for cause in CAUSES:
        assert cause in text
