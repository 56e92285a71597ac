"""The application layer: a run's configuration (:class:`RunConfig`), its folder, its report,
the progress callbacks (:class:`RunHooks`), and the workflows, each a function with typed
arguments returning a typed result, in a module of its own.

This package may import every library package; none of them imports it. The names are imported
on first use: a run needs the world and the estimator (slow to import), ``deformap --help`` not.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from deformap._lazy import lazy_exports

if TYPE_CHECKING:
    from deformap.run._config import (
        CONFIG_NAME,
        RunConfig,
        RunOverrides,
        apply_overrides,
        config_yaml,
        explore_run_config,
        load_run_config,
        resume_run_config,
        run_generators,
    )
    from deformap.run._environment import explore_environment, parse_env_args
    from deformap.run._estimate import EstimateOutput, estimate_one_poke
    from deformap.run._explore import RunOutput, explore_scenario
    from deformap.run._export import POKES_CSV_COLUMNS
    from deformap.run._folder import RUNS_ROOT, default_run_folder
    from deformap.run._hooks import RunHooks, RunStart
    from deformap.run._map import MapOutput, map_recorded_session
    from deformap.run._record import RecordOutput, record_simulation
    from deformap.run._reproduce import ReproduceOutput, reproduce
    from deformap.run._robot import RobotConfig
    from deformap.run._studies import (
        CLUSTER_SIZE_FOAMS,
        StudyOutput,
        run_cluster_size_study,
        run_hardness_study,
    )
    from deformap.run._world import ScenarioSummary, scenario_summaries, show_scenario
    from deformap.run._worlds import (
        RESCORABLE,
        WorldsOutput,
        bench_worlds,
        load_worlds,
        rescore_worlds,
    )
    from deformap.run._worlds_config import WorldsBenchConfig, exploration_with, parse_assignments
    from deformap.run._worlds_engines import BLAS_THREAD_VARIABLES

_MODULES: dict[str, tuple[str, ...]] = {
    "_config": ("CONFIG_NAME", "RunConfig", "RunOverrides", "apply_overrides", "config_yaml",
               "explore_run_config", "load_run_config", "resume_run_config", "run_generators"),
    "_environment": ("explore_environment", "parse_env_args"),
    "_estimate": ("EstimateOutput", "estimate_one_poke"),
    "_explore": ("RunOutput", "explore_scenario"),
    "_export": ("POKES_CSV_COLUMNS",),
    "_folder": ("RUNS_ROOT", "default_run_folder"),
    "_hooks": ("RunHooks", "RunStart"),
    "_map": ("MapOutput", "map_recorded_session"),
    "_record": ("RecordOutput", "record_simulation"),
    "_reproduce": ("ReproduceOutput", "reproduce"),
    "_robot": ("RobotConfig",),
    "_studies": ("CLUSTER_SIZE_FOAMS", "StudyOutput", "run_cluster_size_study",
                "run_hardness_study"),
    "_world": ("ScenarioSummary", "scenario_summaries", "show_scenario"),
    "_worlds": ("RESCORABLE", "WorldsOutput", "bench_worlds", "load_worlds", "rescore_worlds"),
    "_worlds_config": ("WorldsBenchConfig", "exploration_with", "parse_assignments"),
    "_worlds_engines": ("BLAS_THREAD_VARIABLES",),
}  # fmt: skip

__all__ = [
    "BLAS_THREAD_VARIABLES", "CLUSTER_SIZE_FOAMS", "CONFIG_NAME", "POKES_CSV_COLUMNS", "RESCORABLE",
    "RUNS_ROOT", "EstimateOutput", "MapOutput", "RecordOutput", "ReproduceOutput", "RobotConfig",
    "RunConfig", "RunHooks", "RunOutput", "RunOverrides", "RunStart", "ScenarioSummary", "StudyOutput",
    "WorldsBenchConfig", "WorldsOutput", "apply_overrides", "bench_worlds", "config_yaml",
    "default_run_folder", "estimate_one_poke", "exploration_with", "explore_environment",
    "explore_run_config", "explore_scenario", "load_run_config", "load_worlds",
    "map_recorded_session", "parse_assignments", "parse_env_args", "record_simulation", "reproduce",
    "rescore_worlds", "resume_run_config", "run_cluster_size_study", "run_generators",
    "run_hardness_study", "scenario_summaries", "show_scenario",
]

__getattr__, __dir__ = lazy_exports(__name__, _MODULES, __all__, globals())
