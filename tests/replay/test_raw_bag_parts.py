"""The parts of the raw-bag reader on their own: presses found in a force stream, transforms
looked up in time (issue 15, item 1)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from deformap.cloud.io import TransformTree
from deformap.errors import FileFormatError
from deformap.replay._rawpress import find_presses


def test_presses_are_found_from_rise_hold_and_release_and_spikes_are_noise() -> None:
    t = np.arange(0, 4000, dtype=np.int64) * 2_000_000  # 500 Hz, 8 s
    f = np.zeros(t.size)
    f[100] = 0.5  # a spike
    f[1000:1200] = np.linspace(0.0, 1.0, 200)  # a press: ramp, hold, release
    f[1200:1400] = 1.0
    f[2000:2200] = np.linspace(0.0, 0.5, 200)  # one that stops at half the command
    f[2200:2300] = 0.5
    f[3000:3100], f[3100:3120] = np.linspace(0.0, 1.0, 100), 1.0  # a hold of 40 ms
    f[3500:3520] = 1.0  # a tap at the commanded force, 40 ms over the threshold in all
    found = find_presses(t, f, commanded_n=1.0, contact_n=0.02, band=0.1,
                         hold_min_ns=100_000_000, merge_ns=50_000_000, topic="/w")  # fmt: skip
    assert len(found) == 4  # the spike is noise; the tap is a press too short to read, said
    assert "press 4 " in str(found[3].error) and "for only 0.038 s" in str(found[3].error)
    assert found[0].error is None and 1000 < found[0].start < 1010
    assert found[0].hold_start < 1200 < 1399 < found[0].hold_end
    assert "never reached" in str(found[1].error) and "0.5 N" in str(found[1].error)
    assert "held the commanded" in str(found[2].error)


def test_transforms_interpolate_in_time_and_refuse_a_gap() -> None:
    from types import SimpleNamespace as NS

    def msg(t_ns: int, parent: str, child: str, xyz: Any, quat: Any) -> Any:
        stamp = NS(sec=t_ns // 10**9, nanosec=t_ns % 10**9)
        return NS(transforms=[NS(header=NS(stamp=stamp, frame_id=parent), child_frame_id=child,
                                 transform=NS(translation=NS(x=xyz[0], y=xyz[1], z=xyz[2]),
                                              rotation=NS(x=quat[0], y=quat[1], z=quat[2],
                                                          w=quat[3])))])  # fmt: skip

    tree = TransformTree("/tf", tolerance_ns=50_000_000)
    q0 = Rotation.identity().as_quat()
    q1 = Rotation.from_euler("z", 90, degrees=True).as_quat()
    tree.add(msg(0, "world", "tool", (0, 0, 0), q0), static=False, where="m0")
    tree.add(msg(40_000_000, "world", "tool", (0.04, 0, 0), q1), static=False, where="m1")
    tree.add(msg(0, "tool", "tip", (0, 0, -0.1), q0), static=True, where="s")
    rot, trans = tree.lookup("world", "tip", [20_000_000], what="test")
    expected = Rotation.from_euler("z", 45, degrees=True).as_matrix()
    np.testing.assert_allclose(rot[0], expected, atol=1e-12)
    np.testing.assert_allclose(trans[0], [0.02, 0.0, -0.1], atol=1e-12)
    # and the inverse direction
    rot_inv, trans_inv = tree.lookup("tip", "world", [20_000_000], what="test")
    np.testing.assert_allclose(rot_inv[0] @ trans[0] + trans_inv[0], 0.0, atol=1e-12)
    with pytest.raises(FileFormatError, match=r"test: topic '/tf' .*'tool'.* \(nearest 0\.160 s"):
        tree.lookup("world", "tip", [200_000_000], what="test")


def test_settings_come_from_the_yaml_beside_the_bag_and_options_win(tmp_path: Any) -> None:
    from pathlib import Path

    import yaml

    from deformap.errors import ConfigError
    from deformap.replay import RawBagConfig, load_raw_config, raw_config_file

    bag = Path(str(tmp_path)) / "lab.mcap"
    assert raw_config_file(bag).name == "lab.deformap.yaml"
    assert load_raw_config(bag) == RawBagConfig()  # no file: the defaults
    raw_config_file(bag).write_text(yaml.safe_dump(
        {"tip_frame": "probe_tip", "force_n": 0.6,
         "hull": [{"shape": "cylinder", "size_m": [0.01, 0.01, 0.1]}]}))  # fmt: skip
    cfg = load_raw_config(bag, force_n=1.5, cloud_topic=None)
    assert (cfg.tip_frame, cfg.force_n, cfg.cloud_topic) == ("probe_tip", 1.5,
                                                             RawBagConfig().cloud_topic)
    assert cfg.hull[0].shape == "cylinder" and len(cfg.hull) == 1
    raw_config_file(bag).write_text(yaml.safe_dump({"hull": [{"shape": "sphere"}]}))
    with pytest.raises(ConfigError, match=r"hull\[0\]\.shape.*'box', 'cylinder', 'cap'"):
        load_raw_config(bag)
    raw_config_file(bag).write_text(yaml.safe_dump({"workspace_lower": [0, 0]}))
    with pytest.raises(ConfigError, match="given together"):
        load_raw_config(bag)
