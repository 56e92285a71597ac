"""The loop needs nothing but the Environment protocol: a robot-like environment written here.

The surface is analytic (Hertz dents of a sphere on an elastic half-space, from deformap.testing),
not the simulated world: a soft half (60 N foam) and a hard half (150 N foam) side by side.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.environment import PressObservation, Workspace
from deformap.errors import EnvironmentStateError, InvalidArgumentError
from deformap.explore import (
    BetaFieldConfig,
    ExplorationConfig,
    SurfaceGPConfig,
    explore,
)
from deformap.testing import elastic_dent, hardness_to_modulus

TOP_M = 0.04
TIP_M = 0.01


class TwoFoamTable:
    """24×16 cm of foam 4 cm high: 60 N foam for x < 12 cm, 150 N foam beyond."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.workspace = Workspace(lower=(0.0, 0.0), upper=(0.24, 0.16))
        self.xs = np.arange(0.0, 0.2401, 0.003)
        self.ys = np.arange(0.0, 0.1601, 0.003)
        self.rest = np.full((self.ys.size, self.xs.size), TOP_M)
        self.rng = rng
        self.pressing = False
        self.presses = 0

    def _cloud(self, z: np.ndarray) -> np.ndarray:
        gx, gy = np.meshgrid(self.xs, self.ys)
        noisy = z + self.rng.normal(0.0, 0.0005, size=z.shape)
        return np.column_stack([gx.ravel(), gy.ravel(), noisy.ravel()])

    def observe(self) -> PointCloud:
        return PointCloud(self._cloud(self.rest))

    def press(self, target_xy: Any, force_n: float) -> PressObservation:
        if self.pressing:
            raise EnvironmentStateError("release() first")
        target = np.asarray(target_xy, dtype=float)
        if not self.workspace.contains(target)[0]:
            raise InvalidArgumentError(f"`target_xy` outside the workspace: {target}")
        modulus = hardness_to_modulus(60.0 if target[0] < 0.12 else 150.0)
        z, contact = elastic_dent(
            self.xs,
            self.ys,
            self.rest,
            target,
            force_n=force_n,
            tip_radius_m=TIP_M,
            modulus_pa=modulus,
        )
        surface = self._cloud(z)
        # The stick hides what lies right under it; the stick itself is seen.
        hidden = np.hypot(surface[:, 0] - target[0], surface[:, 1] - target[1]) < TIP_M
        c = contact.tip_center
        heights = np.linspace(c[2], c[2] + 0.10, 30)
        stick = np.column_stack([np.full(30, c[0] + 0.004), np.full(30, c[1]), heights])
        robot = np.array(
            [
                [c[0] + dx, c[1] + dy, c[2] + dz]
                for dx in (-0.011, 0.011)
                for dy in (-0.011, 0.011)
                for dz in (0.0, 0.12)
            ]
        )
        self.pressing = True
        self.presses += 1
        return PressObservation(
            cloud=PointCloud(np.vstack([surface[~hidden], stick])),
            contact=contact,
            robot_points=robot,
            target_xy=target,
            force_n=force_n,
        )

    def release(self) -> None:
        self.pressing = False


@pytest.mark.parametrize("strategy", ["max-variance", "planned"])
def test_the_loop_maps_an_environment_written_by_a_user(strategy: str) -> None:
    env = TwoFoamTable(np.random.default_rng(3))
    config = ExplorationConfig(
        max_pokes=4,
        strategy=strategy,  # type: ignore[arg-type]
        first_target=(0.06, 0.08),
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.06),
    )
    result = explore(env, config, rng=np.random.default_rng(0))
    assert env.presses == len(result.pokes) >= 2
    assert not env.pressing  # every press was released
    soft = [p.record.beta for p in result.pokes if p.xy[0] < 0.11]
    hard = [p.record.beta for p in result.pokes if p.xy[0] > 0.13]
    assert soft and hard, f"{strategy} must visit both halves"
    planned = [p.record.planned_after for p in result.pokes[1:]]
    if strategy == "planned":
        # 4 pokes cannot bring this table under T_h = 0.06 (σw = 6 cm): no plan reaches it, so
        # none foresees how many pokes are left
        assert result.stop_reason == "max_pokes"
    assert planned == [None] * len(planned)
    assert min(soft) > max(hard), (soft, hard)
    regions = result.regions
    assert regions is not None and regions.n_regions == 2
    mean, var = result.beta_field.mean, result.beta_field.variance
    assert mean[:, :10].mean() > mean[:, -10:].mean()
    assert var.shape == (32, 48)


