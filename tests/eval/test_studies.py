"""Smoke tests of the studies (β against hardness, fit error against cluster size) on coarse
worlds: a few foams, two presses each, fixed surface hyperparameters.

Coarse-mesh βs are not measurements; what is checked is the studies' contract (the shape of the
results, β in [0, 1), the monotone flags computed from the rows) and what must hold on any mesh:
under the default protocol β falls as hardness rises and the rigid board reads lowest.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from deformap.eval import (
    PROTOCOLS,
    FoamPresses,
    cluster_size_study,
    collect_presses,
    hardness_study,
)
from deformap.explore import ExplorationConfig, SurfaceGPConfig
from deformap.world import WorldConfig

HARDNESSES = (60.0, 150.0, None)
POSITIONS = ((0.30, 0.20), (0.18, 0.12))
CONFIG = ExplorationConfig(surface=SurfaceGPConfig(fit_hyperparameters=False))


def _hardness_key(hardness: float | None) -> float:
    return math.inf if hardness is None else hardness


@pytest.fixture(scope="module")
def foams() -> list[FoamPresses]:
    return collect_presses(HARDNESSES, world_config=WorldConfig.coarse(), config=CONFIG,
                           positions=POSITIONS, rng=np.random.default_rng(0))  # fmt: skip


def test_collect_presses_presses_each_foam_at_each_place(foams: list[FoamPresses]) -> None:
    assert [f.hardness_n for f in foams] == list(HARDNESSES)
    for foam in foams:
        assert len(foam.presses) == len(POSITIONS)
        for press, xy in zip(foam.presses, POSITIONS, strict=True):
            np.testing.assert_allclose(press.target_xy, xy)
            assert press.force_n == CONFIG.force_n


def _check_row(row: dict[str, object]) -> None:
    beta, spread, claimed = row["beta"], row["beta_std"], row["beta_estimate_std"]
    assert isinstance(beta, float) and 0.0 <= beta < 1.0
    assert isinstance(spread, float) and 0.0 <= spread < 1.0  # over the two places
    assert isinstance(claimed, float) and 0.0 < claimed < 1.0
    fit_error = row["fit_error_m"]
    assert isinstance(fit_error, float) and 0.0 < fit_error < 0.01
    iterations = row["iterations"]
    assert isinstance(iterations, int) and iterations >= 1
    assert isinstance(row["converged"], bool)


def test_hardness_study_rows_and_monotone_flags(foams: list[FoamPresses]) -> None:
    protocols = {name: PROTOCOLS[name] for name in ("force/quadratic", "pinned/linear")}
    study = hardness_study(foams, protocols=protocols)
    assert set(study) == {"rows", "monotone", "modulus_monotone", "n_refused"}
    assert study["n_refused"] == 0
    json.dumps(study)  # the CLI writes it as is
    rows = study["rows"]
    assert [(r["protocol"], r["hardness_n"]) for r in rows] == [
        (p, h) for p in protocols for h in HARDNESSES
    ]
    for row in rows:
        _check_row(row)
    assert set(study["monotone"]) == set(protocols)
    for name, flag in study["monotone"].items():
        ordered = sorted((r for r in rows if r["protocol"] == name),
                         key=lambda r: _hardness_key(r["hardness_n"]))  # fmt: skip
        assert isinstance(flag, bool)
        assert flag == all(a["beta"] > b["beta"] for a, b in itertools.pairwise(ordered))
    default = {r["hardness_n"]: r["beta"] for r in rows if r["protocol"] == "force/quadratic"}
    # the default protocol orders the foams and the rigid board reads lowest, near 0
    assert default[60.0] > default[150.0] > default[None]
    assert default[None] < 0.05
    assert study["monotone"]["force/quadratic"] is True
    # the paper's pinned protocol imposes the depth: it cannot order the foams
    assert study["monotone"]["pinned/linear"] is False
    # the force–travel records: E against the world's own modulus, the rigid board read rigid
    stiff = {r["hardness_n"]: r for r in rows if r["protocol"] == "force/quadratic"}
    assert stiff[None]["rigid"] and stiff[None]["modulus_pa"] is None
    assert stiff[None]["true_modulus_pa"] is None
    for hardness in (60.0, 150.0):
        row = stiff[hardness]
        assert not row["rigid"] and row["true_modulus_pa"] > 0
        assert row["modulus_rel_error"] == pytest.approx(
            (row["modulus_pa"] - row["true_modulus_pa"]) / row["true_modulus_pa"])
        # the coarse mesh's 2 cm elements do not resolve a 1 cm tip's contact (it dents too
        # little): this checks the scale only; the default mesh's figures are in the README
        assert 0.5 < row["modulus_pa"] / row["true_modulus_pa"] < 2.0
        assert row["modulus_std_pa"] > 0 and row["stiffness_n_per_m"] > 0
    assert stiff[60.0]["modulus_pa"] < stiff[150.0]["modulus_pa"]
    assert study["modulus_monotone"] is True


def test_cluster_size_study_rows(foams: list[FoamPresses]) -> None:
    sizes = (3, 4)
    study = cluster_size_study(foams, sizes=sizes)
    assert set(study) == {"rows"}
    json.dumps(study)
    rows = study["rows"]
    assert [(r["cluster_size"], r["hardness_n"]) for r in rows] == [
        (k, h) for k in sizes for h in HARDNESSES
    ]
    for row in rows:
        _check_row(row)
    for k in sizes:
        betas = {r["hardness_n"]: r["beta"] for r in rows if r["cluster_size"] == k}
        assert betas[60.0] > betas[150.0] > betas[None], k
