"""The real rosmaster takes names with line breaks too, and our commands escape them.

rosmaster checks a name for ``:`` and spaces only (``rosmaster.validators``), as ours does,
so a peer's newline or U+2028 reaches every tool through either master.
"""

from __future__ import annotations

import json
import xmlrpc.client

from tests.conftest import MasterInfo
from tests.support.env import run_cli
from tests.support.hostilenames import NODE, PARAM, SERVICE, TOPIC, TYPE, cli, register, shown


def test_both_masters_take_hostile_names_and_we_print_them_escaped(
    any_master: MasterInfo,
) -> None:
    dead = register(any_master.uri)
    with xmlrpc.client.ServerProxy(any_master.uri) as master:
        pubs, subs, services = master.getSystemState("/probe")[2]
        assert [TOPIC, [NODE]] in pubs and [TOPIC, ["/legal"]] in subs
        assert [SERVICE, ["/legal"]] in services
        assert master.lookupNode("/probe", NODE)[2] == dead
    env = any_master.cli_env
    out, _ = cli(env, "topic", "list", "-v")
    assert f" * {shown(TOPIC)} [{shown(TYPE)}] 1 publisher" in out
    out, _ = cli(env, "node", "list")
    assert shown(NODE) in out
    out, _ = cli(env, "service", "list")
    assert shown(SERVICE) in out
    out, _ = cli(env, "param", "list")
    assert shown(PARAM) in out
    listed = json.loads(run_cli("node", "list", "-F", "json", env=env).stdout)
    assert NODE in listed
