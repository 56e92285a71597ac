"""Seeded mutants of every reader's input: each must load to a valid result or raise a DeformapError.

    python benchmarks/robustness.py --mutants 3000          # the table in the README
    python benchmarks/robustness.py --mutants 300 --seed 1  # a quick run
    python benchmarks/robustness.py --mutants 0 --cli-mutants 3000  # the command line's only

Templates (a small cloud as PCD ascii/binary/binary_compressed, PLY ascii/binary, NPZ, and a
folder session written by ``write_session``, plus MCAP and sqlite3 sessions when ``rosbags`` is
installed, and a raw robot bag when ``mcap-ros2-support`` is too: the folder session's three
presses written as a robot's drivers record them by ``deformap.testing.robotbag`` — organised
PointCloud2 with NaN holes at 15 Hz, WrenchStamped at 100 Hz, /tf at 25 Hz, /tf_static, in
zstd chunks of 16 kB with their CRCs (``raw-mcap``), and the same messages as a lone sqlite3
``.db3`` written by rosbags' rosbag2 writer (``raw-db3``) — read as ``deformap map BAG`` reads
it, with its ``NAME.deformap.yaml`` beside it)
are mutated by seeded byte flips, truncations, appended bytes, header field edits and point-count
changes (and, for NPZ, the same inside a member, plus edits of its .npy header and shape, with
the member's zip CRC made to match; for sessions,
edits of ``session.yaml``, of one of its files, and links out of the folder; for the raw bag, the
same byte mutants, one MCAP record's content or length damaged or the record left out or
repeated, one message's bytes damaged in a bag rewritten with every CRC made to match, and line
edits of its settings YAML; for the ``.db3``, the byte mutants, and through SQL one message
row's data flipped, cut or extended, the row deleted or inserted again, or one field of a
``topics`` row changed; and the YAML a user
writes, a run configuration and a scenario, by line edits, byte flips and cuts). Each mutant is read
in a worker process under a per-case time limit, and counted as:

- ``clean``: refused with a DeformapError (a session: at load, or at least one of its reads);
- ``same``: accepted, and the data read equal the template's (the mutant touched nothing read);
- ``changed``: accepted with other data, where no check could know (a flipped bit in a coordinate
  of a format without checksum, a number edited in ``session.yaml`` or a raw bag's settings, a
  raw bag's message damaged with the CRCs made to match; in a ``.db3``, which has no checksum, a
  flipped byte, a message's bytes edited in place, a topic's field);
- ``silent``: accepted with other data where a check could have caught it: a different number of
  points or pokes, a structural mutant (truncation, count change, appended bytes, a message's
  length changed) accepted as different data, or any change to a file covered by a checksum (NPZ
  members, a session's ``sha256`` manifest, a raw bag's chunk and summary CRCs), and a ``.db3``
  row deleted or repeated (the bag's metadata table counts its messages);
- ``traceback``: any other exception, or an error of several lines; ``hang``: over the time
  limit.

``--cli-mutants N`` also runs at least N command-line mutants (``benchmarks/_cli_mutants.py``:
every option of every command given seeded hostile values under a guard that stops a run before
its work) and prints, per value kind, how many ended in one clean ``error:`` line, in the parser's
usage box, in a traceback, a hang, or otherwise (another exit code, several error lines).

From a source checkout the ``src/`` beside this folder is imported, installed or not. The tests
``tests/robustness/test_reader_mutants.py`` and ``test_cli_mutants.py`` run the same machinery on
a few hundred mutants each.
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import multiprocessing as mp
import shutil
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

_SRC = Path(__file__).resolve().parents[1] / "src"
for _path in (_SRC, Path(__file__).resolve().parent):
    if _path.is_dir() and str(_path) not in sys.path:
        sys.path.insert(0, str(_path))

from _mutants import (  # noqa: E402
    KINDS,  # noqa: F401  (the tests read it from here)
    kinds_of,
    make_templates,
    mutate_file,
    mutate_raw,
    mutate_session,
)

OUTCOMES = ("clean", "same", "changed", "silent", "traceback", "hang")
STRUCTURAL = {"truncate", "count", "extend", "member-truncate", "member-extend", "member-shape",
              "message-truncate", "message-extend"}  # fmt: skip

# ----------------------------------------------------------------------------- reading


def _digest(*arrays: Any) -> str:
    h = hashlib.sha256()
    for a in arrays:
        if isinstance(a, tuple):  # a raw bag's robot points: one hull per part
            h.update(_digest(*a).encode())
        else:
            h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def read_snapshot(reader: str, path: str) -> tuple[str, Any]:
    """Read ``path`` as ``reader`` does; ``("ok", snapshot)``, ``("clean", message)`` or
    ``("traceback", message)``. A session's snapshot lists each read (load, observation, pokes)."""
    from deformap.errors import DeformapError

    try:
        if reader in ("config", "scenario"):
            from deformap._config import config_to_dict
            from deformap.run import load_run_config
            from deformap.world import load_scenario

            value = (config_to_dict(load_run_config(path)) if reader == "config"
                     else load_scenario(path).to_dict())  # fmt: skip
            return "ok", hashlib.sha256(repr(value).encode()).hexdigest()[:16]
        if not reader.startswith(("session", "raw")):
            from deformap.cloud.io import read_npz, read_pcd, read_ply

            read = {"pcd": read_pcd, "ply": read_ply, "npz": read_npz}[reader.split("-")[0]]
            cloud, extras = read(path)
            return "ok", (len(cloud), _digest(cloud.points, cloud.colors,
                                              *[extras[k] for k in sorted(extras)]))  # fmt: skip
        from deformap.replay import load_raw_bag, load_raw_config, load_session
        from deformap.run import RunConfig

        if reader.startswith("raw"):  # as `deformap map BAG` opens it, settings from beside it
            session = load_raw_bag(path, load_raw_config(Path(path)),
                                   default_force_n=RunConfig().exploration.force_n)
        else:
            session = load_session(path)
        reads: list[Any] = [("obs", _safe(lambda: _digest(session.observation().points)))]
        for i in range(len(session)):
            reads.append((i, _safe(lambda i=i: _press_digest(session.press_observation(i)))))
        truth = session.ground_truth
        reads.append(("truth", None if truth is None else _digest(truth.labels, truth.hardness)))
        return "ok", (len(session), tuple(reads))
    except DeformapError as exc:
        if "\n" in str(exc):  # an error is one line (a refused read's too: _safe)
            return "traceback", f"an error of several lines: {str(exc)[:300]!r}"
        return "clean", str(exc)[:300]
    except Exception as exc:  # counting what escapes is the point
        return "traceback", f"{type(exc).__name__}: {str(exc)[:300]}"


