"""``bag plot`` and ``node graph -o``: the data, the terminal frame and the images, read back."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_writer
from rostools.msgs.codec import Codec
from rostools.msgs.message import Time
from rostools.msgs.store import TypeStore
from tests.support.bagdata import STEP_NS, write_sample
from tests.support.env import run_cli

STAMPED = "geometry_msgs/PointStamped"


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The sample bag (/count and /point are functions of the index), and a stamped one:
    message k is at bag time 10k ms, stamped 100 + k/2 s, with point.x = k * k."""
    tmp = tmp_path_factory.mktemp("plot")
    sample = write_sample(tmp / "sample.bag", 400).path
    store = TypeStore.default()
    codec = Codec.of(store)
    stamped = tmp / "stamped.mcap"
    writer = open_writer(stamped)
    conn = writer.add_connection(
        "/pos", STAMPED, store.md5(STAMPED), store.full_text(STAMPED), callerid="/p"
    )
    for k in range(50):
        msg = codec.message_class(STAMPED)()
        msg.header.stamp = Time.from_sec(100 + k / 2)
        msg.header.frame_id = "map" * (k % 3)
        msg.point.x = float(k * k)
        writer.write(conn, 5_000_000_000 + k * 10_000_000, codec.serialize(msg))
    writer.close()
    return {"sample": sample, "stamped": stamped, "tmp": tmp}


