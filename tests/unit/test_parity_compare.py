"""The parity harness's judging (benchmarks/parity): fake outputs of both tools, no ROS 1.

Each verdict is reached for the reason it claims: normalised noise is identical, a listed
difference that README.md documents is documented (and only when the case lists it), a
ROS 1 tool that hangs or crashes is a ROS 1 failure, anything else is a defect.
"""

from __future__ import annotations

import os
import shutil
import signal
import sys
from pathlib import Path
from typing import Any

import pytest

from benchmarks.parity import documented as d
from benchmarks.parity.compare import (
    Expect,
    Output,
    Pairing,
    Verdict,
    judge,
    normalise_text,
    worst,
)
from benchmarks.parity.runner import run
from tests.support.env import ROOT


def out(stdout: str = "", stderr: str = "", code: int | None = 0, **kw: object) -> Output:
    return Output(code, stdout, stderr, **kw)  # type: ignore[arg-type]


def test_identical_after_masking_what_varies() -> None:
    ros1 = out(" * /rostopic_4242_1700000000000 (http://h:1/)\nPid: 4242\ntime=0.5ms\n")
    ours = out(" * /rostopic_77_1700000000999 (http://h:1/)\nPid: 77\ntime=12.25ms\n")
    assert judge(ros1, ours, Pairing()).verdict is Verdict.IDENTICAL


def test_live_stamps_and_counters_are_masked_but_nsecs_width_is_kept() -> None:
    echo = 'header: \n  seq: {}\n  stamp: \n    secs: {}\n    nsecs: {}\ndata: "hello {}"\n'
    ros1 = out(echo.format(40, 1795571098, "   696659", 12))
    same_width = out(echo.format(43, 1795571099, "300652027", 15))
    unpadded = out(echo.format(43, 1795571099, "696659", 15))
    assert judge(ros1, same_width, Pairing(), live=True).verdict is Verdict.IDENTICAL
    assert judge(ros1, unpadded, Pairing(), live=True).verdict is Verdict.DEFECT
    # the same text is a defect when the case is not live: a bag prints fixed stamps
    assert judge(ros1, same_width, Pairing()).verdict is Verdict.DEFECT


def test_csv_rows_of_live_messages() -> None:
    ros1 = out("%time,field.data\n1795572116869073152,hello 3\n")
    ours = out("%time,field.data\n1795572118629905757,hello 9\n")
    assert judge(ros1, ours, Pairing(), live=True).verdict is Verdict.IDENTICAL
    stamped = "%time,field.header.seq\n1795572116869073152,45,1795572116869073100,map\n"
    other = "%time,field.header.seq\n1795572118629905757,49,1795572118629905700,map\n"
    assert judge(out(stamped), out(other), Pairing(), live=True).verdict is Verdict.IDENTICAL


def test_a_status_line_on_stderr_is_documented_only_where_the_case_allows_it() -> None:
    ros1 = out("subscribed to [/point]\naverage rate: 10.000\n")
    ours = out("average rate: 10.000\n", "subscribed to [/point]\n")
    allowed = judge(ros1, ours, Pairing(rules=(d.STATUS_STDERR,)))
    assert allowed.verdict is Verdict.DOCUMENTED
    assert allowed.rules == ("status-stderr",)
    not_listed = judge(ros1, ours, Pairing(rules=(d.LIST_V_SORTED,)))
    assert not_listed.verdict is Verdict.DEFECT
    assert "subscribed to [/point]" in not_listed.detail


def test_rates_agree_within_the_tolerance_only() -> None:
    block = "subscribed to [/p]\naverage rate: {}\n\tmin: 0.099s max: 0.102s window: {}\n"
    ros1 = out(block.format("9.974", 8) + block.format("10.000", 18))
    close = out(block.format("10.010", 10) * 3)
    far = out(block.format("14.000", 10) * 3)
    pairing = Pairing(rates=("average",))
    assert judge(ros1, close, pairing).verdict is Verdict.IDENTICAL
    judged = judge(ros1, far, pairing)
    assert judged.verdict is Verdict.DEFECT
    assert "more than 25% apart" in judged.detail


