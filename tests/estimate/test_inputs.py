"""Inputs are opened as what they claim to be (issue 26): regular files only, never blocking
on a pipe, read within a bound, nested within a bound before any parser recurses."""

from __future__ import annotations

import json
import os
import re
import tomllib

import pytest

from analogs.errors import InputError
from estimate.inputs import (
    MAX_NESTING,
    file_kind,
    load_json,
    load_toml,
    nesting_problem,
    open_input,
    read_input,
)

pytestmark = pytest.mark.skipif(os.name != "posix", reason="FIFOs and devices")


def test_special_files_are_named_and_never_read(tmp_path):
    os.mkfifo(tmp_path / "pipe")  # opening it for reading without O_NONBLOCK would block
    cases = {tmp_path / "pipe": "a named pipe (FIFO)", "/dev/zero": "a character device",
             tmp_path: "a folder"}
    for path, kind in cases.items():
        assert file_kind(path) == kind
        with pytest.raises(InputError, match=re.escape(f"expected a fit file, found {kind}")):
            open_input(path, "a fit file")


def test_a_missing_file_says_what_was_expected(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"nothere.json does not exist \(expected a fit"):
        read_input(tmp_path / "nothere.json", "a fit file", limit=10)


def test_the_size_bound_is_stated(tmp_path):
    path = tmp_path / "x.json"
    path.write_bytes(b" " * 2049)
    assert read_input(path, "x", limit=2049) == b" " * 2049
    with pytest.raises(InputError, match="larger than 2 KiB, the most read for a fit file"):
        read_input(path, "a fit file", limit=2048)


@pytest.mark.parametrize("depth", [MAX_NESTING + 1, 50_000])
def test_deep_json_and_toml_are_refused_before_parsing(tmp_path, depth):
    (tmp_path / "d.json").write_text("[" * depth + "]" * depth)
    with pytest.raises(InputError, match=f"nested deeper than {MAX_NESTING} arrays or tables"):
        load_json(tmp_path / "d.json", "a fit file")
    (tmp_path / "d.toml").write_text("x = " + "[" * depth + "]" * depth)
    with pytest.raises(InputError, match=f"d.toml: nested deeper than {MAX_NESTING}"):
        load_toml(tmp_path / "d.toml", "a case file", limit=2**22)
    (tmp_path / "k.toml").write_text(".".join(["a"] * depth) + " = 1")
    with pytest.raises(InputError, match="dotted"):
        load_toml(tmp_path / "k.toml", "a case file", limit=2**22)


def test_the_nesting_bound_accepts_what_parsers_read():
    """Exactly MAX_NESTING levels parse; brackets inside strings and comments are not
    nesting (the count agrees with tomllib and json on these documents)."""
    ok_json = "[" * MAX_NESTING + "]" * MAX_NESTING
    assert nesting_problem(ok_json, "json") is None and json.loads(ok_json)
    deep = "[" * 200
    dotted = ".".join(["k"] * MAX_NESTING)
    toml = (f"{dotted} = [1.5, 2.5, 3.5]\ndate = 1979-05-27T07:32:00.999\n"
            f'a = "{deep}"\nb = \'{deep}\'\nc = """\n{deep}\n"""\nd = \'\'\'{deep}\'\'\'\n'
            f'# {deep}\ne = "x\\"[[[" \n[t]\nf = [[1], [2]]\n[[arr]]\ng = 1\n')
    assert nesting_problem(toml, "toml") is None
    doc = tomllib.loads(toml)
    assert doc["a"] == deep and doc["t"]["f"] == [[1], [2]]
    text = json.dumps({"k": deep, "l": [[1]]})
    assert nesting_problem(text, "json") is None