def _press_digest(obs: Any) -> str:
    record = obs.force_travel
    return _digest(obs.cloud.points, obs.robot_points, obs.contact.tip_center, obs.contact.force,
                   obs.target_xy, np.float64(obs.force_n),
                   None if record is None else record.travel_m,
                   None if record is None else record.force_n)  # fmt: skip


def _safe(read: Callable[[], str]) -> str:
    from deformap.errors import DeformapError

    try:
        return read()
    except DeformapError as exc:
        if "\n" in str(exc):
            raise RuntimeError(f"an error of several lines: {str(exc)[:300]!r}") from None
        return "refused"


def classify(reader: str, kind: str, status: str, got: Any, want: Any) -> str:
    """One of :data:`OUTCOMES` for a mutant read (``want``: the template's snapshot)."""
    if status != "ok":
        return status
    if got == want:
        return "same"
    if reader in ("config", "scenario"):  # text a user edits: another valid value is theirs
        return "changed"
    if reader.startswith(("session", "raw")):
        n_got, reads = got
        if any(value == "refused" for _, value in reads):
            changed = [k for (k, v), (_, w) in zip(reads, want[1], strict=False)
                       if v not in ("refused", w)]  # fmt: skip
            if not changed and n_got == want[0]:
                return "clean"
        if reader.startswith("raw"):
            return _raw_change(reader, kind)
        return _session_change(kind, got, want)
    # A zip holds a CRC-32 of each member; the member-* mutants forge it to match.
    checksummed = reader == "npz" and not kind.startswith("member-")
    if got[0] != want[0] or kind in STRUCTURAL or checksummed:
        return "silent"
    return "changed"


