"""``TransformBuffer`` against tf2's own ``BufferCore`` (tf2_py): random trees, the same
transforms in, the same lookups, the same answers to 1e-9 and the same errors, word for word."""

from __future__ import annotations

import math
import random
from typing import Any

import pytest

from rostools.errors import RostoolsError
from rostools.tf.buffer import TransformBuffer
from rostools.tf.records import Stamped
from tests.support.tf2peer import ask_tf2, needs_tf2

pytestmark = needs_tf2

S = 1_000_000_000


def _unit(rng: random.Random) -> list[float]:
    q = [rng.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(v * v for v in q))
    return [v / n for v in q]


def _case(seed: int) -> tuple[int, list[list[Any]]]:
    """A random forest of frames, transforms at random stamps, and lookups at hard times."""
    rng = random.Random(seed)
    cache_ns = rng.choice([10 * S, 3 * S, 60 * S])
    names = [f"f{i}" for i in range(rng.randint(3, 9))]
    ops: list[list[Any]] = []
    stamps: list[int] = [0]
    for i, child in enumerate(names[1:], 1):
        parent = names[rng.randrange(i)] if rng.random() < 0.9 else f"r{i}"  # some other trees
        if rng.random() < 0.25:
            seven = [rng.uniform(-5, 5) for _ in range(3)] + _unit(rng)
            ops.append(["set", parent, child, rng.randrange(20) * S, seven, True, "s"])
            continue
        t = rng.randrange(0, 5 * S)
        for _ in range(rng.randint(1, 12)):
            seven = [rng.uniform(-5, 5) for _ in range(3)] + _unit(rng)
            if rng.random() < 0.05:  # a parent that changes over time
                parent = names[rng.randrange(i)]
            ops.append(["set", parent, child, t, seven, False, "d"])
            stamps.append(t)
            t = max(0, t + rng.choice([rng.randrange(1, 2 * S), 0, -S, 7 * S]))  # repeats, old data
    rng.shuffle(ops)  # arrival order is not stamp order
    frames = [*names, "nowhere", "r2"]
    for _ in range(150):
        target, source = rng.choice(frames), rng.choice(frames)
        at = rng.choice([0, rng.choice(stamps), rng.choice(stamps) + rng.randrange(-S, S), 0])
        ops.append(["lookup", target, source, max(at, 0)])
    return cache_ns, ops


def _ours(cache_ns: int, ops: list[list[Any]]) -> list[dict[str, Any]]:
    buffer = TransformBuffer(cache_ns)
    out: list[dict[str, Any]] = []
    for op in ops:
        if op[0] == "set":
            _, parent, child, stamp, seven, static, who = op
            buffer.set_transform(Stamped(parent, child, stamp, seven[:3], seven[3:]), who, static)
            continue
        try:
            r = buffer.lookup(op[1], op[2], op[3])
        except RostoolsError as err:
            out.append({"error": getattr(err, "kind", ""), "message": str(err)})
            continue
        out.append({"ok": [r.stamp_ns, [*r.translation, *r.rotation]]})
    return out


def test_random_trees_answer_as_tf2s_buffer_core() -> None:
    cases = [_case(seed) for seed in range(40)]
    # one run of tf2 for all the cases, a new buffer for each: 40 interpreters cost 30 s
    answers = iter(ask_tf2(0, [op for c, ops in cases for op in [["reset", c], *ops]]))
    checked = errors = 0
    for seed, (cache_ns, ops) in enumerate(cases):
        lookups = [op for op in ops if op[0] == "lookup"]
        want = [next(answers) for _ in lookups]
        got = _ours(cache_ns, ops)
        assert len(want) == len(got) == len(lookups)
        for op, w, g in zip(lookups, want, got, strict=True):
            where = f"seed {seed}: lookup{tuple(op[1:])}"
            if "error" in w:
                errors += 1
                assert g == w, where
                continue
            assert "ok" in g, f"{where}: tf2 answered {w['ok']}, we raised {g}"
            assert g["ok"][0] == w["ok"][0], where
            assert g["ok"][1] == pytest.approx(w["ok"][1], abs=1e-9), where
            checked += 1
    assert next(answers, None) is None  # tf2 answered exactly the lookups asked
    # the cases must exercise both sides: answers and each kind of error
    assert checked > 2000 and errors > 500


def test_a_loop_is_refused_as_tf2_refuses_it() -> None:
    ops: list[list[Any]] = [
        ["set", "k", "l", S, [1, 0, 0, 0, 0, 0, 1], False, "x"],
        ["set", "m", "k", S, [1, 0, 0, 0, 0, 0, 1], False, "x"],
        ["set", "k", "m", S, [1, 0, 0, 0, 0, 0, 1], False, "x"],
        ["lookup", "l", "m", S],
        ["lookup", "l", "m", 0],
    ]
    want = ask_tf2(10 * S, ops)
    got = _ours(10 * S, ops)
    for w, g in zip(want, got, strict=True):
        assert g["error"] == w["error"] == "LookupException"
        # tf2 lists the frames on lines of their own: ours is one line
        assert g["message"].split(" Frame ")[0] == w["message"].splitlines()[0]
