"""Pose sources: where the recorder's samples come from, behind one small interface.

A *pose source* is any object with

* ``tracks`` — a list of ``(name, role, serial)``, one per tracked object;
* ``rate`` — its nominal samples per second (the recorder polls it at that pace);
* ``device`` — the device name written in the file header (see :mod:`doodle.input.devices`);
* ``read()`` — the next :class:`Frame`, or None when the source has ended;
* ``close()`` — release the device (calling it twice does nothing).

Three sources implement it: :class:`SyntheticSource` (an in-memory doodle, e.g. from
:mod:`doodle.synth.strokes`), :class:`ReplaySource` (a doodle file) and :class:`OpenVRSource` (live
SteamVR controllers and trackers). Every pose is in OUR frame (SPEC "Conventions"): metres,
+x left, +y up, +z forward, quaternions xyzw. A source does not pace itself: the recorder
calls ``read()`` once per tick.
"""

from __future__ import annotations

import os
import tempfile
import time
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from doodle.core import quat
from doodle.input.conventions import to_ours
from doodle.core.errors import DoodleError
from doodle.core.model import Doodle


@dataclass(frozen=True)
class Frame:
    """One poll of a source: time in seconds and one ``(p (3,), q (4,) xyzw, ok)`` per track.

    ``trigger`` is True on the frame where a trigger was pressed (the press edge) on any
    controller.
    """

    t: float
    poses: tuple
    trigger: bool = False


class SyntheticSource:
    """The samples of an in-memory :class:`~doodle.core.model.Doodle`, in order; lost tracking is
    ``ok=False``. ``triggers`` are times (s, on the doodle's clock) of simulated trigger
    presses: each marks the first frame at or after it."""

    def __init__(self, doodle: Doodle, triggers=()):
        self.doodle = doodle
        self.tracks = [(tr.name, tr.role, tr.serial) for tr in doodle.tracks]
        self.rate = float(doodle.rate)
        self.device = doodle.device
        t = doodle.t
        self._presses = set(np.searchsorted(t, np.asarray(triggers, dtype=float), side="left").tolist())
        self._i = 0

    def read(self) -> Frame | None:
        i = self._i
        if i >= len(self.doodle.t):
            return None
        self._i += 1
        poses = tuple((tr.p[i], tr.q[i], bool(tr.valid[i])) for tr in self.doodle.tracks)
        return Frame(float(self.doodle.t[i]), poses, i in self._presses)

    def close(self) -> None:
        pass


class ReplaySource(SyntheticSource):
    """The samples of a doodle file (:func:`doodle.input.loader.load`), like :class:`SyntheticSource`.

    The orientations are read as the device gave them (no mount applied) and the device
    name is kept, so a re-recorded file is mounted the same way as the original when loaded.
    """

    def __init__(self, path, triggers=()):
        from doodle.input.loader import load

        super().__init__(load(path, raw=True), triggers)


# --------------------------------------------------------------------------- OpenVR

NO_STEAMVR = ("SteamVR is not running or not installed (openvr: {detail}); to try the pipeline without a "
              "headset, replay a recording: doodle replay FILE")


@contextmanager
def _stderr_captured():
    """Collect what C code writes to file descriptor 2 meanwhile; yields a list that gets the text."""
    text: list[str] = []
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        saved = os.dup(2)
        os.dup2(tmp.fileno(), 2)
        try:
            yield text
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            text.append(tmp.read().decode("utf-8", "replace"))


def pose_from_matrix(m) -> tuple[np.ndarray, np.ndarray]:
    """Our ``(p, q)`` from an OpenVR 3x4 device-to-absolute matrix (rows of ``[R | p]``).

    OpenVR is right-handed with +x right, +y up, −z forward; the basis change to ours
    (:mod:`doodle.input.conventions`, ``openvr``) applies to the world and the device's own axes, so
    a controller pointing along its −z points along its figurine +z.
    """
    m = np.asarray(m, dtype=float).reshape(3, 4)
    q = quat.from_matrix(m[:, :3])
    return to_ours(m[:, 3], q, "openvr")


