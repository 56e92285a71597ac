"""Seeded mutants of every reader's input and every command-line option, counted by ending.

Each must load to a valid result or end in one clean error.

    python benchmarks/robustness.py --mutants 3000          # reader mutants
    python benchmarks/robustness.py --mutants 300 --seed 1  # a quick run
    python benchmarks/robustness.py --mutants 0 --cli-mutants 3000  # the command line's only
    python benchmarks/robustness.py --mutants 0 --machine 4  # the machine failing under a run

The reader mutants, their templates, the worker process with its per-case time limit and the
classification (``clean``, ``same``, ``changed``, ``silent``, ``traceback``, ``hang``) are
:mod:`deformap.testing.mutants`'s; their kinds include nested YAML alias bombs in every YAML a
user gives (``alias``: a session, a run configuration, a scenario, a raw bag's settings; one
accepted counts as ``silent``) and ascii clouds cut inside their last number
(``cut-number``); the command-line mutants (every option of every command given seeded hostile
values, an alias-bomb YAML among the paths, under a guard that stops a run before its work) and
their endings are
:mod:`deformap.testing.cli_mutants`'s. This script runs any number of them and prints a table per
reader and per value kind; it exits 1 when any traceback, hang, silent corruption or other ending
is counted.

``--machine N`` runs ``deformap explore``, ``record-sim`` and ``map`` (a coarse world, three pokes)
with a full disk (``ENOSPC``) or a read-only file system (``EROFS``) from their first, last and
``N`` seeded writes on (injected at the one write path, :mod:`deformap._files`, so that it runs
without root), and ``N`` times two ``explore --resume`` of one killed run, and two ``record-sim``
into one new folder, started at once. A failed write must end in exit code 2 and one line naming
the file and the cause, leave no temporary, and (``explore``) resume once there is room; of two
runs at once, one must be refused naming the other's PID (or both end, one after the other,
without a poke journalled twice).

From a source checkout the ``src/`` beside this folder is imported, installed or not.
``tests/robustness/`` runs the same machinery on a few hundred mutants each.
"""

from __future__ import annotations

import argparse
import logging
import os
import random
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

_SRC = Path(__file__).resolve().parents[1] / "src"
if _SRC.is_dir() and str(_SRC) not in sys.path:  # a source checkout's, installed or not
    sys.path.insert(0, str(_SRC))

from deformap.testing.mutants import run_mutants, table  # noqa: E402

# -- the machine failing under a run: a full disk, a read-only file system, two runs at once ----

#: Run as ``python -c`` before the command line: the ``DEFORMAP_FAULT_AT``-th write of the run
#: and every one after it (a full disk stays full, a file system remounted read-only stays so)
#: raises ``OSError(DEFORMAP_FAULT)`` at the one write path (every atomic write's rename, every
#: journal line); the number of writes tried goes to stderr at exit.
_INJECT = r"""
import atexit, errno, os, sys
import deformap._files as files
import deformap.explore._journal as journal
code = getattr(errno, os.environ["DEFORMAP_FAULT"])
at = int(os.environ["DEFORMAP_FAULT_AT"])
calls = [0]
def hit():
    calls[0] += 1
    if at and calls[0] >= at:
        raise OSError(code, os.strerror(code))
real_replace, real_write = files.replace_durably, os.write
def replace(tmp, path):
    hit()
    real_replace(tmp, path)
class _Os:
    def __getattr__(self, name):
        return getattr(os, name)
    @staticmethod
    def write(fd, data):
        hit()
        return real_write(fd, data)
files.replace_durably = replace
journal.os = _Os()
atexit.register(lambda: sys.stderr.write(f"\nFAULT-CALLS {calls[0]}\n"))
sys.argv = ["deformap", *sys.argv[1:]]
from deformap.cli import main
main()
"""

