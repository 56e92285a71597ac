"""The YAML loader and the one settings checker, on small dataclasses of their own."""

from __future__ import annotations

import math
import os
import pickle
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pytest

from deformap._config import config_from_dict, config_to_dict, dump_yaml, load_yaml
from deformap._validation import SettingError, check_settings, setting
from deformap.errors import ConfigError, InvalidArgumentError


@dataclass(frozen=True, kw_only=True)
class Inner:
    length_m: float = setting(0.1, gt=0.0)
    corner: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class Outer:
    mode: Literal["a", "b"] = "a"
    count: int = setting(3, ge=1, le=10)
    label: str | None = None
    inner: Inner = field(default_factory=Inner)

    def __post_init__(self) -> None:
        check_settings(self)


@dataclass(frozen=True, kw_only=True)
class Kinds:
    flag: bool = False
    ratio: float = setting(0.5, ge=0.0, lt=1.0)
    anything: float = setting(0.0, finite=False)
    sizes: tuple[float, float, float] = setting((1.0, 2.0, 3.0), gt=0.0)
    many: tuple[int, ...] = ()
    layers: int | None = setting(None, ge=0)
    array: np.ndarray | None = None  # not a settings type: left to the class's own checks

    def __post_init__(self) -> None:
        check_settings(self)


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
        ({"mode": "c"}, r"`config.mode` must be one of \['a', 'b'\]; got 'c'"),
        ({"count": 2.5}, r"`config.count` must be an integer; got 2.5"),
        ({"count": 0}, r"`config.count` must be an integer >= 1; got 0"),
        ({"count": 11}, r"`config.count` must be an integer <= 10; got 11"),
        ({"label": 3}, r"`config.label` must be a string; got 3"),
        ({"inner": {"length_m": -1}}, r"`config.inner.length_m` must be > 0; got -1.0"),
        ({"inner": {"corner": [1]}}, r"`config.inner.corner` must have 2 entries; got 1"),
        ({"inner": {"corner": [1, "x"]}}, r"`config.inner.corner` entry 1 must be a real"),
        ({"inner": {"depth": 1}}, r"`config.inner` has unknown key"),
        ({"inner": 3}, r"`config.inner` must be a mapping"),
        ([1, 2], r"`config` must be a mapping"),
    ],
)
def test_bad_values_name_the_field(data: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        config_from_dict(Outer, data)


@pytest.mark.parametrize(
    ("kwargs", "field_name", "message"),
    [
        ({"mode": "c"}, "mode", r"must be one of \['a', 'b'\]"),
        ({"count": 2.5}, "count", "must be an integer"),
        ({"count": True}, "count", "must be an integer"),
        ({"count": 0}, "count", "must be an integer >= 1"),
        ({"label": 3}, "label", "must be a string"),
        ({"inner": {"length_m": 1.0}}, "inner", "must be a Inner"),
        ({"inner": None}, "inner", "must be a Inner"),
    ],
)
def test_python_construction_is_checked_by_the_same_rules(
    kwargs: dict[str, object], field_name: str, message: str
) -> None:
    with pytest.raises(SettingError, match=rf"`{field_name}` {message}") as info:
        Outer(**kwargs)  # type: ignore[arg-type]
    assert info.value.field == field_name
    assert isinstance(info.value, InvalidArgumentError)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"flag": 1}, "`flag` must be True or False"),
        ({"flag": "yes"}, "`flag` must be True or False"),
        ({"ratio": math.nan}, "`ratio` must be finite; got nan"),
        ({"ratio": math.inf}, "`ratio` must be finite; got inf"),
        ({"ratio": "0.5"}, "`ratio` must be a real number"),
        ({"ratio": -0.1}, "`ratio` must be >= 0; got -0.1"),
        ({"ratio": 1.0}, "`ratio` must be < 1; got 1.0"),
        ({"sizes": (1.0, 0.0, 1.0)}, r"`sizes` entry 1 must be > 0; got 0.0"),
        ({"sizes": (1.0, 1.0)}, "`sizes` must have 3 entries; got 2"),
        ({"sizes": 1.0}, "`sizes` must be a tuple"),
        ({"sizes": np.ones((3, 1))}, "`sizes` must be a tuple"),
        ({"many": (1, 2.5)}, "`many` entry 1 must be an integer"),
        ({"layers": -1}, "`layers` must be an integer >= 0; got -1"),
        ({"layers": 1.0}, "`layers` must be an integer"),
    ],
)
def test_every_kind_of_field_is_checked(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(SettingError, match=message):
        Kinds(**kwargs)  # type: ignore[arg-type]


def test_accepted_values_are_stored_in_their_canonical_type() -> None:
    k = Kinds(flag=np.bool_(True), ratio=np.float32(0.25), anything=math.inf,  # type: ignore[arg-type]
              sizes=np.array([1, 2, 3]), many=[np.int64(4)], layers=np.int64(2))  # type: ignore[arg-type]
    assert k.flag is True
    assert type(k.ratio) is float and k.ratio == 0.25
    assert k.anything == math.inf  # finite=False lets it through
    assert k.sizes == (1.0, 2.0, 3.0) and all(type(v) is float for v in k.sizes)
    assert k.many == (4,) and type(k.many[0]) is int
    assert k.layers == 2 and type(k.layers) is int
    assert Kinds(ratio=0).ratio == 0.0 and type(Kinds(ratio=0).ratio) is float
    assert Kinds(array=np.zeros(2)).array is not None  # unknown annotation: not judged


def test_setting_error_names_the_field_and_survives_pickling() -> None:
    err = SettingError("grid_spacing_m", "must be >= 0.001; got 0.0001")
    assert str(err) == "`grid_spacing_m` must be >= 0.001; got 0.0001"
    back = pickle.loads(pickle.dumps(err))
    assert (back.field, back.detail, str(back)) == (err.field, err.detail, str(err))


def test_unreadable_and_invalid_yaml(tmp_path) -> None:
    with pytest.raises(ConfigError, match="cannot read config file"):
        load_yaml(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("a: [1, 2\n")
    with pytest.raises(ConfigError, match="is not valid YAML"):
        load_yaml(bad)


def test_a_config_that_is_not_a_regular_file_is_refused_without_reading(tmp_path) -> None:
    fifo = tmp_path / "fifo.yaml"
    os.mkfifo(fifo)  # opening it to read would block until a writer came
    for path in (fifo, "/dev/zero", tmp_path):
        with pytest.raises(ConfigError, match=r"cannot read config file .*not a regular file"):
            load_yaml(path)


def test_a_config_larger_than_the_limit_is_refused(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import deformap._config as config_module

    monkeypatch.setattr(config_module, "MAX_YAML_BYTES", 64)
    big = tmp_path / "big.yaml"
    big.write_text("seed: 1\n" + "# padding\n" * 10)
    with pytest.raises(ConfigError, match=r"big\.yaml.*larger than"):
        load_yaml(big)
    big.write_text("seed: 1\n")
    assert load_yaml(big) == {"seed": 1}


def test_an_integer_too_large_for_a_float_field_is_one_setting_error() -> None:
    @dataclass(frozen=True)
    class Settings:
        value: float = setting(1.0, gt=0.0)

        def __post_init__(self) -> None:
            check_settings(self)

    with pytest.raises(SettingError, match=r"`value` must be a real number within .*401 digits"):
        Settings(value=10**400)
    with pytest.raises(ConfigError, match=r"`f\.value` must be a real number within"):
        config_from_dict(Settings, {"value": 10**400}, where="f")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xff\xfeseed: 1\n", r"not UTF-8 text \(byte 0\)"),
        (b"seed: 2020-02-30\n", "is not valid YAML.*day is out of range"),  # PyYAML's timestamps
        (b"a: " + b"[" * 5000 + b"]" * 5000 + b"\n", "YAML nested deeper than 64 levels"),
    ],
)
def test_yaml_that_the_parser_cannot_take_is_a_config_error(
    tmp_path, content: bytes, message: str
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(content)
    with pytest.raises(ConfigError, match=rf"bad\.yaml.*{message}"):
        load_yaml(bad)


def test_a_setting_of_a_pre_release_file_is_refused_in_one_line() -> None:
    from deformap.run import RunConfig

    older = {"world": {"default_force_n": 0.6, "element_size_m": 0.02}}
    with pytest.raises(ConfigError, match=r"`config.world` has unknown key\(s\) \['default_force_n'\]"):
        config_from_dict(RunConfig, older)


def test_a_retired_world_key_is_refused_saying_why_it_went() -> None:
    from deformap.run import RunConfig

    with pytest.raises(ConfigError) as caught:
        config_from_dict(RunConfig, {"world": {"force_travel_spacing": "force"}})
    message = str(caught.value)
    assert "\n" not in message
    assert message.startswith("`config.world.force_travel_spacing` was retired: ")
    assert "sample_rate_hz" in message and message.endswith("delete it")


def test_a_file_that_sets_a_removed_exploration_switch_is_refused_in_one_line() -> None:
    from deformap.run import RunConfig

    for key, value in (("unread_place", "avoid"), ("boundary_score", "straddle")):
        with pytest.raises(ConfigError) as caught:
            config_from_dict(RunConfig, {"exploration": {key: value}})
        message = str(caught.value)
        assert "\n" not in message
        assert message.startswith(f"`config.exploration` has unknown key(s) ['{key}']")
    # noise_samples 0 no longer implies the shape matcher's uncertainty: the file must say so
    with pytest.raises(ConfigError, match=r"touch\.noise_samples.*beta_uncertainty"):
        config_from_dict(RunConfig, {"exploration": {"touch": {"noise_samples": 0}}})
    shape = config_from_dict(RunConfig, {"exploration": {"beta_uncertainty": "shape-matching",
                                                         "touch": {"noise_samples": 0}}})
    assert shape.exploration.beta_uncertainty == "shape-matching"
    with pytest.raises(ConfigError, match=r"touch\.noise_samples"):
        config_from_dict(RunConfig, {"exploration": {"beta_uncertainty": "camera-noise",
                                                     "touch": {"noise_samples": 0}}})


def test_a_key_repeated_in_one_mapping_is_refused_with_its_line(tmp_path) -> None:
    bad = tmp_path / "twice.yaml"
    bad.write_text("exploration:\n  threshold: 0.1\n  max_pokes: 3\n  threshold: 0.2\n")
    with pytest.raises(ConfigError, match=r"twice\.yaml.*'threshold' appears twice.*line 4"):
        load_yaml(bad)
    fine = tmp_path / "fine.yaml"
    fine.write_text("a: {threshold: 1}\nb: {threshold: 2}\nc: [1, 1]\n")
    assert load_yaml(fine) == {"a": {"threshold": 1}, "b": {"threshold": 2}, "c": [1, 1]}
