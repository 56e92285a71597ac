"""Seeded mutants of every reader's input: each must load to a valid result or raise a DeformapError.

    python benchmarks/robustness.py --mutants 3000          # the table in the README
    python benchmarks/robustness.py --mutants 300 --seed 1  # a quick run

Templates (a small cloud as PCD ascii/binary/binary_compressed, PLY ascii/binary, NPZ, and a
folder session written by ``write_session``, plus MCAP and sqlite3 sessions when ``rosbags`` is
installed)
are mutated by seeded byte flips, truncations, appended bytes, header field edits and point-count
changes (and, for NPZ, the same inside a member, plus edits of its .npy header and shape, with
the member's zip CRC made to match; for sessions,
edits of ``session.yaml``, of one of its files, and links out of the folder). Each mutant is read
in a worker process under a per-case time limit, and counted as:

- ``clean``: refused with a DeformapError (a session: at load, or at least one of its reads);
- ``same``: accepted, and the data read equal the template's (the mutant touched nothing read);
- ``changed``: accepted with other data, where no check could know (a flipped bit in a coordinate
  of a format without checksum, a number edited in ``session.yaml``);
- ``silent``: accepted with other data where a check could have caught it: a different number of
  points or pokes, a structural mutant (truncation, count change, appended bytes) accepted as
  different data, or any change to a file covered by a checksum (NPZ members, a session's
  ``sha256`` manifest);
- ``traceback``: any other exception; ``hang``: over the time limit.

From a source checkout the ``src/`` beside this folder is imported, installed or not. The test
``tests/robustness/test_reader_mutants.py`` runs the same machinery on a few hundred mutants.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import logging
import multiprocessing as mp
import os
import shutil
import sys
import tempfile
import time
import zipfile
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

_SRC = Path(__file__).resolve().parents[1] / "src"
if _SRC.is_dir() and str(_SRC) not in sys.path:
    sys.path.insert(0, str(_SRC))

OUTCOMES = ("clean", "same", "changed", "silent", "traceback", "hang")
STRUCTURAL = {"truncate", "count", "extend", "member-truncate", "member-extend", "member-shape"}

Mutator = Callable[[bytes, np.random.Generator], bytes]


# ----------------------------------------------------------------------------- templates


def _cloud(n: int = 120) -> Any:
    from deformap.cloud import PointCloud

    rng = np.random.default_rng(7)
    # On a 1 mm lattice, so that binary_compressed really compresses (LZF needs repeats).
    pts = np.round(rng.uniform([0.0, 0.0, 0.04], [0.3, 0.2, 0.06], (n, 3)), 3)
    return PointCloud(pts, rng.uniform(0, 1, (n, 3)).round(2))


def _session_parts() -> dict[str, Any]:
    """A flat foam top at 5 cm with a dent under each of three pokes (no simulator needed)."""
    from deformap.cloud import PointCloud
    from deformap.environment import ForceTravel, PressObservation, TactileContact, Workspace

    rng = np.random.default_rng(11)

    def surface(dents: list[tuple[np.ndarray, float]]) -> np.ndarray:
        xy = rng.uniform([0.0, 0.0], [0.6, 0.4], (300, 2))
        z = 0.05 + rng.normal(0, 5e-4, 300)
        for center, depth in dents:
            z -= depth * np.exp(-np.sum((xy - center) ** 2, axis=1) / 0.015**2)
        return np.column_stack([xy, z])

    presses = []
    for i in range(3):
        target, depth = np.array([0.1 + 0.2 * i, 0.2]), 0.004 + 0.002 * i
        tip = np.array([target[0], target[1], 0.05 - depth + 0.01])
        corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * 0.006
        robot = np.vstack([np.column_stack([tip[:2] + corners, np.full(4, z)])
                           for z in (tip[2], tip[2] + 0.25)])  # fmt: skip
        record = ForceTravel(travel_m=np.linspace(0.0, depth, 5), force_n=np.linspace(0.05, 1, 5))
        presses.append(PressObservation(
            cloud=PointCloud(np.vstack([surface([(target, depth)]), robot])),
            contact=TactileContact(tip_center=tip, force=np.array([0.0, 0.0, -1.0]),
                                   tip_radius_m=0.01),
            robot_points=robot, target_xy=target, force_n=1.0, force_travel=record))  # fmt: skip
    from deformap.replay import GroundTruth

    xs, ys = np.linspace(0.01, 0.59, 30), np.linspace(0.01, 0.39, 20)
    labels = np.repeat((xs > 0.3)[None, :], 20, axis=0).astype(np.int64)
    truth = GroundTruth(xs, ys, labels, np.where(labels == 1, np.inf, 80.0))
    return {"workspace": Workspace(), "observation": PointCloud(surface([])), "presses": presses,
            "ground_truth": truth}


def make_templates(root: Path) -> dict[str, Path]:
    """Write every template under ``root``: reader kind → file or session folder."""
    from deformap.cloud.io import write_npz, write_pcd, write_ply
    from deformap.replay import write_session

    cloud = _cloud()
    root.mkdir(parents=True, exist_ok=True)
    out: dict[str, Path] = {}
    for enc in ("ascii", "binary", "binary_compressed"):
        out[f"pcd-{enc}"] = root / f"t-{enc}.pcd"
        write_pcd(out[f"pcd-{enc}"], cloud, encoding=enc)
    assert b"DATA binary_compressed" in out["pcd-binary_compressed"].read_bytes()
    for fmt in ("ascii", "binary_little_endian"):
        key = "ply-" + fmt.split("_")[0]
        out[key] = root / f"t-{fmt}.ply"
        write_ply(out[key], cloud, format=fmt, extra_fields={"i": np.arange(len(cloud), dtype=np.int32)})
    out["npz"] = root / "t.npz"
    write_npz(out["npz"], cloud)
    out["session-folder"] = write_session(root / "session", **_session_parts()).parent
    try:
        import rosbags  # noqa: F401
    except ImportError:
        return out
    for storage in ("mcap", "sqlite3"):
        out[f"session-{storage}"] = write_session(root / f"session-{storage}", format=storage,
                                                  **_session_parts()).parent  # fmt: skip
    return out


# ----------------------------------------------------------------------------- mutators


def _flip(data: bytes, rng: np.random.Generator) -> bytes:
    out = bytearray(data)
    for _ in range(int(rng.integers(1, 5))):
        out[int(rng.integers(len(out)))] ^= 1 << int(rng.integers(8))
    return bytes(out)


def _truncate(data: bytes, rng: np.random.Generator) -> bytes:
    return data[: int(rng.integers(0, len(data)))]


def _extend(data: bytes, rng: np.random.Generator) -> bytes:
    if rng.random() < 0.5:
        return data + rng.bytes(int(rng.integers(1, 65)))
    k = int(rng.integers(1, 97))
    return data + data[-k:]  # what looks like one more record


_NUMBERS = ("0", "-1", "1", "2", "3", "7", "1000000000", "1000000000000", "4294967296",
            "18446744073709551617", "nan", "1e308", "-0", "x", "")  # fmt: skip


def _header_end(data: bytes) -> int:
    for marker in (b"end_header\n", b"DATA ascii\n", b"DATA binary_compressed\n",
                   b"DATA binary\n"):  # fmt: skip
        at = data.find(marker)
        if at >= 0:
            return at + len(marker)
    return min(len(data), 512)


def _header(data: bytes, rng: np.random.Generator) -> bytes:
    """Edit one header line: a token replaced (a number, or another word of the header), the
    line dropped or repeated."""
    end = _header_end(data)
    lines = data[:end].split(b"\n")
    i = int(rng.integers(len(lines)))
    words = lines[i].split(b" ")
    choice = rng.random()
    if choice < 0.15:
        del lines[i]
    elif choice < 0.3:
        lines.insert(i, lines[i])
    else:
        j = int(rng.integers(len(words)))
        vocabulary = [w for line in lines for w in line.split(b" ") if w]
        if rng.random() < 0.7 or not vocabulary:
            words[j] = _NUMBERS[int(rng.integers(len(_NUMBERS)))].encode()
        else:
            words[j] = vocabulary[int(rng.integers(len(vocabulary)))]
        lines[i] = b" ".join(words)
    return b"\n".join(lines) + data[end:]


def _count(data: bytes, rng: np.random.Generator) -> bytes:
    """Change the declared point count (PCD: POINTS and WIDTH together; PLY: element vertex)."""
    import re

    pattern = (rb"element vertex (\d+)" if data.startswith(b"ply")
               else rb"POINTS (\d+)")  # fmt: skip
    match = re.search(pattern, data[: _header_end(data)])
    if match is None:
        return _header(data, rng)
    n = int(match.group(1))
    new = [n - 1, n + 1, n // 2, 2 * n, 0, n - 7, 10**9, 10**12][int(rng.integers(8))]
    out = data.replace(match.group(0), match.group(0).replace(match.group(1), str(new).encode()), 1)
    if not data.startswith(b"ply"):
        out = out.replace(f"WIDTH {n}".encode(), f"WIDTH {new}".encode(), 1)
    return out


FILE_MUTATORS: dict[str, Mutator] = {
    "flip": _flip, "truncate": _truncate, "extend": _extend, "header": _header, "count": _count,
}  # fmt: skip


def _npz_member(data: bytes, rng: np.random.Generator, kind: str) -> bytes:
    """Mutate one member's .npy bytes (``kind``: flip, truncate, extend, npy-header, shape) and
    rebuild the zip, so that the member's CRC matches the damage."""
    src = zipfile.ZipFile(io.BytesIO(data))
    names = src.namelist()
    victim = names[int(rng.integers(len(names)))]
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as dst:
        for name in names:
            raw = src.read(name)
            if name == victim:
                if kind == "npy-header":
                    raw = _header_npy(raw, rng)
                elif kind == "shape":
                    raw = _shape_npy(raw, rng)
                else:
                    raw = FILE_MUTATORS[kind](raw, rng)
            dst.writestr(name, raw)
    return buf.getvalue()


