"""The compile pipeline: the one place that ties doodle → grammar → (laban → retarget).

Samples → tokens (Segmenter) → action segments (Matcher) → trajectory and clip sequence →
one animation per track (:func:`compile_doodle`), with quality metrics (:func:`quality`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError
from doodle.core.filters import gaussian_filter1d
from doodle.core.model import Doodle
from doodle.input.repair import repaired
from doodle.input.segmenter import SegmenterParams
from grammar.library import Compiled, compile_library
from doodle.app.placement import interaction_pairs
from grammar.recognizer import recognize
from library.manifest import load_combined


# --- compile: actions → animation ------------------------------------------------------------

CHARACTER_HEIGHT = 1.7  # metres
PROP_SIZE = 0.2  # metres: a 20 cm figurine plays a 1.7 m character
SQUEEZE_SAID = 0.05  # s: a one-shot clip squeezed into less time than it needs by more than this is said


@dataclass(frozen=True, eq=False)
class Animation:
    """One track's animation and what went into it."""

    track: str
    motion: object  # retarget.skeleton.Motion
    segments: list
    tokens: list
    path: np.ndarray  # (F, 3) transferred root path at the output frames
    transitions: list[float]
    clips: dict  # action -> clip path
    roles: dict  # role -> joint index on the output skeleton
    terrain: object = None  # retarget.terrain ground (None: flat y = 0)
    frame_ranges: list = None  # per segment, its first and last output frame
    samples: np.ndarray = None  # the doodle's positions (n, 3), as the segments index them
    placement: tuple = None  # (origin, scale): how the doodle was put into the world
    styles: list = None  # per segment, the (L_t, L_w) applied
    efforts: list = None  # per segment, the recognised Effort (laban.classify.Quality) or None
    sample_times: np.ndarray = None  # s: the doodle's sample times the segments index (walks inserted: longer)
    contacts: tuple = ()  # the scene's interactions as compiled (retarget.qa.Contact), on every track
    sole: float = 0.0  # m: how high the skeleton's lowest foot joint stands above the floor (retarget.qa)

    @property
    def projected(self) -> np.ndarray | None:
        """The doodle scaled and projected on the ground, before the transfer (n, 3): made
        when asked (the previews), not kept beside the animation."""
        if self.samples is None:
            return None
        origin, scale = self.placement
        out = (self.samples - origin) * scale
        out[:, 1] = 0.0 if self.terrain is None else self.terrain.height(out[:, [0, 2]])
        return out


@dataclass(frozen=True)
class Actions:
    """The library a compile uses, loaded once: its definitions, the user part (whose
    skeleton wins), the compiled expressions and the analysed clips."""

    library: object  # library.manifest.Library
    user: object  # the user library or None
    compiled: Compiled
    clips: dict  # action -> [retarget.clips.Clip]
    directions: dict = None  # travelling cyclic action -> the way its clips must travel (rad from the facing)


def load_for_compile(library_dir=None, use_builtin: bool = True, cache: bool = True) -> Actions:
    """The library and its clips; with a user library, every built-in action it has no
    fitting clip of on its skeleton gets the built-in clip retargeted onto that skeleton
    (after its own clips, see :func:`choose`). With ``cache`` (and a cache folder:
    :mod:`doodle.core.cache`), the analysed clips and the automata are read back from the
    last run on the same files (:mod:`doodle.app.libcache`) — the same values."""
    from doodle.app import libcache

    library, user = load_combined(library_dir, use_builtin)
    key = libcache.clips_key(library, user, use_builtin) if cache and libcache.usable() else None
    stored = libcache.read_clips(key) if key is not None else None
    if stored is not None:
        clips, directions, said = stored
    else:
        with warnings.catch_warnings(record=True) as said:  # kept with the clips: said again on every run
            clips, directions = _analysed_clips(library, user, use_builtin)
        said = [libcache.Note.of(w) for w in said]
        if key is not None:
            libcache.write_clips(key, clips, directions, said)
    for note in said:
        note.warn()
    compiled = libcache.compile_library(library) if key is not None else compile_library(library)
    return Actions(library, user, compiled, clips, directions)


def _analysed_clips(library, user, use_builtin: bool) -> tuple[dict, dict]:
    """Every action's clips read and analysed (:func:`retarget.clips.load_clips`), built-in
    ones retargeted onto a user library's skeleton where it has none of its own that fits,
    and the travelling actions' directions."""
    from library.manifest import builtin
    from retarget.clips import load_clips, travel_directions

    clips = load_clips(library)
    own = load_clips(builtin()) if use_builtin and user is not None else {}
    directions = travel_directions(builtin(), own) if use_builtin else travel_directions(library, clips)
    if own:
        clips = _with_retargeted(library, user, clips, own, directions)
    return clips, directions


def _with_retargeted(library, user, clips: dict, own: dict, directions: dict) -> dict:
    """``clips`` with, for each action that has a built-in clip but no clip on the user
    skeleton travelling the way the action means, the built-in clip retargeted onto it."""
    from retarget.clips import fits, retargeted

    mine = [c for a in user.actions for c in clips.get(a.name, [])]
    if not mine:
        return clips
    reference = mine[0].motion
    names = reference.skeleton.names
    out = dict(clips)
    for action in library.actions:
        want = directions.get(action.name)
        on = [c for c in clips.get(action.name, []) if c.motion.skeleton.names == names]
        if own.get(action.name) and not any(fits(c, want) for c in on):
            try:
                extra = retargeted(own[action.name][0], reference.skeleton, reference, mine[0].roles)
            except ValueError as e:  # a skeleton the role chains do not fit: the rest pose, as compile says
                warnings.warn(f"{user.source}: built-in clips cannot be retargeted onto its skeleton: {e}")
                return clips
            out[action.name] = list(clips.get(action.name, [])) + [extra]
    return out


@dataclass(frozen=True)
class Choice:
    """What one segment plays: the clip (stylised), the action's flags, the Laban quality
    applied and what the effort model said."""

    clip: object  # retarget.clips.Clip
    action: object  # library.manifest.ActionDef
    on_skeleton: bool  # a clip of its own (else the rest pose)
    style: tuple  # (L_t, L_w) applied
    effort: object  # laban.classify.Quality or None
    retargeted: bool = False  # the clip is a built-in one retargeted onto the library's skeleton