MACHINE_CLASSES = ("disk-full", "read-only", "concurrent")
_ERRNO = {"disk-full": "ENOSPC", "read-only": "EROFS"}
_CAUSE = {"disk-full": "no space left on the device (ENOSPC)",
          "read-only": "the file system is read-only (EROFS)"}
_MACHINE_LIMIT_S = 300.0


def _deformap(args: list[str], fault: str = "ENOSPC", at: int = 0,
              background: bool = False) -> Any:
    env = {**os.environ, "DEFORMAP_FAULT": fault, "DEFORMAP_FAULT_AT": str(at),
           "PYTHONPATH": os.pathsep.join([str(_SRC), os.environ.get("PYTHONPATH", "")]),
           "OMP_NUM_THREADS": "1"}
    command = [sys.executable, "-c", _INJECT, *args]
    if background:
        return subprocess.Popen(command, env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
    try:
        return subprocess.run(command, env=env, capture_output=True, text=True,
                              timeout=_MACHINE_LIMIT_S, check=False)
    except subprocess.TimeoutExpired:
        return None


def _calls(done: Any) -> int:
    found = re.findall(r"FAULT-CALLS (\d+)", done.stderr)
    return int(found[-1]) if found else -1


def _ending(done: Any, want: str) -> str:
    """How a run with a fault injected ended: ``clean`` (exit 2, one ``error:`` line naming the
    file and ``want``), ``traceback``, ``hang``, ``silent`` (exit 0 though a write failed), or
    ``other``."""
    if done is None:
        return "hang"
    text = done.stdout + done.stderr
    if "Traceback" in text:
        return "traceback"
    errors = [line for line in text.splitlines() if line.strip().startswith("error:")]
    if done.returncode == 0:
        return "silent"
    if done.returncode == 2 and len(errors) == 1 and "cannot write" in errors[0] \
            and want in errors[0]:
        return "clean"
    return "other"


def _leftovers(folder: Path) -> list[str]:
    from deformap._files import is_temporary

    return [p.name for p in folder.rglob("*") if is_temporary(p)] if folder.is_dir() else []


@dataclass
class MachineCase:
    cls: str
    command: str
    at: int
    ending: str
    detail: str = ""


def _config_file(root: Path) -> Path:
    from deformap._config import dump_yaml
    from deformap.explore import ExplorationConfig, SurfaceGPConfig
    from deformap.run import RunConfig
    from deformap.world import WorldConfig

    path = root / "config.yaml"
    dump_yaml(RunConfig(scenario="heterogeneous-60-150", seed=3, world=WorldConfig.coarse(),
                        exploration=ExplorationConfig(
                            max_pokes=3, surface=SurfaceGPConfig(fit_hyperparameters=False))),
              path)  # fmt: skip
    return path


def _commands(root: Path, config: Path) -> dict[str, Callable[[Path], list[str]]]:
    session = root / "session"
    if not session.exists():
        done = _deformap(["record-sim", "-s", "heterogeneous-60-150", "--config", str(config),
                          "--out", str(session)])  # fmt: skip
        assert done is not None and done.returncode == 0, done and done.stdout + done.stderr
    return {
        "explore": lambda out: ["explore", "--config", str(config), "--out", str(out)],
        "record-sim": lambda out: ["record-sim", "-s", "heterogeneous-60-150", "--config",
                                   str(config), "--out", str(out)],
        "map": lambda out: ["map", str(session), "--out", str(out)],
    }


def _fault_case(cls: str, command: str, args: Callable[[Path], list[str]], at: int,
                out: Path, config: Path) -> MachineCase:
    done = _deformap(args(out), _ERRNO[cls], at)
    ending = _ending(done, _CAUSE[cls])
    detail = "" if done is None else (done.stdout + done.stderr).strip().splitlines()[-2:][0]
    if ending == "clean" and _leftovers(out):
        ending, detail = "other", f"temporaries left: {_leftovers(out)}"
    if ending == "clean" and command == "explore":  # the run goes on once there is room:
        # resumed, or started again in its folder when it failed before its first file
        started = (out / "config.yaml").exists()
        again = _deformap(["explore", "--resume", str(out)] if started else args(out))
        if again is None or again.returncode != 0:
            ending = "other"
            detail = "resume failed: " + ("hang" if again is None else
                                          (again.stdout + again.stderr)[-300:])
    return MachineCase(cls, command, at, ending, detail)


def _concurrent_case(command: str, index: int, root: Path, config: Path) -> MachineCase:
    """Two runs at once in one folder: ``explore --resume`` of a run killed after its first
    writes, or two ``record-sim`` into one new folder. One must be refused naming the other's PID
    (or find the folder already taken); two that both end 0 must not have written twice."""
    out = root / f"concurrent-{command}-{index}"
    if command == "explore --resume":
        first = _deformap(["explore", "--config", str(config), "--out", str(out)], "ENOSPC",
                          3 + index % 3)  # fmt: skip
        if first is None or first.returncode != 2:
            return MachineCase("concurrent", command, 0, "other", "could not make a killed run")
        args = ["explore", "--resume", str(out)]
    else:
        args = ["record-sim", "-s", "heterogeneous-60-150", "--config", str(config), "--out",
                str(out)]
    procs = [_deformap(args, background=True) for _ in range(2)]
    texts, codes = [], []
    for proc in procs:
        try:
            text, _ = proc.communicate(timeout=_MACHINE_LIMIT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            return MachineCase("concurrent", command, 0, "hang")
        texts.append(text)
        codes.append(proc.returncode)
    if any("Traceback" in t for t in texts):
        return MachineCase("concurrent", command, 0, "traceback", texts[0][-300:])
    if sorted(codes) == [0, 2]:
        refused = texts[codes.index(2)]
        other = procs[codes.index(0)].pid
        if f"(PID {other})" in refused:
            return MachineCase("concurrent", command, 0, "clean", "refused naming the PID")
        if "not empty" in refused or "written by another process" in refused:
            return MachineCase("concurrent", command, 0, "clean", "found the folder taken")
        return MachineCase("concurrent", command, 0, "other", refused.strip()[-300:])
    if codes == [0, 0] and command == "explore --resume":  # one after the other
        from deformap.explore import JOURNAL_NAME, read_journal

        pokes = [p["index"] for p in read_journal(out / JOURNAL_NAME).pokes]
        ok = len(pokes) == len(set(pokes))
        return MachineCase("concurrent", command, 0, "clean" if ok else "silent",
                           "one after the other" if ok else f"journal pokes {pokes}")
    return MachineCase("concurrent", command, 0, "silent" if codes == [0, 0] else "other",
                       f"exit codes {codes}")


def run_machine(count: int, seed: int, root: Path) -> list[MachineCase]:
    """``count`` cases of each command under each fault class (and of each concurrent pair)."""
    rng = random.Random(seed)
    config = _config_file(root)
    commands = _commands(root, config)
    cases = []
    for cls in ("disk-full", "read-only"):
        for name, args in commands.items():
            probe = _deformap(args(root / f"probe-{cls}-{name}"), _ERRNO[cls], 0)
            writes = _calls(probe) if probe is not None else -1
            if writes < 1:
                cases.append(MachineCase(cls, name, 0, "other", "could not count the writes"))
                continue
            # the first writes, the last one, and seeded ones between
            points = sorted({1, writes, *(rng.randint(1, writes) for _ in range(count))})[:count]
            for at in points:
                cases.append(_fault_case(cls, name, args, at, root / f"{cls}-{name}-{at}",
                                         config))  # fmt: skip
    for name in ("explore --resume", "record-sim"):
        for index in range(count):
            cases.append(_concurrent_case(name, index, root, config))
    return cases


def machine_table(cases: list[MachineCase]) -> str:
    endings = ("clean", "silent", "traceback", "hang", "other")
    head = ("| class | command | cases | one line naming the file and cause, resumable | "
            "silently accepted | tracebacks | hangs | other endings |")
    lines = [head, "|---|---|---:|---:|---:|---:|---:|---:|"]
    keys = list(dict.fromkeys((c.cls, c.command) for c in cases))
    for cls, command in keys:
        mine = [c for c in cases if (c.cls, c.command) == (cls, command)]
        counts = [sum(c.ending == e for c in mine) for e in endings]
        lines.append(f"| {cls} | {command} | {len(mine)} | " + " | ".join(map(str, counts)) + " |")
    totals = [sum(c.ending == e for c in cases) for e in endings]
    lines.append(f"| **all** |  | {len(cases)} | " + " | ".join(map(str, totals)) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", type=int, default=3000,
                        help="how many reader mutants (default 3000; 0: none)")
    parser.add_argument("--cli-mutants", type=int, default=0,
                        help="how many command-line mutants, at least (default 0: none; "
                             "deformap.testing.cli_mutants)")
    parser.add_argument("--machine", type=int, default=0,
                        help="how many cases of each command under each machine failure (a "
                             "full disk, a read-only file system, two runs at once; default 0)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the mutants (default 0)")
    parser.add_argument("--limit", type=float, default=10.0,
                        help="seconds a case may take before it counts as a hang (default 10)")
    args = parser.parse_args(argv)
    if (min(args.mutants, args.cli_mutants, args.machine) < 0
            or args.mutants + args.cli_mutants + args.machine < 1
            or args.seed < 0 or not args.limit > 0):  # fmt: skip
        parser.error("--mutants, --cli-mutants and --machine must be >= 0 and not all 0, "
                     "--seed >= 0 and --limit > 0")
    logging.disable(logging.WARNING)  # refused pokes are counted, not logged
    bad: list[str] = []
    if args.mutants:
        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-robustness-") as tmp:
            cases = run_mutants(args.mutants, args.seed, args.limit, Path(tmp))
        print(table(cases))
        print(f"\n{len(cases)} mutants (seed {args.seed}) in {time.perf_counter() - start:.0f} s, "
              f"per-case limit {args.limit:g} s")
        bad += [f"{c.outcome}: {c.reader} {c.kind}: {c.detail}" for c in cases
                if c.outcome in ("traceback", "hang", "silent")]  # fmt: skip
    if args.cli_mutants:
        from deformap.testing.cli_mutants import HANG_LIMIT_S, cli_table, run_cli

        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-cli-mutants-") as tmp:
            cli_cases = run_cli(args.cli_mutants, args.seed, Path(tmp))
        print(("\n" if args.mutants else "") + cli_table(cli_cases))
        print(f"\n{len(cli_cases)} command-line mutants (seed {args.seed}) in "
              f"{time.perf_counter() - start:.0f} s, hang limit {HANG_LIMIT_S} s")
        bad += [f"{c.ending}: {c.option} ({c.kind}): {c.detail}" for c in cli_cases
                if c.ending in ("traceback", "hang", "other")]  # fmt: skip
    if args.machine:
        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-machine-") as tmp:
            machine = run_machine(args.machine, args.seed, Path(tmp))
        print(("\n" if args.mutants or args.cli_mutants else "") + machine_table(machine))
        print(f"\n{len(machine)} machine-failure cases (seed {args.seed}) in "
              f"{time.perf_counter() - start:.0f} s")
        for how in ("refused naming the PID", "found the folder taken", "one after the other"):
            print(f"two at once, {how}: "
                  f"{sum(c.cls == 'concurrent' and c.detail == how for c in machine)}")
        bad += [f"{c.ending}: {c.cls} {c.command} at write {c.at}: {c.detail}" for c in machine
                if c.ending != "clean"]  # fmt: skip
    for line in bad[:20]:
        print(line)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
