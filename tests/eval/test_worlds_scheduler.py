"""``--scheduler`` is checked: an empty or in-process address is refused while the settings are
read; an address is connected to under a time limit and must answer as a Dask scheduler, else
one line, before any folder is made. The servers here are local sockets: nothing reaches the
network."""

from __future__ import annotations

import asyncio
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from deformap._validation import SettingError
from deformap.errors import ConfigError
from deformap.run import WorldsBenchConfig, _worlds_engines, bench_worlds
from deformap.run._worlds_engines import check_scheduler

pytest.importorskip("distributed")


@pytest.mark.parametrize(("address", "match"), [
    ("", "got an empty value"),
    ("   ", "got an empty value"),
    ("tcp://host :8786", "got blanks"),
    ("inproc://x", "an inproc:// address names one inside this process"),
    ("http://127.0.0.1:8786", r"must start with one of tcp://"),
    ("tcp://127.0.0.1:0", "a port from 1 to 65535"),
    ("tcp://127.0.0.1:http", "a port from 1 to 65535"),
    ("tcp://:8786", "must name a host"),
])
def test_a_malformed_address_is_refused_with_the_settings(address: str, match: str) -> None:
    with pytest.raises(SettingError, match=match) as exc:
        WorldsBenchConfig(scheduler=address)
    assert exc.value.field == "scheduler" and "\n" not in str(exc.value)


def test_the_command_refuses_an_empty_scheduler(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from deformap.cli import app

    out = tmp_path / "b"
    result = CliRunner().invoke(app, ["bench", "worlds", "--scheduler", "", "--out", str(out)])
    assert result.exit_code == 2 and not out.exists(), result.output
    assert "`scheduler` must be a Dask scheduler's address" in result.output


@pytest.fixture
def server() -> Iterator[object]:
    """``start(payload)``: a local TCP server that accepts and sends ``payload`` (then holds the
    connection open); returns its address."""
    sockets: list[socket.socket] = []

    def start(payload: bytes) -> str:
        srv = socket.socket()
        srv.bind(("127.0.0.1", 0))
        srv.listen(8)
        sockets.append(srv)

        def serve() -> None:
            while True:
                try:
                    conn, _ = srv.accept()
                except OSError:
                    return
                sockets.append(conn)
                try:
                    conn.sendall(payload)
                except OSError:
                    pass

        threading.Thread(target=serve, daemon=True).start()
        return f"tcp://127.0.0.1:{srv.getsockname()[1]}"

    yield start
    for s in sockets:
        s.close()


@pytest.mark.parametrize(("payload", "match"), [
    (b"HTTP/1.1 200 OK\r\ncontent-length: 5\r\n\r\nhello" * 4, "answered, but not as a Dask"),
    (b"\xff" * 64, "answered, but not as a Dask"),
    (b"", "no Dask scheduler answered within 1 s"),
])
def test_a_server_that_is_no_scheduler_is_one_line_within_the_limit(
        server, monkeypatch: pytest.MonkeyPatch, payload: bytes, match: str) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(_worlds_engines, "SCHEDULER_TIMEOUT_S", 1.0)
    address = server(payload)
    start = time.perf_counter()
    with pytest.raises(ConfigError, match=match) as exc:
        check_scheduler(address)
    assert time.perf_counter() - start < 5.0
    text = str(exc.value)
    assert "\n" not in text and text.startswith(f"--scheduler {address!r}")


def test_nothing_listening_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_worlds_engines, "SCHEDULER_TIMEOUT_S", 1.0)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]  # closed again: nothing listens there
    with pytest.raises(ConfigError, match=r"cannot reach a Dask scheduler there|no Dask scheduler "
                                          r"answered") as exc:
        check_scheduler(f"tcp://127.0.0.1:{port}")
    assert "\n" not in str(exc.value)


def test_a_junk_address_leaves_no_benchmark_folder(server, tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(_worlds_engines, "SCHEDULER_TIMEOUT_S", 1.0)
    config = WorldsBenchConfig(worlds=1, scheduler=server(b"\xff" * 64))
    with pytest.raises(ConfigError, match="not as a Dask scheduler"):
        bench_worlds(config, tmp_path / "b")
    assert not (tmp_path / "b").exists()


def test_a_real_scheduler_answers_with_its_version() -> None:
    import distributed

    ready: dict[str, object] = {}
    stop = threading.Event()

    async def run() -> None:
        async with distributed.Scheduler(host="127.0.0.1", port=0,
                                         dashboard_address=None) as scheduler:
            ready["address"] = scheduler.address
            while not stop.is_set():
                await asyncio.sleep(0.05)

    thread = threading.Thread(target=asyncio.run, args=(run(),), daemon=True)
    thread.start()
    try:
        for _ in range(200):
            if "address" in ready:
                break
            time.sleep(0.05)
        assert check_scheduler(str(ready["address"])) == distributed.__version__
    finally:
        stop.set()
        thread.join(10)
