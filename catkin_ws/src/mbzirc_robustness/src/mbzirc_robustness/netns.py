"""Hosts as Linux network namespaces: one ground station and one per robot, joined by a private bridge.

Why: on the real system every UAV is its own computer on a Wi-Fi link that drops. To test that in CI we
give each robot its own network stack and address (``ip netns``), wire them to a bridge that lives in
its own "switch" namespace (so nothing touches the caller's network, and parallel labs never clash),
run each robot's nodes inside its namespace with ``ROS_MASTER_URI`` / ``ROS_IP``, and cut a robot's link
by taking its switch port off the bridge.

Layout of a lab owned by process <pid> (names ``<prefix>-<pid>-<host>``)::

    <prefix>-<pid>-sw:   br0  +-- p1 ==veth== eth0 in <prefix>-<pid>-gs      10.77.0.1/24  (master)
                              +-- p2 ==veth== eth0 in <prefix>-<pid>-uav1    10.77.0.2/24
                              +-- ...

A cut takes the robot's port off the bridge (``nomaster``): packets vanish without any local error, as on
a faded Wi-Fi link. Everything is removed by ``close()`` (also on SIGTERM/SIGINT and at exit);
``cleanup_stale()`` removes labs whose owner process died without cleaning up (e.g. SIGKILL).
"""
from __future__ import annotations

import atexit
import os
import re
import signal
import subprocess
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Sequence

from mbzirc_robustness import constants as C

Runner = Callable[[Sequence[str]], subprocess.CompletedProcess]


def run_cmd(argv: Sequence[str]) -> subprocess.CompletedProcess:
    """Run one ip command; raise with its stderr when it fails (a half-built lab must not go unnoticed)."""
    res = subprocess.run(list(argv), capture_output=True, text=True, timeout=20)
    if res.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed: {res.stderr.strip()}")
    return res


@dataclass
class Host:
    """One simulated computer: its namespace, its address and the switch port it hangs from."""

    name: str
    ns: str
    ip: str
    port: str
    index: int
    procs: list[subprocess.Popen] = field(default_factory=list)
    link_up: bool = True


def host_commands(sw: str, host: Host, subnet: str = C.SUBNET) -> list[list[str]]:
    """The ip commands that create ``host`` and plug it into the bridge of switch namespace ``sw``."""
    return [
        ["ip", "netns", "add", host.ns],
        ["ip", "-n", host.ns, "link", "set", "lo", "up"],
        ["ip", "-n", sw, "link", "add", host.port, "type", "veth", "peer", "name", "eth0", "netns", host.ns],
        ["ip", "-n", sw, "link", "set", host.port, "master", "br0"],
        ["ip", "-n", sw, "link", "set", host.port, "up"],
        ["ip", "-n", host.ns, "addr", "add", f"{host.ip}/24", "dev", "eth0"],
        ["ip", "-n", host.ns, "link", "set", "eth0", "up"],
    ]


def switch_commands(sw: str) -> list[list[str]]:
    """The ip commands that create the switch namespace and its bridge."""
    return [
        ["ip", "netns", "add", sw],
        ["ip", "-n", sw, "link", "set", "lo", "up"],
        ["ip", "-n", sw, "link", "add", "br0", "type", "bridge"],
        ["ip", "-n", sw, "link", "set", "br0", "up"],
    ]


def link_commands(sw: str, host: Host, up: bool) -> list[list[str]]:
    """Cut (``up=False``) or restore the link of ``host`` by taking its port off the bridge / back on.

    .. note:: the port stays up and the host keeps its carrier, so packets are lost far away, as on a
       Wi-Fi link that fades: TCP backs off exponentially. Setting the port down instead makes the
       host's own sends fail locally, which TCP retries almost at once (too kind a test).
    """
    if up:
        return [["ip", "-n", sw, "link", "set", host.port, "master", "br0"]]
    return [["ip", "-n", sw, "link", "set", host.port, "nomaster"]]


def ros_env(master_ip: str, host_ip: str, base: dict[str, str] | None = None,
            port: int = C.MASTER_PORT) -> dict[str, str]:
    """Environment of a ROS process on a host: master on the ground station, our own address as ROS_IP.

    .. note:: ROS_HOSTNAME wins over ROS_IP, and env.sh sets it to localhost, so it is removed here.
    """
    env = dict(os.environ if base is None else base)
    env.pop("ROS_HOSTNAME", None)
    env["ROS_MASTER_URI"] = f"http://{master_ip}:{port}"
    env["ROS_IP"] = host_ip
    return env


