"""Hypothesis-generated corruptions of a session never crash with anything but a DeformapError."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformap.errors import DeformapError
from deformap.replay import load_session

SETTINGS = settings(max_examples=40, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])  # fmt: skip


@pytest.fixture(scope="module")
def templates(tmp_path_factory: pytest.TempPathFactory, make_synthetic: Any,
              write_synthetic: Any) -> dict[str, Path]:  # fmt: skip
    syn = make_synthetic(n_pokes=2, n_points=400)
    root = tmp_path_factory.mktemp("templates")
    out = {"folder": write_synthetic(root / "folder", syn).parent}
    try:
        import rosbags  # noqa: F401

        out["mcap"] = write_synthetic(root / "mcap", syn, format="mcap").parent
    except ImportError:
        pass
    return out


def _read_all(folder: Path) -> None:
    """Load the session and read everything in it; only DeformapError may come out."""
    try:
        session = load_session(folder)
    except DeformapError:
        return
    for read in [session.observation] + [
        (lambda i=i: session.press_observation(i)) for i in range(len(session))
    ]:
        try:
            read()
        except DeformapError:
            pass


def _copy(template: Path) -> Path:
    dest = Path(tempfile.mkdtemp(prefix="deformap-corrupt-")) / "s"
    shutil.copytree(template, dest)
    return dest


_LEAVES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(10**12), 10**12)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=12,
)


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix]
    if isinstance(node, dict):
        for key, value in node.items():
            out += _paths(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            out += _paths(value, (*prefix, i))
    return out


@SETTINGS
@given(data=st.data())
def test_structural_yaml_corruption(templates: dict[str, Path], data: st.DataObject) -> None:
    form = data.draw(st.sampled_from(sorted(templates)))
    folder = _copy(templates[form])
    try:
        file = folder / "session.yaml"
        doc = yaml.safe_load(file.read_text())
        for _ in range(data.draw(st.integers(1, 3))):
            paths = [p for p in _paths(doc) if p]
            where = data.draw(st.sampled_from(paths))
            parent: Any = doc
            for key in where[:-1]:
                parent = parent[key]
            if data.draw(st.booleans()) and isinstance(parent, dict):
                del parent[where[-1]]
            else:
                parent[where[-1]] = data.draw(_LEAVES)
        file.write_text(yaml.safe_dump(doc))
        _read_all(folder)
    finally:
        shutil.rmtree(folder.parent)


@SETTINGS
@given(data=st.data())
def test_byte_corruption_of_any_file(templates: dict[str, Path], data: st.DataObject) -> None:
    form = data.draw(st.sampled_from(sorted(templates)))
    folder = _copy(templates[form])
    try:
        files = sorted(p for p in folder.rglob("*") if p.is_file())
        target = data.draw(st.sampled_from(files))
        raw = bytearray(target.read_bytes())
        action = data.draw(st.sampled_from(["truncate", "flip", "insert"]))
        if action == "truncate" or not raw:
            raw = raw[: data.draw(st.integers(0, max(len(raw) - 1, 0)))]
        elif action == "flip":
            for _ in range(data.draw(st.integers(1, 8))):
                i = data.draw(st.integers(0, len(raw) - 1))
                raw[i] = data.draw(st.integers(0, 255))
        else:
            i = data.draw(st.integers(0, len(raw)))
            raw[i:i] = data.draw(st.binary(min_size=1, max_size=16))
        target.write_bytes(bytes(raw))
        _read_all(folder)
    finally:
        shutil.rmtree(folder.parent)
