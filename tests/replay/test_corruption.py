"""Hypothesis-generated corruptions of a session: each read is refused with a DeformapError that
names the session, or returns the right data.

"Right" is what can be known without the bytes that were lost: a read that does not touch the
corrupted file returns exactly what the intact session gives; a cut (truncated) data file is
always refused; the ground truth (a zip with CRCs) is refused or read unchanged; a damaged
``session.yaml`` that still loads gives as many pokes as it lists, each with the target and force
it states. A flipped byte inside a cloud's raw floats, which PCD and bag payloads cannot see, is
caught by the session's ``sha256`` manifest: every read of a changed data file is refused.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from deformap.cloud import PointCloud
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


@pytest.fixture(scope="module")
def intact(templates: dict[str, Path]) -> dict[str, dict[str, Any]]:
    """What each intact template reads as (every read must succeed)."""
    out = {form: _read_all(folder) for form, folder in templates.items()}
    for form, outcomes in out.items():
        assert not any(isinstance(o, DeformapError) for o in outcomes.values()), form
        assert len(outcomes) == 4, form  # load, observation, two pokes
    return out


def _snapshot(value: Any) -> tuple[Any, ...]:
    """What a read returned, as comparable bytes."""
    if hasattr(value, "contact"):  # a PressObservation
        return (value.cloud.points.tobytes(), value.robot_points.tobytes(),
                value.contact.tip_center.tobytes(), value.contact.force.tobytes(),
                np.asarray(value.target_xy).tobytes(), value.force_n)  # fmt: skip
    if isinstance(value, PointCloud):
        return (value.points.tobytes(),)
    truth = value
    if truth is None:
        return (None,)
    return (truth.xs.tobytes(), truth.ys.tobytes(), truth.labels.tobytes(),
            truth.hardness.tobytes())  # fmt: skip


def _read_all(folder: Path) -> dict[str, Any]:
    """Load the session and read everything in it.

    Returns ``{"load": ..., "observation": ..., "press-0": ..., ...}``, each a snapshot of what
    came or the DeformapError raised; anything else raised fails the test.
    """
    try:
        session = load_session(folder)
    except DeformapError as exc:
        return {"load": exc}
    out: dict[str, Any] = {"load": (len(session), _snapshot(session.ground_truth))}
    reads: list[tuple[str, Callable[[], Any]]] = [("observation", session.observation)]
    for i in range(len(session)):
        reads.append((f"press-{i}", (lambda i=i: session.press_observation(i))))
    for name, read in reads:
        try:
            out[name] = _snapshot(read())
        except DeformapError as exc:
            out[name] = exc
    return out


def _check_refusals_name_the_session(outcomes: dict[str, Any], folder: Path) -> None:
    for name, outcome in outcomes.items():
        if isinstance(outcome, DeformapError):
            assert str(folder) in str(outcome), f"{name}: the error does not name the session"


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
        outcomes = _read_all(folder)
        _check_refusals_name_the_session(outcomes, folder)
        if isinstance(outcomes["load"], DeformapError):
            return
        # it loaded, so the file's pokes are a list of entries, each read as the file states it
        n_pokes, _ = outcomes["load"]
        assert n_pokes == len(doc["pokes"])
        for i, entry in enumerate(doc["pokes"]):
            got = outcomes[f"press-{i}"]
            if isinstance(got, DeformapError):
                continue
            force = entry["force_n"]
            assert isinstance(force, (int, float)) and not isinstance(force, bool), force
            assert got[5] == force
            np.testing.assert_array_equal(np.frombuffer(got[4]), entry["target_xy"])
    finally:
        shutil.rmtree(folder.parent)


def _depends_on(form: str, file: str) -> set[str]:
    """The reads that touch ``file`` (relative to the session folder)."""
    if file == "session.yaml":  # says what every read reads
        return {"load", "observation", "press-0", "press-1"}
    if file == "ground_truth.npz":
        return {"load"}
    if form == "folder":
        if file == "observation.pcd":
            return {"observation"}
        return {f"press-{int(file[5:7]) - 1}"}  # poke-NN.pcd, poke-NN-robot.pcd
    return {"observation", "press-0", "press-1"}  # bag/: the one bag holds every message


@SETTINGS
@given(data=st.data())
def test_byte_corruption_of_any_file(
    templates: dict[str, Path], intact: dict[str, dict[str, Any]], data: st.DataObject
) -> None:
    form = data.draw(st.sampled_from(sorted(templates)))
    folder = _copy(templates[form])
    try:
        files = sorted(p for p in folder.rglob("*") if p.is_file())
        target = data.draw(st.sampled_from(files))
        original = target.read_bytes()
        raw = bytearray(original)
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
        outcomes = _read_all(folder)
        _check_refusals_name_the_session(outcomes, folder)
        name = target.relative_to(folder).as_posix()
        touched = _depends_on(form, name) if bytes(raw) != original else set()
        if action == "truncate" and name.endswith((".pcd", ".npz", ".mcap")):
            # a cut data file is always refused, by the load or by each read of it
            for read in touched:
                assert isinstance(outcomes.get(read, outcomes["load"]), DeformapError), read
        if name != "session.yaml":
            # the sha256 manifest: a changed data file is refused by every read of it
            for read in touched:
                assert isinstance(outcomes.get(read, outcomes["load"]), DeformapError), read
        if name == "ground_truth.npz" and not isinstance(outcomes["load"], DeformapError):
            assert outcomes["load"] == intact[form]["load"]  # zip CRCs: refused or unchanged
        if isinstance(outcomes["load"], DeformapError):
            assert "load" in touched or touched >= {"observation"}, "an untouched session refused"
            return
        for read, want in intact[form].items():
            if read not in touched and read != "load":
                assert outcomes[read] == want, f"{read} changed though {name} is not in it"
        if "load" not in touched:
            assert outcomes["load"] == intact[form]["load"]
    finally:
        shutil.rmtree(folder.parent)