def compile_doodle(doodle: Doodle, library_dir=None, use_builtin: bool = True, params: SegmenterParams = SegmenterParams(),
                   fps: float = 30.0, scale: float | None = None, threshold: float = 2.0,
                   pin: bool = True, terrain=None, jump_arc: str = "clip", retime: str = "uniform",
                   qualities: dict | None = None, style: str = "modifiers", effort_model=None,
                   progress=None, cache: bool = True) -> list[Animation]:
    """Every track of a doodle turned into an animation on one timeline.

    Stages: lost tracking repaired as the Segmenter repairs it (:func:`doodle.input.repair.repaired`:
    the path, placement and Effort read the poses themselves; a gap longer than
    ``params.max_gap`` is a DoodleError naming the track and time span); the library loaded
    once (:func:`load_for_compile`); the scene recognised and
    its characters placed for their interactions (:func:`scene`); per track, a clip chosen
    and stylised for each segment (:func:`choose`), the path laid on the terrain, the clips
    sequenced with transitions (:func:`sequenced`), feet pinned and clamped (:func:`finish`); contacts between
    characters reached (:func:`_contacts`).

    Feet are pinned in their contacts unless ``pin`` is False. ``qualities`` maps
    ``(track, segment index)`` — or ``(track, None)`` / ``(None, None)`` for every segment
    of a track / of the doodle — to Laban ``(L_t, L_w)``, applied to one-shot clips as the
    thesis's modifiers or, with ``style="preferred"``, as its study's preferred combination.
    Segments without a quality given get the one ``effort_model`` (a
    :class:`laban.models.EffortModel`) recognises in the hand's motion, if one is given.
    ``progress(done, total)`` is called as segments are done (for a progress bar).
    ``cache``: the library's analysed clips and automata read from (and kept in) the disk
    cache (:func:`load_for_compile`) — the same results either way.
    """
    doodle = repaired(doodle, params.max_gap)
    actions = load_for_compile(library_dir, use_builtin, cache)
    scale = CHARACTER_HEIGHT / PROP_SIZE if scale is None else scale
    doodle, recognised = scene(doodle, actions, params, threshold, scale)
    times = np.arange(int(np.floor(float(doodle.t[-1]) * fps)) + 1) / fps
    skeleton, rest = _compile_skeleton(actions.library, actions.user, actions.clips)
    total, done = sum(len(segs) for _, segs in recognised.values()), 0
    origin = doodle.tracks[0].p[0]  # one origin for the scene: characters keep their relative places
    results, missing, retargeted, chosen = [], {}, {}, {}
    interacting = {(tr, seg.first, seg.action) for ta, a, tb, b in interaction_pairs(recognised)
                   for tr, seg in ((ta, a), (tb, b))}
    for track in doodle.tracks:
        tokens, segments = recognised[track.name]
        choices, styled = [], {}  # styled: one stylised clip per distinct (clip, quality), shared by its segments
        given = [_quality_of(qualities, track.name, index) for index in range(len(segments))]
        efforts = track_efforts(effort_model, track, segments, given)
        for seg, quality, effort in zip(segments, given, efforts):
            choices.append(choose(seg, track, actions, skeleton, rest, quality, effort, style, styled))
            if progress:
                done += 1
                progress(done, total)
        staged = sequenced(track, segments, choices, times, skeleton, rest, scale, terrain, origin, fps, jump_arc,
                           retime, style, pin)
        # only interactions read their clips again (their contact frames): the others are let go
        # before the feet are pinned, so a long track does not hold every styled clip through it
        choices = [c if (track.name, seg.first, seg.action) in interacting
                   else replace(c, clip=_Unplayed(c.clip.path, c.clip.retargeted)) for seg, c in zip(segments, choices)]
        chosen[track.name] = choices
        styled.clear()  # (an interaction's clip stays in its choice)
        _release_heap()
        results.append(finish(track, tokens, segments, staged, times, rest, scale, terrain, origin))
        del staged
        for seg, c in zip(segments, choices):
            if (c.retargeted or not c.on_skeleton) and seg.action != "unknown":
                (retargeted if c.retargeted else missing).setdefault(seg.action, []).append(
                    f"{track.name} {track.t[seg.start] - track.t[0]:.2f}–{track.t[min(seg.end, len(track.t) - 1)] - track.t[0]:.2f} s")
    for action, where in missing.items():
        warnings.warn(f"the library has no clip of {action} on its skeleton: {len(where)} segment"
                      f"{'s' * (len(where) != 1)} hold{'s' * (len(where) == 1)} the rest pose ({', '.join(where[:4])}"
                      f"{', …' if len(where) > 4 else ''}); an action's clips are listed in its library.toml entry "
                      "(clips = [\"clips/NAME.bvh\"])")
    for action, where in retargeted.items():
        own = any(not c.retargeted and c.motion.skeleton.names == skeleton.names for c in actions.clips.get(action, []))
        warnings.warn(f"the library has no clip of {action}{' travelling the way it means' if own else ''} on its "
                      f"skeleton: {len(where)} segment"
                      f"{'s' * (len(where) != 1)} play{'s' * (len(where) == 1)} the built-in clip retargeted onto it "
                      f"({', '.join(where[:4])}{', …' if len(where) > 4 else ''})")
    contacts = _contacts(results, recognised, {i.name: i for i in actions.library.interactions}, chosen)
    _apart(results, recognised, contacts)
    return [replace(r, contacts=contacts) for r in results]


def _release_heap() -> None:
    """The heap freed so far handed back to the system (glibc's ``malloc_trim``; elsewhere
    nothing): a long track's clips are many small arrays, and the peak comes after them."""
    import ctypes

    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def scene(doodle: Doodle, actions: Actions, params: SegmenterParams, threshold: float, scale: float):
    """The doodle recognised, with its characters placed for their interactions (§6.2.2):
    walks to an interaction's configuration and back inserted where the library gives one,
    else the receiver stepping within reach. Placing changes the doodle, so it is read
    again after each change. Returns (doodle, recognised)."""
    recognised = recognize(doodle, actions.compiled, params, threshold)
    placements = {i.name: i.placement if i.placement is not None else _pair_placement(i)
                  for i in actions.library.interactions if i.placement is not None or i.pair}
    if placements:
        from doodle.app.placement import place

        placed = place(doodle, recognised, scale, placements)
        if placed is not doodle:
            doodle = placed
            recognised = recognize(doodle, actions.compiled, params, threshold)
    met = meet(doodle, recognised, scale, skip=set(placements), actions=actions)
    if met is not doodle:  # characters brought within reach: read the scene again
        doodle = met
        recognised = recognize(doodle, actions.compiled, params, threshold)
    return doodle, recognised