def test_an_error_in_other_words_with_the_readme_exit_code_is_documented() -> None:
    ros1 = out("", "ERROR: Unknown topic /nope\n", code=1)
    ours = out("", "rostools: unknown topic /nope\n", code=3)
    pairing = Pairing(rules=d.error(3), expect=Expect(error=3))
    judged = judge(ros1, ours, pairing)
    assert judged.verdict is Verdict.DOCUMENTED
    assert set(judged.rules) == {"one-line-error", "exit-3"}
    # a code that is neither ROS 1's nor the README's for this case: a defect
    other = judge(ros1, ours.but(code=4), pairing)
    assert other.verdict is Verdict.DEFECT
    assert "exit: 1 (ROS 1) != 4 (rostools)" in other.detail
    # an error of two lines is not rostools' documented one-line error
    two = ours.but(stderr="rostools: unknown topic /nope\nmore\n")
    assert judge(ros1, two, pairing).verdict is Verdict.DEFECT
    # nor is an error where ROS 1 succeeded quietly
    assert judge(out("x\n"), ours, pairing).verdict is Verdict.DEFECT


@pytest.mark.parametrize(
    ("ros1", "why"),
    [
        (out("", "Traceback (most recent call last):\n  ...\nValueError: x\n", code=1), "crashed"),
        (out("", "WARNING: topic [/a/b] does not appear to be published yet\n", code=None), "hung"),
    ],
)
def test_a_ros1_tool_that_crashes_or_hangs_is_a_ros1_failure(ros1: Output, why: str) -> None:
    ours = out("", "rostools: no field named b in std_msgs/String\n", code=2)
    judged = judge(ros1, ours, Pairing())
    assert judged.verdict is Verdict.ROS1_FAILURE
    assert why in judged.detail
    # both hanging is no failure of ROS 1 alone
    assert judge(ros1, ours.but(code=None), Pairing()).verdict is Verdict.DEFECT


def test_a_planned_stop_is_not_a_hang() -> None:
    ros1 = out("", "WARNING: topic [/nope] does not appear to be published yet\n", stopped=True)
    ours = out("", "rostools: nothing publishes /nope yet; waiting\n", stopped=True)
    assert judge(ros1, ours, Pairing(rules=(d.WAITS_NOTICE,))).verdict is Verdict.DOCUMENTED
    assert judge(ros1, ours, Pairing()).verdict is Verdict.DEFECT


def test_sorted_listings() -> None:
    ros1 = out("\nPublished topics:\n * /b [T] 1 publisher\n * /a [T] 1 publisher\n\n")
    ours = out("\nPublished topics:\n * /a [T] 1 publisher\n * /b [T] 1 publisher\n\n")
    assert judge(ros1, ours, Pairing(rules=(d.LIST_V_SORTED,))).verdict is Verdict.DOCUMENTED
    assert judge(out("/b\n/a\n"), out("/a\n/b\n"), Pairing(rules=(d.FIND_SORTED,))).verdict is (
        Verdict.DOCUMENTED
    )
    # a listing that is sorted but not the same set is still a defect
    assert judge(out("/b\n/a\n"), out("/a\n/c\n"), Pairing(rules=(d.FIND_SORTED,))).verdict is (
        Verdict.DEFECT
    )


