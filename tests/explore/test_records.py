"""Typed poke records: plain data only at the journal and report boundary, refused when broken."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from deformap.environment import TactileContact
from deformap.errors import FileFormatError
from deformap.explore import (
    ContactRecord,
    PokeRecord,
    PokeTimings,
    Target,
)
from deformap.explore._planning import PokePlan


def _record(**changes: object) -> PokeRecord:
    base = PokeRecord(
        index=2, target_xy=(0.3, 0.2), contact_xy=(0.301, 0.199),
        contact=ContactRecord.of(TactileContact(tip_center=np.array([0.301, 0.199, 0.052]),
                                                force=np.array([0.0, 0.0, -0.6]),
                                                tip_radius_m=0.01)),
        force_n=0.6, beta=0.71, beta_std=0.012, betas=(0.0, 0.5, 0.71), errors=(2e-3, 1e-3, 5e-4),
        iterations=42, residual=1e-7, converged=True, n_roi_points=812, camera_noise_m=0.0011,
        timings=PokeTimings(filter_s=0.01, touch_gp_s=0.02, beta_s=0.3, field_s=0.001,
                            target_s=0.02, environment_s=0.2),
        purpose="variance", planned_after=3, max_variance_after=0.071,
    )  # fmt: skip
    return dataclasses.replace(base, **changes)  # type: ignore[arg-type]


def test_a_record_survives_the_journal_round_trip() -> None:
    record = _record()
    line = json.dumps(record.to_dict(), allow_nan=False)
    assert PokeRecord.from_dict(json.loads(line)) == record
    # a journal line carries its kind beside the record
    assert PokeRecord.from_dict({"kind": "poke", **record.to_dict()}) == record


def test_unset_fields_are_left_out_and_read_back_unset() -> None:
    record = _record(purpose=None, planned_after=None, max_variance_after=None,
                     camera_noise_m=None,
                     timings=PokeTimings(filter_s=0.1, touch_gp_s=0.2, beta_s=0.3))
    data = record.to_dict()
    assert "purpose" not in data and "planned_after" not in data
    assert "max_variance_after" not in data
    assert data["camera_noise_m"] is None  # always written
    assert data["timings"] == {"filter_s": 0.1, "touch_gp_s": 0.2, "beta_s": 0.3}
    assert PokeRecord.from_dict(data) == record


def test_compute_time_leaves_out_the_environment() -> None:
    t = PokeTimings(filter_s=0.1, touch_gp_s=0.2, beta_s=0.3, field_s=0.05, environment_s=5.0)
    assert t.compute_s == pytest.approx(0.65)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.pop("beta"), "has no `beta`"),
        (lambda d: d.update(beta="0.7"), "`poke.beta` must be a number"),
        (lambda d: d.update(beta=float("nan")), "`poke.beta` must be finite"),
        (lambda d: d.update(index=1.5), "`poke.index` must be an integer"),
        (lambda d: d.update(converged=1), "`poke.converged` must be true or false"),
        (lambda d: d.update(purpose="curiosity"), "`poke.purpose` must be one of"),
        (lambda d: d.update(contact_xy=[0.3]), "`poke.contact_xy` must be a list of 2"),
        (lambda d: d["contact"].pop("force"), "`poke.contact.force` must be a list of 3"),
        (lambda d: d["timings"].pop("beta_s"), "`poke.timings` has no `beta_s`"),
        (lambda d: d["timings"].update(warp_s=1.0), "unknown key"),
        (lambda d: d.update(betas="0.1 0.2"), "`poke.betas` must be a list"),
        (lambda d: d.update(colour="red"), "unknown key"),
    ],
)
def test_a_broken_record_is_refused_naming_the_field(change, message) -> None:  # type: ignore[no-untyped-def]
    data = json.loads(json.dumps(_record().to_dict()))
    change(data)
    with pytest.raises(FileFormatError, match=message):
        PokeRecord.from_dict(data)


def test_a_target_says_how_many_pokes_its_plan_foresees() -> None:
    targets = np.array([[0.1, 0.1], [0.2, 0.2], [0.3, 0.3]])
    reaching = PokePlan(targets=targets, max_variance=0.05, reaches=True)
    short = PokePlan(targets=targets, max_variance=0.07, reaches=False)
    assert Target(targets[0], "variance", reaching).planned_after == 2
    assert Target(targets[0], "variance", short).planned_after is None
    assert Target(targets[0], "first").planned_after is None


def test_records_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        _record().beta = 0.2  # type: ignore[misc]


#: A journal line exactly as deformap 179946e wrote it (``deformap reproduce``, homogeneous-60,
#: seed 0, its first poke).
OLD_LINE = (
    '{"kind": "poke", "index": 0, "target_xy": [0.3, 0.2], "contact_xy": [0.29983638551331826, '
    '0.19965923332812302], "contact": {"tip_center": [0.3, 0.2, 0.05254550737716549], "force": '
    '[-0.010007937524023595, -0.020843946227377206, -0.6112407842648694], "tip_radius_m": 0.01}, '
    '"force_n": 0.6, "beta": 0.84, "beta_std": 0.008250152362627425, "betas": [0.0, 0.1, 0.2, '
    '0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.83, 0.84, 0.85, 0.9], "errors": [0.0007108014353514295, '
    '0.0007082795558651988, 0.0007051626308674533, 0.0007012134859064481, 0.0006960489887286717, '
    '0.0006890181425795369, 0.0006789215878648256, 0.0006633755879424201, 0.0006383415140023154, '
    '0.000630160873817498, 0.0006285408798056407, 0.0006287739404293335, 0.0006991194325470164], '
    '"iterations": 7, "residual": 8.333270929676657e-05, "converged": true, "n_roi_points": 2558, '
    '"camera_noise_m": 0.0014825174977852475, "timings": {"filter_s": 0.026820267999994485, '
    '"touch_gp_s": 0.09715296199999557, "beta_s": 0.2328804889999958, "field_s": '
    '0.001231501000006574, "target_s": 1.59329999860347e-05, "environment_s": 0.2596760909999887}, '
    '"purpose": "first", "max_variance_after": 0.08985003756925422}'
)


def test_journal_lines_of_earlier_versions_are_read_as_written() -> None:
    old = json.loads(OLD_LINE)
    record = PokeRecord.from_dict(old)
    assert record.beta == 0.84 and record.purpose == "first" and record.planned_after is None
    assert record.timings.environment_s == pytest.approx(0.2596760909999887)
    # the same line written back is the line read (kind aside)
    assert record.to_dict() == {k: v for k, v in old.items() if k != "kind"}
    # lines from before purpose, planned_after and camera_noise_m existed
    for key in ("purpose", "camera_noise_m"):
        older = {k: v for k, v in old.items() if k != key}
        assert getattr(PokeRecord.from_dict(older), key) is None


def test_a_record_with_its_stiffness_survives_the_round_trip() -> None:
    from deformap.stiffness import StiffnessEstimate

    soft = StiffnessEstimate(stiffness_n_per_m=120.0, stiffness_std_n_per_m=4.0,
                             stiffness_lower_n_per_m=None, modulus_pa=5000.0, modulus_std_pa=150.0,
                             contact_offset_m=1e-4, depth_m=0.006, max_chi=0.18, reduced_chi2=0.9,
                             rigid=False, n_samples=9)
    rigid = StiffnessEstimate(stiffness_n_per_m=None, stiffness_std_n_per_m=None,
                              stiffness_lower_n_per_m=5000.0, modulus_pa=None, modulus_std_pa=None,
                              contact_offset_m=None, depth_m=2e-5, max_chi=None, reduced_chi2=None,
                              rigid=True, n_samples=9)
    for estimate in (soft, rigid):
        record = _record(stiffness=estimate, layer_thickness_m=0.05)
        data = json.loads(json.dumps(record.to_dict(), allow_nan=False))
        assert PokeRecord.from_dict(data) == record
    refused = _record(stiffness_error="`force_travel`: force not rising", layer_thickness_m=0.05)
    assert PokeRecord.from_dict(refused.to_dict()) == refused
    data = _record(stiffness=soft).to_dict()
    data["stiffness"]["rigid"] = "no"
    with pytest.raises(FileFormatError, match=r"`poke\.stiffness\.rigid` must be true or false"):
        PokeRecord.from_dict(data)
    # an estimate that cannot be: rigid with a modulus, a negative modulus, an unknown model
    for change in ({"rigid": True}, {"modulus_pa": -3.0}, {"model": "guess"}, {"n_samples": 1}):
        data = _record(stiffness=soft).to_dict()
        data["stiffness"].update(change)
        with pytest.raises(FileFormatError, match=r"`poke\.stiffness`"):
            PokeRecord.from_dict(data)
