"""Quaternions and rigid transforms in numpy, with tf2's conventions.

A quaternion is ``(x, y, z, w)``, as ROS writes it. Every function takes arrays whose last
axis is the vector (3) or quaternion (4), so one call does one value or many.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def _f(a: ArrayLike) -> Array:
    return np.asarray(a, dtype=np.float64)


def multiply(a: ArrayLike, b: ArrayLike) -> Array:
    """The Hamilton product ``a * b``: rotate by ``b``, then by ``a``."""
    a, b = _f(a), _f(b)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def inverse(q: ArrayLike) -> Array:
    """The inverse rotation: the conjugate over the squared norm."""
    q = _f(q)
    conj = q * np.array([-1.0, -1.0, -1.0, 1.0])
    out: Array = conj / np.sum(q * q, axis=-1, keepdims=True)
    return out


def rotate(q: ArrayLike, v: ArrayLike) -> Array:
    """``v`` rotated by the unit quaternion ``q``."""
    q, v = _f(q), _f(v)
    u = q[..., :3]
    w = q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def from_rpy(roll: ArrayLike, pitch: ArrayLike, yaw: ArrayLike) -> Array:
    """The quaternion of fixed-axis roll (x), then pitch (y), then yaw (z), as tf2's ``setRPY``."""
    hr, hp, hy = _f(roll) / 2.0, _f(pitch) / 2.0, _f(yaw) / 2.0
    cr, sr = np.cos(hr), np.sin(hr)
    cp, sp = np.cos(hp), np.sin(hp)
    cy, sy = np.cos(hy), np.sin(hy)
    return np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=-1,
    )


def matrix(q: ArrayLike) -> Array:
    """The 3x3 rotation matrix of a quaternion, as tf2's ``Matrix3x3::setRotation``.

    Scaled by the squared norm, so a quaternion a little off unit length reads as tf2 reads it.
    """
    q = _f(q)
    x, y, z, w = np.moveaxis(q, -1, 0)
    s = 2.0 / np.sum(q * q, axis=-1)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    return np.stack(
        [
            np.stack([1.0 - (yy + zz), xy - wz, xz + wy], -1),
            np.stack([xy + wz, 1.0 - (xx + zz), yz - wx], -1),
            np.stack([xz - wy, yz + wx, 1.0 - (xx + yy)], -1),
        ],
        axis=-2,
    )


def to_rpy(q: ArrayLike) -> Array:
    """Roll, pitch and yaw (radians) of a quaternion, as tf2's ``Matrix3x3::getRPY`` reads it.

    At the singularity (pitch +-90 degrees) yaw is 0 and roll takes the whole turn, as tf2's.
    """
    m = matrix(q)
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    locked = np.abs(m20) >= 1.0
    pitch = np.where(
        locked, np.where(m20 < 0, np.pi / 2, -np.pi / 2), -np.arcsin(np.clip(m20, -1, 1))
    )
    c = np.where(locked, 1.0, np.cos(pitch))
    roll = np.where(locked, np.arctan2(m21, m22), np.arctan2(m21 / c, m22 / c))
    yaw = np.where(locked, 0.0, np.arctan2(m[..., 1, 0] / c, m[..., 0, 0] / c))
    return np.stack([roll, pitch, yaw], axis=-1)


def slerp(a: ArrayLike, b: ArrayLike, t: ArrayLike) -> Array:
    """Spherical interpolation from ``a`` (t=0) to ``b`` (t=1), the short way round."""
    a, b = _f(a), _f(b)
    t = _f(t)[..., None]
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(dot < 0.0, -b, b)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(theta)
    near = sin < 1e-12
    safe = np.where(near, 1.0, sin)
    wa = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    wb = np.where(near, t, np.sin(t * theta) / safe)
    out: Array = wa * a + wb * b
    return out


def compose(t1: ArrayLike, q1: ArrayLike, t2: ArrayLike, q2: ArrayLike) -> tuple[Array, Array]:
    """The transform ``(t1, q1) * (t2, q2)``: first ``(t2, q2)``, then ``(t1, q1)``."""
    return _f(t1) + rotate(q1, t2), multiply(q1, q2)


def invert(t: ArrayLike, q: ArrayLike) -> tuple[Array, Array]:
    """The inverse of the transform ``(t, q)``."""
    qi = inverse(q)
    return -rotate(qi, t), qi
