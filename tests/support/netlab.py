"""Several hosts on one machine, for tests that cross a network: Linux network namespaces.

Each host is a namespace with its own address in a private test range that exists only in
these namespaces, joined to the others by a bridge that lives in a namespace of its own. Each
has its own host name (a UTS namespace per process) and its own ``/etc/hosts`` (``ip netns
exec`` mounts ``/etc/netns/NS/hosts`` over it), so name resolution can be made right or
wrong per host. Nothing touches the machine's own network: no interface, address or route
outside the namespaces this module makes, and ``close`` deletes all of them.

Needs root and ``ip netns`` (iproute2); ``missing()`` says why not, for a skip.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from tests.support.procs import Proc

#: The test range: 10.223.0.0/24, inside the namespaces only.
SUBNET = "10.223.0"
NETNS_ETC = Path("/etc/netns")
_PREFIX = "rtlab"


def missing() -> str | None:
    """Why namespaces cannot be made here, or None when they can."""
    if os.geteuid() != 0:
        return "the multi-host tests need root (ip netns)"
    for tool in ("ip", "unshare"):
        if shutil.which(tool) is None:
            return f"the multi-host tests need '{tool}' (iproute2, util-linux)"
    probe = f"{_PREFIX}probe{os.getpid()}"
    made = subprocess.run(["ip", "netns", "add", probe], capture_output=True, check=False)
    if made.returncode != 0:
        return f"cannot make a network namespace: {made.stderr.decode().strip()}"
    subprocess.run(["ip", "netns", "delete", probe], capture_output=True, check=False)
    return None


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True)


def remove_stale() -> None:
    """Delete the namespaces of earlier runs whose process is gone (a run killed outright)."""
    listing = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True, check=False)
    for line in listing.stdout.splitlines():
        name = line.split()[0] if line.split() else ""
        found = re.fullmatch(rf"{_PREFIX}(\d+)[a-z]+", name)
        if found and not Path(f"/proc/{found.group(1)}").exists():
            subprocess.run(["ip", "netns", "delete", name], capture_output=True, check=False)
            shutil.rmtree(NETNS_ETC / name, ignore_errors=True)


class Host:
    """One host: its namespace, host name and address."""

    def __init__(self, lab: Lab, name: str, index: int) -> None:
        self.lab = lab
        self.name = name
        self.ns = f"{_PREFIX}{os.getpid()}{name}"
        self.address = f"{SUBNET}.{index}"

    def set_hosts(self, entries: dict[str, str]) -> None:
        """This host's ``/etc/hosts``: name -> address, after localhost."""
        lines = ["127.0.0.1 localhost"] + [f"{addr} {name}" for name, addr in entries.items()]
        path = NETNS_ETC / self.ns / "hosts"
        # rewritten in place: a bind mount of it in a running process sees the new text
        with path.open("w") as out:
            out.write("\n".join(lines) + "\n")

    def argv(self, argv: Sequence[str]) -> list[str]:
        """``argv`` run on this host: in its namespace, under its host name."""
        shell = 'hostname "$1" && shift && exec "$@"'
        return ["ip", "netns", "exec", self.ns, "unshare", "--uts", "--", "sh", "-c", shell,
                "sh", self.name, *argv]  # fmt: skip

    def start(self, argv: Sequence[str], env: dict[str, str]) -> Proc:
        """A process on this host, stopped by ``Lab.close`` if the test has not."""
        proc = Proc(self.argv(argv), env=env)
        self.lab.procs.append(proc)
        return proc

    def run(
        self,
        argv: Sequence[str],
        env: dict[str, str],
        timeout: float = 60,
        stdin: str = "",
    ) -> subprocess.CompletedProcess[str]:
        """Run ``argv`` on this host to the end; its output."""
        return subprocess.run(
            self.argv(argv), env=env, capture_output=True, text=True, timeout=timeout,
            input=stdin, check=False,
        )  # fmt: skip

    def rostools(
        self, *args: str, env: dict[str, str], timeout: float = 60
    ) -> subprocess.CompletedProcess[str]:
        """``rostools ARGS`` on this host."""
        return self.run([sys.executable, "-m", "rostools", *args], env, timeout)


class Lab:
    """Hosts on one bridge: ``with Lab(["robot", "hostb"]) as lab: lab["hostb"].run(...)``.

    By default every host's ``/etc/hosts`` names every host; ``Host.set_hosts`` changes that.
    """

    def __init__(self, names: Sequence[str]) -> None:
        self.hosts = {name: Host(self, name, i + 1) for i, name in enumerate(names)}
        self.bridge = f"{_PREFIX}{os.getpid()}br"
        self.procs: list[Proc] = []
        self.made: list[str] = []
        self.made_etc = False

    def __getitem__(self, name: str) -> Host:
        return self.hosts[name]

    def start(self) -> Lab:
        """Make the namespaces, the bridge and the links; fill the hosts files."""
        remove_stale()
        self.made_etc = not NETNS_ETC.exists()
        try:
            self._add(self.bridge)
            _ip("-n", self.bridge, "link", "add", "br0", "type", "bridge")
            _ip("-n", self.bridge, "link", "set", "br0", "up")
            for i, host in enumerate(self.hosts.values()):
                self._add(host.ns)
                port = f"port{i}"
                _ip("-n", self.bridge, "link", "add", port, "type", "veth",
                    "peer", "name", "eth0", "netns", host.ns)  # fmt: skip
                _ip("-n", self.bridge, "link", "set", port, "master", "br0")
                _ip("-n", self.bridge, "link", "set", port, "up")
                _ip("-n", host.ns, "addr", "add", f"{host.address}/24", "dev", "eth0")
                _ip("-n", host.ns, "link", "set", "eth0", "up")
                _ip("-n", host.ns, "link", "set", "lo", "up")
                (NETNS_ETC / host.ns).mkdir(parents=True, exist_ok=True)
            everyone = {h.name: h.address for h in self.hosts.values()}
            for host in self.hosts.values():
                host.set_hosts(everyone)
        except BaseException:
            self.close()
            raise
        return self

    def _add(self, ns: str) -> None:
        _ip("netns", "add", ns)
        self.made.append(ns)

    def close(self) -> None:
        """Stop every process started here, by PID, then delete every namespace made."""
        for proc in self.procs:
            with contextlib.suppress(Exception):
                proc.stop(timeout=3)
        self.procs.clear()
        for ns in reversed(self.made):
            subprocess.run(["ip", "netns", "delete", ns], capture_output=True, check=False)
            shutil.rmtree(NETNS_ETC / ns, ignore_errors=True)
        self.made.clear()
        if self.made_etc:
            with contextlib.suppress(OSError):
                NETNS_ETC.rmdir()  # only when empty: another run may be using it

    def __enter__(self) -> Lab:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()
