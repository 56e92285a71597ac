"""The appearance prior: the image and its segments, the learned weight, the fall backs, and the
blind path unchanged."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from deformap.cloud import PointCloud
from deformap.errors import InvalidArgumentError
from deformap.explore import BetaFieldConfig, ExplorationConfig, PokeSet, explore
from deformap.explore._appearance import AppearanceImage, build_appearance
from deformap.explore._appearance_prior import BLIND_PRIOR, AppearanceModels, AppearancePrior
from deformap.explore._field import BetaField
from deformap.gp import GaussianRandomField

XS = np.arange(0.0025, 0.3, 0.005)
YS = np.arange(0.0025, 0.2, 0.005)
FOOTPRINT_M = 0.03
RED, BLUE = (0.8, 0.2, 0.2), (0.2, 0.3, 0.8)


def _cloud(colour_of, rng: np.random.Generator, *, noise: float = 0.01) -> PointCloud:
    """Four points per map cell on a flat table (z = 0) coloured by ``colour_of(x, y)``."""
    gx, gy = np.meshgrid(np.arange(0.0, 0.3, 0.0025), np.arange(0.0, 0.2, 0.0025))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
    cols = np.array([colour_of(x, y) for x, y in pts[:, :2]], dtype=float)
    cols = np.clip(cols + noise * rng.standard_normal(cols.shape), 0.0, 1.0)
    return PointCloud(pts, cols)


def _halves(x: float, y: float) -> tuple[float, float, float]:
    return RED if x < 0.15 else BLUE


def _image(colour_of=_halves, **kw) -> AppearanceImage | str:
    return build_appearance(_cloud(colour_of, np.random.default_rng(0), **kw), XS, YS,
                            np.zeros((YS.size, XS.size)), FOOTPRINT_M)


def test_two_looks_give_segments_that_keep_to_their_halves_and_differ_in_features() -> None:
    image = _image()
    assert isinstance(image, AppearanceImage)
    left, right = image.segments[:, XS < 0.14], image.segments[:, XS > 0.16]
    assert not set(np.unique(left)) & set(np.unique(right))
    f_left = image.features[np.unique(left)].mean(axis=0)
    f_right = image.features[np.unique(right)].mean(axis=0)
    assert np.linalg.norm(f_left - f_right) > 1.5  # the look's spread is the unit
    assert image.lab.shape == (YS.size, XS.size, 3) and np.isfinite(image.lab).all()
    assert np.allclose(image.rgb()[0, 0], RED, atol=0.03)


def test_the_same_cloud_gives_the_same_image() -> None:
    a, b = _image(), _image()
    assert isinstance(a, AppearanceImage) and isinstance(b, AppearanceImage)
    assert np.array_equal(a.segments, b.segments) and np.array_equal(a.features, b.features)


@pytest.mark.parametrize(("colour_of", "kw", "says"), [
    (lambda x, y: (0.5, 0.5, 0.5), {"noise": 0.0}, "all alike"),
    (lambda x, y: (0.5, 0.5, 0.5), {"noise": 0.01}, "shows no layout"),
    (lambda x, y: (1.0, 1.0, 1.0), {"noise": 0.0}, "saturated"),
    (lambda x, y: (0.0, 0.0, 0.0), {"noise": 0.0}, "black"),
])
def test_an_image_that_shows_no_layout_falls_back_to_the_blind_map_with_a_reason(
        colour_of, kw, says) -> None:  # fmt: skip
    why = _image(colour_of, **kw)
    assert isinstance(why, str) and says in why


def test_colour_on_part_of_the_map_or_no_colour_falls_back_with_a_reason() -> None:
    cloud = _cloud(_halves, np.random.default_rng(0))
    part = cloud.points[:, 0] < 0.1
    partial = PointCloud(cloud.points[part], cloud.colors[part])
    why = build_appearance(partial, XS, YS, np.zeros((YS.size, XS.size)), FOOTPRINT_M)
    assert isinstance(why, str) and "covers" in why
    why = build_appearance(PointCloud(cloud.points), XS, YS, np.zeros((YS.size, XS.size)),
                           FOOTPRINT_M)  # fmt: skip
    assert why == "the cloud has no colour"


def test_segments_all_smaller_than_a_dent_fall_back_with_a_reason() -> None:
    cloud = _cloud(_halves, np.random.default_rng(0))
    why = build_appearance(cloud, XS, YS, np.zeros((YS.size, XS.size)), footprint_m=1.0)
    assert isinstance(why, str) and "no segment" in why


@pytest.mark.parametrize("bad", [np.nan, 1.5, -0.1])
def test_colours_nan_or_out_of_range_are_refused_naming_the_field(bad: float) -> None:
    cols = np.full((4, 3), 0.5)
    cols[1, 2] = bad
    with pytest.raises(InvalidArgumentError, match="colors"):
        PointCloud(np.zeros((4, 3)), cols)


def _models(image: AppearanceImage, xy, values, std=0.02) -> AppearanceModels:
    prior = AppearancePrior(image, XS, YS)
    xy = np.asarray(xy, dtype=float)
    return AppearanceModels(prior, xy, np.asarray(values, float), np.full(len(xy), std),
                            signal_std=0.3, length_scale=0.05)  # fmt: skip


def test_pokes_that_agree_with_the_looks_raise_the_weight_and_contradicting_ones_lower_it(
        ) -> None:  # fmt: skip
    image = _image()
    assert isinstance(image, AppearanceImage)
    xy = [(0.03, 0.03), (0.12, 0.17), (0.18, 0.03), (0.27, 0.17)]
    prior_mean = (1 - BLIND_PRIOR) * float(np.mean([0.5, 0.8, 0.95]))
    agree = _models(image, xy, [0.2, 0.2, 0.7, 0.7]).posterior
    one_look_two_materials = _models(image, xy, [0.2, 0.7, 0.2, 0.7]).posterior
    assert agree.mean_weight > prior_mean + 0.1
    assert one_look_two_materials.mean_weight < prior_mean - 0.1
    assert np.isclose(agree.probability.sum(), 1.0)


def test_at_weight_zero_the_prior_is_the_blind_field_and_the_average_variance_is_bounded(
        ) -> None:  # fmt: skip
    image = _image()
    assert isinstance(image, AppearanceImage)
    xy = np.array([(0.05, 0.05), (0.25, 0.1)])
    models = _models(image, xy, [0.3, 0.6])
    gp = GaussianRandomField(length_scale=0.05, signal_std=0.3, noise_std=0.02,
                             method="exact").fit(xy, np.array([0.3, 0.6]))  # fmt: skip
    _, std = gp.predict(models.prior.cells_xy, return_std=True)
    assert np.allclose(models.blind_variance(models.prior.cells_xy), std**2, atol=1e-10)
    mean, var = models.predict(models.prior.cells_xy)
    assert np.all(var >= 0) and np.all(np.isfinite(mean))
    # the pokes' own cells are known to about their noise under every weight
    at = models.prior.cells_of(xy)
    assert np.all(var[at] < 0.1 * 0.3**2)


def test_a_field_under_the_prior_labels_a_cell_by_its_look_not_by_distance() -> None:
    from deformap.explore import map_regions

    image = _image()
    assert isinstance(image, AppearanceImage)
    # red pokes far left, blue pokes just right of the edge: cells just left of the edge are
    # nearer a blue poke but look red
    xy = np.array([[0.02, 0.05], [0.02, 0.15], [0.17, 0.05], [0.17, 0.15]])
    pokes = PokeSet(xy, np.array([0.2, 0.21, 0.8, 0.79]), np.full(4, 0.01))
    field = BetaField(pokes, XS, YS, BetaFieldConfig(length_scale_m=0.05)).with_prior(
        AppearancePrior(image, XS, YS))
    assert field.models is not None and field.prior is not None
    config = ExplorationConfig(field="beta", merge_seams=False, split_by_place=False)
    cells = field.prior.cells_xy
    looks = map_regions(field.mean, pokes, cells, config, "beta",
                        correlation=field.models.correlation)  # fmt: skip
    blind = map_regions(field.mean, pokes, cells, config, "beta")
    assert looks.n_regions == blind.n_regions == 2
    edge_left = (np.abs(cells[:, 0] - 0.13) < 0.003).reshape(YS.size, XS.size)
    red = looks.poke_labels[0]
    assert np.all(looks.labels[edge_left] == red)
    assert np.all(blind.labels[edge_left] != red)


class _Colourless:
    """An environment whose camera gives no colour (the world's otherwise)."""

    def __init__(self, world) -> None:
        self._world = world
        self.workspace = world.workspace

    def observe(self) -> PointCloud:
        return PointCloud(self._world.observe().points)

    def press(self, xy, force_n):
        obs = self._world.press(xy, force_n)
        return dataclasses.replace(obs, cloud=PointCloud(obs.cloud.points))

    def release(self) -> None:
        self._world.release()


@pytest.mark.slow
def test_off_and_a_cloud_without_colour_give_the_same_map_byte_for_byte() -> None:
    from deformap.testing import coarse_world

    config = ExplorationConfig(max_pokes=3)
    off = explore(coarse_world(), dataclasses.replace(config, appearance="off"),
                  rng=np.random.default_rng(0))  # fmt: skip
    bare = explore(_Colourless(coarse_world()), config, rng=np.random.default_rng(0))
    assert off.appearance.reason == "exploration.appearance is off"
    assert bare.appearance.reason == "the cloud has no colour"
    assert not off.appearance.used and not bare.appearance.used
    assert [p.record.contact_xy for p in off.pokes] == [p.record.contact_xy for p in bare.pokes]
    assert [p.record.beta for p in off.pokes] == [p.record.beta for p in bare.pokes]
    for a, b in ((off.beta_field, bare.beta_field), (off.map_field, bare.map_field)):
        assert a.mean.tobytes() == b.mean.tobytes()
        assert a.variance.tobytes() == b.variance.tobytes()
    assert off.regions is not None and bare.regions is not None
    assert off.regions.labels.tobytes() == bare.regions.labels.tobytes()


def test_the_deepest_reachable_place_of_a_segment_and_the_area_one_poke_covers() -> None:
    from deformap.environment import Workspace
    from deformap.explore import MapGrid
    from deformap.explore._targets import covered_area_m2, segment_interior

    config = ExplorationConfig()
    grid = MapGrid.build(Workspace(lower=(0.0, 0.0), upper=(0.6, 0.4)), config)
    segments = np.where(grid.cells_xy[:, 0] < 0.2, 0, 1).reshape(grid.shape)
    found = segment_interior(grid, segments, 0)
    assert found is not None
    xy, depth = found
    assert grid.target_mask[np.argmin(np.hypot(*(grid.cells_xy - xy).T))]
    assert 0.09 < xy[0] < 0.11 and 0.09 < depth < 0.11  # the middle of the 20 cm strip
    assert segment_interior(grid, segments, 2) is None
    # σ² (1 − k²) = T_h at the disc's edge
    beta = config.beta_field
    r = np.sqrt(covered_area_m2(config, "beta") / np.pi)
    k = np.exp(-(r**2) / beta.length_scale_m**2)
    assert np.isclose(beta.signal_std**2 * (1 - k**2), config.threshold)


@pytest.mark.slow
def test_on_an_informative_world_the_prior_is_used_and_its_weight_is_learned_between_its_bounds(
        ) -> None:  # fmt: skip
    from deformap.world import SimulatedWorld, WorldConfig, random_scenario

    world = SimulatedWorld(random_scenario(np.random.default_rng(3), appearance="informative"),
                           config=WorldConfig.coarse(), rng=np.random.default_rng(0))
    result = explore(world, ExplorationConfig(max_pokes=6, appearance="auto"),
                     rng=np.random.default_rng(0))  # fmt: skip
    used = result.appearance
    # six pokes on the coarse mesh leave the weight's posterior between its ends (one half of its
    # prior mass on the blind map); whether the map beats the blind one is the benchmark's to say
    # over many worlds (docs/results.md, the appearance prior): on six coarse worlds at six
    # pokes it does in three and not in the other three
    assert used.used and used.image is not None and used.n_segments > 1
    assert used.weight is not None and 0.0 < used.weight < 0.95