def _header_npy(raw: bytes, rng: np.random.Generator) -> bytes:
    end = raw.find(b"\n", 10)
    header = bytearray(raw[10:end])
    for _ in range(int(rng.integers(1, 4))):
        at = int(rng.integers(len(header)))
        header[at] = b"{}()[]',: 0123456789<>fiuUOb"[int(rng.integers(28))]
    return raw[:10] + bytes(header) + raw[end:]


def _shape_npy(raw: bytes, rng: np.random.Generator) -> bytes:
    import re

    match = re.search(rb"'shape': \(([^)]*)\)", raw[:200])
    if match is None:
        return raw
    new = [b"0, 3", b"1, 3", b"1000000000, 3", b"119, 3", b"121, 3", b"3,", b"120, 3, 1",
           b"-1, 3", b"10000000000000, 3"][int(rng.integers(9))]  # fmt: skip
    padded = match.group(0).replace(match.group(1), new)
    return raw.replace(match.group(0), padded, 1)


# ----------------------------------------------------------------------------- sessions


def _yaml_edit(text: str, rng: np.random.Generator) -> str:
    lines = text.split("\n")
    choice = rng.random()
    if choice < 0.2:  # cut after a random line
        return "\n".join(lines[: int(rng.integers(1, len(lines)))]) + "\n"
    if choice < 0.35:  # cut at a poke boundary
        starts = [i for i, line in enumerate(lines) if line.startswith("- ")]
        if starts:
            return "\n".join(lines[: starts[int(rng.integers(len(starts)))]]) + "\n"
    i = int(rng.integers(len(lines)))
    if choice < 0.5:
        del lines[i]
    elif choice < 0.6:
        lines.insert(i, lines[i])
    elif choice < 0.75:  # a file name outside the folder
        names = [j for j, line in enumerate(lines) if ".pcd" in line or ".npz" in line
                 or line.startswith("bag:")]  # fmt: skip
        if names:
            j = names[int(rng.integers(len(names)))]
            key, _, value = lines[j].partition(":")
            bad = ("../", "/tmp/", "./../s/", "sub/../../")[int(rng.integers(4))]
            lines[j] = f"{key}: {bad}{value.strip()}"
    else:  # a number replaced
        import re

        numbers = list(re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", lines[i]))
        if numbers:
            m = numbers[int(rng.integers(len(numbers)))]
            new = _NUMBERS[int(rng.integers(len(_NUMBERS)))] or "1"
            lines[i] = lines[i][: m.start()] + new + lines[i][m.end():]
    return "\n".join(lines)


def mutate_session(template: Path, out: Path, kind: str, rng: np.random.Generator) -> None:
    """Copy the session folder ``template`` to ``out`` and damage it (``kind``)."""
    shutil.copytree(template, out, symlinks=True)
    data_files = sorted(p for p in out.rglob("*") if p.is_file() and p.name != "session.yaml")
    if kind == "yaml":
        file = out / "session.yaml"
        file.write_text(_yaml_edit(file.read_text(), rng))
    elif kind == "link":
        victim = data_files[int(rng.integers(len(data_files)))]
        outside = out.parent / f"{out.name}-outside-{victim.name}"
        shutil.move(victim, outside)
        os.symlink(outside, victim)
    else:
        victim = data_files[int(rng.integers(len(data_files)))]
        name = ("flip", "truncate", "extend", "header", "count")[int(rng.integers(5))]
        victim.write_bytes(FILE_MUTATORS[name](victim.read_bytes(), rng))


# ----------------------------------------------------------------------------- reading


def _digest(*arrays: Any) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(b"-" if a is None else np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def read_snapshot(reader: str, path: str) -> tuple[str, Any]:
    """Read ``path`` as ``reader`` does; ``("ok", snapshot)``, ``("clean", message)`` or
    ``("traceback", message)``. A session's snapshot lists each read (load, observation, pokes)."""
    from deformap.errors import DeformapError

    try:
        if not reader.startswith("session"):
            from deformap.cloud.io import read_npz, read_pcd, read_ply

            read = {"pcd": read_pcd, "ply": read_ply, "npz": read_npz}[reader.split("-")[0]]
            cloud, extras = read(path)
            return "ok", (len(cloud), _digest(cloud.points, cloud.colors,
                                              *[extras[k] for k in sorted(extras)]))  # fmt: skip
        from deformap.replay import load_session

        session = load_session(path)
        reads: list[Any] = [("obs", _safe(lambda: _digest(session.observation().points)))]
        for i in range(len(session)):
            reads.append((i, _safe(lambda i=i: _press_digest(session.press_observation(i)))))
        truth = session.ground_truth
        reads.append(("truth", None if truth is None else _digest(truth.labels, truth.hardness)))
        return "ok", (len(session), tuple(reads))
    except DeformapError as exc:
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
    except DeformapError:
        return "refused"


def classify(reader: str, kind: str, status: str, got: Any, want: Any) -> str:
    """One of :data:`OUTCOMES` for a mutant read (``want``: the template's snapshot)."""
    if status != "ok":
        return status
    if got == want:
        return "same"
    if reader.startswith("session"):
        n_got, reads = got
        if any(value == "refused" for _, value in reads):
            changed = [k for (k, v), (_, w) in zip(reads, want[1], strict=False)
                       if v not in ("refused", w)]  # fmt: skip
            return "clean" if not changed and n_got == want[0] else _session_change(kind, got, want)
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

KINDS: dict[str, tuple[str, ...]] = {
    "pcd": ("flip", "truncate", "extend", "header", "count"),
    "ply": ("flip", "truncate", "extend", "header", "count"),
    "npz": ("flip", "truncate", "extend", "member-flip", "member-truncate", "member-extend",
            "member-npy-header", "member-shape"),
    "session": ("yaml", "file", "link"),
}


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
    plan = [(r, k) for r in names for k in KINDS[r.split("-")[0]]]
    cases = []
    try:
        for index in range(n_mutants):
            reader, kind = plan[index % len(plan)]
            rng = np.random.default_rng([seed, index])
            target = work / f"m{index}"
            if reader.startswith("session"):
                mutate_session(templates[reader], target, kind, rng)
            else:
                target = target.with_suffix(templates[reader].suffix)
                data = templates[reader].read_bytes()
                if kind.startswith("member-"):
                    mutated = _npz_member(data, rng, kind.removeprefix("member-"))
                else:
                    mutated = FILE_MUTATORS[kind](data, rng)
                target.write_bytes(mutated)
            status, got = worker.read(reader, target)
            outcome = classify(reader, kind, status, got, want[reader][1])
            cases.append(Case(reader, kind, outcome, str(got)[:300]))
            if target.is_dir():
                shutil.rmtree(target)
                for link in work.glob(f"{target.name}-outside-*"):
                    link.unlink()
            else:
                target.unlink()
    finally:
        worker.close()
    return cases


def table(cases: list[Case]) -> str:
    """A markdown table: one row per reader, the kinds tried and the count of each outcome."""
    rows = ["| reader | kinds tried | mutants | clean errors | accepted, same | accepted, changed "
            "(undetectable) | silently accepted corruptions | tracebacks | hangs |",
            "|---|---|---:|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for reader in dict.fromkeys(c.reader for c in cases):
        mine = [c for c in cases if c.reader == reader]
        n = Counter(c.outcome for c in mine)
        kinds = ", ".join(dict.fromkeys(c.kind for c in mine))
        rows.append(f"| {reader} | {kinds} | {len(mine)} | {n['clean']} | {n['same']} | "
                    f"{n['changed']} | {n['silent']} | {n['traceback']} | {n['hang']} |")  # fmt: skip
    n = Counter(c.outcome for c in cases)
    rows.append(f"| **all** | | {len(cases)} | {n['clean']} | {n['same']} | {n['changed']} | "
                f"{n['silent']} | {n['traceback']} | {n['hang']} |")  # fmt: skip
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mutants", type=int, default=3000, help="how many mutants (default 3000)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the mutants (default 0)")
    parser.add_argument("--limit", type=float, default=10.0,
                        help="seconds a case may take before it counts as a hang (default 10)")
    args = parser.parse_args(argv)
    if args.mutants < 1 or args.seed < 0 or not args.limit > 0:
        parser.error("--mutants must be >= 1, --seed >= 0 and --limit > 0")
    logging.disable(logging.WARNING)  # refused pokes are counted, not logged
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="deformap-robustness-") as tmp:
        cases = run(args.mutants, args.seed, args.limit, Path(tmp))
    print(table(cases))
    print(f"\n{len(cases)} mutants (seed {args.seed}) in {time.perf_counter() - start:.0f} s, "
          f"per-case limit {args.limit:g} s")
    bad = [c for c in cases if c.outcome in ("traceback", "hang", "silent")]
    for case in bad[:20]:
        print(f"{case.outcome}: {case.reader} {case.kind}: {case.detail}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