class OpenVRSource:
    """Live poses of the SteamVR controllers and generic trackers.

    Tracks are named ``c0``, ``c1``, … — the right hand first, then the left hand, then other
    controllers and trackers by device index — with their role (``right_hand``,
    ``left_hand``, ``controller``, ``tracker``) and serial number. ``read()`` polls
    ``getDeviceToAbsoluteTrackingPose`` (standing universe, no prediction); a pose is ok when
    it is valid and its tracking result is Running_OK. Times are ``clock()`` seconds since
    the first read. Raises DoodleError when SteamVR is missing (one line pointing to
    ``doodle replay``) or sees no controller or tracker.
    """

    def __init__(self, rate: float = 90.0, clock=time.monotonic):
        try:
            import openvr
        except ImportError as exc:  # the package or its C library is missing
            raise DoodleError(NO_STEAMVR.format(detail=f"cannot import: {exc}")) from None
        self._vr, self.rate, self._clock = openvr, float(rate), clock
        try:
            with _stderr_captured() as said:  # the C library explains its failure on stderr
                system = openvr.init(openvr.VRApplication_Other)
        except openvr.OpenVRError as exc:
            detail = "; ".join(x for x in [str(exc).strip() or type(exc).__name__, *said[0].split("\n")] if x.strip())
            raise DoodleError(NO_STEAMVR.format(detail=" ".join(detail.split()))) from None
        if said and said[0]:
            os.write(2, said[0].encode())
        self._system = system
        try:
            self._devices, self.tracks = self._enumerate()
        except BaseException:
            self.close()
            raise
        self.device = "vive-controller" if any(r != "tracker" for _, r, _ in self.tracks) else "vive-tracker"
        self._poses = (openvr.TrackedDevicePose_t * openvr.k_unMaxTrackedDeviceCount)()
        self._pressed = {i: False for i in self._devices}
        self._t0: float | None = None

    def _enumerate(self):
        vr, system = self._vr, self._system
        classes = {vr.TrackedDeviceClass_Controller: "controller", vr.TrackedDeviceClass_GenericTracker: "tracker"}
        hands = {vr.TrackedControllerRole_RightHand: "right_hand", vr.TrackedControllerRole_LeftHand: "left_hand"}
        found = []
        for i in range(vr.k_unMaxTrackedDeviceCount):
            kind = classes.get(system.getTrackedDeviceClass(i))
            if kind is None or not system.isTrackedDeviceConnected(i):
                continue
            role = hands.get(system.getControllerRoleForTrackedDeviceIndex(i), kind) if kind == "controller" else kind
            try:
                serial = system.getStringTrackedDeviceProperty(i, vr.Prop_SerialNumber_String)
            except vr.OpenVRError:
                serial = ""
            serial = "_".join(serial.replace(",", " ").split())
            found.append((("right_hand", "left_hand").index(role) if role in ("right_hand", "left_hand") else 2, i,
                          role, serial))
        if not found:
            raise DoodleError("SteamVR sees no controller or tracker: switch them on and check they are tracked")
        found.sort()
        devices = [i for _, i, _, _ in found]
        tracks = [(f"c{k}", role, serial) for k, (_, _, role, serial) in enumerate(found)]
        return devices, tracks

    def read(self) -> Frame:
        vr, system = self._vr, self._system
        now = self._clock()
        if self._t0 is None:
            self._t0 = now
        poses = system.getDeviceToAbsoluteTrackingPose(vr.TrackingUniverseStanding, 0, self._poses)
        out, trigger = [], False
        for i in self._devices:
            pose = poses[i]
            ok = bool(pose.bPoseIsValid) and pose.eTrackingResult == vr.TrackingResult_Running_OK
            p, q = np.full(3, np.nan), np.full(4, np.nan)
            if ok:
                m = np.array([[float(x) for x in row] for row in pose.mDeviceToAbsoluteTracking.m])
                ok = bool(np.isfinite(m).all()) and abs(np.linalg.det(m[:, :3]) - 1.0) < 0.1
                if ok:
                    p, q = pose_from_matrix(m)
            out.append((p, q, ok))
            got, state = system.getControllerState(i)
            pressed = bool(got) and bool(state.ulButtonPressed & (1 << vr.k_EButton_SteamVR_Trigger))
            trigger |= pressed and not self._pressed[i]
            self._pressed[i] = pressed
        return Frame(now - self._t0, tuple(out), trigger)

    def close(self) -> None:
        if getattr(self, "_system", None) is not None:
            self._system = None
            self._vr.shutdown()