def choose(seg, track, actions: Actions, skeleton, rest, given, effort, style: str, styled: dict) -> Choice:
    """The clip a segment plays on the output skeleton (the rest pose where its action has
    none): the first that travels the way the action means (a side step sideways, relative
    to its facing; :func:`retarget.clips.fits`) — the library's own before a retargeted
    built-in one — stylised by the quality ``given`` or, without one, the ``effort`` the
    effort model recognised in the hand's motion (:func:`track_efforts`), on the
    :data:`STYLE_STEP` grid (a cycle is never retimed: its pace is the hand's travel; a
    jump's timing is left as it is — its flight lasts what gravity gives it — and it takes
    the quality in its poses). ``styled``: stylised clips already made, by clip and quality
    (filled here; segments asking for the same share one — a long doodle asks for the same
    few again and again, and clips are never changed in place)."""
    from retarget.clips import fits

    library = actions.library
    on_skeleton = [c for c in actions.clips.get(seg.action, []) if c.motion.skeleton.names == skeleton.names]
    want = (actions.directions or {}).get(seg.action)
    fitting = [c for c in on_skeleton if fits(c, want)] or on_skeleton
    clip = fitting[0] if fitting else rest
    name = seg.action if seg.action in library.names else "Idle"
    action = library.action(name) if name in library.names else library.action(rest.action)
    if given is None and effort is not None:
        given = (_on_grid(effort.time), _on_grid(effort.weight))
    lt, lw = given or (0.0, 0.0)
    if action.cyclic:
        lt = 0.0
    styling = bool((lt or lw) and on_skeleton)
    if styling:
        how = "preferred" if action.jumping else style
        key = (id(clip), repr(lt), repr(lw), how, action.cyclic)  # (repr: -0.0 is not 0.0); the neutral
        # clip is kept beside its stylisation, so its id stays its own
        if key not in styled:
            styled[key] = (clip, _stylized(clip, lt, lw, how, action.cyclic))
        clip = styled[key][1]
    return Choice(clip, action, bool(on_skeleton), (lt, lw) if styling else (0.0, 0.0), effort,
                  bool(on_skeleton) and clip.retargeted)


@dataclass(frozen=True)
class _Unplayed:
    """What is still read of a clip once its track is sequenced (outside interactions)."""

    path: object
    retargeted: bool


def _span(seg, track, choice: Choice):
    """The segment's place on the doodle's timeline with what the trajectory transfer needs
    (flags, execution stage, the clip's own travel direction, how fast it may travel:
    :func:`retarget.trajectory.travel_most` of the clip's own pace); and whether it travels."""
    from retarget.sequence import pelvis_travel
    from retarget.trajectory import Span, travel_most

    clip, action = choice.clip, choice.action
    n = clip.motion.frames
    b = clip.stages.bounds()
    execution = (b["execution"][0] / max(n - 1, 1), b["execution"][1] / max(n - 1, 1))
    travel = pelvis_travel(clip.motion, int(clip.roles["pelvis"]))  # once per clip: segments share them
    travels = not action.in_place and float(np.linalg.norm(travel)) > 0.2  # a walk, a jump
    most = travel_most(float(np.linalg.norm(travel)) / max((n - 1) * clip.motion.frame_time, 1e-9)) \
        if not action.in_place and not action.jumping else np.inf
    span = Span(seg.action, float(track.t[seg.start]), float(track.t[min(seg.end, len(track.t) - 1)]),
                seg.start, seg.end, action.in_place, action.jumping, action.cyclic, execution,
                float(np.arctan2(travel[0], travel[1])) if travels else 0.0, most)
    return span, travels


def sequenced(track, segments, choices, times, skeleton, rest, scale, terrain, origin, fps, jump_arc,
              retime, style, pin) -> "Sequenced":
    """One track's chosen clips laid on its path and sequenced on the timeline, with what
    :func:`finish` needs (the clips' contacts where ``pin``)."""
    from retarget.sequence import (Placed, blend_lengths, boundary_gaps, contact_states, entry_phase, paced,
                                   rising_blends, roll_states, sequence, shortest, stride_scale)
    from retarget.timing import flight_times, in_flight, make_room, speed_limit
    from retarget.trajectory import overspeed, world_path

    pieces, points, known = [], {}, {}
    for seg, choice in zip(segments, choices):  # one pass per clip while its forward kinematics is fresh
        span, travels = _span(seg, track, choice)
        clip = choice.clip
        cycles, driven = 0.0, None
        if span.cyclic:
            cycles = max((span.t1 - span.t0) / clip.motion.duration, 1.0)
            if travels and not span.in_place and clip.cycle_length:
                driven = np.zeros(1)  # by the distance along the path, once it is laid
        by_hand = retime == "gesture" or (style == "preferred" and choice.style != (0.0, 0.0))
        gesture = gesture_timing(track, span) if by_hand and not span.cyclic else None
        pieces.append(Placed(span, clip.motion, clip.roles["pelvis"], cycles, times, driven, travels,
                             gesture=gesture, contacts=clip.contacts))
        _prime(pieces[-1], clip)
        if len(pieces) > 1:
            points[len(pieces) - 2] = _transition_point(pieces[-2], pieces[-1], choices[len(pieces) - 2].clip, clip,
                                                         known)
    pieces = _transition_points(pieces, points)
    limits = [speed_limit(pc, _jump_travel(pc.span, track, scale)) for pc in pieces]
    before, pieces = pieces, make_room(pieces, track.t, limits, [c.clip.stages for c in choices])
    for pc, was, limit in zip(pieces, before, limits):  # what no room could be found for: played faster
        if pc is not was and pc.fitted:  # (a piece that fitted is left as it was: its need is not worked out again)
            need, given = shortest(pc.motion, pc.clip_in, pc.clip_out, limit, flight_times(pc)), pc.span.t1 - pc.span.t0
            if need > given + SQUEEZE_SAID:
                warnings.warn(f"{track.name} {pc.span.t0 - track.t[0]:.2f}–{pc.span.t1 - track.t[0]:.2f} s: "
                              f"{pc.span.action} has {given:.2f} s with what the stands around it could lend, and "
                              f"its clip needs {need:.2f} s for every joint to keep under a person's fastest: it is "
                              "played faster (a slower gesture, or a pause beside it, gives it room)")
    pieces = [replace(pc, pace=paced(pc.motion, pc.clip_in, pc.clip_out, pc.span.t1 - pc.span.t0, limit,
                                     flight_times(pc), None if pc.contacts is None else ~pc.contacts.all(axis=1)))
              if pc.fitted else pc
              for pc, limit in zip(pieces, limits)]
    pieces = [in_flight(pc) for pc in pieces]
    spans = [pc.span for pc in pieces]
    front = quat.rotate(track.q[:1], np.array([[0.0, 0.0, 1.0]]))[0]  # the figurine's front at the start
    path, heading = world_path(track.t, track.p, spans, scale, terrain, jump_arc, origin,
                               float(np.arctan2(front[0], front[2])))
    for span, asked, most, behind in overspeed(track.t, track.p, spans, scale):
        when = f"{track.name} {span.t0 - track.t[0]:.2f}–{span.t1 - track.t[0]:.2f} s"
        warnings.warn(f"{when}: the doodle jumps the character {asked:.1f} m in {span.action}, farther than its "
                      f"flight can carry it ({most:.1f} m): it lands {behind:.1f} m short (a smaller --scale keeps "
                      "to the doodle)" if span.jumping else
                      f"{when}: the doodle moves the character at up to {asked:.1f} m/s in {span.action}, faster than "
                      f"it can walk ({most:.1f} m/s): it keeps to the path but ends {behind:.1f} m behind (a smaller "
                      "--scale, or a slower doodle, keeps to it)")
    frame_path = np.column_stack([np.interp(times, track.t, path[:, k]) for k in range(3)])
    frame_heading = _eased(np.interp(times, track.t, np.unwrap(heading)), fps)
    step = np.linalg.norm(np.diff(frame_path[:, [0, 2]], axis=0), axis=1)
    for k, pc in enumerate(pieces):
        if pc.progress is not None:
            window, progress = walk_progress(times, step, pc.span.t0, pc.span.t1)
            stride = stride_scale(pc.motion, pc.pelvis, progress[-1] / max(pc.span.t1 - pc.span.t0, 1e-9))
            phase = 0.0
            if k > 0 and pieces[k - 1].progress is None:  # entered from a stand or an action
                before, feet = pieces[k - 1], [choices[k].clip.roles[f] for f in ("left_foot", "right_foot")]
                at = before.clip_out if before.clip_out is not None else before.motion.duration - before.motion.frame_time
                phase = entry_phase(before.motion, before.pelvis,
                                    [choices[k - 1].clip.roles[f] for f in ("left_foot", "right_foot")],
                                    at if before.cycles == 0 else 0.0, pc.motion, pc.pelvis, feet)
            # longer strides, faster steps
            pieces[k] = replace(pc, times=window, progress=progress / stride, phase=phase)
    gaps, rises = boundary_gaps(pieces, times, frame_path[:, [0, 2]], frame_heading, skeleton)
    blends = rising_blends(pieces, times, blend_lengths(gaps), rises)
    motion, transitions = sequence(pieces, times, frame_path[:, [0, 2]], frame_heading, skeleton, fps, blends,
                                   ground_y=frame_path[:, 1])
    used = {seg.action: (c.clip.path if c.on_skeleton else None) for seg, c in zip(segments, choices)}
    return Sequenced(motion, transitions, contact_states(pieces, times, blend=blends) if pin else None, spans,
                     frame_path, used,
                     [c.style for c in choices], [c.effort for c in choices],
                     roll_states(pieces, times, blend=blends) if pin else None)


