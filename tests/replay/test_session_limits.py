"""A session file's aliases, tip radius and number of pokes are refused at load, in one line
naming the file and the key, by the rules the settings obey (``_validation.LIMITS``)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml

from deformap.errors import ConfigError
from deformap.replay import load_session
from deformap.testing._mutators import alias_bomb


@pytest.fixture
def session(tmp_path: Path, synthetic, write_synthetic) -> Path:  # type: ignore[no-untyped-def]
    return write_synthetic(tmp_path / "s", synthetic, sealed=False)  # type: ignore[no-any-return]


def _refused(file: Path, match: str) -> str:
    with pytest.raises(ConfigError, match=match) as exc:
        load_session(file.parent)
    text = str(exc.value)
    assert "\n" not in text and str(file) in text
    return text


def test_an_alias_bomb_in_source_is_refused_at_once(session: Path) -> None:
    text = session.read_text()
    assert "\nsource:" not in text
    session.write_text(text + f"source: {{note: {alias_bomb(9, 9)}}}\n")
    start = time.perf_counter()
    _refused(session, "YAML anchors and aliases")
    assert time.perf_counter() - start < 2.0


def _edit(file: Path, change) -> None:  # type: ignore[no-untyped-def]
    doc = yaml.safe_load(file.read_text())
    change(doc)
    file.write_text(yaml.safe_dump(doc, sort_keys=False))


@pytest.mark.parametrize("radius", [1e-300, 1e-7, 2.0])
def test_a_tip_radius_beyond_a_probes_is_refused(session: Path, radius: float) -> None:
    _edit(session, lambda doc: doc["probe"].update(tip_radius_m=radius))
    _refused(session, r"`probe.tip_radius_m` must be [<>]= 1.* \(a probe's spherical tip")


def test_a_session_of_more_pokes_than_a_map_is_refused(session: Path) -> None:
    # the count is checked before any entry is: empty entries keep the file small
    _edit(session, lambda doc: doc.update(pokes=[{} for _ in range(1001)]))
    _refused(session, r"`pokes` lists 1,001 pokes; a map is made of at most 1,000")
    _edit(session, lambda doc: doc.update(pokes=[{} for _ in range(1000)]))
    _refused(session, r"`pokes\[0\]` lacks required key")  # the count passes


def test_what_deformap_writes_has_no_alias_and_reads_back(tmp_path: Path, synthetic,
                                                          write_synthetic) -> None:  # type: ignore[no-untyped-def]
    shared = [1, 2, 3]
    file = write_synthetic(tmp_path / "s", synthetic, source={"a": shared, "b": shared})
    assert "&" not in file.read_text() and "*id" not in file.read_text()
    assert load_session(file.parent).source == {"a": shared, "b": shared}


def test_map_names_a_cloud_or_a_bag_given_as_the_session(session: Path, tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    bag = tmp_path / "robot.mcap"
    bag.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)))
    for given, args, kind in ((session.parent / "observation.pcd", [], "a PCD point cloud"),
                              (bag, ["--layout", "session"], "an MCAP file (a ROS 2 bag)")):
        out = tmp_path / f"out-{given.suffix[1:]}"
        result = CliRunner().invoke(app, ["map", str(given), *args, "--out", str(out)])
        assert result.exit_code == 2, result.output
        assert f"is {kind}, not YAML (the session file)" in result.output
        assert "UTF-8" not in result.output and not out.exists()
