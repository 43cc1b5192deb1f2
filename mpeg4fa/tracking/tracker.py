"""Frames in, FAPs out: :class:`FaceTracker` follows one face through a video, frame by frame.

Each frame: the landmark model's points (:mod:`.landmarks`) -> the feature points it sees
(:mod:`.points`, MPEG-4 axes) -> the head pose fitted to the neutral face (:mod:`.pose`) ->
the points with the head's motion taken out -> FAP values (jaw, lips, lids, brows: the map learned on
renders of the playing head, :mod:`.learned`; gaze, head turns and the rest: each FAP's rule,
:mod:`.faps`) -> a One Euro filter
(:mod:`.filters`) -> the row the stream sends. Until the neutral face is known (by default
the calmest stretch of the first seconds, :mod:`.neutral`) frames are kept and answered with
None; once it is, they are worked off, so the stream has a row for every frame pushed.

A frame where the face is lost holds the last values (the decoder would show them anyway)
and is counted; a video where no frame shows a face is a :class:`~.errors.NoFaceError`.

    with FaceTracker(fps=30) as tracker:
        for rgb in frames:
            row = tracker.push(rgb)      # (68,) int32 FAP values, or None while the neutral is chosen
        stream = tracker.stream()        # FapStream: encode it with mpeg4fa.fba.encode
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mpeg4fa.decoded.limits import clamp
from mpeg4fa.fba.params import RANGE_DELTA
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import ANGLE_UNIT, N_BAPS, N_FAPS, QUANT_STEP
from mpeg4fa.tracking import faps as fap_rules
from mpeg4fa.tracking import learned
from mpeg4fa.tracking.errors import NoFaceError, TrackingError
from mpeg4fa.tracking.filters import OneEuroFilter
from mpeg4fa.tracking.landmarks import LandmarkFinder, Landmarks
from mpeg4fa.tracking.neutral import NeutralChoice, SEARCH_SECONDS, calmest_neutral, given_neutral
from mpeg4fa.tracking.points import feature_point_array
from mpeg4fa.tracking.pose import fit_similarity
from mpeg4fa.tracking.video import VideoInfo

TRANSLATION_SCALE = 64.0
"""Filter scale of translational FAPs (FAPU): a speed of one scale a second counts as one unit of speed."""
ANGLE_SCALE = 0.05 / ANGLE_UNIT
"""Filter scale of angles (AU): 0.05 rad (about 3 degrees)."""
MIN_CUTOFF, BETA = 2.0, 0.6
"""The One Euro filter's settings for tracked FAPs (Hz, per unit of speed): see tools/bench_tracking.py."""


def filter_scale() -> np.ndarray:
    """Per-FAP scale the filter's speed is measured in (68,)."""
    scale = np.full(N_FAPS, TRANSLATION_SCALE)
    for fap in (*fap_rules.GAZE_YAW, *fap_rules.GAZE_PITCH, *fap_rules.HEAD):
        scale[fap - 1] = ANGLE_SCALE
    return scale


@dataclass(frozen=True)
class TrackSummary:
    """What a finished track holds."""

    frames: int
    lost: int            # frames without a face, holding the last values
    neutral: NeutralChoice
    fps: float


