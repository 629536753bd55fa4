"""A real RouDi and a real robodiffd for the server-mode tests, as subprocesses.

Mirrors the C++ fixtures (tests/shm/roudi_fixture.hpp, tests/robodiffd/robodiffd_process.hpp):

- RouDi (`iox-roudi -c deploy/roudi.toml`) lives for the rest of the pytest session: an
  iceoryx 2.0 runtime cannot move to another RouDi, and this process's runtime (made by the
  first shm Client) stays until the process exits. It is stopped by PID with SIGKILL (a
  RouDi stopping gracefully hangs when a killed robodiffd left a port's mutex locked) and
  its socket and shared memory are removed. /tmp/robodiff-roudi.lock is held meanwhile,
  because the C++ tests share the machine's one RouDi.
- robodiffd runs on its own temporary cache and config, its own iceoryx service, and DDS
  on loopback in a domain derived from this process's id (outside 1..200, the C++ tests').
  It is stopped by PID: SIGTERM to drain, SIGKILL to simulate a crash.

Every wait has a timeout. $ROBODIFFD overrides build/bin/robodiffd.
"""

from __future__ import annotations

import fcntl
import grp
import json
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import time
from typing import Callable, Iterator, Optional

import pytest

import robodiff

REPO = pathlib.Path(__file__).resolve().parents[2]
ROUDI_CONFIG = REPO / "deploy" / "roudi.toml"
LOOPBACK_DDS = REPO / "deploy" / "cyclonedds-loopback.xml"
LOCK_PATH = pathlib.Path("/tmp/robodiff-roudi.lock")
ROUDI_SOCKET = pathlib.Path("/tmp/roudi")  # iceoryx's IPC_CHANNEL_ROUDI_NAME under /tmp
LOCK_TIMEOUT_S = float(os.environ.get("ROBODIFF_ROUDI_LOCK_TIMEOUT", "120"))

# DDS domains for this test process's server: 201..232 never meets the C++ tests' 1..200;
# the first where no other robodiffd answers is taken, starting from one derived from the pid.
DDS_DOMAINS = [201 + (os.getpid() + k) % 32 for k in range(32)]
SHM_SERVICE = f"robodiff-pytest-{os.getpid()}"


def robodiffd_path() -> pathlib.Path:
    return pathlib.Path(os.environ.get("ROBODIFFD", REPO / "build" / "bin" / "robodiffd"))


def roudi_running() -> bool:
    """True when something answers on RouDi's socket (as shm::roudiRunning() checks)."""
    if not ROUDI_SOCKET.exists():
        return False
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(str(ROUDI_SOCKET))
            return True
        except OSError:
            return False


def stale_iceoryx_runtime() -> bool:
    """True when this process registered with a RouDi that is gone (its management segment
    unlinked): such a runtime cannot be used with a new RouDi, so shm tests cannot run."""
    with open("/proc/self/maps", encoding="utf-8") as maps:
        return any("iceoryx_mgmt" in line and "(deleted)" in line for line in maps)


def _remove_roudi_leftovers() -> None:
    """RouDi's socket and shared memory, once no RouDi answers (a SIGKILL leaves them)."""
    if roudi_running():
        return
    group = grp.getgrgid(os.getgid()).gr_name  # the data segment is named after the group
    for leftover in (ROUDI_SOCKET, pathlib.Path("/dev/shm/iceoryx_mgmt"), pathlib.Path("/dev/shm") / group):
        try:
            leftover.unlink()
        except (FileNotFoundError, PermissionError):
            pass


def _wait_until(condition, timeout: float, step: float = 0.02) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(step)
    return condition()


def _ancestors() -> set[int]:
    """This process and its ancestors' pids."""
    pids, pid = set(), os.getpid()
    while pid > 1 and pid not in pids:
        pids.add(pid)
        try:
            with open(f"/proc/{pid}/stat", encoding="utf-8") as stat:
                pid = int(stat.read().rsplit(")", 1)[1].split()[1])  # the field after the state: ppid
        except (OSError, IndexError, ValueError):
            break
    return pids


