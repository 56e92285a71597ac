"""`deformap config dump`: the configuration reference, each setting under its description, unit
and bounds, that loads back as the default run configuration."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import yaml
from typer.testing import CliRunner

from deformap._config import described_yaml, dump_yaml, setting_docs
from deformap._validation import check_settings, setting
from deformap.cli import app
from deformap.run import RunConfig, load_run_config

runner = CliRunner()


@dataclass(frozen=True, kw_only=True)
class _Probe:
    """Settings of a probe.

    Parameters
    ----------
    tip_radius_m : float
        Radius of the spherical tip. A second sentence the reference leaves out.
    mode : {"soft", "hard"}
        How it presses.
    """

    tip_radius_m: float = setting(0.01, gt=0.0, le=0.05)
    force_n: float = setting(0.3, gt=0.0, ge=0.1, doc="Commanded press force.")
    mode: Literal["soft", "hard"] = "soft"
    layers: int | None = setting(None, ge=0)

    def __post_init__(self) -> None:
        check_settings(self)


def test_each_setting_gets_its_description_unit_bounds_and_choices() -> None:
    docs = {name: (doc, facts) for name, doc, facts in setting_docs(_Probe)}
    assert docs["tip_radius_m"] == ("Radius of the spherical tip.", ["unit: m", "range: (0, 0.05]"])
    assert docs["force_n"] == ("Commanded press force.", ["unit: N", "range: >= 0.1"])
    assert docs["mode"] == ("How it presses.", ["one of: soft, hard"])
    assert docs["layers"] == (None, ["range: >= 0", "null allowed"])
    text = described_yaml(_Probe())
    assert "# Radius of the spherical tip.\n# unit: m; range: (0, 0.05]\ntip_radius_m: 0.01\n" in text
    assert yaml.safe_load(text) == yaml.safe_load(dump_yaml(_Probe()))


def test_config_dump_is_described_and_loads_back_as_the_defaults(tmp_path) -> None:
    result = runner.invoke(app, ["config", "dump", "--out", str(tmp_path / "c.yaml")])
    assert result.exit_code == 0, result.output
    text = (tmp_path / "c.yaml").read_text()
    assert "  # unit: m; range: >= 0.001\n  element_size_m: 0.0075\n" in text
    assert "one of: paper, max-variance" in text
    assert yaml.safe_load(text) == yaml.safe_load(dump_yaml(RunConfig()))
    assert load_run_config(tmp_path / "c.yaml") == RunConfig()  # what `explore --config` reads
    # explore reads the file, then refuses only the override (before any work is done)
    refused = runner.invoke(app, ["explore", "--config", str(tmp_path / "c.yaml"),
                                  "--out", str(tmp_path / "run"), "--max-pokes", "0"])
    assert refused.exit_code == 2
    assert "`max_pokes` must be an integer >= 1" in refused.output
    assert "c.yaml" not in refused.output
    printed = runner.invoke(app, ["config", "dump"])
    assert printed.exit_code == 0 and printed.output == text


def test_every_run_setting_has_a_description() -> None:
    missing = [name for name, doc, _ in setting_docs(RunConfig) if not doc]
    # each needs setting(doc=...) or an entry in its class's numpydoc "Parameters"
    assert missing == [], f"settings without a description: {missing}"
