"""Evaluation: metrics against ground truth, studies and benchmarks over many worlds."""

from __future__ import annotations

from deformap.eval._metrics import RegionScores, region_scores

__all__ = ["RegionScores", "region_scores"]