def test_bag_plot_data_is_every_message_in_the_window(
    bags: dict[str, Path], cli_env: dict[str, str]
) -> None:
    done = run_cli(
        "bag", "plot", str(bags["sample"]), "/point/x", "/count/data", "--start", "0.1",
        "--end", "0.2", "-F", "json", env=cli_env,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    series = {r["series"]: r for r in map(json.loads, done.stdout.splitlines())}
    assert list(series) == ["/point/x", "/count/data"]
    lo, hi = 100_000_000, 200_000_000  # the window, in ns from the bag's start (0)
    for label, rest in (("/point/x", 3), ("/count/data", 2)):
        want = [i for i in range(400) if i % 4 == rest and lo <= i * STEP_NS <= hi]
        assert series[label]["value"] == want
        assert series[label]["t"] == [i * STEP_NS / 1e9 for i in want]
        assert series[label]["time"] == "bag time"


def test_bag_plot_stamp_and_filter(bags: dict[str, Path], cli_env: dict[str, str]) -> None:
    done = run_cli(
        "bag", "plot", str(bags["stamped"]), "/pos/point/x", "--stamp",
        "--filter", "m.point.x >= 100 and t.to_sec() < 5.3", "-F", "json", env=cli_env,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    [record] = map(json.loads, done.stdout.splitlines())
    ks = [k for k in range(50) if k * k >= 100 and 5 + k / 100 < 5.3]
    assert record["time"] == "header.stamp"
    assert record["t"] == [100 + k / 2 for k in ks] and record["value"] == [k * k for k in ks]


def test_bag_plot_terminal_frame(bags: dict[str, Path], cli_env: dict[str, str]) -> None:
    env = {**cli_env, "COLUMNS": "72", "LINES": "20"}
    done = run_cli("bag", "plot", str(bags["sample"]), "/point/x", "/point/y", env=env)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert len(lines) == 20 and max(map(len, lines)) <= 72, done.stdout
    assert "\x1b" not in done.stdout  # no colour into a pipe
    assert lines[0].strip() == "sample.bag"
    assert "• /point/x" in done.stdout and "x /point/y" in done.stdout  # a marker each
    assert re.search(r"^ 399┤", done.stdout, re.M) and re.search(r"^-399┤", done.stdout, re.M)
    assert "seconds since" in lines[-2] and "(bag time)" in lines[-2]
    assert lines[-1] == "100 messages over 0.4 s"  # each gives /point/x and /point/y


def test_bag_plot_images_read_back(bags: dict[str, Path], cli_env: dict[str, str]) -> None:
    import matplotlib.image

    png, svg = bags["tmp"] / "plot.png", bags["tmp"] / "plot.svg"
    # one font cache for both runs (HOME is new for each test)
    env = {**cli_env, "MPLCONFIGDIR": str(bags["tmp"] / "mpl")}
    for out in (png, svg):
        done = run_cli("bag", "plot", str(bags["sample"]), "/point/x", "/point/z", "-o", str(out),
                       env=env)  # fmt: skip
        assert done.returncode == 0 and done.stdout == "", done.stderr
    pixels = matplotlib.image.imread(png)
    assert pixels.shape[:2] == (480, 1000)
    rgb = pixels[:, :, :3]
    assert (rgb.min(axis=2) < 0.9).mean() > 0.02  # far from blank
    blue = (abs(rgb[:, :, 0] - 0x1F / 255) < 0.05) & (abs(rgb[:, :, 2] - 0xB4 / 255) < 0.05)
    assert blue.sum() > 300  # the first series' line, in matplotlib's first colour
    lines = {}
    for path in ET.parse(svg).iter("{http://www.w3.org/2000/svg}path"):
        style = path.get("style", "")
        found = re.search(r"stroke: (#[0-9a-f]{6})", style)
        if found and "fill: none" in style:
            lines.setdefault(found.group(1), []).append(len(re.findall(r"L", path.get("d", ""))))
    # /point/x and /point/z: 100 points each, drawn as lines of 99 segments
    assert max(lines["#1f77b4"]) == 99 and max(lines["#ff7f0e"]) == 99


def test_bag_plot_refusals(bags: dict[str, Path], cli_env: dict[str, str], tmp_path: Path) -> None:
    sample = str(bags["sample"])
    done = run_cli("bag", "plot", sample, "/nope/x", env=cli_env)
    assert done.returncode == 3 and done.stderr.startswith("rostools: topic /nope/x is not in ")
    done = run_cli("bag", "plot", sample, "/point/x", "-o", str(tmp_path / "x.jpg"), env=cli_env)
    assert done.returncode == 2 and "cannot tell the image format" in done.stderr
    # An output that cannot be written is named before the bag is read (and its topics checked)
    nowhere = str(tmp_path / "no" / "x.png")
    done = run_cli("bag", "plot", sample, "/nope/x", "-o", nowhere, env=cli_env)
    assert done.returncode == 2 and done.stderr.startswith(f"rostools: cannot write {nowhere}")
    # Without the plot extra: a hint in one line, exit 3 (matplotlib is not found)
    shadow = tmp_path / "shadow" / "matplotlib"
    shadow.mkdir(parents=True)
    (shadow / "__init__.py").write_text("raise ImportError('not installed')\n")
    env = {**cli_env, "PYTHONPATH": str(shadow.parent)}
    done = run_cli("bag", "plot", sample, "/point/x", "-o", str(tmp_path / "x.png"), env=env)
    assert done.returncode == 3 and done.stderr.count("\n") == 1, done.stderr
    assert "needs matplotlib" in done.stderr and "pip install 'rostools[plot]'" in done.stderr
    assert not (tmp_path / "x.png").exists()


@pytest.fixture
def graph_env(cli_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """An in-process master where /cam publishes /image to /viewer."""
    from rostools.master.server import MasterThread

    with MasterThread() as master:
        cli_env["ROS_MASTER_URI"] = master.uri.rstrip("/")
        proxy = xmlrpc.client.ServerProxy(master.uri)
        proxy.registerPublisher("/cam", "/image", "sensor_msgs/Image", "http://127.0.0.1:1/")
        proxy.registerSubscriber("/viewer", "/image", "sensor_msgs/Image", "http://127.0.0.1:2/")
        yield cli_env


def test_node_graph_pictures(graph_env: dict[str, str], tmp_path: Path) -> None:
    svg, png, dot = tmp_path / "g.svg", tmp_path / "g.png", tmp_path / "g.dot"
    for out in (svg, png, dot):
        done = run_cli("node", "graph", "-o", str(out), env=graph_env)
        assert done.returncode == 0 and done.stdout == "" and done.stderr == "", done.stderr
    texts = [t.text for t in ET.parse(svg).iter("{http://www.w3.org/2000/svg}text")]
    assert {"/cam", "/viewer", "/image", "sensor_msgs/Image"} <= set(texts)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert '"n:/cam" -> "t:/image";' in dot.read_text()


def test_node_graph_without_graphviz(graph_env: dict[str, str], tmp_path: Path) -> None:
    """No dot on PATH: the DOT is written beside the name asked for, and exit 3 says so."""
    env = {**graph_env, "PATH": str(tmp_path / "empty")}
    done = run_cli("node", "graph", "-o", str(tmp_path / "g.svg"), env=env)
    assert done.returncode == 3, done.stderr
    assert done.stderr.count("\n") == 1 and "Graphviz's dot is not on PATH" in done.stderr
    assert not (tmp_path / "g.svg").exists()
    assert '"n:/cam" -> "t:/image";' in (tmp_path / "g.dot").read_text()
    done = run_cli("node", "graph", "-o", str(tmp_path / "g.txt"), env=graph_env)
    assert done.returncode == 2 and "cannot tell the format" in done.stderr
