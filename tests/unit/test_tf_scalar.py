"""``tf/scalar.py`` (one rotation, plain floats) agrees with ``tf/math.py`` (numpy arrays)."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from rostools.tf import math as tfmath, scalar

quats = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: sum(v * v for v in q) > 0.01)


@settings(max_examples=300, deadline=None)
@given(quats)
def test_matrix_and_rpy_agree_with_the_numpy_forms(q: tuple[float, float, float, float]) -> None:
    assert np.allclose(np.array(scalar.matrix(q)), tfmath.matrix(q), atol=1e-12)
    n = math.sqrt(sum(v * v for v in q))
    unit = (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
    assert np.allclose(np.array(scalar.rpy(unit)), tfmath.to_rpy(unit), atol=1e-9)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_at_the_singularity_yaw_is_zero_as_tf2s(sign: float) -> None:
    half = sign * math.pi / 4  # pitch +-90 degrees
    _, pitch, yaw = scalar.rpy((0.0, math.sin(half), 0.0, math.cos(half)))
    assert yaw == 0.0 and pitch == pytest.approx(sign * math.pi / 2)
    assert tfmath.to_rpy((0.0, math.sin(half), 0.0, math.cos(half)))[2] == 0.0


def test_tf_echo_prints_without_importing_numpy() -> None:
    # numpy's import is a quarter of a second on a busy machine: the first answer waits for it
    code = (
        "import sys; from rostools.cli.tf import echo; from rostools.tf.buffer import"
        " TransformBuffer; from rostools.tf.records import Stamped;"
        "b = TransformBuffer(); b.set_transform(Stamped('a', 'b', 1, (1.0, 0.0, 0.0),"
        " (0.0, 0.0, 0.0, 1.0)));"
        "echo._record(b.lookup('a', 'b', 0)); print('numpy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_a_quaternion_off_unit_length_reads_as_tf2_reads_it() -> None:
    # tf2's Matrix3x3::setRotation scales by the squared norm: (0, 0, 1, 1) is 90 degrees of yaw
    quarter = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    assert np.allclose(tfmath.matrix((0.0, 0.0, 1.0, 1.0)), quarter)
    assert np.allclose(np.array(scalar.matrix((0.0, 0.0, 1.0, 1.0))), quarter)
