"""The 3D recording: a timeline with the observation, each press and the β-field as it grows."""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1] / "explore"))


def test_record_run_writes_a_recording_rerun_can_read(tmp_path) -> None:
    pytest.importorskip("rerun")
    from test_own_environment import TwoFoamTable  # type: ignore[import-not-found]

    from deformap.explore import BetaFieldConfig, ExplorationConfig, SurfaceGPConfig, explore
    from deformap.viz import record_run

    env = TwoFoamTable(np.random.default_rng(1))
    config = ExplorationConfig(
        max_pokes=2, strategy="max-variance", first_target=(0.06, 0.08),
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.06),
    )  # fmt: skip
    result = explore(env, config, rng=np.random.default_rng(0))
    path = record_run(tmp_path / "run.rrd", result, initial_points=env.observe().points)
    assert path.stat().st_size > 50_000
    assert sorted(tmp_path.iterdir()) == [path]  # written under a temporary name, then renamed
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    entities = {str(chunk.entity_path) for chunk in reader.stream()}
    for entity in ("/world/observation", "/world/press/dent", "/maps/beta", "/metrics/beta",
                   "/maps/variance", "/maps/regions"):  # fmt: skip
        assert entity in entities, (entity, sorted(entities))
    columns = _columns(path)
    # the maps as values, not colours; the regions as classes with names
    assert "Tensor:data" in columns["/maps/beta"] and "Tensor:data" in columns["/maps/variance"]
    assert "SegmentationImage:buffer" in columns["/maps/regions"]
    assert "AnnotationContext:context" in columns["/maps/regions"]
    # a blueprint the viewer opens on, stored with the recording
    assert [b.kind for b in reader.blueprints()] == ["blueprint"]
    layout = {str(c.entity_path) for c in reader.stream(store=reader.blueprints()[0])}
    views = {e for e in layout if e.startswith("/view/") and e.count("/") == 2}
    # the 3D scene, four maps, the regions and the time series, in three containers
    assert len(views) == 7 and sum(e.startswith("/container/") for e in layout) == 3
    # a Z-up world; each step on both timelines, the time rising with the pokes' own timings
    assert "ViewCoordinates:xyz" in columns["/world"]
    batches = [c.to_record_batch() for c in reader.stream() if str(c.entity_path) == "/metrics/beta"]
    assert all({"poke", "time"} <= set(b.schema.names) for b in batches)
    times = [int(t) for b in batches for t in b.column("time").cast("int64").to_pylist()]  # ns
    assert len(times) == 2 and 0 < times[0] < times[1]
    spent = [p.record.timings.compute_s + (p.record.timings.environment_s or 0.0)
             for p in result.pokes]  # fmt: skip
    assert times[1] / 1e9 == pytest.approx(sum(spent), rel=1e-6)
    # without a world: no ground truth, no robot hull
    assert "/maps/truth_hardness_n" not in entities and "/world/press/robot_hull" not in entities


def _columns(path: Path) -> dict[str, set[str]]:
    from rerun.chunk import RrdReader

    out: dict[str, set[str]] = {}
    for chunk in RrdReader(path).stream():
        out.setdefault(str(chunk.entity_path), set()).update(chunk.to_record_batch().schema.names)
    return out


def test_the_recording_holds_the_ground_truth_and_the_robot_hull_when_given(tmp_path) -> None:
    pytest.importorskip("rerun")
    from test_own_environment import TwoFoamTable  # type: ignore[import-not-found]

    from deformap.explore import ExplorationConfig, SurfaceGPConfig, explore
    from deformap.viz import hull_mesh, record_run

    env = TwoFoamTable(np.random.default_rng(1))
    config = ExplorationConfig(
        max_pokes=1, strategy="max-variance", first_target=(0.06, 0.08),
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
    )  # fmt: skip
    result = explore(env, config, rng=np.random.default_rng(0))
    truth = np.full((result.ys.size, result.xs.size), 60.0)
    truth[:, : result.xs.size // 2] = np.inf  # rigid: NaN in the tensor
    box = np.array([[x, y, z] for x in (0, 0.1) for y in (0, 0.1) for z in (0.05, 0.2)])
    path = record_run(tmp_path / "run.rrd", result, initial_points=env.observe().points,
                      truth_hardness=truth, robot_points=[box])  # fmt: skip
    columns = _columns(path)
    assert "Tensor:data" in columns["/maps/truth_hardness_n"]
    assert "Mesh3D:vertex_positions" in columns["/world/press/robot_hull"]
    vertices, triangles = hull_mesh(box)
    assert len(vertices) == 8 and len(triangles) == 12  # a box: 8 corners, 2 triangles a face
    assert triangles.max() == 7


def test_a_failed_recording_leaves_no_file(tmp_path) -> None:
    pytest.importorskip("rerun")
    from deformap.viz import record_run

    # fails after the observation is logged: a poke without its arrays
    result = SimpleNamespace(mapper=SimpleNamespace(surface=None, pokes=[object()]))
    with pytest.raises(AttributeError):
        record_run(tmp_path / "run.rrd", result, initial_points=np.zeros((3, 3)))
    assert list(tmp_path.iterdir()) == []


def test_the_recording_logs_the_modulus_field_when_a_poke_has_a_modulus(tmp_path) -> None:
    pytest.importorskip("rerun")
    import dataclasses

    from test_own_environment import TwoFoamTable  # type: ignore[import-not-found]

    from deformap.explore import (
        ExplorationConfig,
        ModulusField,
        PokeResult,
        SurfaceGPConfig,
        explore,
    )
    from deformap.stiffness import StiffnessEstimate
    from deformap.viz import record_run

    env = TwoFoamTable(np.random.default_rng(1))
    config = ExplorationConfig(
        max_pokes=2, strategy="max-variance", first_target=(0.06, 0.08),
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
    )  # fmt: skip
    result = explore(env, config, rng=np.random.default_rng(0))
    estimate = StiffnessEstimate(
        stiffness_n_per_m=500.0, stiffness_std_n_per_m=10.0, stiffness_lower_n_per_m=None,
        modulus_pa=2e4, modulus_std_pa=1e3, contact_offset_m=0.0, depth_m=0.002, max_chi=0.3,
        reduced_chi2=1.0, rigid=False, n_samples=8)  # fmt: skip
    pokes = tuple(PokeResult(dataclasses.replace(p.record, stiffness=estimate), p.dent)
                  for p in result.pokes)  # fmt: skip
    field = ModulusField.of_records([p.record for p in pokes], result.xs, result.ys,
                                    config.modulus_field, 0.33)  # fmt: skip
    result = dataclasses.replace(result, pokes=pokes, modulus_field=field)
    path = record_run(tmp_path / "run.rrd", result, initial_points=env.observe().points)
    from rerun.chunk import RrdReader

    entities = {str(chunk.entity_path) for chunk in RrdReader(path).stream()}
    for entity in ("/maps/modulus_kpa", "/metrics/modulus_kpa", "/metrics/modulus_max_variance"):
        assert entity in entities, (entity, sorted(entities))
