"""``rostools doctor``: what is wrong with this host's view of the ROS graph, one check a line.

roswtf looks at a graph from the inside; most failures across machines come from addresses,
so these checks ask the network: can the master be reached, does the name this host gives
out work, does every node answer from here, is sim time running, do the clocks agree.
Blocking calls, each bounded by ``timeout``; nodes are asked in parallel.
"""

from __future__ import annotations

import email.utils
import os
import socket
import time
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from typing import Any

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError
from rostools.rosgraph.masterapi import MasterError, XmlRpcNode, ros_value
from rostools.rosgraph.network import (
    Failure,
    explain,
    host_name,
    is_loopback,
    local_addresses,
    uri_host,
)

#: How far apart two clocks may be before we say so (s); HTTP dates have 1 s resolution.
MAX_SKEW = 1.0
#: Nodes asked at once.
WORKERS = 16


class _NotRosError(RostoolsError):
    """The server answered, but not as a ROS master does: a fault, or no XML-RPC answer."""


@dataclass
class Check:
    """One check: ``ok``, ``fail`` or ``skip``, a one-line verdict, and a hint when it failed."""

    name: str
    status: str
    verdict: str
    hint: str = ""
    #: The exit code this failure stands for (0 unless ``status`` is ``fail``).
    exit_code: int = 0
    details: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """For ``--format json``."""
        return asdict(self)


@dataclass
class Answer:
    """An XML-RPC answer and what the HTTP exchange tells about the peer's clock."""

    value: Any
    #: Peer clock minus ours at the answer (s); None without a ``Date`` header.
    skew: float | None


def ask(uri: str, method: str, params: tuple[Any, ...], timeout: float) -> Answer:
    """One XML-RPC call on a fresh connection, reading the ``Date`` header too.

    Through the one client (``masterapi.XmlRpcNode``): its failures are its errors, raised
    from the transport's (``_failure`` reads both).
    """
    caller, *args = params
    client = XmlRpcNode(uri, str(caller), timeout, "node")
    try:
        sent = time.time()
        value, message = client.answered(method, *args)
        received = time.time()
    finally:
        client.http.close()
    date = message.headers.get("date")
    skew = None
    if date:
        with_tz = email.utils.parsedate_to_datetime(date)
        skew = with_tz.timestamp() + 0.5 - (sent + received) / 2  # the date is truncated to 1 s
    return Answer(value, skew)


def _failure(err: BaseException, host: str, peer: bool = True) -> Failure:
    """Why a call to ``host`` failed, from the client's error and the transport's under it."""
    cause = err.__cause__
    if isinstance(err, UnreachableError | TimeoutExpired) and cause is not None:
        return explain(cause, host, peer)
    if isinstance(err, RostoolsError) and cause is not None:  # a fault, a bad answer
        return Failure(f"it does not speak the ROS XML-RPC API ({type(cause).__name__})")
    if isinstance(err, RostoolsError):  # no call was made: the URI is not one
        return Failure(str(err))
    return explain(err, host, peer)


def _resolve(name: str) -> list[str]:
    infos = socket.getaddrinfo(name, None, socket.AF_INET, socket.SOCK_STREAM)
    return list(dict.fromkeys(str(info[4][0]) for info in infos))