def lab_namespaces(names: Sequence[str], prefix: str = C.NETNS_PREFIX) -> dict[int, list[str]]:
    """Namespaces of labs, grouped by owner pid, from the names ``ip netns list`` prints."""
    out: dict[int, list[str]] = {}
    pat = re.compile(rf"^{re.escape(prefix)}-(\d+)-\S+")
    for line in names:
        name = line.split()[0] if line.split() else ""
        m = pat.match(name)
        if m:
            out.setdefault(int(m.group(1)), []).append(name)
    return out


def pid_alive(pid: int) -> bool:
    """True when process ``pid`` exists."""
    try:
        os.kill(pid, 0)
        return True
    except ProcessLookupError:
        return False
    except PermissionError:
        return True


def _kill_ns_pids(ns: str) -> None:
    """SIGKILL every process still running in namespace ``ns``."""
    res = subprocess.run(["ip", "netns", "pids", ns], capture_output=True, text=True, timeout=10)
    for tok in res.stdout.split():
        try:
            if int(tok) == os.getpid():
                continue  # the fault suite itself lives in the ground-station namespace
            os.kill(int(tok), signal.SIGKILL)
        except (ValueError, ProcessLookupError, PermissionError):
            pass


def delete_namespace(ns: str) -> None:
    """Kill whatever runs in ``ns`` and delete it (its veth ends go with it); never raises."""
    try:
        _kill_ns_pids(ns)
        subprocess.run(["ip", "netns", "del", ns], capture_output=True, timeout=10)
    except Exception:  # noqa: BLE001 - cleanup must go on with the other namespaces
        pass


def cleanup_stale(prefix: str = C.NETNS_PREFIX, include_alive: bool = False) -> list[str]:
    """Delete the namespaces of labs whose owner process is gone; returns the names deleted."""
    res = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, timeout=10)
    removed = []
    for pid, names in lab_namespaces(res.stdout.splitlines(), prefix).items():
        if include_alive or not pid_alive(pid):
            # hosts first, the switch last
            for ns in sorted(names, key=lambda n: n.endswith("-sw")):
                delete_namespace(ns)
                removed.append(ns)
    return removed