def test_get_p_of_a_mapping_is_documented_only_for_what_valid_yaml_needs() -> None:
    value = {"empty": "", "list": [1, 2], "num": "123"}
    ros1 = out("empty: \nlist: - 1\n- 2\nnum: 123\n")
    ours = out("empty: ''\nlist:\n- 1\n- 2\nnum: '123'\n")
    pairing = Pairing(rules=(d.PRETTY_MAPPING,), expect=Expect(value=value))
    assert judge(ros1, ours, pairing).verdict is Verdict.DOCUMENTED
    # rosparam printed this scalar as valid YAML: a different spelling is not documented
    value2 = {**value, "u": "h\u00e9llo"}
    ros1_u = ros1.but(stdout=ros1.stdout + "u: h\u00e9llo\n")
    ours_u = ours.but(stdout=ours.stdout + 'u: "h\\xE9llo"\n')
    pairing2 = Pairing(rules=(d.PRETTY_MAPPING,), expect=Expect(value=value2))
    assert judge(ros1_u, ours_u, pairing2).verdict is Verdict.DEFECT
    # ours must read back as the value itself
    wrong = ours.but(stdout="empty: ''\nlist: [1, 3]\nnum: '123'\n")
    assert judge(ros1, wrong, pairing).verdict is Verdict.DEFECT


def test_builtin_types_may_only_add_what_the_readme_names() -> None:
    ros1 = out("diagnostic_msgs map_msgs std_srvs\n")
    named = out("diagnostic_msgs dynamic_reconfigure map_msgs std_srvs\n")
    unnamed = out("diagnostic_msgs map_msgs std_srvs turtlesim\n")
    tutorials = out("diagnostic_msgs map_msgs roscpp_tutorials std_srvs\n")  # TwoInts
    srv = Pairing(rules=(d.BUILTIN_TYPES,), expect=Expect(kind="srv"))
    assert judge(ros1, named, srv).verdict is Verdict.DOCUMENTED
    assert judge(ros1, unnamed, srv).verdict is Verdict.DEFECT
    assert judge(ros1, tutorials, srv).verdict is Verdict.DOCUMENTED  # README names TwoInts
    # ours must keep everything ROS 1 lists
    assert judge(ros1, out("dynamic_reconfigure map_msgs std_srvs\n"), srv).verdict is (
        Verdict.DEFECT
    )


def test_bag_info_yaml_may_add_keys_not_change_values() -> None:
    ros1 = out("path: a.bag\nversion: 2.0\nindexed: True\n")
    more = out("path: a.bag\nversion: 2.0\nformat: bag\nindexed: true\n")
    changed = out("path: a.bag\nversion: '2.0'\nindexed: true\n")
    pairing = Pairing(rules=(d.INFO_YAML,))
    assert judge(ros1, more, pairing).verdict is Verdict.DOCUMENTED
    assert judge(ros1, changed, pairing).verdict is Verdict.DEFECT


def _only_with(rule: d.Difference, ros1: Output, ours: Output, **kw: Any) -> None:
    """Documented with ``rule`` (and only it), a defect without it."""
    with_rule = judge(ros1, ours, Pairing(rules=(rule,), **kw))
    assert with_rule.verdict is Verdict.DOCUMENTED and with_rule.rules == (rule.key,)
    without = judge(ros1, ours, Pairing(**kw))
    assert without.verdict is Verdict.DEFECT


def test_service_find_and_ping_all_sort() -> None:
    _only_with(d.SERVICE_FIND_SORTED, out("/trigger\n/slow\n"), out("/slow\n/trigger\n"))
    ping = "pinging {0} with a timeout of 3.0s\nxmlrpc reply from http://h:{1}/\ttime=MS\n"
    head = "Will ping the following nodes: \n * {0}\n * {1}\n\n"
    ros1 = out(head.format("/rosout", "/add") + ping.format("/rosout", 1) + ping.format("/add", 2))
    ours = out(head.format("/add", "/rosout") + ping.format("/add", 2) + ping.format("/rosout", 1))
    _only_with(d.PING_ALL_SORTED, ros1, ours)
    # the same nodes, but a reply from another port: still a defect
    moved = ours.but(stdout=ours.stdout.replace("h:2", "h:3"))
    assert judge(ros1, moved, Pairing(rules=(d.PING_ALL_SORTED,))).verdict is Verdict.DEFECT