def _route_to(address: str) -> str | None:
    """Our address on the way to ``address``: what a peer there sees us as."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect((address, 9))  # UDP: nothing is sent
        except OSError:
            return None
        local: str = probe.getsockname()[0]
        return local


class Doctor:
    """Runs the checks against ``master_uri`` from this host."""

    def __init__(
        self, master_uri: str, timeout: float = 2.0, env: Mapping[str, str] | None = None
    ) -> None:
        self.master_uri = master_uri
        self.timeout = timeout
        self.env = os.environ if env is None else env
        self.caller = f"/rostools_doctor_{os.getpid()}"
        self.master_addresses: list[str] = []
        self.skews: dict[str, float] = {}
        self.mine = set(local_addresses())

    @property
    def master_remote(self) -> bool:
        """Whether the master is on another host."""
        return bool(self.master_addresses) and not any(
            is_loopback(a) or a in self.mine for a in self.master_addresses
        )

    def run(self) -> list[Check]:
        """Every check, in order; a check that needs the master is skipped without one."""
        master = self.check_master()
        checks = [master, self.check_host()]
        if master.status == "ok":
            checks += [self.check_nodes(), self.check_sim_time()]
        else:
            checks += [Check(n, "skip", "needs the master") for n in ("nodes", "sim time")]
        checks.append(self.check_clock())
        return checks

    # the master ------------------------------------------------------------------------

    def check_master(self) -> Check:
        """The master answers at ``master_uri``, and the URI it gives out reaches it too."""
        uri, host = self.master_uri, uri_host(self.master_uri)
        try:
            self.master_addresses = _resolve(host)
            pid = self._master("getPid", uri)
            given = self._master("getUri", uri)
        except (OSError, UnreachableError, TimeoutExpired, _NotRosError) as err:
            failure = _failure(err, host, peer=False)
            reason, hint = failure.reason, failure.hint
            cause = err.__cause__ or err
            if isinstance(cause, ConnectionRefusedError):
                hint = (
                    "is a master running there, listening beyond loopback? ('rostools core' "
                    "listens on loopback unless given --host or ROS_IP)"
                )
            elif isinstance(cause, socket.gaierror):
                hint = "use the master's address in ROS_MASTER_URI, or add its name to /etc/hosts"
            code = 5 if isinstance(err, TimeoutExpired) else 4
            return Check(
                "master", "fail", f"cannot reach the master at {uri}: {reason}", hint, code
            )
        details = {"uri": uri, "pid": pid, "gives_out": given}
        if str(given).rstrip("/") == uri.rstrip("/"):
            return Check("master", "ok", f"{uri} answers (pid {pid})", details=details)
        try:
            same = self._master("getPid", str(given)) == pid
            reason = "" if same else "another process answers there"
        except (OSError, UnreachableError, TimeoutExpired, _NotRosError) as err:
            same, reason = False, _failure(err, uri_host(str(given)), peer=False).reason
        if same:
            verdict = f"{uri} answers (pid {pid}); it gives out {given}, which reaches it too"
            return Check("master", "ok", verdict, details=details)
        return Check(
            "master",
            "fail",
            f"{uri} answers (pid {pid}), but the URI it gives out, {given}, does not reach it "
            f"from here: {reason}",
            "set ROS_IP or ROS_HOSTNAME on the master's host to an address every host reaches",
            4,
            details,
        )

    def _master(self, method: str, uri: str, *args: Any) -> Any:
        try:
            answer = ask(uri, method, (self.caller, *args), self.timeout)
        except RostoolsError as err:
            if isinstance(err, UnreachableError | TimeoutExpired) or err.__cause__ is None:
                raise
            raise _NotRosError(str(err)) from err.__cause__  # a fault or a bad answer
        if answer.skew is not None and uri == self.master_uri:
            self.skews["the master"] = answer.skew
        try:
            return ros_value(answer.value, method, "master", args)
        except (MasterError, NotFoundError):
            raise  # a failure code: the master said no
        except RostoolsError as err:  # not a [code, message, value] triple
            raise _NotRosError(str(err)) from err

    # this host -------------------------------------------------------------------------

    def check_host(self) -> Check:
        """The name our nodes give out resolves, to us, and not to loopback for a remote master."""
        try:
            name = host_name(self.env)
        except RostoolsError as err:
            return Check("this host", "fail", str(err), "fix ROS_IP or ROS_HOSTNAME", 2)
        route = _route_to(self.master_addresses[0]) if self.master_addresses else None
        fix = f"set ROS_IP={route}" if route else "set ROS_IP to this host's address"
        try:
            addresses = _resolve(name)
        except OSError:
            return Check(
                "this host",
                "fail",
                f"this host gives out '{name}', which does not resolve here, so others cannot "
                "resolve it either",
                fix,
                1,
            )
        details = {"name": name, "addresses": addresses, "route_to_master": route}
        if self.master_remote and all(is_loopback(a) for a in addresses):
            return Check(
                "this host",
                "fail",
                f"this host gives out '{name}', which resolves here to {addresses[0]}, a loopback "
                "address, while the master is on another host",
                fix,
                1,
                details,
            )
        if not any(a in self.mine or is_loopback(a) for a in addresses):
            return Check(
                "this host",
                "fail",
                f"this host gives out '{name}', which resolves to {', '.join(addresses)}, not "
                "an address of this host",
                fix,
                1,
                details,
            )
        verdict = f"this host gives out '{name}' ({', '.join(addresses)})"
        if self.master_remote:
            verdict += "; other hosts must resolve it too"
        return Check("this host", "ok", verdict, details=details)

    # the nodes -------------------------------------------------------------------------

    def check_nodes(self) -> Check:
        """Every registered node's URI resolves and answers from here."""
        pubs, subs, srvs = self._master("getSystemState", self.master_uri)
        names = sorted({n for entries in (pubs, subs, srvs) for _, ns in entries for n in ns})
        uris: dict[str, str] = {}
        for name in names:
            try:
                uris[name] = str(self._master("lookupNode", self.master_uri, name))
            except RostoolsError:
                continue  # gone since getSystemState
        with ThreadPoolExecutor(WORKERS) as pool:
            results = dict(zip(uris, pool.map(self._probe_node, uris.values()), strict=True))
        bad = {n: (uris[n], why) for n, why in results.items() if why is not None}
        details = {"nodes": len(uris), "unreachable": {n: u for n, (u, _) in bad.items()}}
        if not bad:
            every = "the one node answers" if len(uris) == 1 else f"all {len(uris)} nodes answer"
            return Check("nodes", "ok", f"{every} from here", details=details)
        listed = ", ".join(f"{n} at {u} ({why})" for n, (u, why) in sorted(bad.items()))
        return Check(
            "nodes",
            "fail",
            f"{len(bad)} of {len(uris)} nodes cannot be reached from here: {listed}",
            "set ROS_IP or ROS_HOSTNAME on their hosts; 'rostools node cleanup' purges nodes "
            "that died",
            4,
            details,
        )

    def _probe_node(self, uri: str) -> str | None:
        """Why the node at ``uri`` cannot be reached from here, or None when it answers."""
        host = uri_host(uri)
        if self.master_remote and is_loopback(host):
            return "a loopback address, on a host other than the master's"
        try:
            answer = ask(uri, "getPid", (self.caller,), self.timeout)
        except Exception as err:  # noqa: BLE001 - any failure is the verdict
            return _failure(err, host).reason
        if answer.skew is not None:
            self.skews[uri] = answer.skew
        return None

    # time ------------------------------------------------------------------------------

    def check_sim_time(self) -> Check:
        """``/use_sim_time`` set means someone must publish ``/clock``."""
        try:
            sim = self._master("getParam", self.master_uri, "/use_sim_time")
        except RostoolsError:
            return Check("sim time", "ok", "/use_sim_time is not set: wall-clock time")
        if not sim:
            return Check("sim time", "ok", "/use_sim_time is false: wall-clock time")
        pubs, _, _ = self._master("getSystemState", self.master_uri)
        clock: list[str] = next((ns for t, ns in pubs if t == "/clock"), [])
        if clock:
            return Check("sim time", "ok", f"/use_sim_time is true; {', '.join(clock)} "
                         "publish /clock")  # fmt: skip
        return Check(
            "sim time",
            "fail",
            "/use_sim_time is true but nothing publishes /clock: ROS time stands still",
            "start the clock source (a simulator, 'bag play --clock'), or set /use_sim_time false",
            1,
        )

    def check_clock(self) -> Check:
        """Peers whose HTTP ``Date`` is more than ``MAX_SKEW`` from our clock."""
        if not self.skews:
            return Check("clock", "skip", "no peer sends an HTTP Date header to compare clocks")
        details = {"skew_s": {k: round(v, 3) for k, v in self.skews.items()}}
        off = {k: v for k, v in self.skews.items() if abs(v) > MAX_SKEW + 0.5}
        if not off:
            verdict = f"{len(self.skews)} peers' clocks agree with ours within {MAX_SKEW:g} s"
            return Check("clock", "ok", verdict, details=details)
        listed = ", ".join(f"{k} by {v:+.0f} s" for k, v in sorted(off.items()))
        return Check(
            "clock",
            "fail",
            f"clocks differ from ours: {listed}",
            "synchronise the clocks (chrony or ntpd on every host)",
            1,
            details,
        )
