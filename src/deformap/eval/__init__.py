"""Evaluation: metrics against ground truth, studies, the paper's Table I, and benchmarks.

The runs that write folders belong to :mod:`deformap.run`, which uses this package; this package
never imports it. The names are imported on first use: the studies and benchmarks pull in the
simulated world and the whole estimator (slow to import), which a metric alone never needs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformap._lazy import lazy_exports

if TYPE_CHECKING:
    from deformap.eval._behaviour_study import (
        BEHAVIOUR_READS,
        BEHAVIOUR_TOLERANCES,
        BEHAVIOUR_TRUTHS,
        FULL_BEHAVIOUR_MATERIALS,
        QUICK_BEHAVIOUR_MATERIALS,
        BehaviourMaterial,
        behaviour_presses,
        behaviour_summary,
        material_scenario,
    )
    from deformap.eval._bench_gp import bench_surface_gp
    from deformap.eval._bench_io import IO_GOAL_S, bench_io
    from deformap.eval._bench_memory import bench_memory, measure_case
    from deformap.eval._bench_msm import bench_beta_sweep
    from deformap.eval._bench_world import bench_world
    from deformap.eval._metrics import OrderingScores, RegionScores, ordering_scores, region_scores
    from deformap.eval._rescore import rescore_world
    from deformap.eval._studies import (
        DEFAULT_HARDNESSES,
        DEFAULT_POSITIONS,
        DEFAULT_PROTOCOL,
        PAPER_PROTOCOL,
        PROTOCOLS,
        STUDY_PROTOCOLS,
        FoamPresses,
        block_scenario,
        cluster_size_study,
        collect_presses,
        hardness_study,
        hardness_summary,
    )
    from deformap.eval._table_i import PAPER_TABLE_I, markdown_table, table_row
    from deformap.eval._world_draw import (
        FORCES_N,
        HARDNESS_RANGE_N,
        THICKNESSES_M,
        WorldDraw,
        WorldTask,
        choices,
        draw_world,
        material_truth,
    )
    from deformap.eval._world_result import POKES_FORMAT, TIME_COLUMNS, WorldResult, row_values
    from deformap.eval._worlds import run_world
    from deformap.eval._worlds_paired import paired_cells
    from deformap.eval._worlds_summary import (
        CSV_COLUMNS,
        GOOD_ACCURACY,
        accuracy_curves,
        combination_name,
        markdown_summary,
        pokes_to_good,
        runs_csv,
        summarise_worlds,
    )

_MODULES = {
    "_bench_gp": ("bench_surface_gp",),
    "_bench_io": ("IO_GOAL_S", "bench_io"),
    "_bench_memory": ("bench_memory", "measure_case"),
    "_bench_msm": ("bench_beta_sweep",),
    "_bench_world": ("bench_world",),
    "_metrics": ("OrderingScores", "RegionScores", "ordering_scores", "region_scores"),
    "_behaviour_study": ("BEHAVIOUR_READS", "BEHAVIOUR_TOLERANCES", "BEHAVIOUR_TRUTHS",
                         "FULL_BEHAVIOUR_MATERIALS", "QUICK_BEHAVIOUR_MATERIALS",
                         "BehaviourMaterial", "behaviour_presses", "behaviour_summary",
                         "material_scenario"),
    "_studies": ("DEFAULT_HARDNESSES", "DEFAULT_POSITIONS", "DEFAULT_PROTOCOL", "PAPER_PROTOCOL",
                 "PROTOCOLS", "STUDY_PROTOCOLS", "FoamPresses", "block_scenario",
                 "cluster_size_study", "collect_presses", "hardness_study", "hardness_summary"),
    "_table_i": ("PAPER_TABLE_I", "markdown_table", "table_row"),
    "_rescore": ("rescore_world",),
    "_world_draw": ("FORCES_N", "HARDNESS_RANGE_N", "THICKNESSES_M", "WorldDraw", "WorldTask",
                    "choices", "draw_world", "material_truth"),
    "_world_result": ("POKES_FORMAT", "TIME_COLUMNS", "WorldResult", "row_values"),
    "_worlds": ("run_world",),
    "_worlds_paired": ("paired_cells",),
    "_worlds_summary": ("CSV_COLUMNS", "GOOD_ACCURACY", "accuracy_curves", "combination_name",
                        "markdown_summary", "pokes_to_good", "runs_csv", "summarise_worlds"),
}  # fmt: skip

__all__ = [
    "BEHAVIOUR_READS",
    "BEHAVIOUR_TOLERANCES",
    "BEHAVIOUR_TRUTHS",
    "CSV_COLUMNS",
    "DEFAULT_HARDNESSES",
    "DEFAULT_POSITIONS",
    "DEFAULT_PROTOCOL",
    "FORCES_N",
    "FULL_BEHAVIOUR_MATERIALS",
    "GOOD_ACCURACY",
    "HARDNESS_RANGE_N",
    "IO_GOAL_S",
    "PAPER_PROTOCOL",
    "PAPER_TABLE_I",
    "POKES_FORMAT",
    "PROTOCOLS",
    "QUICK_BEHAVIOUR_MATERIALS",
    "STUDY_PROTOCOLS",
    "THICKNESSES_M",
    "TIME_COLUMNS",
    "BehaviourMaterial",
    "FoamPresses",
    "OrderingScores",
    "RegionScores",
    "WorldDraw",
    "WorldResult",
    "WorldTask",
    "accuracy_curves",
    "behaviour_presses",
    "behaviour_summary",
    "bench_beta_sweep",
    "bench_io",
    "bench_memory",
    "bench_surface_gp",
    "bench_world",
    "block_scenario",
    "choices",
    "cluster_size_study",
    "collect_presses",
    "combination_name",
    "draw_world",
    "hardness_study",
    "hardness_summary",
    "markdown_summary",
    "markdown_table",
    "material_scenario",
    "material_truth",
    "measure_case",
    "ordering_scores",
    "paired_cells",
    "pokes_to_good",
    "region_scores",
    "rescore_world",
    "row_values",
    "run_world",
    "runs_csv",
    "summarise_worlds",
    "table_row",
]


__getattr__, __dir__ = lazy_exports(__name__, _MODULES, __all__, globals())
