"""Device profiles and the calibration that sets the figurine's "forward".

A device reports the pose of its own body frame; the figurine frame is +x LEFT, +y UP,
+z FRONT. A profile carries the device's nominal rate and a fixed *mount* rotation ``D``
(device-to-figurine): the figurine's orientation is ``R_fig = R_dev · D``, i.e.
``q_fig = q_dev ⊗ d``. Conventions (:mod:`doodle.input.conventions`) already change the basis of
the device's own axes along with the world's, so a Vive controller read through either the
``openvr`` or the ``unity`` convention points along its figurine +z: its mount is identity.

A prop held another way (a controller lying on its side, a tracker glued under a toy) gets
its mount from :func:`calibrate_mount`: hold it still "facing forward" for half a second,
then push it forward a few centimetres.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError
from doodle.core.model import Doodle, Track

IDENTITY = (0.0, 0.0, 0.0, 1.0)


@dataclass(frozen=True)
class DeviceProfile:
    """A tracked device's name, nominal rate, mount (device to figurine) and description."""

    name: str
    rate: float  # nominal samples per second
    mount: tuple[float, float, float, float]  # device-to-figurine quaternion, xyzw
    about: str


PROFILES: dict[str, DeviceProfile] = {
    p.name: p
    for p in (
        DeviceProfile("vive-controller", 90.0, IDENTITY, "HTC Vive wand held upright, tip pointing forward"),
        DeviceProfile("vive-tracker", 90.0, IDENTITY, "HTC Vive tracker; its mount depends on the prop: calibrate"),
        DeviceProfile("synthetic", 90.0, IDENTITY, "doodles made by doodle.synth.strokes"),
        DeviceProfile("generic", 90.0, IDENTITY, "any 6-DoF source already in figurine axes"),
    )
}


def profile(name: str) -> DeviceProfile:
    """The profile of a device name; unknown devices get the generic profile."""
    return PROFILES.get(name, PROFILES["generic"])


def apply_mount(track: Track, mount) -> Track:
    """The track with orientations turned from the device's frame to the figurine's."""
    d = np.asarray(mount, dtype=float)
    if np.allclose(d, IDENTITY):
        return track
    q = quat.normalise(quat.multiply(track.q, np.broadcast_to(d, track.q.shape)))
    return replace(track, q=q)


def calibrate_mount(track: Track, still_s: float = 0.5, min_push: float = 0.02) -> tuple[float, ...]:
    """Mount quaternion from a calibration take: still "facing forward", then a push forward.

    The figurine's up is the world's up; its front is the horizontal direction of the push
    (from the rest position to the farthest point reached). Raises DoodleError when the
    take has no still start or no push of at least ``min_push`` metres.
    """
    ok = track.valid
    rest = ok & (track.t <= track.t[0] + still_s)
    if rest.sum() < 3:
        raise DoodleError(f"calibration: track {track.name} needs {still_s:g} s of tracked stillness at the start")
    q_rest = quat.make_continuous(track.q[rest]).mean(axis=0)
    q_rest /= np.linalg.norm(q_rest)
    p_rest = track.p[rest].mean(axis=0)
    d = track.p[ok] - p_rest
    d[:, 1] = 0.0
    reach = np.linalg.norm(d, axis=1)
    far = int(np.argmax(reach))
    if reach[far] < min_push:
        raise DoodleError(
            f"calibration: track {track.name} moved only {reach[far] * 100:.1f} cm; push the prop forward "
            f"at least {min_push * 100:g} cm after holding it still"
        )
    front = d[far] / reach[far]
    up = np.array([0.0, 1.0, 0.0])
    target = np.column_stack([np.cross(up, front), up, front])  # columns: figurine x, y, z
    return tuple(quat.from_matrix(quat.as_matrix(q_rest).T @ target).tolist())


def mount_doodle(doodle: Doodle, mounts: dict[str, tuple]) -> Doodle:
    """The doodle with per-track mounts applied (tracks not named keep their orientation)."""
    tracks = tuple(apply_mount(tr, mounts[tr.name]) if tr.name in mounts else tr for tr in doodle.tracks)
    return replace(doodle, tracks=tracks)