def _session_change(kind: str, got: Any, want: Any) -> str:
    # Files are covered by the manifest; session.yaml is text a user may edit: only a lost poke
    # (a count that disagrees) is then something a check could see.
    if kind != "yaml" or got[0] < want[0]:
        return "silent"
    return "changed"


def _raw_change(reader: str, kind: str) -> str:
    # An MCAP bag's chunks and summary carry CRCs and its records lengths: a change from a byte
    # or record mutant is one they could have caught. A message rewritten with its CRCs made to
    # match, or a settings YAML a user edits, is other valid data, unless the message's length
    # changed (the decoder could tell). A sqlite3 bag carries no CRC: a flipped byte, a
    # message's data edited or a topic's field changed is other data nothing could tell, unless
    # bytes or a message were cut or added; a row deleted or repeated disagrees with the message
    # counts in the bag's metadata table, which the reader compares.
    if kind in STRUCTURAL or (reader == "raw-db3" and kind in ("row-delete", "row-repeat")):
        return "silent"
    if reader == "raw-db3" or kind == "yaml" or kind.startswith("message-"):
        return "changed"
    return "silent"


def _worker(conn: Any) -> None:
    while True:
        job = conn.recv()
        if job is None:
            return
        conn.send(read_snapshot(*job))


@dataclass
class Worker:
    """A reader process; a case over the time limit kills it (a hang) and a new one starts."""

    limit_s: float
    _proc: Any = None
    _conn: Any = None

    def read(self, reader: str, path: Path) -> tuple[str, Any]:
        if self._proc is None:
            ctx = mp.get_context("fork")
            self._conn, child = ctx.Pipe()
            self._proc = ctx.Process(target=_worker, args=(child,), daemon=True)
            self._proc.start()
        self._conn.send((reader, str(path)))
        if self._conn.poll(self.limit_s):
            try:
                return self._conn.recv()  # type: ignore[no-any-return]
            except EOFError:  # the worker died (killed for memory, a crash in C)
                self.close()
                return "traceback", "the reader process died"
        self.close()
        return "hang", f"over {self.limit_s} s"

    def close(self) -> None:
        if self._proc is not None:
            self._proc.kill()
            self._proc.join()
            self._proc = None


# ----------------------------------------------------------------------------- the run


@dataclass
class Case:
    reader: str
    kind: str
    outcome: str
    detail: str


def run(n_mutants: int, seed: int, limit_s: float, work: Path,
        readers: tuple[str, ...] | None = None) -> list[Case]:  # fmt: skip
    """Make the templates in ``work``, then ``n_mutants`` mutants spread over readers and kinds."""
    templates = make_templates(work / "templates")
    names = [r for r in templates if readers is None or r in readers]
    worker = Worker(limit_s)
    want = {r: read_snapshot(r, str(templates[r])) for r in names}
    for r, (status, snap) in want.items():
        if status != "ok":
            raise RuntimeError(f"template {r} does not read: {snap}")
    plan = [(r, k) for r in names for k in kinds_of(r)]
    cases = []
    try:
        for index in range(n_mutants):
            reader, kind = plan[index % len(plan)]
            rng = np.random.default_rng([seed, index])
            target = work / f"m{index}"
            if reader.startswith("session"):
                mutate_session(templates[reader], target, kind, rng)
            elif reader.startswith("raw"):
                target = mutate_raw(templates[reader], target, kind, rng)
            else:
                target = target.with_suffix(templates[reader].suffix)
                data = templates[reader].read_bytes()
                mutated = mutate_file(data, kind, rng)
                target.write_bytes(mutated)
            status, got = worker.read(reader, target)
            outcome = classify(reader, kind, status, got, want[reader][1])
            cases.append(Case(reader, kind, outcome, str(got)[:300]))
            if reader.startswith("raw"):
                shutil.rmtree(target.parent)
            elif target.is_dir():
                shutil.rmtree(target)
                for link in work.glob(f"{target.name}-outside-*"):
                    link.unlink()
            else:
                target.unlink()
    finally:
        worker.close()
    return cases


