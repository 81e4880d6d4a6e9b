"""The shapes of what the CLI reports (doodle.app.report): ``report.json`` of ``doodle
compile`` and ``doodle recognize --json`` — the keys scripts rely on, and their types."""

import json
from pathlib import Path

from doodle.app.cli.main import main

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
SEGMENT = {"action": str, "start": float, "end": float, "exact": bool, "interaction": (str, type(None)),
           "role": (int, type(None)), "tokens": list}


def _typed(entry, shape):
    for key, kind in shape.items():
        assert key in entry, key
        value = entry[key]
        assert isinstance(value, kind) or (kind is float and isinstance(value, int)), (key, value)


def test_recognize_json_shape(capsys):
    assert main(["recognize", "--json", str(DEMO)]) == 0
    line = json.loads(capsys.readouterr().out)
    assert set(line) == {"file", "segments"}
    for s in line["segments"]:
        _typed(s, {"track": str, **SEGMENT, "samples": list})
        assert s["start"] <= s["end"] and (s["distance"] is None) == (s["action"] == "unknown")


def test_compile_report_shape(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["compile", str(DEMO), "-o", str(out), "--no-effort"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert set(report) == {"file", "fps", "duration_s", "terrain", "tracks", "interactions"}
    assert report["interactions"] == []  # one character: no interaction, no contact
    track = report["tracks"]["c0"]
    assert set(track) == {"bvh", "frames", "sole_m", "segments", "transitions", "metrics", "check"}
    assert isinstance(track["check"]["passes"], bool) and isinstance(track["check"]["sliding_frames"], list)
    assert isinstance(track["check"]["contacts_missed"], list) and isinstance(track["check"]["reaction_lead_frames"], list)
    assert Path(track["bvh"]).exists() and track["frames"] > 0
    assert set(track["metrics"]) >= {"ground_penetration_m", "root_deviation_m",
                                     "transition_smoothness"}
    for i, s in enumerate(track["segments"]):
        _typed(s, {"index": int, **SEGMENT, "time": float, "weight": float})
        assert s["index"] == i and "clip" in s and "effort" in s
