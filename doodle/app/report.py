"""What the CLI reports, in one place: ``report.json`` of ``doodle compile`` and the segments
of ``doodle recognize --json`` (their shapes are tested in ``tests/test_report.py``).

Times are seconds from the first sample; a segment is ``{track?, index?, action, start, end,
exact, distance, interaction, role, …, tokens}`` where ``interaction`` and ``role`` are null
unless the segment plays a role in an interaction, and a refused action carries
``refused`` and ``reason``.
"""

from __future__ import annotations

from grammar.contexter import InteractionSegment, Refused


def seconds_of(doodle):
    """Sample index → seconds from the first sample (an end index past the last sample
    gives the last sample's time); ``doodle`` may also be an array of sample times."""
    t = doodle.t if hasattr(doodle, "t") else doodle
    last = len(t) - 1
    return lambda i: round(float(t[min(i, last)] - t[0]), 6)


def segment_entry(s, seconds, tokens) -> dict:
    """One segment: its action, span, how it matched, its interaction role and tokens."""
    role = (s.interaction, s.role) if isinstance(s, InteractionSegment) else (None, None)
    entry = {"action": s.action, "start": seconds(s.start), "end": seconds(s.end), "exact": s.exact,
             "distance": s.distance, "interaction": role[0], "role": role[1]}
    if isinstance(s, Refused):
        entry.update(refused=s.refused, reason=s.reason)
    entry["samples"] = [s.start, s.end]
    entry["tokens"] = [k.name for k in tokens[s.first:s.stop]]
    return entry


def recognized(path, doodle, result: dict) -> dict:
    """``doodle recognize --json`` for one file: every track's segments in order."""
    seconds = seconds_of(doodle)
    return {"file": str(path),
            "segments": [{"track": name, **segment_entry(s, seconds, toks)} for name, (toks, segs) in result.items()
                         for s in segs]}


def effort_entry(effort) -> dict | None:
    """What the effort model said about a segment (None: given by the user, or not asked)."""
    if effort is None:
        return None
    return {"time": effort.time, "weight": effort.weight, "p_sudden": round(effort.p_sudden, 3),
            "p_strong": round(effort.p_strong, 3), "time_confidence": round(effort.time_confidence, 3),
            "weight_confidence": round(effort.weight_confidence, 3), "drive": effort.drive, "state": effort.state}


def compiled(file, fps: float, terrain: str | None, results: list, bvh_paths: dict, metrics: dict,
             checks: dict | None = None) -> dict:
    """``report.json`` of ``doodle compile``: per track its BVH, segments (with the clip
    used, the Laban quality applied and what the effort model said), transitions,
    motion-quality metrics and the animation check (:mod:`retarget.qa`); and the scene's
    interactions as compiled (``interactions``: what ``doodle qa`` checks contacts with)."""
    report = {"file": str(file), "fps": fps,
              "duration_s": round(float(results[0].sample_times[-1] - results[0].sample_times[0]), 6),
              "terrain": terrain or "flat", "tracks": {}}
    for r in results:
        seconds = seconds_of(r.sample_times)  # the compiled timeline (placement may insert walks)
        segments = []
        for i, s in enumerate(r.segments):
            entry = segment_entry(s, seconds, r.tokens)
            del entry["samples"]
            entry = {"index": i, **entry, "clip": r.clips.get(s.action), "time": r.styles[i][0],
                     "weight": r.styles[i][1], "effort": effort_entry(r.efforts[i])}
            entry["tokens"] = entry.pop("tokens")
            segments.append(entry)
        report["tracks"][r.track] = {"bvh": str(bvh_paths[r.track]), "frames": r.motion.frames,
                                     "sole_m": round(float(r.sole), 4), "segments": segments,
                                     "transitions": [round(b, 6) for b in r.transitions],
                                     "metrics": metrics[r.track]}
        if checks is not None:
            report["tracks"][r.track]["check"] = checks[r.track].figures()
    report["interactions"] = [contact_entry(c) for c in (results[0].contacts if results else ())]
    return report


def contact_entry(c) -> dict:
    """One interaction as compiled (retarget.qa.Contact): its tracks by role, contact joints,
    contact frame and, when role 1 reacts, its reaction's first and last frames."""
    return {"interaction": c.interaction, "tracks": list(c.tracks), "contact": list(c.joints), "frame": int(c.frame),
            "reaction": None if c.reaction is None else [int(f) for f in c.reaction]}


def read_contacts(report: dict, where: str) -> tuple:
    """The interactions of a report.json (:func:`contact_entry`) back as
    retarget.qa.Contact; a malformed entry is a DoodleError naming it."""
    from doodle.core.errors import DoodleError
    from retarget.qa import Contact

    entries = report.get("interactions", [])
    if not isinstance(entries, list):
        raise DoodleError(f"{where}: 'interactions' must be a list")
    out = []
    for k, e in enumerate(entries, 1):
        try:
            tracks, joints, frame = e["tracks"], e["contact"], e["frame"]
            reaction = e.get("reaction")
            ok = (len(tracks) == 2 and len(joints) == 2 and all(isinstance(x, str) for x in [*tracks, *joints])
                  and isinstance(frame, int) and not isinstance(frame, bool) and frame >= 0
                  and (reaction is None or (len(reaction) == 2 and all(isinstance(f, int) for f in reaction))))
        except (KeyError, TypeError, AttributeError):
            ok = False
        if not ok:
            raise DoodleError(f"{where}: interactions #{k}: needs 'tracks' and 'contact' (two names each), "
                              f"'frame' (a frame number) and 'reaction' (null or [first, last])")
        out.append(Contact(str(e.get("interaction", "")), tuple(tracks), tuple(joints), frame,
                           None if reaction is None else tuple(reaction)))
    return tuple(out)
