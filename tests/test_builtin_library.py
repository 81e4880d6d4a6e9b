"""The built-in library as shipped: manifest and generated clip index agree, every clip
loads with its stages, and the contact sheet draws them."""

import tomllib
from pathlib import Path

import pytest

from doodle.app.cli.main import main
from library.manifest import BUILTIN, builtin
from retarget.clips import load_clips


def test_manifest_matches_the_generated_clip_index():
    """library/builtin/make_clips.py writes clips.toml; its clips, stages and cycle lengths
    must have been merged into library.toml."""
    index = tomllib.loads((BUILTIN / "clips.toml").read_text())
    lib = builtin()
    for entry in index["actions"]:
        action = lib.action(entry["name"])
        assert [Path(c).name for c in action.clips] == [Path(c).name for c in entry["clips"]], entry["name"]
        assert list(action.stages) == entry["stages"], entry["name"]
        assert action.cycle_length == entry.get("cycle_length"), entry["name"]
    assert lib.roles == index["skeleton"]


def test_every_action_and_interaction_clip_loads_with_stages():
    lib = builtin()
    clips = load_clips(lib)
    assert set(clips) == set(lib.names) and len(clips) == 31
    for name, (clip,) in clips.items():
        b = clip.stages.bounds()
        assert 0 < b["execution"][1] - b["execution"][0], name
        assert clip.stages.transition == clip.motion.frames
        if lib.action(name).cyclic and name != "Idle":
            assert clip.cycle_length > 0.3, name
    assert {i.name for i in lib.interactions} == {"Slap", "Kiss"}


def test_library_sheet_draws_every_clip(tmp_path, capsys):
    out = tmp_path / "sheet.png"
    assert main(["library", "sheet", "-o", str(out)]) == 0
    assert "31 clips" in capsys.readouterr().out
    import matplotlib.image as mpimg

    image = mpimg.imread(out)
    assert image.shape[0] > 1000 and image.shape[1] > 500
    ink = (image[..., :3].mean(axis=2) < 0.5).mean()
    assert 0.002 < ink < 0.3  # figures are drawn, the page is not blank nor black


def test_library_show_and_list(capsys):
    assert main(["library", "show", "Walk"]) == 0
    out = capsys.readouterr().out
    assert "(T_Z | T_X_Z | T_N_X_Z)+" in out and "cyclic" in out and "stages: preparation 0-8" in out
    assert main(["library", "list"]) == 0
    assert len(capsys.readouterr().out.strip().splitlines()) == 28  # the recognisable actions
    assert main(["library", "show", "Fly"]) == 1
    assert "no action 'Fly'" in capsys.readouterr().err


THESIS = Path(__file__).resolve().parents[2] / "shared" / "seeds" / "spatial-motion-doodles-thesis.txt"
# the text's two unreadable tokens, as the library reads them: Despair's "T N G" is T_N_Y (a
# hand sinking), Dodge's "T N G B" is T_N_X_N_Y (the diagonal back down that its other groups use)
OCR = {"T_N_G": "T_N_Y", "T_N_G_B": "T_N_X_N_Y"}


@pytest.mark.skipif(not THESIS.exists(), reason="../shared/seeds is not here")
def test_every_expression_has_the_appendix_tokens_in_order():
    """The 28-action table against thesis Appendix 2: each reconstructed expression holds
    exactly the tokens the appendix prints for the action, in the same order — what was
    guessed (where wrapped lines join, a stray parenthesis) is only the grouping, and each
    guess is written in the action's ``note``."""
    import re

    text = THESIS.read_text()
    block = text[text.index("Appendix 2: Animation Database"):][:12000]
    actions = tomllib.loads((Path(BUILTIN) / "library.toml").read_text())["actions"]
    starts = sorted((m.start(), a["name"]) for a in actions
                    if (m := re.search(r"(?m)^" + re.escape(a["name"]) + r"\b", block)))
    assert len(starts) == 28
    for k, (at, name) in enumerate(starts):
        end = starts[k + 1][0] if k + 1 < len(starts) else at + 800
        printed = [OCR.get(t, t) for t in (t.replace(" ", "_") for t in re.findall(r"T(?:\s(?:N\s)?[XYZGB])+",
                                                                                      block[at + len(name):end]))]
        expression = next(a for a in actions if a["name"] == name).get("expression", "")
        ours = re.findall(r"T(?:_(?:N_)?[XYZ])+", expression)
        if name != "Idle":
            assert ours == printed, name
