"""Evaluation: metrics against ground truth, studies and benchmarks over many worlds."""

from __future__ import annotations

from deformap.eval._experiment import RunConfig, RunOutput, load_run_config, run_experiment
from deformap.eval._metrics import RegionScores, region_scores
from deformap.eval._reproduce import PAPER_TABLE_I, markdown_table, reproduce
from deformap.eval._studies import (
    DEFAULT_HARDNESSES,
    DEFAULT_POSITIONS,
    PROTOCOLS,
    FoamPresses,
    cluster_size_study,
    collect_presses,
    hardness_study,
)

__all__ = [
    "DEFAULT_HARDNESSES",
    "DEFAULT_POSITIONS",
    "PAPER_TABLE_I",
    "PROTOCOLS",
    "FoamPresses",
    "RegionScores",
    "RunConfig",
    "RunOutput",
    "cluster_size_study",
    "collect_presses",
    "hardness_study",
    "load_run_config",
    "markdown_table",
    "region_scores",
    "reproduce",
    "run_experiment",
]