def finish(track, tokens, segments, staged: "Sequenced", times, rest, scale, terrain, origin) -> Animation:
    """A track's sequenced motion (:func:`sequenced`) with its feet pinned in their
    contacts (where it has them: foot pinning on) and clamped to the ground, as an
    Animation. Needs none of the clips any more: they can be let go first. The sequenced
    motion's arrays are changed in place (nothing else holds them: a long track's timeline is
    not copied twice more)."""
    from retarget.feet import clamp_to_ground, pin_feet

    motion, frame_path = staged.motion, staged.path
    feet = [rest.roles["left_foot"], rest.roles["right_foot"]]
    standing, sole = _standing(rest, feet)
    if staged.contacts is not None:
        motion = pin_feet(motion, feet, terrain=terrain, contacts=staged.contacts, rolls=staged.rolls,
                          standing=standing, sole=sole, ground_y=frame_path[:, 1], in_place=True)
    motion = clamp_to_ground(motion, terrain, in_place=True)
    ranges = [(int(np.searchsorted(times, sp.t0)), int(min(np.searchsorted(times, sp.t1), len(times) - 1)))
              for sp in staged.spans]
    return Animation(track=track.name, motion=motion, segments=segments, tokens=tokens, path=frame_path,
                     transitions=staged.transitions, clips=staged.clips, roles=rest.roles, terrain=terrain,
                     frame_ranges=ranges, samples=track.p, placement=(origin, scale), styles=staged.styles,
                     efforts=staged.efforts, sample_times=track.t, sole=sole)


@dataclass(frozen=True, eq=False)
class Sequenced:
    """A track's clips sequenced on the timeline (:func:`sequenced`), before its feet are
    pinned (:func:`finish`): what that needs, without the clips themselves."""

    motion: object  # retarget.skeleton.Motion
    transitions: list
    contacts: np.ndarray | None  # (F, feet) where the clips mean the feet to stand; None: no pinning
    spans: list
    path: np.ndarray  # (F, 3) the path per frame
    clips: dict  # action -> clip path (None: the rest pose)
    styles: list
    efforts: list
    rolls: np.ndarray | None = None  # (F, feet) where a jump's feet turn on their toes in place