class FaceTracker:
    """Follows one face through frames pushed one by one; see the module docstring.

    ``neutral``: None (default) for the calmest stretch of the first :data:`SEARCH_SECONDS`, or the
    frame index of the neutral face (0: the first frame, and rows come back from the first push).
    ``face``: the head the FAPs are meant for (its jaw carry and eye radius, :func:`.faps.receiver`);
    default the generic head. ``smooth``: the One Euro filter (off: raw values). ``where``: the name
    errors and warnings give (a file). ``finder``: an open :class:`LandmarkFinder` to share; by default
    the tracker opens its own video-mode finder (close it with :meth:`close` or a ``with`` block).
    ``fap_map``: the learned landmark -> FAP map (:mod:`.learned`) for the FAPs it gives, the rest read by
    their rules (:mod:`.faps`); default the shipped one, None for the rules alone. ``keep_inputs``: keep
    every frame's landmark displacements and head angles (:meth:`inputs`: what the map is trained on).
    """

    def __init__(self, fps: float, *, neutral: int | None = None, face=None, smooth: bool = True,
                 where: str | None = None, finder: LandmarkFinder | None = None,
                 fap_map: learned.FapMap | None | str = "shipped", keep_inputs: bool = False) -> None:
        if not (isinstance(fps, (int, float)) and np.isfinite(fps) and fps > 0):
            raise TrackingError(f"frame rate {fps!r} is not a positive number", where)
        if neutral is not None and (not isinstance(neutral, (int, np.integer)) or neutral < 0):
            raise TrackingError(f"neutral frame {neutral!r} is not a frame index >= 0", where)
        self.fps = float(fps)
        self.where = where
        self._neutral_at = None if neutral is None else int(neutral)
        self._search = max(int(round(SEARCH_SECONDS * self.fps)), 1)
        self._face = face
        self._filter = OneEuroFilter(self.fps, MIN_CUTOFF, BETA, scale=filter_scale()) if smooth else None
        self._own_finder = finder is None
        self._finder = finder
        self._points: list[np.ndarray] = []   # per frame until the neutral is known: (L + R, 3), NaN when lost
        self._rows: list[np.ndarray] = []     # per frame (68,) float32, once the neutral is known
        self._rigid: np.ndarray | None = None  # the R landmarks the head pose is fitted on (from the first face)
        self._count = 0
        self._neutral: NeutralChoice | None = None
        self._rules: fap_rules.Neutral | None = None
        self._receiver: fap_rules.Receiver | None = None
        self._last = np.zeros(N_FAPS)
        self._map = learned.trained_map() if isinstance(fap_map, str) else fap_map
        self._inputs: list[np.ndarray] | None = [] if keep_inputs else None
        self.lost = 0

    # -- life cycle -----------------------------------------------------------------------------
    def __enter__(self) -> "FaceTracker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the landmark model if this tracker opened it."""
        if self._own_finder and self._finder is not None:
            self._finder.close()
            self._finder = None

    # -- input ----------------------------------------------------------------------------------
    @property
    def frames(self) -> int:
        """Frames pushed so far."""
        return self._count

    def push(self, rgb: np.ndarray) -> np.ndarray | None:
        """Track one RGB frame ((H, W, 3) uint8); its FAP row (68,) int32, or None while the neutral is chosen."""
        if self._finder is None:
            if not self._own_finder:
                raise TrackingError("the tracker's landmark finder is closed", self.where)
            self._finder = LandmarkFinder(static=False).__enter__()
        where = f"{self.where}: frame {self.frames}" if self.where else f"frame {self.frames}"
        return self.push_landmarks(self._finder.find(rgb, where))

    def push_landmarks(self, found: Landmarks | np.ndarray | None) -> np.ndarray | None:
        """As :meth:`push`, for landmarks found elsewhere (a :class:`Landmarks`, a (478, 3) pixel array, or
        None for a frame without a face)."""
        self._count += 1
        if found is not None:
            pixels = found.points if isinstance(found, Landmarks) else np.asarray(found, dtype=np.float64)
            landmarks = fap_rules.to_face_axes(pixels)
            if self._rigid is None:
                rigid = fap_rules.rigid_landmarks(landmarks)
                self._rigid = rigid[rigid < learned.FACE_LANDMARKS]
            points = np.concatenate([feature_point_array(landmarks), landmarks[:learned.FACE_LANDMARKS]])
        else:
            points = None
        if self._neutral is None:
            self._points.append(points)
            if not self._settle(final=False):
                return None
            return self._row_int(len(self._rows) - 1)
        self._rows.append(self._track(points))
        return self._row_int(len(self._rows) - 1)

    # -- the neutral ----------------------------------------------------------------------------
    def _settle(self, final: bool) -> bool:
        """Choose the neutral once enough frames are in (or at the end); work off the kept frames."""
        n = len(self._points)
        width = len(fap_rules.LABELS) + learned.FACE_LANDMARKS
        points = np.full((n, width, 3), np.nan)
        for k, frame in enumerate(self._points):
            if frame is not None:
                points[k] = frame
        if self._neutral_at is not None:
            if n <= self._neutral_at:
                if not final:
                    return False
                raise TrackingError(f"the neutral frame {self._neutral_at} is past the last frame ({n - 1})",
                                    self.where, "give an earlier --neutral")
            try:
                choice = given_neutral(points, self._neutral_at)
            except ValueError as exc:
                raise NoFaceError(str(exc), self.where, "give another --neutral frame or time") from None
        else:
            if n < self._search and not final:
                return False
            choice = calmest_neutral(points, self.fps)
            if choice is None:
                if not final and n < len(points):  # pragma: no cover - guarded above
                    return False
                seen = np.flatnonzero(np.isfinite(points).all(axis=(1, 2)))
                if not len(seen):
                    if not final:
                        return False
                    raise NoFaceError(f"no face found in any of the {n} frames", self.where,
                                      "use a video that shows one face from the front")
                choice = calmest_neutral(points[seen[0]:], self.fps)
                choice = NeutralChoice(choice.first + seen[0], choice.last + seen[0], choice.how, choice.points,
                                       choice.motion)
        self._neutral = choice
        try:
            self._rules = fap_rules.Neutral.from_points(choice.points[:len(fap_rules.LABELS)])
        except ValueError as exc:  # FaceError: the neutral's points give no FAPU
            raise NoFaceError(f"the neutral face (frame {choice.first}) gives no face units: {exc}", self.where,
                              "choose a frame with the face upright and seen from the front (--neutral)") from None
        self._receiver = fap_rules.receiver(self._face)
        for frame in self._points:
            self._rows.append(self._track(frame))
        self._points = []  # from here on each frame is worked off as it comes
        return True

    # -- per frame ------------------------------------------------------------------------------
    def _track(self, points: np.ndarray | None) -> np.ndarray:
        if points is None or not np.isfinite(points).all():
            self.lost += 1
            if self._filter is not None:
                self._filter(np.full(N_FAPS, np.nan))
            if self._inputs is not None:
                self._inputs.append(np.full(learned.FACE_LANDMARKS * 3 + 3, np.nan, dtype=np.float32))
            return self._last.copy()
        labels = len(fap_rules.LABELS)
        rigid = labels + self._rigid
        pose = fit_similarity(self._neutral.points[rigid], points[rigid])
        local = pose.to_neutral(points)
        angles = np.array([pose.angles()])
        values = fap_rules.fap_values(local[None, :labels], self._rules, angles, self._receiver)[0]
        if self._map is not None or self._inputs is not None:
            moved = (local[labels:] - self._neutral.points[labels:]) / self._rules.fapu.ES0
            if self._inputs is not None:
                self._inputs.append(np.concatenate([moved.ravel(), angles[0]]).astype(np.float32))
            if self._map is not None:
                faps = self._map.faps - 1
                values[faps] = self._map.predict(moved[None], angles, self._rules.fapu)[0]
        if self._filter is not None:
            values = self._filter(values)
        self._last = values.astype(np.float32)
        return self._last

    def _row_int(self, k: int) -> np.ndarray:
        return np.rint(sendable(self._rows[k][None])[0]).astype(np.int32)

    # -- output ---------------------------------------------------------------------------------
    def finish(self) -> TrackSummary:
        """Settle the neutral if the video ended before it was chosen; NoFaceError if no frame had a face."""
        if not self._count:
            raise NoFaceError("no frames to track", self.where, "the video holds no frames")
        if self._neutral is None:
            self._settle(final=True)
        return TrackSummary(frames=self._count, lost=self.lost, neutral=self._neutral, fps=self.fps)

    def values(self) -> np.ndarray:
        """(n, 68) float FAP values of every frame pushed (after :meth:`finish`)."""
        self.finish()
        return np.asarray(self._rows, dtype=np.float64).reshape(-1, N_FAPS)

    @property
    def fapu(self):
        """The FAPU measured on the neutral face (after :meth:`finish`), in pixels."""
        self.finish()
        return self._rules.fapu

    def inputs(self) -> tuple[np.ndarray, np.ndarray]:
        """Every frame's face landmarks' displacement from the neutral over ES0, head motion out
        ``(n, FACE_LANDMARKS, 3)``, and head angles ``(n, 3)`` (NaN where the face was lost); needs ``keep_inputs``."""
        if self._inputs is None:
            raise TrackingError("the tracker keeps no inputs: open it with keep_inputs=True", self.where)
        self.finish()
        rows = np.asarray(self._inputs, dtype=np.float64).reshape(-1, learned.FACE_LANDMARKS * 3 + 3)
        return rows[:, :-3].reshape(-1, learned.FACE_LANDMARKS, 3), rows[:, -3:]

    def stream(self) -> FapStream:
        """The FAP stream of every frame pushed: the tracked FAPs (:data:`.faps.SENT`) in every frame."""
        return fap_stream(self.values(), self.fps)


