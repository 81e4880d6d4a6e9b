"""Two characters who respect each other's bodies (§6.2.2): placed from where they really are
when the interaction begins, facing each other; no interpenetration; the contact met by the
slapping hand from in front; the reaction timed to the hit — on generated two-track scenes
(Slap alone, Kiss, a walk-up–slap–step-back story) in several layouts."""

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.app.pipeline import compile_doodle
from doodle.synth.strokes import stroke, synth_doodle
from retarget.analysis import guess_roles
from retarget.qa import Contact, Limits, check_scene
from retarget.skeleton import forward_kinematics

KISS = ["T_N_Z", "T_Z", "T_N_Z", "T_Z"]


def _yaw(degrees):
    return tuple(Rotation.from_euler("y", degrees, degrees=True).as_quat())


def _scene(a, b, where, turn=180.0, seed=1):
    """c0 at the origin facing +z performing ``a``; c1 at ``where`` (prop metres) turned
    ``turn`` degrees, performing ``b``."""
    def strokes(words):
        return [stroke("T_STILL", 0.4)] + [stroke(w, 0.3) for w in words] + [stroke("T_STILL", 0.5)]

    return synth_doodle({"c0": strokes(a), "c1": strokes(b)}, seed=seed,
                        start_p={"c0": (0.0, 1.0, 0.0), "c1": (where[0], 1.0, where[1])},
                        start_q={"c0": (0.0, 0.0, 0.0, 1.0), "c1": _yaw(turn)})


SCENES = {
    "slap": (["T_N_Z", "T_Z"], [], (0.0, 0.3), 180.0, 1),
    "slap, B to the right, turned": (["T_N_Z", "T_Z"], [], (-0.12, 0.25), 160.0, 3),
    "slap, B to the left": (["T_N_Z", "T_Z"], [], (0.1, 0.32), 200.0, 4),
    "kiss": (KISS, KISS, (0.0, 0.15), 180.0, 2),
    "walk up, slap, step back": (["T_Z", "T_Z", "T_Z", "T_STILL", "T_N_Z", "T_Z", "T_STILL", "T_N_Z", "T_N_Z"], [],
                                 (0.0, 0.6), 180.0, 1),
    "walk up from farther, B off to the side": (["T_Z", "T_Z", "T_Z", "T_Z", "T_STILL", "T_N_Z", "T_Z", "T_STILL",
                                                 "T_N_Z", "T_N_Z"], [], (0.08, 0.75), 190.0, 5),
}
_CACHE = {}


def compiled(name):
    if name not in _CACHE:
        a, b, where, turn, seed = SCENES[name]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            results = compile_doodle(_scene(a, b, where, turn, seed))
        _CACHE[name] = results
    return _CACHE[name]


def _check(results):
    return check_scene({r.track: r.motion for r in results}, contacts=results[0].contacts)


@pytest.mark.parametrize("name", list(SCENES))
def test_no_interpenetration(name):
    checks = _check(compiled(name))
    assert not any(checks["c0"].touching.values()), checks["c0"].touching


@pytest.mark.parametrize("name", list(SCENES))
def test_the_interaction_is_compiled_and_its_contact_met(name):
    results = compiled(name)
    (contact,) = results[0].contacts
    assert contact.tracks == ("c0", "c1")
    checks = _check(results)
    assert not checks["c0"].missed and abs(checks["c0"].gap) <= Limits().contact, checks["c0"].gap
    if contact.joints == ("head", "head"):  # a kiss: the heads touch, neither sinks into the other
        assert -Limits().touch <= checks["c0"].gap <= 0.02


@pytest.mark.parametrize("name", [n for n in SCENES if n != "kiss"])
def test_the_reaction_does_not_lead_the_hit(name):
    results = compiled(name)
    (contact,) = results[0].contacts
    assert contact.reaction is not None
    assert not _check(results)["c1"].leads


@pytest.mark.parametrize("name", [n for n in SCENES if n != "kiss"])
def test_the_hand_reaches_the_head_from_in_front(name):
    a, b = compiled(name)
    frame = a.contacts[0].frame
    positions, rotations = forward_kinematics(a.motion)
    roles = guess_roles(a.motion.skeleton)
    front = Rotation.from_quat(rotations[frame, 0]).apply([0.0, 0.0, 1.0]) * [1.0, 0.0, 1.0]
    front /= np.linalg.norm(front)
    hand, chest = positions[frame, roles["right_hand"]], positions[frame, roles["chest"]]
    assert (hand - chest) @ front > 0.25  # well in front of the slapper's chest, not over its shoulder
    head = forward_kinematics(b.motion)[0][frame, guess_roles(b.motion.skeleton)["head"]]
    assert (head - chest) @ front > 0.3  # the other stands in front of the slapper


@pytest.mark.parametrize("name", list(SCENES))
def test_they_face_each_other_at_the_contact(name):
    a, b = compiled(name)
    frame = a.contacts[0].frame
    fronts = [Rotation.from_quat(forward_kinematics(r.motion)[1][frame, 0]).apply([0.0, 0.0, 1.0]) * [1, 0, 1]
              for r in (a, b)]
    fronts = [f / np.linalg.norm(f) for f in fronts]
    assert fronts[0] @ fronts[1] < -0.94  # within 20° of face to face


def test_a_reaction_that_leads_and_a_missed_contact_are_found():
    """The check is able to fail: the same Slap with its contact said to be 12 frames later
    finds the reaction leading it, and with the heads named as the contact, a miss."""
    results = compiled("slap")
    c = results[0].contacts[0]
    motions = {r.track: r.motion for r in results}
    late = check_scene(motions, contacts=(Contact(c.interaction, c.tracks, c.joints, c.frame + 12, c.reaction),))
    assert late["c1"].leads and not late["c1"].passes
    wrong = check_scene(motions, contacts=(Contact(c.interaction, c.tracks, ("head", "head"), c.frame, None),))
    assert wrong["c0"].missed == (c.frame,) and wrong["c0"].gap > 0.1
