"""YAML is read through one reader that refuses anchors and aliases anywhere (a nested alias bomb
inside a known key included), string settings must be strings, and the bounds of one table
(``_validation.LIMITS``) hold wherever a quantity comes from."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from deformap._config import load_yaml, parse_yaml
from deformap._validation import LIMITS, SettingError, check_limit
from deformap.environment import Workspace
from deformap.errors import ConfigError, DeformapError
from deformap.explore import ExplorationConfig, check_exploration_budget
from deformap.run import load_run_config
from deformap.testing._mutators import alias_bomb
from deformap.world import WorldConfig, load_scenario

SCENARIO = """\
name: custom
description: two blocks
blocks:
  - name: soft
    rect: [0.0, 0.0, 0.3, 0.4]
    hardness_n: 60
    color: "#c8a165"
  - name: hard
    rect: [0.3, 0.0, 0.6, 0.4]
    hardness_n: 150
"""


def _write(tmp_path: Path, text: str, name: str = "s.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _one_line(exc: pytest.ExceptionInfo[BaseException]) -> str:
    text = str(exc.value)
    assert "\n" not in text
    return text


@pytest.mark.parametrize("text", [
    "a: &x [1, 2]\nb: *x\n",          # anchor and alias at the top level
    "a:\n  b: [&x 1, *x]\n",           # nested, in a flow sequence
    "a: &x 1\n",                       # an anchor alone
    "a: {<<: *x}\n",                   # a merge key is an alias
])
def test_anchors_and_aliases_are_refused_anywhere(text: str) -> None:
    with pytest.raises(ConfigError, match=r"^T: YAML anchors and aliases .* not accepted \(line"):
        parse_yaml(text, where="T")


def test_plain_yaml_still_reads() -> None:
    assert parse_yaml("a: [1, {b: x}]\nc: 'a & b *c'\n", where="T") == {
        "a": [1, {"b": "x"}], "c": "a & b *c"}
    with pytest.raises(ConfigError, match="appears twice"):
        parse_yaml("a: 1\na: 2\n", where="T")


@pytest.mark.parametrize("line", ["description: two blocks", "name: custom", "  - name: soft",
                                  '    color: "#c8a165"'])
def test_a_nested_alias_bomb_in_a_scenario_key_is_refused_at_once(tmp_path: Path,
                                                                  line: str) -> None:
    key = line.split(":")[0]
    path = _write(tmp_path, SCENARIO.replace(line, f"{key}: {alias_bomb(9, 9)}"))
    start = time.perf_counter()
    with pytest.raises(ConfigError) as exc:
        load_scenario(path)
    assert time.perf_counter() - start < 2.0
    text = _one_line(exc)
    assert str(path) in text and "anchors and aliases" in text


def test_an_alias_bomb_in_a_run_config_and_a_set_value_is_refused(tmp_path: Path) -> None:
    path = _write(tmp_path, f"exploration:\n  strategy: {alias_bomb(9, 9)}\n", "c.yaml")
    with pytest.raises(ConfigError, match="anchors and aliases"):
        load_run_config(path)
    from deformap.run._worlds_config import parse_assignments

    with pytest.raises(ConfigError, match="--set strategy: the value must be a scalar"):
        parse_assignments(["strategy=&a x"])


@pytest.mark.parametrize(("line", "new", "match"), [
    ("name: custom", "name: [a]", r"`name` must be a string; got a list"),
    ("description: two blocks", "description: 7", r"`description` must be a string; got 7"),
    ("  - name: soft", "  - name: {a: 1}", r"`name` must be a string; got \{'a': 1\}"),
    ('    color: "#c8a165"', "    color: [a]", r"`color` must be a string; got a list"),
])
def test_string_settings_are_not_coerced(tmp_path: Path, line: str, new: str, match: str) -> None:
    with pytest.raises(ConfigError, match=match) as exc:
        load_scenario(_write(tmp_path, SCENARIO.replace(line, new)))
    assert _one_line(exc).startswith(str(tmp_path))


@pytest.mark.parametrize(("workspace", "match"), [
    ("{lower: 5, upper: [0.6, 0.4]}", r"`lower` must be a \(2,\) array .* got shape \(\)"),
    ("{lower: [0, 0], upper: [a, b]}", r"`upper` must be a \(2,\) array .* dtype"),
    ("{lower: [0, 0, 0], upper: [0.6, 0.4]}", r"`lower` .* got shape \(3,\)"),
])
def test_a_workspace_of_the_wrong_shape_is_one_line(tmp_path: Path, workspace: str,
                                                    match: str) -> None:
    text = SCENARIO.replace("description: two blocks", f"workspace: {workspace}")
    with pytest.raises(ConfigError, match=match) as exc:
        load_scenario(_write(tmp_path, text))
    assert "workspace" in _one_line(exc)


def test_a_block_wholly_outside_the_workspace_is_refused(tmp_path: Path) -> None:
    text = SCENARIO.replace("[0.3, 0.0, 0.6, 0.4]", "[2.0, 2.0, 2.3, 2.4]")
    with pytest.raises(ConfigError, match="block 'hard' lies wholly outside the workspace"):
        load_scenario(_write(tmp_path, text))
    # touching the workspace's edge from outside is outside too; a block half inside is kept
    text = SCENARIO.replace("[0.3, 0.0, 0.6, 0.4]", "[0.6, 0.0, 0.9, 0.4]")
    with pytest.raises(ConfigError, match="wholly outside"):
        load_scenario(_write(tmp_path, text))
    text = SCENARIO.replace("[0.3, 0.0, 0.6, 0.4]", "[0.3, 0.0, 0.9, 0.4]")
    assert len(load_scenario(_write(tmp_path, text)).blocks) == 2


def test_a_first_target_outside_the_workspace_is_refused_before_any_world() -> None:
    config = ExplorationConfig(first_target=(2.0, 0.1))
    with pytest.raises(SettingError) as exc:
        check_exploration_budget(config, Workspace())
    text = _one_line(exc)
    assert text.startswith("`first_target` must lie inside the workspace [0, 0.6] × [0, 0.4]")
    assert "array(" not in text and "np." not in text and text.endswith("got (2, 0.1)")
    check_exploration_budget(ExplorationConfig(first_target=(0.6, 0.4)), Workspace())  # an edge


def test_a_first_target_outside_is_refused_by_explore_before_the_folder(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    config = _write(tmp_path, "exploration:\n  first_target: [2.0, 0.1]\n", "c.yaml")
    out = tmp_path / "run"
    result = CliRunner().invoke(app, ["explore", "-s", "homogeneous-60", "--config", str(config),
                                      "--out", str(out)])
    assert result.exit_code == 2 and not out.exists(), result.output
    assert "`first_target` must lie inside the workspace" in result.output


def test_one_table_bounds_a_tip_and_the_pokes_with_a_reason() -> None:
    with pytest.raises(SettingError, match=r"`tip_radius_m` must be >= 1e-06 \(a probe's "
                                           r"spherical tip, from a micrometre"):
        WorldConfig(tip_radius_m=1e-300)
    with pytest.raises(SettingError, match=r"`max_pokes` must be an integer <= 1000"):
        ExplorationConfig(max_pokes=1001)
    assert check_limit("n", 0.01, "tip_radius_m") == 0.01
    with pytest.raises(SettingError, match="must be an integer"):
        check_limit("n", 2.5, "pokes")
    with pytest.raises(DeformapError, match="must be finite"):
        check_limit("r", float("nan"), "tip_radius_m")
    assert LIMITS["pokes"]["le"] == ExplorationConfig.__dataclass_fields__[
        "max_pokes"].metadata["deformap.bounds"]["le"]


def test_load_yaml_names_the_file(tmp_path: Path) -> None:
    path = _write(tmp_path, "a: *undefined\n")
    with pytest.raises(ConfigError, match=f"^{str(path)!r}: YAML anchors"):
        load_yaml(path)


def test_dump_yaml_writes_a_shared_value_in_full() -> None:
    from deformap._config import dump_yaml

    shared = [1.0, 2.0]
    text = dump_yaml({"a": shared, "b": shared})
    assert "&" not in text and parse_yaml(text, where="T") == {"a": shared, "b": shared}


@pytest.mark.parametrize(("name", "head", "kind"), [
    ("observation.pcd", b"# .PCD v0.7 - Point Cloud Data\nVERSION 0.7\n\x00\x93", "a PCD point cloud"),
    ("cloud.txt", b"VERSION 0.7\nFIELDS x y z\n", "a PCD point cloud"),
    ("cloud.ply", b"ply\nformat binary_little_endian 1.0\n\xff\xfe", "a PLY point cloud"),
    ("bag.mcap", b"\x89MCAP0\r\n\x01\x02", "an MCAP file (a ROS 2 bag)"),
    ("bag.db3", b"SQLite format 3\x00\x10\x00", "a sqlite3 database (a ROS 2 bag?)"),
    ("truth.npz", b"PK\x03\x04\x14\x00", "a zip archive (an NPZ file?)"),
])
def test_a_data_file_read_as_yaml_is_named_for_what_it_is(tmp_path: Path, name: str, head: bytes,
                                                          kind: str) -> None:
    path = tmp_path / name
    path.write_bytes(head)
    with pytest.raises(ConfigError) as exc:
        load_yaml(path, what="the session file")
    assert str(exc.value) == f"{str(path)!r} is {kind}, not YAML (the session file)"


def test_yaml_that_starts_like_a_header_word_is_still_yaml(tmp_path: Path) -> None:
    path = _write(tmp_path, "VERSION: 2\nply: 1\n", "c.yaml")
    assert load_yaml(path) == {"VERSION": 2, "ply": 1}


def test_nesting_is_bounded_in_one_line() -> None:
    from deformap._config import MAX_YAML_DEPTH

    deep = MAX_YAML_DEPTH
    assert parse_yaml("[" * deep + "]" * deep, where="T") is not None
    for n in (deep + 1, 5000):  # 5000: PyYAML's own recursion would end in a RecursionError
        with pytest.raises(ConfigError, match=f"^T: YAML nested deeper than {deep} levels"):
            parse_yaml("a: " + "[" * n + "]" * n, where="T")


def test_many_unknown_keys_are_named_in_a_short_line(tmp_path: Path) -> None:
    keys = "".join(f"k{i}{'x' * 100}: 1\n" for i in range(10_000))
    with pytest.raises(ConfigError) as exc:
        load_run_config(_write(tmp_path, keys, "c.yaml"))
    text = str(exc.value)
    assert "and 9,995 more" in text and len(text) < 1000
    with pytest.raises(ConfigError, match=r"unknown key\(s\) \['k0x.*and 9,995 more\]") as exc:
        load_scenario(_write(tmp_path, SCENARIO + keys))
    assert len(str(exc.value)) < 1000