def test_cleanup_gives_reasons_and_asks_on_stderr() -> None:
    question = (
        "Warning: these might include alive and functioning nodes, e.g. in unstable networks.\n"
        "Cleanup will purge all information about these nodes from the master.\n"
        "Please type y or n to continue:"
    )
    ros1 = out(
        f"Unable to contact the following nodes:\n * /victim\n{question}\n"
        "Unregistering /victim\ndone\n",
        "ERROR: connection refused to [http://127.0.0.1:43271/]\n",
    )
    ours = out(
        "Unable to contact the following nodes:\n * /victim (cannot reach the node /victim at "
        "http://127.0.0.1:3/: Connection refused)\nUnregistering /victim\ndone\n",
        question + " ",
    )
    _only_with(d.CLEANUP_OUTPUT, ros1, ours)
    other = ours.but(stdout=ours.stdout.replace("Unregistering /victim", "Kept /victim"))
    assert judge(ros1, other, Pairing(rules=(d.CLEANUP_OUTPUT,))).verdict is Verdict.DEFECT


def test_a_missing_verb_is_exit_2() -> None:
    pairing: dict[str, Any] = {"streams": "code", "expect": Expect(error=2)}
    _only_with(d.VERB_USAGE, out("Commands:\n\trosparam set\n"), out("", "usage\n", code=2),
               **pairing)  # fmt: skip
    # ROS 1 printing nothing at all is no list of verbs
    quiet = judge(out(""), out("", "x\n", code=2), Pairing(rules=(d.VERB_USAGE,), **pairing))
    assert quiet.verdict is Verdict.DEFECT


def test_show_bag_of_a_type_it_lacks_is_exit_3() -> None:
    ours = out("", "rostools: no connection of type nope/Nope in graph.bag\n", code=3)
    _only_with(d.SHOW_BAG_LACKS_TYPE, out(""), ours, expect=Expect(error=3))
    two_lines = ours.but(stderr=ours.stderr * 2)
    pairing = Pairing(rules=(d.SHOW_BAG_LACKS_TYPE,), expect=Expect(error=3))
    assert judge(out(""), two_lines, pairing).verdict is Verdict.DEFECT


def test_pub_from_a_file_says_nothing_per_message() -> None:
    line = "publishing and latching message for 3.0 seconds\n"
    _only_with(d.PUB_FILE_QUIET, out(line * 2), out(""))
    # other status lines are still compared
    assert judge(out(line + "x\n"), out(""), Pairing(rules=(d.PUB_FILE_QUIET,))).verdict is (
        Verdict.DEFECT
    )


def test_info_of_unsorted_chunks_and_of_unindexed_bags() -> None:
    table = "path: u.bag\nversion: 2.0\nduration: {}\nstart: {}\nend: {}\nmessages: 3\n"
    ros1 = out(table.format("-1.0s", "2.00", "1.00"))
    ours = out(table.format("2.0s", "1.00", "3.00"))
    _only_with(d.UNSORTED_CHUNKS, ros1, ours)
    more = ours.but(stdout=ours.stdout.replace("messages: 3", "messages: 4"))
    assert judge(ros1, more, Pairing(rules=(d.UNSORTED_CHUNKS,))).verdict is Verdict.DEFECT
    refused = out("", "ERROR bag unindexed: c.bag.  Run rosbag reindex.\n", code=1)
    said = out("path: c.bag\n", "rostools: c.bag: unindexed: an unclosed recording; ...\n", 1)
    _only_with(d.UNINDEXED_INFO, refused, said)
    assert judge(refused, said.but(code=0), Pairing(rules=(d.UNINDEXED_INFO,))).verdict is (
        Verdict.DEFECT
    )


