"""Which way is up: 3-D poses (a TUM or KITTI truth file) read onto the ground plane.

odomkit's poses are planar, in a frame whose z axis points up (REP 103). A 3-D pose file
need not be: a motion capture's default frame is Y-up (OptiTrack Motive, Vicon's exports),
and KITTI's camera frame has y pointing down. Read as if z were up, such a file's ground
track is its x and its height, and its heading is no heading of the robot's.

:func:`planar_poses` re-expresses the poses in a right-handed frame whose third axis is the
given ``up`` (one of :data:`UP_AXES`): the ground axes (a, b) are the two others, taken in
the order that keeps a × b = up, so ``+y`` reads (z, x), ``-y`` (KITTI's camera frame: x
right, y down, z forward) reads (z, −x), forward and left, ``+z`` is the identity. The
heading is the yaw of the rotation in that frame, atan2(b·R·a, a·R·a): the direction in
which the body's own a axis points, as odomkit's ``+z`` reading always was (the Z-Y-X yaw of
the quaternion). :func:`likely_up` tells from the positions alone which axis a ground
robot's path says points up.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["ground_basis", "likely_up", "planar_poses", "quaternion_matrices", "UP_AXES"]

#: The axes a 3-D frame may have pointing up (``--truth-up``, ``--imu-up``).
UP_AXES = ("+x", "-x", "+y", "-y", "+z", "-z")

#: The ground axes (a, b) for each up axis, as (index, sign) pairs with a × b = up: cyclic
#: order x → y → z → x for a positive axis, reversed for a negative one (but -y, below).
_GROUND = {
    "+z": ((0, 1.0), (1, 1.0)), "+x": ((1, 1.0), (2, 1.0)), "+y": ((2, 1.0), (0, 1.0)),
    # -y is KITTI's camera frame (x right, y down, z forward): the ground is (z, -x), forward
    # and left, so that the heading is the camera's z axis, the way the car drives.
    "-z": ((1, 1.0), (0, 1.0)), "-x": ((2, 1.0), (1, 1.0)), "-y": ((2, 1.0), (0, -1.0)),
}
#: :func:`likely_up` names an axis only where reading the file z-up keeps less than this
#: share of the breadth of its path (the spread across its main direction), and the path is
#: at least :data:`_LEAST_SPREAD` [m] broad: a ground robot's 2-D path seen from the wrong
#: side collapses onto a line, while a tilted floor or a slope keeps most of it.
_SPREAD_SHARE = 0.2
_LEAST_SPREAD = 0.05


def ground_basis(up: str) -> NDArray[np.float64]:
    """The frame whose third axis is ``up``: rows a, b, up, shape (3, 3), right-handed.

    Examples
    --------
    >>> ground_basis("+y").astype(int).tolist()
    [[0, 0, 1], [1, 0, 0], [0, 1, 0]]
    """
    if up not in _GROUND:
        raise ValueError(f"up must be one of {', '.join(UP_AXES)}, got {up!r}")
    basis = np.zeros((3, 3))
    for row, (index, sign) in enumerate(_GROUND[up]):
        basis[row, index] = sign
    basis[2] = np.cross(basis[0], basis[1])
    return basis


def quaternion_matrices(q: ArrayLike) -> NDArray[np.float64]:
    """The rotation matrix of each quaternion, times its squared norm.

    Parameters
    ----------
    q : array_like, shape (N, 4)
        Quaternions (qx, qy, qz, qw), the TUM order, any non-zero norm.

    Returns
    -------
    ndarray, shape (N, 3, 3)
        R·|q|²: left unnormalised, so that a yaw taken as an atan2 of two entries needs no
        division (and an unnormalised quaternion gives the same angle).
    """
    x, y, z, w = np.asarray(q, dtype=float).reshape(-1, 4).T
    rows = ((w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)),
            (2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)),
            (2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z))
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def planar_poses(positions: ArrayLike, rotations: ArrayLike | None, up: str = "+z"
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """3-D poses onto the ground plane of the frame whose third axis is ``up``.

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        x, y, z [m] in the file's frame.
    rotations : array_like, shape (N, 3, 3), or None
        Each pose's rotation matrix (body to file frame; only its direction matters, so a
        scaled one serves), or None for positions alone.
    up : one of :data:`UP_AXES`

    Returns
    -------
    (xy, yaw) : ndarray (N, 2) [m], the positions along a and b (:func:`ground_basis`), and
        ndarray (N,) [rad], the yaw of each rotation about ``up`` (the direction its body's a
        axis points in, atan2(b·R·a, a·R·a)); None without rotations.
    """
    basis = ground_basis(up)
    p = np.asarray(positions, dtype=float)
    xy = p @ basis[:2].T
    if rotations is None:
        return xy, None
    forward = np.einsum("nij,j->ni", np.asarray(rotations, dtype=float), basis[0])  # R·a
    return xy, np.arctan2(forward @ basis[1], forward @ basis[0])


def likely_up(positions: ArrayLike) -> str | None:
    """The axis a ground robot's positions say points up, where it is not z: ``"+x"`` or
    ``"+y"`` (the sign cannot be told from positions), else None.

    The path's breadth is its spread across its main direction, the second singular value of
    the centred positions (over √N: a standard deviation [m]); read z-up (x, y alone) a path
    whose plane is across x or y collapses onto a line. Named only where the z-up reading
    keeps under :data:`_SPREAD_SHARE` of a breadth of at least :data:`_LEAST_SPREAD`, and
    the normal of the path's plane lies along x or y. A straight road that climbs (a line in
    3-D) or a path on a tilted floor names nothing.

    Parameters
    ----------
    positions : array_like, shape (N, 3), x, y, z [m]
    """
    p = np.asarray(positions, dtype=float)
    if p.shape[0] < 3:
        return None
    p = p - p.mean(axis=0)
    root = np.sqrt(p.shape[0])
    _, spread, axes = np.linalg.svd(p, full_matrices=False)
    breadth = spread[1] / root
    kept = np.linalg.svd(p[:, :2], compute_uv=False)[1] / root
    if not breadth > _LEAST_SPREAD or not kept < _SPREAD_SHARE * breadth:
        return None
    up = int(np.argmax(np.abs(axes[2])))  # the normal of the path's plane
    return None if up == 2 else "+" + "xyz"[up]
