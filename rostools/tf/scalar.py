"""One rotation's matrix and roll, pitch and yaw in plain floats, as tf2's ``Matrix3x3``.

``rostools.tf.math`` holds the same in numpy, for arrays of many; printing one transform
(``tf echo``) uses these, so that its start-up does not pay for importing numpy.
"""

from __future__ import annotations

import math

Matrix3 = tuple[tuple[float, float, float], ...]


def matrix(q: tuple[float, float, float, float]) -> Matrix3:
    """The 3x3 rotation matrix of ``(x, y, z, w)``, as ``Matrix3x3::setRotation``.

    Scaled by the squared norm, as tf2's.
    """
    x, y, z, w = q
    s = 2.0 / (x * x + y * y + z * z + w * w)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    return (
        (1.0 - (yy + zz), xy - wz, xz + wy),
        (xy + wz, 1.0 - (xx + zz), yz - wx),
        (xz - wy, yz + wx, 1.0 - (xx + yy)),
    )


def rpy(q: tuple[float, float, float, float]) -> tuple[float, float, float]:
    """Roll, pitch and yaw (radians), as ``Matrix3x3::getRPY``: at pitch +-90 degrees, yaw 0."""
    m = matrix(q)
    m20, m21, m22 = m[2]
    if abs(m20) >= 1.0:
        return math.atan2(m21, m22), (math.pi / 2 if m20 < 0 else -math.pi / 2), 0.0
    pitch = -math.asin(m20)
    c = math.cos(pitch)
    return math.atan2(m21 / c, m22 / c), pitch, math.atan2(m[1][0] / c, m[0][0] / c)
