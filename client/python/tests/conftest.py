"""Fixtures of the Python client's tests: a tiny node-only model trained once, primlabel-server
processes on 127.0.0.1 (free ports, stopped at the end), and a synthetic LMS400 scan larger than
one request chunk. CTest (python.Client) sets the environment: PYTHONPATH (the build's
python/ with the generated stubs), PRIMLABEL_BIN_DIR, PRIMLABEL_BUILD_DIR, PRIMLABEL_CMAKE."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pytest

import primlabel

BIN_DIR = Path(os.environ.get("PRIMLABEL_BIN_DIR", "build/bin"))
SOURCE_DIR = Path(__file__).resolve().parents[3]
TEST_DATA = SOURCE_DIR / "tests" / "data"
SHARED_DATA = Path(os.environ.get("PRIMLABEL_SHARED_DATA", SOURCE_DIR.parent / "shared" / "data"))
TOKEN = "s3cret-token"


def binary(name: str) -> str:
    path = BIN_DIR / name
    if not path.exists():
        pytest.skip(f"{path} is not built")
    return str(path)


def run(*command, cwd=None, timeout=60) -> subprocess.CompletedProcess:
    result = subprocess.run([str(c) for c in command], cwd=cwd, timeout=timeout,
                            capture_output=True, text=True)
    assert result.returncode == 0, f"{command} exited {result.returncode}:\n{result.stderr}"
    return result


class Server:
    """A primlabel-server child; the port is read from its "listening" log line."""

    def __init__(self, models: Path, log: Path, *extra: str):
        self.log = log
        self._log_file = open(log, "wb")
        self.process = subprocess.Popen(
            [binary("primlabel-server"), "--models", str(models), "--listen", "127.0.0.1:0",
             "--metrics-listen", "", "--reload-seconds", "0", "--drain-seconds", "0", *extra],
            stdout=self._log_file, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30
        self.port = None
        while self.port is None:
            match = re.search(r"event=listening .* port=(\d+)", log.read_text())
            if match:
                self.port = int(match.group(1))
            elif self.process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"the server did not start:\n{log.read_text()}")
            else:
                time.sleep(0.05)
        self.address = f"127.0.0.1:{self.port}"

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log_file.close()


@pytest.fixture(scope="session", autouse=True)
def built_package():
    """The tests run against the build tree's package, not one installed elsewhere."""
    root = os.environ.get("PRIMLABEL_PYTHON_ROOT")
    if root:
        assert Path(primlabel.__file__).resolve().is_relative_to(Path(root).resolve())


@pytest.fixture(scope="session")
def work(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("primlabel")


@pytest.fixture(scope="session")
def models(work) -> Path:
    """A model repository with one node-only model from one synthetic scene (about 2 s)."""
    repo = work / "models"
    model = repo / "tiny" / "1" / "model.plm"
    model.parent.mkdir(parents=True)
    run(binary("primlabel-train"), "--synth-train", 1, "--synth-val", 0, "--kind", "node",
        "--iterations", 30, "--threads", 2, "--name", "tiny", "-q", "-o", model)
    return repo


@pytest.fixture(scope="session")
def server(models, work):
    s = Server(models, work / "server.log")
    yield s
    s.stop()


@pytest.fixture(scope="session")
def token_server(models, work):
    """A server that wants the bearer token on every call."""
    token_file = work / "token"
    token_file.write_text(TOKEN + "\n")
    s = Server(models, work / "token-server.log", "--token-file", str(token_file),
               "--token-for-all")
    yield s
    s.stop()


@pytest.fixture(scope="session")
def scan(work) -> Path:
    """A held-out synthetic LMS400 table scene (seed 3001, about 85k points)."""
    path = work / "scan.pcd"
    run(binary("primlabel-synth"), "--scene", "table", "--sensor", "lms400", "--seed", 3001,
        "-o", path)
    return path


@pytest.fixture()
def client(server):
    with primlabel.Client(server.address, deadline=30) as c:
        yield c