class NetnsLab:
    """A set of hosts (network namespaces) on one private bridge; a context manager that always cleans up.

    Args:
        prefix: namespace name prefix (a lab is ``<prefix>-<pid>-*``).
        subnet: first two octets of the /24 addresses (hosts get ``<subnet>.0.<n>``).
        runner: runs one command (tests pass a recorder); the default raises on failure.

    .. note:: creating namespaces needs root (CAP_SYS_ADMIN + CAP_NET_ADMIN). Processes started with
       ``popen`` get their own session, so ``close()`` can end them and their children by process group.
    """

    def __init__(self, prefix: str = C.NETNS_PREFIX, subnet: str = C.SUBNET, runner: Runner = run_cmd) -> None:
        self.prefix = prefix
        self.lab = f"{prefix}-{os.getpid()}"
        self.sw = f"{self.lab}-sw"
        self.subnet = subnet
        self.run = runner
        self.hosts: dict[str, Host] = {}
        self._created: list[str] = []
        self._timers: list[threading.Timer] = []
        self._closed = False
        self._lock = threading.Lock()

    # ---- building -------------------------------------------------------------------------------
    def start(self) -> "NetnsLab":
        """Create the switch; removes stale labs of dead owners first."""
        if self.run is run_cmd:
            cleanup_stale(self.prefix)
            atexit.register(self.close)
        self._created.append(self.sw)
        for cmd in switch_commands(self.sw):
            self.run(cmd)
        return self

    def add_host(self, name: str) -> Host:
        """Create host ``name`` with the next address (the first host gets ``.1``)."""
        idx = len(self.hosts) + 1
        host = Host(name=name, ns=f"{self.lab}-{name}", ip=f"{self.subnet}.0.{idx}", port=f"p{idx}", index=idx)
        self._created.append(host.ns)
        self.hosts[name] = host
        for cmd in host_commands(self.sw, host, self.subnet):
            self.run(cmd)
        return host

    def __enter__(self) -> "NetnsLab":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- link faults ---------------------------------------------------------------------------
    def set_link(self, name: str, up: bool) -> None:
        """Cut or restore the network link of host ``name``."""
        host = self.hosts[name]
        with self._lock:
            if self._closed:
                return
            for cmd in link_commands(self.sw, host, up):
                self.run(cmd)
            host.link_up = up

    def cut(self, name: str, seconds: float | None = None) -> threading.Timer | None:
        """Cut the link of ``name``; restore it after ``seconds`` (None: for good). Returns the timer."""
        self.set_link(name, False)
        if seconds is None:
            return None
        timer = threading.Timer(seconds, self.set_link, args=(name, True))
        timer.daemon = True
        self._timers.append(timer)
        timer.start()
        return timer

    # ---- processes -----------------------------------------------------------------------------
    def env_for(self, name: str, master: str = C.GROUND_STATION, base: dict[str, str] | None = None) -> dict[str, str]:
        """ROS environment of a process on host ``name`` whose master runs on host ``master``."""
        return ros_env(self.hosts[master].ip, self.hosts[name].ip, base)

    def popen(self, name: str, argv: Sequence[str], env: dict[str, str] | None = None,
              log_path: str | None = None) -> subprocess.Popen:
        """Start ``argv`` inside host ``name`` (own session; output to ``log_path`` or discarded)."""
        host = self.hosts[name]
        out = open(log_path, "ab") if log_path else subprocess.DEVNULL  # noqa: SIM115 - owned by the process
        proc = subprocess.Popen(["ip", "netns", "exec", host.ns, *argv], env=env or self.env_for(name),
                                stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                start_new_session=True)
        if log_path:
            out.close()
        host.procs.append(proc)
        return proc

    def exec(self, name: str, argv: Sequence[str], env: dict[str, str] | None = None,
             timeout: float = 30.0) -> subprocess.CompletedProcess:
        """Run ``argv`` in host ``name`` to completion; returns its result (does not raise)."""
        return subprocess.run(["ip", "netns", "exec", self.hosts[name].ns, *argv],
                              env=env or self.env_for(name), capture_output=True, text=True, timeout=timeout)

    @staticmethod
    def stop(proc: subprocess.Popen, grace: float = 5.0) -> None:
        """SIGINT the process group (roslaunch shuts its nodes down), then SIGKILL after ``grace`` s."""
        if proc.poll() is not None:
            return
        for sig, wait in ((signal.SIGINT, grace), (signal.SIGKILL, 2.0)):
            try:
                os.killpg(proc.pid, sig)
            except (ProcessLookupError, PermissionError):
                return
            try:
                proc.wait(wait)
                return
            except subprocess.TimeoutExpired:
                continue

    # ---- cleanup -------------------------------------------------------------------------------
    def close(self) -> None:
        """Stop every process, delete every namespace of this lab. Idempotent; never raises."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        for t in self._timers:
            t.cancel()
        for host in reversed(list(self.hosts.values())):
            for proc in reversed(host.procs):
                try:
                    self.stop(proc)
                except Exception:  # noqa: BLE001
                    pass
        if self.run is not run_cmd:  # dry run: record the deletions only
            for ns in reversed(self._created):
                self.run(["ip", "netns", "del", ns])
            return
        for ns in reversed(self._created):
            delete_namespace(ns)


def install_signal_cleanup(lab: NetnsLab) -> None:
    """On SIGTERM / SIGHUP (e.g. ``timeout`` or rostest's time-limit), clean up and exit.

    SIGINT keeps raising KeyboardInterrupt so ``with NetnsLab()`` blocks unwind normally.
    """
    def handler(signum, _frame):
        lab.close()
        raise SystemExit(128 + signum)

    for sig in (signal.SIGTERM, signal.SIGHUP):
        try:
            signal.signal(sig, handler)
        except ValueError:  # not the main thread
            pass


def wait_tcp(lab: NetnsLab, name: str, ip: str, port: int, timeout: float = 20.0) -> bool:
    """Wait until host ``name`` can open a TCP connection to ``ip:port`` (e.g. the master)."""
    code = ("import socket,sys\ns=socket.socket();s.settimeout(1.0)\n"
            f"sys.exit(0 if s.connect_ex(({ip!r},{port}))==0 else 1)")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if lab.exec(name, ["/usr/bin/python3", "-c", code], timeout=5).returncode == 0:
            return True
        time.sleep(0.3)
    return False