def lock_held_by_an_ancestor() -> bool:
    """True when `flock /tmp/robodiff-roudi.lock pytest ...` (or a script above it) holds
    the lock for this run: /proc/locks names the holder's pid and the file's inode."""
    try:
        inode = os.stat(LOCK_PATH).st_ino
        with open("/proc/locks", encoding="utf-8") as locks:
            entries = [line.replace("->", "").split() for line in locks]
    except OSError:
        return False
    ancestors = _ancestors()
    return any(len(e) > 5 and e[1] == "FLOCK" and e[5].rsplit(":", 1)[-1] == str(inode) and int(e[4]) in ancestors
               for e in entries)


class RoudiLock:
    """/tmp/robodiff-roudi.lock (flock), waited for up to `timeout` seconds; taken as held
    when an ancestor process holds it (`flock ... pytest`)."""

    def __init__(self, timeout: float) -> None:
        self._file = open(LOCK_PATH, "a")  # noqa: SIM115 (held until release())
        if lock_held_by_an_ancestor():
            return
        if not _wait_until(self._try_lock, timeout, step=0.1):
            self._file.close()
            raise TimeoutError(f"{LOCK_PATH} stayed locked for {timeout:g} s (other RouDi tests running)")

    def _try_lock(self) -> bool:
        try:
            fcntl.flock(self._file, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            return False

    def release(self) -> None:
        fcntl.flock(self._file, fcntl.LOCK_UN)
        self._file.close()


class RoudiProcess:
    """iox-roudi with the project's pools, started and waited for until it is ready."""

    def __init__(self, log_path: pathlib.Path, timeout: float = 10.0) -> None:
        self.log_path = log_path
        with open(log_path, "wb") as log:
            self.process = subprocess.Popen(["iox-roudi", "-c", str(ROUDI_CONFIG)], stdout=log,
                                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        ready = _wait_until(lambda: self.process.poll() is not None
                            or ("RouDi is ready for clients" in self.log() and roudi_running()), timeout)
        if self.process.poll() is not None or not ready:
            self.stop()
            raise RuntimeError(f"iox-roudi did not become ready within {timeout:g} s; its log:\n{self.log()}")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait(timeout=10)
        _remove_roudi_leftovers()


def free_dds_domain() -> int:
    """The first of DDS_DOMAINS where no robodiffd answers within 0.3 s (another test's
    server there would answer our clients). Needs CYCLONEDDS_URI set first."""
    for domain in DDS_DOMAINS:
        try:
            robodiff.Client(f"dds:{domain}", timeout=0.3)
        except robodiff.Error:
            return domain
    raise RuntimeError(f"a robodiffd answers in every DDS domain {DDS_DOMAINS[0]}..{DDS_DOMAINS[-1]}")


def write_robodiffd_config(path: pathlib.Path, cache_dir: pathlib.Path, dds_domain: int) -> None:
    """A config of the test's own: its cache, service and domain, the external RouDi, no HTTP
    (no port to clash over), one build worker (two cores)."""
    path.write_text(
        "[build]\nworkers = 1\n"
        f"[cache]\ndir = {json.dumps(str(cache_dir))}\n"
        f'[iceoryx]\nservice = "{SHM_SERVICE}"\nroudi = "external"\n'
        f"[dds]\ndomain = {dds_domain}\n"
        "[http]\nenabled = false\n"
        '[log]\nformat = "json"\n')


class RobodiffdProcess:
    """robodiffd on a config file, started (and restarted) on demand, stopped by PID."""

    def __init__(self, config_path: pathlib.Path, log_dir: pathlib.Path, dds_domain: int) -> None:
        self.config_path = config_path
        self.dds_domain = dds_domain
        self.log_dir = log_dir
        self.process: Optional[subprocess.Popen] = None
        self.starts = 0

    @property
    def log_path(self) -> pathlib.Path:
        return self.log_dir / f"robodiffd-{self.starts}.log"

    def log(self) -> str:
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def events(self) -> list[dict]:
        """The current run's log lines (--log-format json), parsed; unparsable lines left out."""
        parsed = []
        for line in self.log().splitlines():
            try:
                parsed.append(json.loads(line))
            except ValueError:
                pass
        return parsed

    def wait_for_event(self, predicate: Callable[[dict], bool], timeout: float) -> Optional[dict]:
        """The first logged event of the current run that `predicate` accepts, waited for up
        to `timeout` s; None if none came."""
        found: list[dict] = []

        def seen() -> bool:
            found[:] = [event for event in self.events() if predicate(event)][:1]
            return bool(found)

        return found[0] if _wait_until(seen, timeout, step=0.05) else None

    def address(self, mode: str) -> str:
        """The Client server string reaching this robodiffd over `mode` ("shm" or "dds")."""
        return {"shm": f"shm:{SHM_SERVICE}", "dds": f"dds:{self.dds_domain}"}[mode]

    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def start(self, timeout: float = 30.0) -> None:
        """Starts robodiffd and waits until it logs "serving"; raises naming its log if not."""
        self.starts += 1
        environment = dict(os.environ, CYCLONEDDS_URI=f"file://{LOOPBACK_DDS}")
        with open(self.log_path, "wb") as log:
            self.process = subprocess.Popen([str(robodiffd_path()), "--config", str(self.config_path)],
                                            stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                            env=environment)
        serving = _wait_until(lambda: not self.running() or '"event":"serving"' in self.log(), timeout)
        if not self.running() or not serving:
            self.kill(settle=0)
            raise RuntimeError(f"robodiffd did not serve within {timeout:g} s; its log:\n{self.log()}")

    def kill(self, settle: float = 0.1) -> None:
        """SIGKILL (a crash), after `settle` s so that it finds robodiffd idle: killed inside
        an iceoryx send it would leave a port's mutex locked and RouDi hung (iceoryx 2.0)."""
        if not self.running():
            return
        time.sleep(settle)
        self.process.send_signal(signal.SIGKILL)
        self.process.wait(timeout=10)

    def terminate(self, timeout: float = 30.0) -> None:
        """SIGTERM (drain and exit), SIGKILL if it is still there after `timeout` s."""
        if not self.running():
            return
        self.process.send_signal(signal.SIGTERM)
        try:
            self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill(settle=0)


@pytest.fixture(scope="session")
def roudi(tmp_path_factory) -> Iterator[None]:
    """A RouDi for the rest of the session (ours, or one already running), the lock held."""
    if shutil.which("iox-roudi") is None:
        pytest.skip("iox-roudi is not installed (deploy/install-deps.sh installs iceoryx)")
    if not robodiffd_path().exists():
        pytest.skip(f"{robodiffd_path()} is not built (cmake --build build --target robodiffd)")
    try:
        lock = RoudiLock(LOCK_TIMEOUT_S)
    except TimeoutError as error:
        pytest.skip(str(error))
    try:
        if stale_iceoryx_runtime():
            pytest.skip("this pytest process registered with a RouDi that has gone since; run these tests alone")
        ours = None if roudi_running() else RoudiProcess(tmp_path_factory.mktemp("roudi") / "roudi.log")
        try:
            yield
        finally:
            if ours is not None:
                ours.stop()
    finally:
        lock.release()


@pytest.fixture(scope="module")
def loopback_dds() -> Iterator[None]:
    """CYCLONEDDS_URI at the loopback configuration for the DDS clients made meanwhile."""
    before = os.environ.get("CYCLONEDDS_URI")
    os.environ["CYCLONEDDS_URI"] = f"file://{LOOPBACK_DDS}"
    yield
    if before is None:
        os.environ.pop("CYCLONEDDS_URI", None)
    else:
        os.environ["CYCLONEDDS_URI"] = before


@pytest.fixture(scope="module")
def robodiffd(roudi, loopback_dds, tmp_path_factory) -> Iterator[RobodiffdProcess]:
    """A running robodiffd on a fresh cache (tests may kill and restart it: it is running
    again after each test that does); SIGTERM at the end of the module."""
    directory = tmp_path_factory.mktemp("robodiffd")
    config = directory / "robodiffd.conf"
    domain = free_dds_domain()
    write_robodiffd_config(config, directory / "cache", domain)
    server = RobodiffdProcess(config, directory, domain)
    server.start()
    try:
        yield server
    finally:
        server.terminate()

