"""Reproduce the paper's Table I on the simulated world: one live run per scenario, in
``out/<scenario>/``, and the table beside the paper's numbers in ``out/table.md`` and
``out/table.json`` (rows and markdown from :mod:`deformap.eval`).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from deformap.errors import ConfigError
from deformap.eval import PAPER_TABLE_I, markdown_table, table_row
from deformap.run._config import RunConfig
from deformap.run._explore import explore_scenario
from deformap.run._folder import (
    claim_run_folder,
    default_run_folder,
    run_stem,
    write_json,
    write_text,
)
from deformap.run._hooks import NO_HOOKS, RunHooks, RunStart
from deformap.world import load_scenario

__all__ = ["ReproduceOutput", "reproduce"]


@dataclass(frozen=True, kw_only=True)
class ReproduceOutput:
    """What :func:`reproduce` wrote: ``table`` (``{"seed", "strategy", "rows"}``, the content of
    ``table.json``), ``markdown`` (of ``table.md``) and the ``folder``."""

    table: dict[str, Any]
    markdown: str
    folder: Path


def _scenario_stage(hooks: RunHooks, scenario: str, text: str) -> None:
    hooks.stage(f"{scenario}: {text}")


def reproduce(out: Path | None = None, *, base: RunConfig | None = None,
              scenarios: Sequence[str] | None = None, figures: bool = True,
              on_run: Callable[[dict[str, Any]], None] | None = None,
              hooks: RunHooks = NO_HOOKS) -> ReproduceOutput:
    """Run every scenario of Table I (or ``scenarios``: built-in names or YAML files) with
    ``base``'s settings, each in ``out/<scenario>/`` (``out`` new or empty, default stem
    ``table-i``), with its figures when ``figures``; ``on_run`` is called with each table row as
    its run ends, ``hooks.step`` once per run and ``hooks.stage`` per stage of each.
    """
    base = base or RunConfig()
    names = list(scenarios) if scenarios else list(PAPER_TABLE_I)
    stems = [run_stem(name) for name in names]  # a YAML path's run is named by its file's stem
    repeated = sorted({s for s in stems if stems.count(s) > 1})
    if repeated:
        raise ConfigError(f"`scenarios` must name each scenario once; got {repeated} twice or more")
    for name in names:  # an unknown scenario fails here, before any folder or run
        load_scenario(name)
    folder = out or default_run_folder("table-i", "reproduce", base.seed)
    with claim_run_folder(folder, what="reproduction"):
        hooks.start(RunStart(kind="reproduce", title=f"{len(names)} scenarios, seed {base.seed}",
                             folder=folder, total=len(names)))  # fmt: skip
        rows = []
        for name, stem in zip(names, stems, strict=True):
            cfg = dataclasses.replace(base, scenario=name)
            hooks.stage(name)
            inner = RunHooks(on_stage=functools.partial(_scenario_stage, hooks, name))
            report = explore_scenario(cfg, folder / stem, figures=figures, hooks=inner).report
            row = table_row(name, report, threshold=cfg.exploration.threshold)
            rows.append(row)
            if on_run is not None:
                on_run(row)
            hooks.step(name)
        table = {"seed": base.seed, "strategy": base.exploration.strategy, "rows": rows}
        markdown = markdown_table(table)
        write_json(folder / "table.json", table)
        write_text(folder / "table.md", markdown)
        return ReproduceOutput(table=table, markdown=markdown, folder=folder)
