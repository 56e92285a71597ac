"""docs/scenarios.md documents the scenario YAML: its examples parse, and its key tables name
exactly the keys the reader takes, each used in an example that parses."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from deformap.errors import ConfigError
from deformap.world import load_scenario
from deformap.world._scenario_io import _BLOCK_KEYS, _SCENARIO_KEYS, _WORKSPACE_KEYS, parse_scenario

DOC = Path(__file__).resolve().parents[1] / "docs" / "scenarios.md"
TEXT = DOC.read_text(encoding="utf-8")


def _yaml_blocks() -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", TEXT, flags=re.S)


def _table_keys(heading: str) -> set[str]:
    """The first-column keys of the table after the line ``heading``."""
    part = TEXT.split(heading, 1)[1]
    rows = []
    for line in part.splitlines()[1:]:
        if line.startswith("|"):
            rows.append(line)
        elif rows:
            break
    return {m.group(1) for row in rows[2:] if (m := re.match(r"\|\s*`(\w+)`", row))}


def test_every_example_parses(tmp_path: Path) -> None:
    blocks = _yaml_blocks()
    assert blocks
    for i, text in enumerate(blocks):
        path = tmp_path / f"example-{i}.yaml"
        path.write_text(text)
        scenario = load_scenario(path)
        assert scenario.blocks


def test_the_tables_name_exactly_the_keys_the_reader_takes() -> None:
    assert _table_keys("The scenario:") == _SCENARIO_KEYS
    assert _table_keys("The workspace:") == _WORKSPACE_KEYS
    assert _table_keys("A block:") == _BLOCK_KEYS


def test_every_documented_key_is_used_in_an_example_that_parses() -> None:
    used_top, used_ws, used_block = set(), set(), set()
    for text in _yaml_blocks():
        data = yaml.safe_load(text)
        parse_scenario(data)
        used_top |= set(data)
        used_ws |= set(data.get("workspace", {}))
        for block in data["blocks"]:
            used_block |= set(block)
    assert used_top == _SCENARIO_KEYS and used_ws == _WORKSPACE_KEYS and used_block == _BLOCK_KEYS


@pytest.mark.parametrize("key", sorted(_BLOCK_KEYS | _SCENARIO_KEYS))
def test_a_misspelt_key_is_refused_as_the_doc_says(key: str) -> None:
    data = yaml.safe_load(_yaml_blocks()[0])
    if key in _SCENARIO_KEYS:
        data[key + "x"] = data.pop(key)
    else:
        block = next(b for b in data["blocks"] if key in b)
        block[key + "x"] = block.pop(key)
    with pytest.raises(ConfigError, match=f"{key}x"):
        parse_scenario(data)