CARRIED_LEVELS = 30 * RANGE_DELTA
"""Quantised levels every tracked value is kept within: one range code below the largest (31 x 60), so any
``fap_quant`` carries it (a tracker's outlier must not make the stream unencodable)."""


def sendable(values: np.ndarray) -> np.ndarray:
    """``(n, 68)`` values held within what a face shows and a stream carries (see :func:`fap_stream`); NaN as 0."""
    values = np.nan_to_num(np.asarray(values, dtype=np.float64).reshape(-1, N_FAPS))
    values, _ = clamp(values)
    bound = CARRIED_LEVELS * QUANT_STEP
    return np.clip(values, -bound, bound)


def fap_stream(values: np.ndarray, fps: float) -> FapStream:
    """A FapStream sending :data:`.faps.SENT` in every frame from ``(n, 68)`` float values, rounded and held
    within what a face shows (:func:`mpeg4fa.decoded.limits.clamp`: no negative jaw) and a stream carries."""
    n = len(values)
    values = sendable(values)
    stream = FapStream.empty(0)
    sent = np.array(fap_rules.SENT) - 1
    mask = np.zeros((n, N_FAPS), dtype=bool)
    mask[:, sent] = True
    rows = np.zeros((n, N_FAPS), dtype=np.int32)
    rows[:, sent] = np.rint(np.asarray(values)[:, sent]).astype(np.int32)
    no_body = np.broadcast_to(np.zeros(N_BAPS, dtype=bool), (n, N_BAPS))
    stream.fap_mask, stream.fap_values = mask, rows
    stream.viseme = np.zeros((n, 4), dtype=np.int32)
    stream.expression = np.zeros((n, 6), dtype=np.int32)
    stream.bap_mask = no_body
    stream.bap_values = np.broadcast_to(np.zeros(N_BAPS, dtype=np.int32), (n, N_BAPS))
    stream.timestamps = np.arange(n, dtype=np.float64) / fps
    stream.object_mask = np.full(n, 1, dtype=np.uint8)
    stream.skip = np.zeros(n, dtype=np.int32)
    stream.start_code = np.zeros(n, dtype=np.uint32)
    stream.bits = np.zeros(n, dtype=np.int32)
    stream.source_fps = fps
    return stream


