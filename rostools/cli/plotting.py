"""Drawing for ``topic plot`` and ``bag plot``: a terminal frame, an image file, or the data.

The samples come from ``msgs.sample`` into a ``series.SeriesSet``; this module only draws
them. The terminal frame is plotext's (imported here, lazily: it costs every other command
nothing), the image matplotlib's (the ``plot`` extra), and the data is one record per series
in the usual output formats. Both plot commands share it; neither imports the other.
"""

from __future__ import annotations

import os
import shutil
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

from rostools.cli import output
from rostools.cli.output import Format, check_writable
from rostools.errors import NotFoundError, UsageError, cannot_write
from rostools.series import SeriesSet, columns

if TYPE_CHECKING:
    from collections.abc import Iterator

#: Seconds between two frames of a live plot, whatever the message rate.
FRAME_PERIOD: Final = 0.1
#: The size of a frame when the terminal does not say (output into a pipe or a file).
DEFAULT_SIZE: Final = (100, 30)
#: Image formats ``-o`` writes, by file suffix.
IMAGE_FORMATS: Final = ("png", "svg", "pdf")
#: Line colours on a colour terminal, and markers where there is no colour, per series.
COLORS: Final = ("cyan", "orange", "green", "magenta", "blue", "red", "yellow", "gray")
MARKERS: Final = ("•", "x", "+", "o", "*", "#", "%", "@")
#: Points per series an image draws at most (min and max per column beyond that).
IMAGE_COLUMNS: Final = 2000

#: What the x axis is: the time a message was received, its header.stamp, or its bag time.
TIME_KINDS: Final = {"receive": "receive time", "stamp": "header.stamp", "bag": "bag time"}


def image_format(path: Path) -> str:
    """The image format ``-o PATH`` asks for, from its suffix."""
    kind = path.suffix.lower().lstrip(".")
    if kind not in IMAGE_FORMATS:
        raise UsageError(
            f"-o {path}: cannot tell the image format from the name",
            hint="end it in " + ", ".join("." + k for k in IMAGE_FORMATS),
        )
    return kind


def check_image_target(path: Path, command: str) -> None:
    """Fail now, not after a whole bag was read, when ``-o PATH`` cannot be drawn or written."""
    import importlib.util

    image_format(path)
    if importlib.util.find_spec("matplotlib") is None:
        raise _no_matplotlib(command)
    check_writable(path)


def _no_matplotlib(command: str) -> NotFoundError:
    return NotFoundError(
        f"{command} -o needs matplotlib, which is not installed",
        hint="pip install 'rostools[plot]', or leave out -o to plot in the terminal",
    )


def axis_label(kind: str, origin: float, with_date: bool = False) -> str:
    """The x axis title: seconds since ``origin`` (epoch seconds), and which time it is."""
    when = time.strftime("%Y-%m-%d %H:%M:%S" if with_date else "%H:%M:%S", time.localtime(origin))
    return f"seconds since {when} ({TIME_KINDS[kind]})"


def use_color() -> bool:
    """Whether stdout is a terminal that takes colour (NO_COLOR unset)."""
    return sys.stdout.isatty() and not os.environ.get("NO_COLOR")


def terminal_size() -> tuple[int, int]:
    """Columns and lines of the terminal (``COLUMNS``/``LINES`` win; DEFAULT_SIZE without)."""
    size = shutil.get_terminal_size(DEFAULT_SIZE)
    return max(size.columns, 40), max(size.lines, 12)


def frame(
    plot: SeriesSet,
    *,
    origin: float,
    title: str,
    xlabel: str,
    status: str,
    x_range: tuple[float, float] | None = None,
    color: bool = False,
    size: tuple[int, int] | None = None,
) -> str:
    """One terminal frame: the plot, then a status line. ``x_range`` is in epoch seconds."""
    import plotext as plt

    width, height = size or terminal_size()
    plt.clf()
    plt.plotsize(width, height - 1)
    plt.theme("clear")
    held = plot.bounds()
    lo, hi = x_range if x_range is not None else (held or (origin, origin + 1.0))
    columns_ = max(width - 12, 10) * 2  # braille packs two points a cell across
    for i, (label, series) in enumerate(plot.series.items()):
        xs, ys = columns(series, lo, hi, columns_)
        if not xs:
            continue
        style: dict[str, Any] = (
            {"marker": "braille", "color": COLORS[i % len(COLORS)]}
            if color
            else {"marker": MARKERS[i % len(MARKERS)]}
        )
        plt.plot([x - origin for x in xs], ys, label=label, **style)
    if hi > lo:
        plt.xlim(lo - origin, hi - origin)
    plt.title(title)
    plt.xlabel(xlabel)
    text: str = plt.build()
    if not color:
        text = plt.uncolorize(text)
    return text.rstrip("\n") + "\n" + status + "\n"


def write_image(
    plot: SeriesSet, path: Path, *, origin: float, title: str, xlabel: str, command: str
) -> None:
    """Draw the plot into ``path`` (PNG, SVG or PDF, by its suffix) with matplotlib."""
    kind = image_format(path)
    try:
        from matplotlib.figure import Figure
    except ImportError as err:
        raise _no_matplotlib(command) from err
    fig = Figure(figsize=(10, 4.8), dpi=100, layout="constrained")
    ax = fig.add_subplot()
    held = plot.bounds()
    for label, series in plot.series.items():
        if held is None:
            break
        xs, ys = columns(series, held[0], held[1], IMAGE_COLUMNS)
        ax.plot([x - origin for x in xs], ys, label=label, linewidth=1.0)
    ax.set_title(title)
    ax.set_xlabel(xlabel)
    ax.grid(alpha=0.3)
    if plot.series:
        ax.legend(loc="best", fontsize="small")
    # No date in the file: the same data draws the same bytes.
    metadata: dict[str, Any] = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}.get(kind, {})
    try:
        fig.savefig(path, format=kind, metadata=metadata)
    except OSError as err:
        raise cannot_write(path, err.strerror or str(err)) from err


def records(plot: SeriesSet, kind: str) -> Iterator[dict[str, Any]]:
    """The data of each series, as ``-F json``/``yaml`` print it."""
    for label, series in plot.series.items():
        yield {
            "series": label,
            "time": TIME_KINDS[kind],
            "t": list(series.xs),
            "value": [_number(v) for v in series.ys],
            "thinned": series.thinned,
        }


def emit_records(fmt: Format, plot: SeriesSet, kind: str) -> None:
    """Print every series as one record of a stream (NDJSON, or YAML documents)."""
    for record in records(plot, kind):
        output.write(fmt, record)


def _number(value: float) -> float | int:
    """Integers as integers (a seq, a count), everything else as it is."""
    return int(value) if value.is_integer() and abs(value) < 2**53 else value


class Screen:
    """A terminal that shows one frame after another in its alternate screen.

    On leaving, the terminal is as it was, and the last frame stays printed below the
    command line, so it can be scrolled back to and copied.
    """

    def __init__(self) -> None:
        self.last = ""

    def __enter__(self) -> Screen:
        output.put("\x1b[?1049h\x1b[?25l")  # alternate screen, cursor hidden
        output.flush()
        return self

    def show(self, text: str) -> None:
        """Replace what is on the screen with ``text``."""
        self.last = text
        output.put("\x1b[H" + text.replace("\n", "\x1b[K\n") + "\x1b[J")
        output.flush()

    def __exit__(self, *exc: object) -> None:
        output.put("\x1b[?25h\x1b[?1049l" + self.last)
        output.flush()