def walk_progress(times: np.ndarray, step: np.ndarray, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """The distance (m) travelled along the path from ``t0`` to each output time (``step``:
    the path's length between each two frames, counted where the later frame is in
    ``(t0, t1]``), over only the frames around the span: (times, distances), 0 at the
    first and the whole walk at the last, as constant outside as :func:`numpy.interp` keeps
    them — the same values as the whole timeline's running sum, in an array the span's size."""
    lo = max(int(np.searchsorted(times, t0, side="right")) - 1, 0)  # the last frame at or before t0
    hi = min(int(np.searchsorted(times, t1, side="right")), len(times) - 1)  # the first after t1
    inside = (times[lo + 1 : hi + 1] > t0) & (times[lo + 1 : hi + 1] <= t1)
    return times[lo : hi + 1], np.concatenate([[0.0], np.cumsum(np.where(inside, step[lo:hi], 0.0))])


def _standing(rest, feet: list[int]) -> tuple[list[float], float]:
    """How the library's skeleton stands on its floor (y = 0 in its clips), from the rest
    pose: each ankle's height, and the height of its feet's lowest joint or end site (the
    skeleton's sole sits this far above the floor: 0 for the built-in humanoid, 2–4 cm
    for motion capture whose foot joints are inside the shoe)."""
    from retarget.skeleton import end_site_positions, forward_kinematics

    world = forward_kinematics(rest.motion.slice(0, 1))
    ends = end_site_positions(rest.motion.slice(0, 1), world)
    lowest = []
    for ankle in feet:
        below = rest.motion.skeleton.subtree(ankle)
        lowest += [world[0][0, j, 1] for j in below] + [ends[j][0, 1] for j in below if j in ends]
    return [float(world[0][0, a, 1]) for a in feet], max(0.0, float(min(lowest)))


def _jump_travel(span, track, scale: float) -> float:
    """Metres a jumping segment's doodle travels over the ground (0 for other segments)."""
    if not span.jumping:
        return 0.0
    return float(np.linalg.norm((track.p[min(span.i1, len(track.p)) - 1] - track.p[span.i0])[[0, 2]]) * scale)


TURN_EASE_S = 0.1  # s: the standard deviation of the Gaussian a heading's changes are eased over


def _eased(heading: np.ndarray, fps: float) -> np.ndarray:
    """The character's heading per frame with its changes eased over a few frames: where
    the path's direction jumps (a walk starting from a standstill facing elsewhere) the
    body turns over about half a second instead of in one frame."""
    sigma = TURN_EASE_S * fps
    return gaussian_filter1d(heading, sigma, mode="nearest") if sigma >= 0.5 and len(heading) > 1 else heading


def _pair_placement(interaction) -> tuple[float, float, float]:
    """The placement an interaction's two-character clip shows at its first frame."""
    from retarget.bvh import read_bvh
    from retarget.pair import placement

    motions = []
    for path in interaction.pair:
        try:
            motions.append(read_bvh(path))
        except OSError as e:
            raise DoodleError(f"{path}: cannot read the two-character clip of interaction "
                              f"{interaction.name!r}: {e.strerror or e}") from None
    return placement(*motions)


MEET_DISTANCE = 0.6  # m between two interacting characters' roots without a contact to meet (§6.2.2)
HEAD_RADIUS = 0.09  # m: the head's capsule radius (retarget.qa.Limits.head): contacts meet its surface
LIMB_RADIUS = 0.05  # m: a limb's capsule radius (retarget.qa.Limits.limb)
CLEARANCE = 0.35  # m: interacting characters' roots never closer (two 10 cm trunks and room to move)
MEET_S = 0.8  # s: the shortest step in of a receiver that has walked before the interaction
WALK_SPEED = 1.0  # m/s: ... and its pace, so a longer step takes longer


def meet(doodle: Doodle, recognised: dict, scale: float, skip=frozenset(), actions: Actions | None = None) -> Doodle:
    """Interaction placement (§6.2.2, simplified): for each recognised two-character
    interaction the second character (role 1) stands in front of the first, facing it, at
    the distance where their contact joints meet (:func:`meet_distance`; else
    :data:`MEET_DISTANCE`) — measured from where both really are when role 0's part begins,
    after their earlier walks (:func:`ground_paths`). A receiver that has not walked before
    is moved and turned from the start; one that has steps in before (a minimum-jerk move in
    the doodle, read back as an implicit walk at about :data:`WALK_SPEED`). A learned
    two-handed action (``doodle learn --tracks c0,c1``: roles of one gesture, no interaction
    of the library) is played where it was performed: nothing says its characters should
    touch, and moving one would change the gesture the scene is read again by."""
    from doodle.app.placement import stand_in_front

    tracks = {tr.name: tr for tr in doodle.tracks}
    interactions = {i.name: i for i in actions.library.interactions} if actions is not None else {}
    changed = False
    for ta, a, tb, b in interaction_pairs(recognised):
        if a.interaction in skip:  # placed by its own configuration (doodle.app.placement)
            continue
        if actions is not None and a.interaction not in interactions:  # a learned two-handed action
            continue
        A, B = tracks[ta], tracks[tb]
        j = min(a.start, len(A.t) - 1)
        i = int(np.argmin(np.abs(B.t - A.t[j])))
        origin = doodle.tracks[0].p[0]
        path_a, heading_a = ground_paths(A, recognised[ta][1], actions, scale, origin)
        path_b, heading_b = ground_paths(B, recognised[tb][1], actions, scale, origin)
        want = meet_distance(interactions.get(a.interaction), a.action, b.action, actions)
        gap = (path_b[i] - path_a[j]) * [1.0, 0.0, 1.0]
        front = np.array([np.sin(heading_a[j]), 0.0, np.cos(heading_a[j])])
        if (np.linalg.norm(gap - want * front) < 0.05
                and abs((heading_b[i] - heading_a[j]) % (2 * np.pi) - np.pi) < np.radians(10)):
            continue
        still = not any(_travels(s, actions) for s in recognised[tb][1] if s.start < i)
        walk_s = max(MEET_S, float(np.linalg.norm(gap - want * front)) / WALK_SPEED)
        tracks[tb] = stand_in_front(B, i, path_a[j], heading_a[j], path_b[i], heading_b[i], want, scale, still,
                                    walk_s)
        changed = True
    return replace(doodle, tracks=tuple(tracks[tr.name] for tr in doodle.tracks)) if changed else doodle


def _travels(seg, actions: Actions | None) -> bool:
    """Whether a recognised segment moves its character (a walk, a jump)."""
    library = actions.library if actions is not None else None
    if library is None or seg.action not in library.names:
        return seg.action in ("Walk", "Walk Back", "Side Walk Left", "Side Walk Right", "Jump", "Flip")
    return not library.action(seg.action).in_place


def ground_paths(track, segments, actions: Actions | None, scale: float, origin) -> tuple[np.ndarray, np.ndarray]:
    """Where a character really stands (n, 3, world metres, the scene's ``origin`` at the
    world's) and its heading (n, radians) at each of its samples, as the compile will lay
    it: in-place actions holding their spot, walks carrying it (retarget.trajectory)."""
    from retarget.trajectory import Span, world_path

    spans = []
    for seg in segments:
        clips = actions.clips.get(seg.action, []) if actions is not None else []
        library = actions.library if actions is not None else None
        if clips and library is not None and seg.action in library.names:
            span, _ = _span(seg, track, Choice(clips[0], library.action(seg.action), True, (0.0, 0.0), None))
        else:
            span = Span(seg.action, float(track.t[seg.start]), float(track.t[min(seg.end, len(track.t) - 1)]),
                        seg.start, seg.end, not _travels(seg, actions), False, False, (0.0, 1.0), 0.0)
        spans.append(span)
    front = quat.rotate(track.q[:1], np.array([[0.0, 0.0, 1.0]]))[0]
    return world_path(track.t, track.p, spans, scale, None, "clip", origin, float(np.arctan2(front[0], front[2])))


def _contact_clips(interaction, action_a: str, action_b: str, clips: dict):
    """(clip, joint, reference frame) per role of an interaction with a contact: role 0's
    contact frame (:func:`retarget.contact.contact_frame`), and role 1's — its own contact
    frame when it acts alike (a kiss), else the frame its reaction gets under way. None
    when a role has no clip or no such joint."""
    from retarget.analysis import guess_roles
    from retarget.contact import contact_frame
    from retarget.qa import reaction_onset

    if interaction is None or len(interaction.contact) != 2:
        return None
    out = []
    for k, (clip, name) in enumerate(zip(clips, interaction.contact)):
        joint = guess_roles(clip.motion.skeleton).get(name) if clip is not None else None
        if joint is None:
            return None
        if k == 0 or action_b == action_a:
            frame = contact_frame(clip.motion, clip.stages, joint)
        else:
            lo, hi = clip.stages.bounds()["execution"]
            frame = reaction_onset(clip.motion, joint, lo, clip.motion.frames - 1)
            frame = lo if frame is None else frame
        out.append((clip, joint, frame))
    return out


def meet_distance(interaction, action_a: str, action_b: str, actions: Actions | None) -> float:
    """How far in front of role 0 role 1's root stands (m) so that, at the contact frame,
    their contact joints meet from in front: role 0's joint as far forward as its clip puts
    it then, role 1's head (say) as far forward as its clip puts it, their surfaces
    touching (:data:`HEAD_RADIUS`, :data:`LIMB_RADIUS`); never under :data:`CLEARANCE`.
    :data:`MEET_DISTANCE` for an interaction without a contact."""
    clips = [(actions.clips.get(name) or [None])[0] if actions is not None else None for name in (action_a, action_b)]
    found = _contact_clips(interaction, action_a, action_b, clips)
    if found is None:
        return MEET_DISTANCE
    (ca, ja, fa), (cb, jb, fb) = found
    oa, ob = _front_point(ca.motion, ja, fa), _front_point(cb.motion, jb, fb)
    radii = sum(HEAD_RADIUS if name == "head" else LIMB_RADIUS for name in interaction.contact)
    side = oa[0] + ob[0]  # role 1 faces role 0: its right is role 0's left
    depth = float(np.sqrt(max(radii ** 2 - side ** 2, 0.0)))
    return max(float(oa[2] + ob[2]) + depth, CLEARANCE)


def _front_point(motion, joint: int, frame: int) -> np.ndarray:
    """The farther forward of a joint and its end site (a fingertip, the top of the head)
    at ``frame``, in the clip's ground frame (right, up, front) from its start
    (retarget.contact.body_offset)."""
    from retarget.contact import body_offset, facing_frame
    from retarget.skeleton import end_site_positions, forward_kinematics

    world = forward_kinematics(motion)
    points = [body_offset(motion, joint, frame, world)]
    tip = end_site_positions(motion, world).get(joint)
    if tip is not None:
        points.append((tip[frame] - world[0][0, 0] * [1.0, 0.0, 1.0]) @ facing_frame(motion, world)[frame])
    return max(points, key=lambda p: p[2])


def _contacts(results: list, recognised: dict, interactions: dict, chosen: dict) -> tuple:
    """For each recognised interaction with a ``contact`` (e.g. the slapper's right hand and
    the other's head): the contact frame is where role 0's clip reaches farthest forward in
    its execution (:func:`retarget.contact.contact_frame`, as played); role 1's part is
    retimed so its reaction gets under way there, not before (or, acting alike — a kiss —
    so its own contact frame falls there); a hand then meets the other's joint on its
    surface, from where it comes (retarget.contact.reach). Returns the interactions as
    compiled (:class:`retarget.qa.Contact`)."""
    from retarget.contact import playing_frame, retimed
    from retarget.qa import Contact

    by_track = {r.track: k for k, r in enumerate(results)}
    out = []
    for ta, a, tb, b in interaction_pairs(recognised):
        interaction = interactions.get(a.interaction)
        ra, rb = results[by_track[ta]], results[by_track[tb]]
        ia, ib = _index_of(ra.segments, a), _index_of(rb.segments, b)
        if interaction is None or ia is None or ib is None or not ra.frame_ranges:
            continue
        choices = (chosen[ta][ia], chosen[tb][ib])
        found = _contact_clips(interaction, a.action, b.action,
                               [c.clip if c.on_skeleton else None for c in choices])
        if found is None:
            continue
        (ca, ja, fa), (cb, jb, fb) = found
        f0, f1 = ra.frame_ranges[ia]
        g0, g1 = rb.frame_ranges[ib]
        frame = playing_frame(ra.motion, ca.motion, fa, f0, f1)
        mutual = a.action == b.action
        there = playing_frame(rb.motion, cb.motion, fb, g0, g1)
        if there < frame or (mutual and there != frame):
            last = min(rb.motion.frames - 1, max(g1, frame + (g1 - there)))
            rb = replace(rb, motion=retimed(rb.motion, g0, last, there, frame))
            results[by_track[tb]] = rb
        if interaction.contact[0].endswith("_hand"):
            results[by_track[ta]] = replace(ra, motion=_touch(ra.motion, rb.motion, interaction.contact, frame))
        out.append(Contact(a.interaction, (ta, tb), tuple(interaction.contact), int(frame),
                           None if mutual else (int(g0), int(g1))))
    return tuple(out)


def _apart(results: list, recognised: dict, contacts: tuple) -> None:
    """Interacting characters' arms bent out of each other's bodies (retarget.contact.apart):
    the receiver's first (an arm meeting an arm passes under it), then role 0's (over);
    contact joints may touch."""
    from retarget.analysis import guess_roles
    from retarget.contact import apart

    by_track = {r.track: k for k, r in enumerate(results)}
    for ta, _, tb, _ in interaction_pairs(recognised):
        ka, kb = by_track[ta], by_track[tb]
        joints = next((c.joints for c in contacts if c.tracks == (ta, tb)), None)
        ra, rb = guess_roles(results[ka].motion.skeleton), guess_roles(results[kb].motion.skeleton)
        pair = (ra.get(joints[0]), rb.get(joints[1])) if joints else (None, None)
        results[kb] = replace(results[kb], motion=apart(results[kb].motion, results[ka].motion,
                                                        ((pair[1], pair[0]),) if None not in pair else (), vertical=-1.0))
        results[ka] = replace(results[ka], motion=apart(results[ka].motion, results[kb].motion,
                                                        (pair,) if None not in pair else (), vertical=1.0))


def _index_of(segments, seg) -> int | None:
    return next((k for k, s in enumerate(segments) if s is seg or (s.first, s.action) == (seg.first, seg.action)),
                None)


def _touch(motion, other, contact, frame: int, rounds: int = 4):
    """``motion``'s hand (``contact[0]``) bent to meet ``other``'s ``contact[1]`` at
    ``frame`` on its surface, coming from where the hand is: its target moved by the gap
    the animation check measures (retarget.qa.contact_gap) until they touch."""
    from retarget.analysis import guess_roles
    from retarget.contact import reach
    from retarget.qa import contact_gap
    from retarget.skeleton import forward_kinematics

    from retarget.skeleton import end_site_positions

    hand = guess_roles(motion.skeleton)[contact[0]]
    joint = guess_roles(other.skeleton).get(contact[1])
    if joint is None:
        return motion
    world = forward_kinematics(other)
    top = end_site_positions(other, world).get(joint)
    centre = world[0][frame, joint] if top is None else (world[0][frame, joint] + top[frame]) / 2
    side = contact[0].split("_")[0]
    now = forward_kinematics(motion)[0][frame, hand]
    towards = (now - centre) * [1.0, 0.0, 1.0]  # the hand comes at it level, from where it is
    towards = towards / max(float(np.linalg.norm(towards)), 1e-9)
    target = centre + (HEAD_RADIUS + LIMB_RADIUS) * towards
    out = reach(motion, target, frame, side)
    for _ in range(rounds):
        gap = contact_gap(out, other, hand, joint, frame, world_b=world)
        if abs(gap) < 0.004:
            break
        target = target - (gap + 0.002) * towards
        out = reach(motion, target, frame, side)
    return out


def gesture_timing(track, span) -> tuple[np.ndarray, np.ndarray] | None:
    """Gesture-based retiming (§5.3.3): the share of the segment's arc length the hand has
    covered at each of its sample times, ``β(t)/L`` — of the path, or of the rotation for a
    gesture that barely translates. None for a gesture that does not move."""
    seg = slice(span.i0, span.i1)
    t = track.t[seg]
    if len(t) < 2:
        return None
    steps = np.linalg.norm(np.diff(track.p[seg], axis=0), axis=1)
    if steps.sum() < 1e-3:
        q = track.q[seg]
        steps = 2 * np.arccos(np.clip(np.abs(np.sum(q[1:] * q[:-1], axis=1)), 0.0, 1.0))
    total = steps.sum()
    if not total > 0:
        return None
    return t, np.concatenate([[0.0], np.cumsum(steps)]) / total


def _quality_of(qualities: dict | None, track: str, index: int) -> tuple[float, float] | None:
    """The user's (L_t, L_w) for a segment, or None where they gave none."""
    for key in ((track, index), (track, None), (None, None)):
        if qualities and key in qualities:
            return qualities[key]
    return None


STYLE_STEP = 0.05  # recognised qualities are applied rounded to this: the model's probabilities are not
# calibrated finer (expected calibration error 0.07 Time, 0.15 Weight), and a long doodle then asks for
# a bounded number of stylised clips (each kept for the segments that share it) however long it is


def _on_grid(value: float) -> float:
    """A recognised quality rounded to :data:`STYLE_STEP` (0.0, never -0.0, for a neutral one)."""
    return round(round(value / STYLE_STEP) * STYLE_STEP, 6) + 0.0


def track_efforts(model, track, segments, given) -> list:
    """Per segment of a track, the Effort ``model`` recognises in it (laban, §4.4),
    all scored together — None without a model, where a quality is ``given`` and for an
    ``unknown`` action."""
    asked = [k for k, (seg, quality) in enumerate(zip(segments, given))
             if model is not None and quality is None and seg.action != "unknown"]
    efforts = [None] * len(segments)
    if asked:
        from laban.classify import qualities as laban_qualities

        pieces = [samples_of(track, segments[k].start, segments[k].end) for k in asked]
        for k, effort in zip(asked, laban_qualities(model, pieces)):
            efforts[k] = effort
    return efforts


def samples_of(track, start: int, end: int) -> tuple:
    """``(t, p, q)`` of samples [start, end] of a track."""
    seg = slice(start, min(end + 1, len(track.t)))
    return track.t[seg], track.p[seg], track.q[seg]


def _stylized(clip, lt: float, lw: float, style: str = "modifiers", cycle: bool = False):
    """The clip with Time then Weight applied, its stages moved with it (``style``
    "preferred": motion scale and reshaping only, the timing left to the gesture; a
    ``cycle`` gets Weight's swing and posture only)."""
    from retarget.stylize import cyclic, preferred, stylize_staged

    stages = clip.stages
    if cycle:
        motion = cyclic(clip.motion, lw)
    elif style == "preferred":
        motion = preferred(clip.motion, clip.stages, lt, lw)
    else:
        motion, stages = stylize_staged(clip.motion, clip.stages, lt, lw)
    if motion.frames == clip.motion.frames:  # poses edited in place: the feet stand when they stood
        contacts = clip.contacts
    else:  # retimed: the neutral clip's contacts carried along with its stages
        old = [0, clip.stages.preparation, clip.stages.anticipation, clip.stages.execution,
               clip.stages.follow_through, clip.motion.frames - 1]
        new = [0, stages.preparation, stages.anticipation, stages.execution, stages.follow_through, motion.frames - 1]
        at = np.interp(np.arange(motion.frames), np.maximum.accumulate(new), old)
        contacts = clip.contacts[np.clip(np.rint(at).astype(int), 0, len(clip.contacts) - 1)]
    return replace(clip, motion=motion, stages=stages, contacts=contacts)


def read_edits(path) -> dict:
    """Per-segment qualities from a JSON edit file::

        {"time": 0.5, "weight": 0.0,                      # every segment (optional)
         "segments": [{"track": "c0", "index": 5, "time": 1.0, "weight": -0.5}]}
    """
    import json
    from pathlib import Path

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise DoodleError(f"{path}: cannot read: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise DoodleError(f"{path}: not UTF-8 text ({e.reason} at byte {e.start})") from None
    except json.JSONDecodeError as e:
        raise DoodleError(f"{path}:{e.lineno}: not valid JSON: {e.msg}") from None
    except RecursionError:
        raise DoodleError(f"{path}: not valid JSON: nested too deeply") from None
    if not isinstance(data, dict):
        raise DoodleError(f"{path}: expected a JSON object with 'segments'")
    if not isinstance(data.get("segments", []), list):
        raise DoodleError(f"{path}: 'segments' must be a list of objects")
    out = {}

    def quality(entry, where):
        values = []
        for key in ("time", "weight"):
            v = entry.get(key, 0.0)
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not -1.0 <= v <= 1.0:
                raise DoodleError(f"{path}: {where}: '{key}' must be a number in [-1, 1], not {v!r}")
            values.append(float(v))
        return tuple(values)

    if "time" in data or "weight" in data:
        out[(None, None)] = quality(data, "top level")
    for i, entry in enumerate(data.get("segments", []), 1):
        if not isinstance(entry, dict) or not isinstance(entry.get("track"), str):
            raise DoodleError(f"{path}: segments #{i}: needs a 'track' name")
        index = entry.get("index")
        if index is not None and (not isinstance(index, int) or isinstance(index, bool) or index < 0):
            raise DoodleError(f"{path}: segments #{i}: 'index' must be a segment number (0, 1, …)")
        out[(entry["track"], index)] = quality(entry, f"segments #{i}")
    return out



def check_edits(path, qualities: dict, segments: dict) -> None:
    """An edit naming a track the doodle has not, or a segment its track has not, is a
    mistake (a typo, a file meant for another doodle), never silently ignored: DoodleError
    naming the edit file, the entry and what there is. ``segments`` maps each track to its
    number of segments (None: not known yet, only the tracks are checked)."""
    for track, index in qualities:
        if track is None:
            continue
        entry = f"{path}: segments entry for track {track!r}" + (f", index {index}" if index is not None else "")
        if track not in segments:
            raise DoodleError(f"{entry}: no such track (tracks: {', '.join(segments)})")
        count = segments[track]
        if index is not None and count is not None and index >= count:
            have = f"segments 0–{count - 1}" if count > 1 else ("segment 0" if count else "no segments")
            raise DoodleError(f"{entry}: track {track} has {have} (see report.json's 'index')")

def _prime(piece, clip) -> None:
    """What later passes over the pieces read of a clip, worked out now, while its forward
    kinematics is still in the recency cache (each is kept as long as the clip's motion):
    a one-shot's joint speeds (pacing, room), a distance-driven cycle's travel curve and
    stances (its phase, strides). Values only: nothing here changes the result."""
    from retarget.sequence import _frame_speeds, feet_around_pelvis, travel_curve

    if piece.cycles == 0 and piece.progress is None:
        _frame_speeds(piece.motion)
    elif piece.progress is not None:
        travel_curve(piece.motion, piece.pelvis)
        feet_around_pelvis(piece.motion, piece.pelvis, (clip.roles["left_foot"], clip.roles["right_foot"]))


def _transition_point(a, b, clip_a, clip_b, known: dict | None = None):
    """The transition point (:func:`retarget.transitions.transition_point`) from piece ``a``
    to piece ``b``, or None where neither is a one-shot or a clip is too short to have one;
    ``known``: points already found, by clip pair (the same few clips meet many times)."""
    from retarget.transitions import transition_point

    one_shot_a, one_shot_b = a.cycles == 0 and a.progress is None, b.cycles == 0 and b.progress is None
    if not (one_shot_a or one_shot_b) or a.motion.frames < 4 or b.motion.frames < 4:
        return None
    key = (id(a.motion), id(b.motion), a.pelvis, b.pelvis, clip_a.stages, clip_b.stages)
    if known is not None and key in known:
        return known[key]
    point = transition_point(a.motion, b.motion, clip_a.stages, clip_b.stages, a.pelvis, b.pelvis)
    if known is not None:
        known[key] = point
    return point


def _transition_points(pieces: list, points: dict) -> list:
    """Clip ranges between transition points (§5.3.1) for neighbouring one-shot clips
    (``points``: the point of pieces k and k + 1 at k, :func:`_transition_point`)."""
    pieces = list(pieces)
    for k in range(len(pieces) - 1):
        a, b = pieces[k], pieces[k + 1]
        found = points[k]
        if found is None:
            continue
        i, j = found
        one_shot_a, one_shot_b = a.cycles == 0 and a.progress is None, b.cycles == 0 and b.progress is None
        start = a.clip_in / a.motion.frame_time
        if one_shot_a and i - start >= 2:
            pieces[k] = replace(a, clip_out=i * a.motion.frame_time)
        if one_shot_b and b.motion.frames - 1 - j >= 2:
            pieces[k + 1] = replace(b, clip_in=j * b.motion.frame_time)
    return pieces


def _compile_skeleton(library, user, clips):
    """The skeleton of the output (the user library's own clips' when it has any, else the
    built-in humanoid) and a rest clip on it, played for actions that have no clip on that
    skeleton: its Idle (the library's own, else the retargeted built-in one), else the
    held first frame of its first clip."""
    from retarget.analysis import Stages

    mine = [c for a in (user.actions if user else ()) for c in clips.get(a.name, []) if not c.retargeted]
    pool = mine or [c for found in clips.values() for c in found]
    if not pool:
        raise DoodleError(f"{library.source}: no action has a clip to animate")
    skeleton = pool[0].motion.skeleton
    same = [c for c in pool if c.motion.skeleton.names == skeleton.names]
    idles = [c for c in clips.get("Idle", []) if c.motion.skeleton.names == skeleton.names]
    base = min(idles, key=lambda c: c.retargeted) if idles else same[0]
    if base.action == "Idle":
        return skeleton, base
    still = base.motion.slice(0, 1)
    still = replace(still, translations=np.repeat(still.translations, 2, axis=0),
                     rotations=np.repeat(still.rotations, 2, axis=0))
    rest = replace(base, motion=still, stages=Stages(0, 0, 1, 1, 2), cycle_length=None,
                    contacts=np.ones((2, 2), dtype=bool))
    return skeleton, rest


def quality(result: Animation, world: tuple | None = None) -> dict:
    """Report metrics: ground penetration, root deviation from the path, transition
    smoothness. (Sliding feet, pops and the rest are the animation check's: retarget.qa.)
    ``world``: the motion's forward kinematics, where already worked out."""
    roles = result.roles
    from retarget.skeleton import end_site_positions, forward_kinematics

    motion = result.motion
    world = forward_kinematics(motion) if world is None else world
    positions = world[0]
    ends = end_site_positions(motion, world)
    block = 4096  # frames at once: a long motion's (F, points, 3) is never copied whole

    def below(a: int) -> float:  # the lowest point's height above the ground in frames [a, a + block)
        points = np.concatenate([positions[a:a + block]] + [e[a:a + block, None] for e in ends.values()], axis=1)
        ground = 0.0 if result.terrain is None else result.terrain.height(points[:, :, [0, 2]])
        return float(np.min(points[:, :, 1] - ground))

    lowest = min(below(a) for a in range(0, motion.frames, block))
    pelvis = positions[:, roles["pelvis"]]
    deviation = float(np.mean(np.linalg.norm(pelvis[:, [0, 2]] - result.path[:, [0, 2]], axis=1)))
    acc = np.concatenate([np.linalg.norm(np.diff(positions[a:a + block + 2], n=2, axis=0), axis=2).max(axis=1)
                          for a in range(0, max(motion.frames - 2, 0), block)] or [np.zeros(0)]) / motion.frame_time ** 2
    times = np.arange(motion.frames) * motion.frame_time
    inner = times[1:-1]
    near = np.zeros(len(acc), dtype=bool)
    for b in result.transitions:  # only the frames around each transition looked at
        lo, hi = np.searchsorted(inner, [b - 0.2, b + 0.2])
        near[lo:hi] |= np.abs(inner[lo:hi] - b) <= 0.15
    smooth = float(acc[near].max() / max(acc[~near].max(), 1e-9)) if near.any() and (~near).any() else None
    return {"ground_penetration_m": round(max(0.0, -lowest), 4),
            "root_deviation_m": round(deviation, 4),
            "transition_smoothness": None if smooth is None else round(smooth, 3)}