def test_a_bag_with_unsorted_chunks_is_echoed_in_time_order() -> None:
    ros1, ours = (
        out('data: "2"\n---\ndata: "3"\n---\ndata: "1"\n---\n'),
        out('data: "1"\n---\ndata: "2"\n---\ndata: "3"\n---\n'),
    )
    _only_with(d.TIME_ORDER, ros1, ours)
    csv = "%time,field.data\n{}000,2\n{}000,3\n{}000,1\n"
    _only_with(d.TIME_ORDER, out(csv.format(2, 3, 1)), out(csv.format(2, 3, 1).replace(
        "2000,2\n3000,3\n1000,1", "1000,1\n2000,2\n3000,3")))  # fmt: skip
    # other messages, or ours out of time order, are defects
    pairing = Pairing(rules=(d.TIME_ORDER,))
    assert judge(ros1, out('data: "1"\n---\ndata: "4"\n---\n'), pairing).verdict is (Verdict.DEFECT)
    backwards = out("%time,field.data\n3000,3\n2000,2\n1000,1\n")
    assert judge(out(csv.format(2, 3, 1)), backwards, pairing).verdict is Verdict.DEFECT


def test_a_case_is_as_bad_as_its_worst_run() -> None:
    assert worst([Verdict.IDENTICAL, Verdict.DOCUMENTED]) is Verdict.DOCUMENTED
    assert worst([Verdict.DEFECT, Verdict.ROS1_FAILURE, Verdict.IDENTICAL]) is Verdict.DEFECT
    assert worst([]) is Verdict.IDENTICAL


def test_every_documented_difference_cites_text_that_the_docs_have(tmp_path: Path) -> None:
    assert d.check_docs(ROOT) == []
    # a copy of the docs without one phrase: the difference that cites it is named
    shutil.copy(ROOT / "README.md", tmp_path / "README.md")
    shutil.copytree(ROOT / "docs", tmp_path / "docs")
    readme = (tmp_path / "README.md").read_text()
    assert "where rostopic keeps the master's order" in readme
    (tmp_path / "README.md").write_text(
        readme.replace("where rostopic keeps the master's order", "")
    )
    assert d.check_docs(tmp_path) == ["list-v-sorted"]
    # a phrase on a page of docs/ counts as much as one in README.md
    service = (tmp_path / "docs" / "service.md").read_text()
    cut = service.replace("learn a service's type from the server itself", "")
    assert cut != service
    (tmp_path / "docs" / "service.md").write_text(cut)
    assert d.check_docs(tmp_path) == ["list-v-sorted", "types-from-peer"]


def test_normalise_text_masks_anonymous_names_of_every_tool() -> None:
    text = "/rostools_echo_12_345 /rosnode_1_2 /record_3_4 Pid: 99"
    assert normalise_text(text) == "/rostools_echo_ANON /rosnode_ANON /record_ANON Pid: PID"


def test_a_planned_stop_ends_a_command_where_sigint_is_ignored(tmp_path: Path) -> None:
    # the defect: under a shell's background job (the release check in .ci/run), SIGINT is
    # ignored, the command inherited that, took no Ctrl-C and was counted as hung
    sleeper = [sys.executable, "-c", "import time; print('up', flush=True); time.sleep(30)"]
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        stopped = run(sleeper, dict(os.environ), tmp_path, stop_after=2.0)
    finally:
        signal.signal(signal.SIGINT, before)
    assert stopped.stopped and stopped.code == -signal.SIGINT, stopped


def test_run_records_a_hang_and_a_planned_stop(tmp_path: Path) -> None:
    env = dict(os.environ)
    sleeper = [sys.executable, "-c", "import time; print('up', flush=True); time.sleep(30)"]
    hung = run(sleeper, env, tmp_path, limit=1.0)
    assert hung.code is None and not hung.stopped and hung.stdout == "up\n"
    stopped = run(sleeper, env, tmp_path, stop_after=2.0)  # up by then, even on a busy machine
    assert stopped.stopped and stopped.code is not None
    done = run([sys.executable, "-c", "import sys; sys.exit(3)"], env, tmp_path)
    assert done.code == 3 and not done.stopped