def test_a_planned_run_reports_how_many_pokes_its_plan_foresees() -> None:
    # σw = 12 cm on the 24×16 cm table: a handful of pokes reaches T_h, so each plan reaches it
    env = TwoFoamTable(np.random.default_rng(3))
    config = ExplorationConfig(
        max_pokes=8,
        strategy="planned",
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.12),
    )
    result = explore(env, config, rng=np.random.default_rng(0))
    assert result.stop_reason == "threshold"
    planned = [p.record.planned_after for p in result.pokes[1:]]
    assert planned[-1] == 0  # the last poke was the last of its plan
    assert all(isinstance(n, int) and 0 <= n < config.max_pokes for n in planned)
    assert result.pokes[0].record.planned_after is None  # the first poke is the configured one


def test_boundary_pokes_come_after_the_threshold_and_regions_by_nearest_poke() -> None:
    env = TwoFoamTable(np.random.default_rng(3))
    config = ExplorationConfig(
        max_pokes=12,
        strategy="planned",
        boundary_pokes=3,
        region_labels="nearest",
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.12),
    )
    result = explore(env, config, rng=np.random.default_rng(0))
    purposes = [p.record.purpose for p in result.pokes]
    n_variance = purposes.count("variance")
    assert purposes == ["first"] + ["variance"] * n_variance + ["boundary"] * 3
    assert result.stop_reason == "threshold"
    records = [p.record for p in result.pokes]
    # the variance was under T_h before the first boundary poke, not before
    assert records[n_variance].max_variance_after <= config.threshold
    assert all(r.max_variance_after > config.threshold for r in records[:n_variance])
    xy = np.array([p.xy for p in result.pokes])
    for k in range(n_variance + 1, len(xy)):  # a quarter ROI (3 cm) from every earlier poke
        assert np.min(np.linalg.norm(xy[:k] - xy[k], axis=1)) >= 0.25 * config.touch.roi_size_m
    regions = result.regions
    assert regions is not None and regions.n_regions == 2
    # soft foam (x < 12 cm) is the higher-β class: label 1
    truth = (result.grid.cells_xy[:, 0] < 0.12).astype(int).reshape(regions.labels.shape)
    assert np.mean(regions.labels == truth) >= 0.85
    # each cell has the class of a poke nearest to it (any of a tie)
    d = np.linalg.norm(result.grid.cells_xy[:, None] - xy[None], axis=-1)
    nearest = d <= d.min(axis=1, keepdims=True) + 1e-12
    own = regions.poke_labels[None, :] == regions.labels.reshape(-1, 1)
    assert np.all(np.any(nearest & own, axis=1))


def test_a_poke_limit_that_cuts_the_boundary_pokes_short_is_the_stop_reason() -> None:
    env = TwoFoamTable(np.random.default_rng(3))
    config = ExplorationConfig(
        max_pokes=4,  # the variance is under T_h after 3 pokes (see above): one boundary poke
        strategy="planned",
        boundary_pokes=3,
        surface=SurfaceGPConfig(fit_hyperparameters=False, length_scale_m=0.02),
        beta_field=BetaFieldConfig(length_scale_m=0.12),
    )
    result = explore(env, config, rng=np.random.default_rng(0))
    assert [p.record.purpose for p in result.pokes][-1] == "boundary"
    assert result.max_variance <= config.threshold
    # two of the three boundary pokes are still owed
    assert sum(p.record.purpose == "boundary" for p in result.pokes) == 1
    assert result.stop_reason == "max_pokes"
