"""Chapter V claim rows judged on stand-in runs (no simulation)."""

from types import SimpleNamespace

import numpy as np

from design.reproduce.grasp_rows import BACK_OFF, pushed_back


def run(xs, fx=-1.0, jammed=False):
    """A run whose centre X goes through ``xs`` (m), one per 0.5 s, with one
    finger (finger 3) pushing along X by ``fx`` (N) throughout; ``jammed``:
    a finger passed its fold force."""
    finger = SimpleNamespace(force=np.array([fx, 0.0, 0.0]))
    records = [SimpleNamespace(y=np.array([x, 0.07, 0.0]), t=0.5 * k, fingers=[finger])
               for k, x in enumerate(xs)]
    grasper = SimpleNamespace(fingers=[SimpleNamespace(design_name="3")])
    return SimpleNamespace(trajectory=SimpleNamespace(records=records),
                           setup=SimpleNamespace(duration=1.6, grasper=grasper),
                           summary={"centre_rise_m": 0.01, "max_pitch_rad": 0.1,
                                    "max_finger_force_N": 9.0, "max_finger_force_finger": "4a",
                                    "jammed": jammed, "jam": ["finger 5a past its fold force"]
                                    if jammed else []})


def test_pushed_back_holds_only_when_the_first_fails_and_the_others_pass():
    """Figures 5-17 and 5-18: the first setting pushed back (more than
    BACK_OFF behind its furthest X), every other past the drum axis without
    a jam; the note (why ours disagrees) only where it does."""
    back = run([-0.3, -0.1, -0.1 - 2 * BACK_OFF])
    through = run([-0.3, 0.0, 0.2])
    named = {"µ = 0": "back", "µ = 0.4": "through", "µ = 1.16": "also"}
    row = pushed_back({"back": back, "through": through, "also": through}, "Fig", "friction",
                      named, note="Unresolved.")
    assert row.agrees and row.thesis == "pushed back at µ = 0; passes at µ = 0.4 and µ = 1.16"
    assert "Unresolved" not in row.explanation and "Jams" not in row.explanation
    jammed = pushed_back({"back": back, "through": through,
                          "also": run([-0.3, 0.0, 0.2], jammed=True)}, "Fig", "friction", named,
                         note="Unresolved.")
    assert not jammed.agrees and jammed.explanation.endswith("Unresolved.")
    assert "Jams: µ = 1.16: finger 5a past its fold force." in jammed.explanation
    # both drums' -1 N for 1 s
    assert "µ = 0 -2.000 N s" in row.explanation
    assert not pushed_back({"back": through, "through": through, "also": through}, "Fig",
                           "friction", named).agrees
    assert not pushed_back({"back": back, "through": through, "also": back}, "Fig",
                           "friction", named).agrees