@dataclass(frozen=True)
class TrackedVideo:
    """A video tracked whole: its stream, what the track holds, and the video's header facts."""

    stream: FapStream
    summary: TrackSummary
    info: VideoInfo


def _push_until(tracker: "FaceTracker", rgb: np.ndarray, ticks: float) -> None:
    """Push ``rgb`` for the output frames before ``ticks`` (a time in output frames)."""
    while tracker.frames < math.ceil(ticks - 1e-9):
        tracker.push(rgb)


def track_video(path, *, fps: float | None = None, neutral: int | float | None = None, face=None,
                smooth: bool = True, progress=None) -> TrackedVideo:
    """Track every frame of the video at ``path`` into a FapStream at the video's frame rate (or ``fps``).

    ``neutral``: None (the calmest stretch of the first seconds), a frame index (int) or a time in seconds
    (float). ``progress(done, total)`` is called per frame (total: the header's frame count, an estimate).
    Frames where the face is lost hold the last values and are counted (``summary.lost``); a video with no
    face at all, or one that is not a readable video, is a TrackingError naming the file (and frame)."""
    from mpeg4fa.tracking.video import probe_video, timed_frames

    info = probe_video(path)
    rate = fps if fps is not None else info.fps
    if not rate or not np.isfinite(rate) or rate <= 0:
        raise TrackingError("the video does not say its frame rate", info.path, "give --fps")
    if isinstance(neutral, float):
        if not (np.isfinite(neutral) and neutral >= 0):
            raise TrackingError(f"neutral time {neutral!r} s is not a time >= 0", info.path)
        at = neutral * rate  # the frame showing at that time (1.99 s at 25 fps is frame 49, not 50)
        if not at < 2 ** 31:  # 1e308 s: no frame of any video (the tracker says where a nearer one falls)
            raise TrackingError(f"neutral time {neutral:g} s is past the end of any video", info.path,
                                "give a time within the video")
        neutral = int(math.floor(at + 1e-9))
    source = info.fps if info.fps and info.fps > 0 else rate
    total = max(int(round(info.frames * rate / source)), 1)
    with FaceTracker(rate, neutral=neutral, face=face, smooth=smooth, where=info.path) as tracker:
        # each frame is pushed for every output frame whose time it covers, from its own time stamp to the next
        # frame's (repeated when the rate is higher, left out when lower, held over a variable rate's gaps), so the
        # stream keeps the video's timing from its first frame (a start offset between its video and its sound, as
        # some files have, is not read)
        held, until = None, 0.0
        for t, rgb in timed_frames(path, max(rate, source)):
            if held is not None:
                _push_until(tracker, held, t * rate)
            held, until = rgb, t + 1.0 / source
            if progress is not None:
                progress(tracker.frames, max(total, tracker.frames))
        if held is not None:
            _push_until(tracker, held, until * rate)
        summary = tracker.finish()
        return TrackedVideo(tracker.stream(), summary, info)
