from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import pytest

from deformap._config import config_from_dict, config_to_dict, dump_yaml, load_yaml
from deformap._validation import check_positive
from deformap.errors import ConfigError


@dataclass(frozen=True, kw_only=True)
class Inner:
    length_m: float = 0.1
    corner: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        check_positive("length_m", self.length_m)


@dataclass(frozen=True, kw_only=True)
class Outer:
    mode: Literal["a", "b"] = "a"
    count: int = 3
    label: str | None = None
    inner: Inner = field(default_factory=Inner)


def test_round_trip_through_yaml(tmp_path) -> None:
    cfg = Outer(mode="b", count=5, inner=Inner(length_m=0.2, corner=(1.0, 2.0)))
    dump_yaml(cfg, tmp_path / "c.yaml")
    back = config_from_dict(Outer, load_yaml(tmp_path / "c.yaml"))
    assert back == cfg
    assert config_to_dict(back)["inner"]["corner"] == [1.0, 2.0]


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"colour": 1}, r"`config` has unknown key\(s\) \['colour'\]"),
        ({"mode": "c"}, r"`config.mode` must be one of \['a', 'b'\]"),
        ({"count": 2.5}, r"`config.count` must be an integer"),
        ({"inner": {"length_m": -1}}, r"`config.inner`: `length_m` must be > 0"),
        ({"inner": {"corner": [1]}}, r"`config.inner.corner` must have 2 entries"),
        ({"inner": {"depth": 1}}, r"`config.inner` has unknown key"),
        ([1, 2], r"`config` must be a mapping"),
    ],
)
def test_bad_values_name_the_field(data: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        config_from_dict(Outer, data)


def test_unreadable_and_invalid_yaml(tmp_path) -> None:
    with pytest.raises(ConfigError, match="cannot read config file"):
        load_yaml(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("a: [1, 2\n")
    with pytest.raises(ConfigError, match="is not valid YAML"):
        load_yaml(bad)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfeseed: 1\n", r"not UTF-8 text \(byte 0\)"),
        (b"seed: 2020-02-30\n", "is not valid YAML.*day is out of range"),  # PyYAML's timestamps
        (b"a: " + b"[" * 5000 + b"]" * 5000 + b"\n", "is not valid YAML.*RecursionError"),
    ],
)
def test_yaml_that_the_parser_cannot_take_is_a_config_error(
    tmp_path, content: bytes, message: str
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(content)
    with pytest.raises(ConfigError, match=rf"bad\.yaml.*{message}"):
        load_yaml(bad)