def _count_table(header: list[str], cases: list[Any], group: str, outcome: str,
                 outcomes: tuple[str, ...], lead: Callable[[list[Any]], list[str]]) -> str:
    """A markdown table: a row per value of the cases' attribute ``group`` (its name, ``lead``'s
    cells, the count of each of ``outcomes`` in their attribute ``outcome``), then the row of all
    (``lead`` of all of them; a "kinds tried" column left empty there)."""
    rows = ["| " + " | ".join(header) + " |",
            "|---|" + "|".join("---" if h == "kinds tried" else "---:" for h in header[1:]) + "|"]
    groups: dict[str, list[Any]] = {}
    for case in cases:
        groups.setdefault(getattr(case, group), []).append(case)
    for name, mine in [*groups.items(), ("**all**", cases)]:
        n = Counter(getattr(c, outcome) for c in mine)
        cells = [name, *lead(mine), *(str(n[o]) for o in outcomes)]
        if name == "**all**" and "kinds tried" in header:
            cells[header.index("kinds tried")] = ""
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def table(cases: list[Case]) -> str:
    """A markdown table: one row per reader, the kinds tried and the count of each outcome."""
    return _count_table(
        ["reader", "kinds tried", "mutants", "clean errors", "accepted, same",
         "accepted, changed (undetectable)", "silently accepted corruptions", "tracebacks",
         "hangs"], cases, "reader", "outcome",
        ("clean", "same", "changed", "silent", "traceback", "hang"),
        lambda mine: [", ".join(dict.fromkeys(c.kind for c in mine)), str(len(mine))])


def cli_table(cases: list[Any]) -> str:
    """A markdown table of command-line mutants: one row per value kind, the options given it
    and the count of each ending."""
    return _count_table(
        ["value kind", "mutants", "options", "one line naming the option or value",
         "one line naming the guard", "one line naming neither", "usage errors (parser)",
         "tracebacks", "hangs", "other endings"],
        sorted(cases, key=lambda c: c.kind), "kind", "ending",
        ("named", "guard", "clean", "usage", "traceback", "hang", "other"),
        lambda mine: [str(len(mine)), str(len({c.option for c in mine}))])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", type=int, default=3000,
                        help="how many reader mutants (default 3000; 0: none)")
    parser.add_argument("--cli-mutants", type=int, default=0,
                        help="how many command-line mutants, at least (default 0: none; "
                             "benchmarks/_cli_mutants.py)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the mutants (default 0)")
    parser.add_argument("--limit", type=float, default=10.0,
                        help="seconds a case may take before it counts as a hang (default 10)")
    args = parser.parse_args(argv)
    if (args.mutants < 0 or args.cli_mutants < 0 or args.mutants + args.cli_mutants < 1
            or args.seed < 0 or not args.limit > 0):  # fmt: skip
        parser.error("--mutants and --cli-mutants must be >= 0 and not both 0, --seed >= 0 and "
                     "--limit > 0")
    logging.disable(logging.WARNING)  # refused pokes are counted, not logged
    bad: list[str] = []
    if args.mutants:
        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-robustness-") as tmp:
            cases = run(args.mutants, args.seed, args.limit, Path(tmp))
        print(table(cases))
        print(f"\n{len(cases)} mutants (seed {args.seed}) in {time.perf_counter() - start:.0f} s, "
              f"per-case limit {args.limit:g} s")
        bad += [f"{c.outcome}: {c.reader} {c.kind}: {c.detail}" for c in cases
                if c.outcome in ("traceback", "hang", "silent")]  # fmt: skip
    if args.cli_mutants:
        from _cli_mutants import HANG_LIMIT_S, run_cli

        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="deformap-cli-mutants-") as tmp:
            cli_cases = run_cli(args.cli_mutants, args.seed, Path(tmp))
        print(("\n" if args.mutants else "") + cli_table(cli_cases))
        print(f"\n{len(cli_cases)} command-line mutants (seed {args.seed}) in "
              f"{time.perf_counter() - start:.0f} s, hang limit {HANG_LIMIT_S} s")
        bad += [f"{c.ending}: {c.option} ({c.kind}): {c.detail}" for c in cli_cases
                if c.ending in ("traceback", "hang", "other")]  # fmt: skip
    for line in bad[:20]:
        print(line)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
