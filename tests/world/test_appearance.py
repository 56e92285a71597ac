"""The world renders appearance: looks in YAML, shading, the colour sensor, built-in looks."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from deformap._validation import SettingError
from deformap.errors import ConfigError
from deformap.world import (
    CAMERA_PRESETS,
    Appearance,
    Block,
    CameraConfig,
    Scenario,
    SimulatedWorld,
    Split,
    WorldConfig,
    camera_preset,
    load_scenario,
    save_scenario,
)
from deformap.world._appearance import (
    _KEYS,
    DEFAULT_APPEARANCE,
    lambert,
    linear_to_srgb,
    srgb_to_linear,
)
from deformap.world._scenario_io import parse_scenario
from deformap.world._texture import texture_values

DOC = Path(__file__).resolve().parents[2] / "docs" / "scenarios.md"
GREY = (0.5, 0.5, 0.5)
BLOCK = (0.2, 0.1, 0.4, 0.3)  # x0, y0, x1, y1: a 20 cm square in the middle of the workspace


def _rect(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])


def _world(look: Appearance | None = None, seed: int = 0, **settings: Any) -> SimulatedWorld:
    camera = settings.pop("camera", CameraConfig(width=160, height=120))
    block = Block(name="b", polygon=_rect(*BLOCK), hardness_n=100.0,
                  appearance=look or Appearance(color=GREY))
    config = WorldConfig.coarse(camera=camera, **settings)
    return SimulatedWorld(Scenario(name="one", blocks=(block,)), config=config,
                          rng=np.random.default_rng(seed))


def _top(points: np.ndarray, margin: float = 0.02) -> np.ndarray:
    x0, y0, x1, y1 = BLOCK
    return ((points[:, 0] > x0 + margin) & (points[:, 0] < x1 - margin)
            & (points[:, 1] > y0 + margin) & (points[:, 1] < y1 - margin)
            & (points[:, 2] > 0.045))


# ---- YAML -------------------------------------------------------------------------------------

_FILE = {
    "name": "looks",
    "blocks": [
        {"name": "a", "rect": [0, 0, 0.3, 0.4], "hardness_n": 60,
         "appearance": {"color": "#c8a040", "texture": "noise", "scale_m": 0.01,
                        "amplitude": 0.2, "seed": 3}},
        {"name": "b", "rect": [0.3, 0, 0.6, 0.4], "rigid": True,
         "appearance": {"color": [0.1, 0.2, 0.3], "texture": "photo", "photo": "grass",
                        "scale_m": 0.1, "split": {"through": [0.45, 0.2], "normal_deg": 90,
                                                  "color": "#2e86ab", "texture": "stripes",
                                                  "scale_m": 0.01, "angle_deg": 30}}},
    ],
    "table_appearance": {"color": [0.3, 0.3, 0.3], "texture": "stripes", "scale_m": 0.05},
}


def test_appearances_round_trip_through_yaml(tmp_path: Path) -> None:
    scenario = parse_scenario(_FILE)
    a, b = (block.appearance for block in scenario.blocks)
    assert a is not None and b is not None and b.split is not None
    assert a.color == pytest.approx((200 / 255, 160 / 255, 64 / 255))
    assert b.split.look.texture == "stripes" and b.split.through == (0.45, 0.2)
    save_scenario(scenario, tmp_path / "s.yaml")
    again = load_scenario(tmp_path / "s.yaml")
    assert [blk.appearance for blk in again.blocks] == [a, b]
    assert again.table_appearance == scenario.table_appearance
    assert again.to_dict() == scenario.to_dict()


def test_builtin_looks_round_trip_and_use_their_figure_colours(tmp_path: Path) -> None:
    scenario = load_scenario("heterogeneous-60-110-rigid")
    for block in scenario.blocks:
        assert block.appearance is not None and block.appearance.texture != "plain"
        hexed = "#" + "".join(f"{round(c * 255):02x}" for c in block.appearance.color)
        assert hexed == block.color
    save_scenario(scenario, tmp_path / "s.yaml")
    assert [b.appearance for b in load_scenario(tmp_path / "s.yaml").blocks] == [
        b.appearance for b in scenario.blocks]


@pytest.mark.parametrize(("look", "named"), [
    ({"amplitude": float("nan")}, "`amplitude` must be finite"),
    ({"amplitude": 1.5}, "`amplitude` must be <= 1"),
    ({"color": [1.2, 0.0, 0.0]}, "`color` entry 0 must be <= 1"),
    ({"color": [0.1, 0.2]}, "`color` must have 3 entries"),
    ({"color": "#zzzzzz"}, "`color` must be '#rrggbb'"),
    ({"color": "red"}, "`color` must be '#rrggbb'"),
    ({"texture": "wood"}, "`texture` must be one of"),
    ({"texture": "photo", "photo": "marble"}, "`photo` must be one of"),
    ({"scale_m": 0.0}, "`scale_m` must be >= 0.001"),
    ({"seed": -1}, "`seed` must be an integer >= 0"),
    ({"shine": 1}, r"unknown key\(s\) \['shine'\]"),
    ({"split": [0, 1]}, "split: must be a mapping"),
    ({"split": {"color": "#000000", "split": {}}}, r"unknown key\(s\) \['split'\]"),
    ({"split": {"through": [0.1, float("nan")]}}, "`through` entry 1 must be finite"),
])
def test_a_bad_appearance_is_refused_in_one_line_naming_block_and_key(look: dict[str, Any],
                                                                      named: str) -> None:
    data = {"name": "bad", "blocks": [{"name": "a", "rect": [0, 0, 0.3, 0.4], "rigid": True,
                                       "appearance": look}]}
    with pytest.raises(ConfigError, match=named) as err:
        parse_scenario(data, source="f.yaml")
    message = str(err.value)
    assert message.startswith("f.yaml: blocks[0].appearance") and "\n" not in message
    table = {"name": "bad", "blocks": data["blocks"][:0] or [{"name": "a", "rect": [0, 0, 1, 1],
                                                              "rigid": True}],
             "table_appearance": look}
    with pytest.raises(ConfigError, match=named):
        parse_scenario(table, source="f.yaml")


def test_the_doc_lists_every_appearance_key() -> None:
    text = DOC.read_text(encoding="utf-8").split("An appearance (", 1)[1]
    rows = [line for line in text.splitlines() if line.startswith("| `")]
    assert {row.split("`")[1] for row in rows} == _KEYS


def test_a_block_without_appearance_is_neutral_grey_and_plain() -> None:
    assert DEFAULT_APPEARANCE.texture == "plain"
    assert DEFAULT_APPEARANCE.color[0] == DEFAULT_APPEARANCE.color[1] == DEFAULT_APPEARANCE.color[2]
    world = _world(Appearance())
    block = Block(name="b", polygon=_rect(*BLOCK), hardness_n=100.0)
    assert block.appearance is None
    plain = SimulatedWorld(Scenario(name="one", blocks=(block,)), config=world.config,
                           rng=np.random.default_rng(0))
    np.testing.assert_array_equal(world.observe().colors, plain.observe().colors)  # type: ignore[arg-type]


# ---- textures and shading --------------------------------------------------------------------

@pytest.mark.parametrize("texture", ["noise", "stripes", "photo"])
def test_textures_lie_in_unit_range_with_a_mean_near_zero(texture: str) -> None:
    uv = np.random.default_rng(1).uniform(0.0, 0.6, size=(20000, 2))
    t = texture_values(texture, uv, scale_m=0.02, photo="gravel")
    assert t.min() >= -1.0 and t.max() <= 1.0 and t.std() > 0.05
    assert abs(t.mean()) < 0.1


def test_srgb_encoding_inverts() -> None:
    c = np.linspace(0.0, 1.0, 101)
    np.testing.assert_allclose(linear_to_srgb(srgb_to_linear(c)), c, atol=1e-12)


def test_lambert_shows_albedo_on_top_and_darker_sides() -> None:
    light = np.array([-0.3, -0.4, 1.0]) / np.linalg.norm([-0.3, -0.4, 1.0])
    normals = np.array([[0, 0, 1.0], [0, -1.0, 0], [1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0]])
    shade = lambert(normals, light, 0.3)
    assert shade[0] == pytest.approx(1.0)
    assert np.all(shade[1:] < 1.0) and shade[1] > shade[2]  # the side facing the light is brighter


def test_side_faces_are_darker_than_the_top_under_a_top_light() -> None:
    world = _world(light_direction=(0.0, 0.0, 1.0), ambient=0.3, noise=False)
    cloud = world.observe()
    assert cloud.colors is not None
    top = _top(cloud.points)
    x0, y0, x1, _ = BLOCK
    front = ((np.abs(cloud.points[:, 1] - y0) < 0.004) & (cloud.points[:, 0] > x0 + 0.02)
             & (cloud.points[:, 0] < x1 - 0.02) & (cloud.points[:, 2] > 0.01)
             & (cloud.points[:, 2] < 0.04))
    assert top.sum() > 100 and front.sum() > 20
    top_grey, front_grey = cloud.colors[top].mean(), cloud.colors[front].mean()
    assert top_grey == pytest.approx(0.5, abs=0.01)
    # straight-down light: a side face gets the ambient share alone
    assert front_grey == pytest.approx(float(linear_to_srgb(srgb_to_linear(np.array(0.5)) * 0.3)),
                                       abs=0.02)


# ---- the colour sensor -----------------------------------------------------------------------

def test_colour_noise_has_the_std_the_camera_says() -> None:
    camera = CameraConfig(width=320, height=240, color_noise=0.05)
    cloud = _world(camera=camera).observe()
    assert cloud.colors is not None
    top = cloud.colors[_top(cloud.points)]
    assert len(top) > 500
    np.testing.assert_allclose(top.std(axis=0), 0.05, rtol=0.1)
    np.testing.assert_allclose(top.mean(axis=0), 0.5, atol=0.01)
    quiet = _world(noise=False).observe()
    assert quiet.colors is not None
    assert np.ptp(quiet.colors[_top(quiet.points)]) < 1e-9


def test_colour_settings_leave_the_points_alone() -> None:
    base = _world().observe()
    other = _world(Appearance(color="#2e86ab", texture="noise"), light_direction=(1.0, 0.0, 1.0),
                   camera=CameraConfig(width=160, height=120, color_noise=0.2,
                                       white_balance=(2.0, 1.0, 0.5), vignetting=0.5)).observe()
    np.testing.assert_array_equal(base.points, other.points)
    assert not np.allclose(base.colors, other.colors)  # type: ignore[arg-type]


def test_white_balance_scales_each_channel_of_the_light() -> None:
    gains = (1.4, 1.0, 0.6)
    plain = _world(noise=False).observe()
    shifted = _world(noise=False, camera=CameraConfig(width=160, height=120,
                                                      white_balance=gains)).observe()
    assert plain.colors is not None and shifted.colors is not None
    ratio = srgb_to_linear(shifted.colors) / srgb_to_linear(plain.colors)
    top = ratio[_top(plain.points)]
    assert len(top) > 100
    np.testing.assert_allclose(top, np.tile(gains, (len(top), 1)), rtol=1e-9)


def test_vignetting_darkens_toward_the_corners() -> None:
    camera = CameraConfig(width=160, height=120, vignetting=0.5)
    flat = _world(noise=False).rgb_image()
    dim = _world(noise=False, camera=camera).rgb_image()
    ratio = srgb_to_linear(dim[..., 1]) / srgb_to_linear(flat[..., 1])
    v, u = np.mgrid[0:120, 0:160]
    r2 = ((u + 0.5 - 80) ** 2 + (v + 0.5 - 60) ** 2) / (80**2 + 60**2)
    lit = np.isfinite(ratio) & (flat[..., 1] > 0.05) & (flat[..., 1] < 0.95)
    assert lit.sum() > 5000
    np.testing.assert_allclose(ratio[lit], (1 - 0.5 * r2)[lit], rtol=1e-6)
    assert r2[lit].max() > 0.5  # the check reaches far from the centre


def test_a_blocks_mean_colour_recovers_its_base_colour() -> None:
    world = SimulatedWorld(load_scenario("heterogeneous-60-150"),
                           config=WorldConfig.coarse(camera=CameraConfig(width=320, height=240)),
                           rng=np.random.default_rng(3))
    cloud = world.observe()
    assert cloud.colors is not None
    for block in world.regions:
        assert block.appearance is not None
        inside = block.contains(cloud.points[:, :2]) & (cloud.points[:, 2] > 0.045)
        lo, hi = block.polygon.min(axis=0) + 0.02, block.polygon.max(axis=0) - 0.02
        inside &= np.all((cloud.points[:, :2] > lo) & (cloud.points[:, :2] < hi), axis=1)
        assert inside.sum() > 1000
        np.testing.assert_allclose(cloud.colors[inside].mean(axis=0), block.appearance.color,
                                   atol=0.02)


def test_the_split_paints_one_block_in_two_colours() -> None:
    look = Appearance(color=(0.8, 0.2, 0.2), split=Split(
        through=(0.3, 0.2), normal_deg=0.0, look=Appearance(color=(0.2, 0.2, 0.8))))
    cloud = _world(look, noise=False).observe()
    assert cloud.colors is not None
    top = _top(cloud.points)
    right = top & (cloud.points[:, 0] > 0.31)
    left = top & (cloud.points[:, 0] < 0.29)
    np.testing.assert_allclose(cloud.colors[right].mean(axis=0), (0.2, 0.2, 0.8), atol=0.01)
    np.testing.assert_allclose(cloud.colors[left].mean(axis=0), (0.8, 0.2, 0.2), atol=0.01)


def test_the_probe_shows_its_own_colours() -> None:
    world = _world(noise=False, hand_color="#2040c0", light_direction=(0.0, 0.0, 1.0))
    press = world.press((0.3, 0.2), 0.6)
    assert press.cloud.colors is not None
    hand_top = press.cloud.points[:, 2] > 0.05 + 0.10 + 0.09  # the hand's upper part
    assert hand_top.sum() > 10
    np.testing.assert_allclose(np.median(press.cloud.colors[hand_top], axis=0),
                               (0x20 / 255, 0x40 / 255, 0xC0 / 255), atol=0.01)


@pytest.mark.parametrize("name", sorted(CAMERA_PRESETS))
def test_every_camera_preset_returns_colours(name: str) -> None:
    camera = replace(camera_preset(name), width=80, height=60)
    cloud = _world(camera=camera).observe()
    assert cloud.colors is not None and cloud.colors.shape == cloud.points.shape
    assert cloud.colors.min() >= 0.0 and cloud.colors.max() <= 1.0


def test_world_colour_settings_are_checked() -> None:
    with pytest.raises(SettingError, match="`light_direction` must point up"):
        WorldConfig(light_direction=(0.0, 0.0, -1.0))
    with pytest.raises(SettingError, match="`tip_color` must be '#rrggbb'"):
        WorldConfig(tip_color="#12")  # type: ignore[arg-type]
    with pytest.raises(SettingError, match="`vignetting` must be < 1"):
        CameraConfig(vignetting=1.0)
    assert WorldConfig(hand_color="#ff0000").hand_color == (1.0, 0.0, 0.0)  # type: ignore[arg-type]
