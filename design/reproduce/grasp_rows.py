"""Chapter V (Figures 5-5 to 5-20) against the thesis's statements.

Every run uses the spatial finger model (design.reproduce.grasp.VALIDATION_MODEL),
the Table 5-1 layout as printed and a solid belt (docs/MODEL.md, "Finger
layout"); the football is also run over fingers 1 and 2's tilt and the drum
phase, which the thesis does not print, and mean bird and football with
finger 5 through a slotted pallet, as context; the mean bird is also run
with the planar model, to show what that model says and how far outside its
validity it is, and mean bird and football with the thesis's own model (planar
fingers with its chapter III friction convention, ``planar-thesis``), to show
which of its statements that model makes. The thesis gives mostly trends and
readings of plots; each becomes a claim row with the criterion it is judged
by, or a numeric row whose tolerance is fixed by how the thesis states the
number (a reading "of the order of", "around": 30 %). SI: m, N, s, rad.
"""

from __future__ import annotations

from dataclasses import replace
from functools import partial

import numpy as np

from design.physics.bird import G
from design.physics.kinematics import rot_y
from design.reproduce.figures import finger_force_x_figure, path_figure, transverse_figure
from design.reproduce.grasp import (SIZES_START, football_setup, mean_bird_setup, simulate_all,
                                    sizes_setup, slotted)
from design.reproduce.rows import (THESIS_MEASUREMENT, Row, Section, claim, compare,
                                   context)
from design.solvers.grasp.simulation import GraspRun
from design.solvers.grasp.validity import validity_problems

TITLE = "Chapter V: grasp simulations (Figures 5-5 to 5-20)"
HARD, SOFT, CONSTANT = ("mean bird, hard lower fingers", "mean bird, soft lower fingers",
                        "mean bird, constant EI")
PLANAR_HARD, PLANAR_SOFT = (f"{HARD}, planar model", f"{SOFT}, planar model")
#: Table 5-3's start as printed: the bird placed at X0 = -0.075 m at t = 0
PLACED = ", placed at X0 = -0.075 m at t = 0"
SOFT_PLACED, CONSTANT_PLACED = SOFT + PLACED, CONSTANT + PLACED
#: the soft case with the finger friction off (the belt's kept): how much of
#: the peak the drums' sweep friction makes
SOFT_FRICTIONLESS = f"{SOFT}, frictionless fingers"
#: the thesis's own model: planar fingers with its chapter III friction convention
THESIS_MODEL = "planar-thesis"
OWN = ", the thesis's own model"
THESIS_SOFT, THESIS_HARD, THESIS_CONSTANT = SOFT + OWN, HARD + OWN, CONSTANT + OWN
FOOTBALL = "football (Table 5-4), µ = 1.16"
#: the thesis prints no pallet: finger 5 passing through slots cut for it
SLOTTED = ", finger 5 through a slotted pallet"
SOFT_SLOTTED, FOOTBALL_SLOTTED = SOFT + SLOTTED, FOOTBALL + SLOTTED
#: the football's spread over what the thesis does not print: fingers 1 and
#: 2's φy (deg) and the drums' phase from the designed one (deg)
SPREAD_TILTS, SPREAD_PHASES = (-25.0, -15.0, -5.0), (-20.0, 0.0, 20.0)
FIGURE_5_16, FIGURE_5_17, FIGURE_5_18 = (
    "Figure 5-16, football", "Figure 5-17, football from X0 = -0.381 m",
    "Figure 5-18, football from X0 = -0.381 m")
BIRDS = ("small_1_20kg", "mean_1_66kg", "mean_1_80kg", "large_2_05kg", "large_2_30kg")
#: Figure 5-7: forces 'concentrate densely' from -1.5 to +1.5 in of the drums (m)
DENSE = 0.0381
#: the thesis's numbers: Figure 5-7 peak (N), Figure 5-13 rise (m), §5.3's
#: finger 4 estimate (N), Figure 5-19 height (m)
PEAK_MEAN, RISE_FOOTBALL, PEAK_FOOTBALL, HEIGHT_MEAN = 11.0, 0.018, 8.5, 0.080
#: the thesis states these as readings ("of the order of", "around"): 30 %
READING_REL = 0.3
#: Figure 5-19's Z grid is 10 mm: half of it
HEIGHT_TOL = 0.005
#: 'passes the grasper': ends past the drum axis, and never backs off more than this (m)
BACK_OFF = 0.01
#: wall time allowed per run (s): each run takes 2-30 s of CPU time (the
#: football runs the longest), so this only stops a run that has gone wrong;
#: one it stops is reported as not finished
RUN_BUDGET = 360.0
#: the same for the football's spread over unprinted settings (context): a run
#: whose fingers clamp the ball past their fold force crawls on (tiny steps
#: through the nearly singular contact), and the table shows it as far as it got
SPREAD_BUDGET = 150.0


def football_far(label: str) -> str:
    return f"football from X0 = -0.381 m, {label}"


def spread_name(tilt: float, phase: float) -> str:
    """The run of the football's spread with fingers 1 and 2 at φy = ``tilt``
    and the drums turned on by ``phase`` (deg); Table 5-1's tilt at the
    designed phase is the football run itself."""
    if (tilt, phase) == (-15.0, 0.0):
        return FOOTBALL
    return f"{FOOTBALL}, fingers 1 and 2 at φy = {tilt:g}°, drums turned {phase:+g}°"


#: Figure 5-17's µ = 0 read as eq. 4.40's one µ: fingers and belt frictionless
ONE_MU = football_far("µ = 0 on fingers and belt")
#: the Figure 5-17/5-18 rows' status, and where the candidate causes measured
#: for them are reported
UNRESOLVED = ("An unresolved disagreement with the thesis's simulation (its experiment "
              "measured no such trend). Candidate causes measured: the drum phase over a whole "
              "set period (examples/validation/football_phase.py), the finger friction "
              "(friction_sensitivity.py); docs/MODEL.md, 'Validation status', gives what each "
              "shows.")


def setups() -> dict:
    """Every chapter V run's setup, by name."""
    out = {HARD: mean_bird_setup("hard"), SOFT: mean_bird_setup("soft"),
           CONSTANT: mean_bird_setup("constant"),
           PLANAR_HARD: mean_bird_setup("hard", "planar"),
           PLANAR_SOFT: mean_bird_setup("soft", "planar"),
           SOFT_PLACED: mean_bird_setup("soft", arriving=False),
           SOFT_FRICTIONLESS: replace(mean_bird_setup("soft"), finger_friction=0.0),
           THESIS_SOFT: mean_bird_setup("soft", THESIS_MODEL),
           THESIS_HARD: mean_bird_setup("hard", THESIS_MODEL),
           THESIS_CONSTANT: mean_bird_setup("constant", THESIS_MODEL),
           FOOTBALL + OWN: football_setup(model=THESIS_MODEL),
           CONSTANT_PLACED: mean_bird_setup("constant", arriving=False),
           FOOTBALL: football_setup(),
           SOFT_SLOTTED: slotted(mean_bird_setup("soft")),
           FOOTBALL_SLOTTED: slotted(football_setup())}
    out.update({spread_name(t, p): football_setup(upper_tilt=t, phase=p)
                for t in SPREAD_TILTS for p in SPREAD_PHASES})
    out.update({football_far(f"finger µ = {mu:g}"): football_setup(SIZES_START, mu)
                for mu in (0.0, 0.4, 1.16)})
    out.update({football_far(f"finger 3 φx = {deg:g}°"): football_setup(SIZES_START, 1.16, deg)
                for deg in (45.0, 70.0)})
    out[ONE_MU] = replace(football_setup(SIZES_START, 0.0), conveyor_friction=0.0)
    out.update({f"Table 5-5: {b}": sizes_setup(b) for b in BIRDS})
    return out


def compute(progress=None) -> dict[str, GraspRun]:
    """Every chapter V run, by name, finished or not (:func:`failures`)."""
    every = setups()
    spread = {spread_name(t, p) for t in SPREAD_TILTS for p in SPREAD_PHASES} - {FOOTBALL}
    runs = simulate_all({k: v for k, v in every.items() if k not in spread}, progress, RUN_BUDGET)
    runs.update(simulate_all({k: every[k] for k in every if k in spread}, progress,
                             SPREAD_BUDGET))
    return runs


def stopped(run: GraspRun) -> bool:
    """Whether the run ended before its duration: failed, or stopped by its budget."""
    return not run.trajectory.ok


def failures(runs: dict[str, GraspRun]) -> list[str]:
    """The runs that failed (not those their wall-time budget stopped), in words."""
    return [f"grasp run '{k}' failed: {r.summary['message']}" for k, r in runs.items()
            if not r.trajectory.ok and not r.trajectory.out_of_time]


def _series(run: GraspRun, index: int) -> np.ndarray:
    return np.array([r.y[index] for r in run.trajectory.records])


def x_end(run: GraspRun) -> float:
    """Centre X at the end of the run, m."""
    return float(run.trajectory.records[-1].y[0])


def back_off(run: GraspRun) -> float:
    """Largest distance the centre ever moved back from its furthest X, m."""
    x = _series(run, 0)
    return float(np.max(np.maximum.accumulate(x) - x))


def passes(run: GraspRun) -> bool:
    """Through the grasper: past the drum axis at the end, never pushed back."""
    return x_end(run) > 0.0 and back_off(run) <= BACK_OFF


def clears(run: GraspRun) -> bool:
    """Passes and does not jam (no finger past its fold force, carried on)."""
    return passes(run) and not run.summary["jammed"]


def z_max(run: GraspRun) -> float:
    """Highest centre Z, m."""
    return float(_series(run, 1).max())


def family(run: GraspRun, name: str) -> str:
    """The designed finger (Table 5-1's number) of a mounted finger name."""
    return next(gf.design_name for gf in run.setup.grasper.fingers if gf.name == name)


def family_peaks(run: GraspRun) -> dict[str, float]:
    """Largest force (N) of each designed finger (Table 5-1's number) over its sets."""
    out: dict[str, float] = {}
    for name, force in run.summary["max_force_per_finger_N"].items():
        key = family(run, name)
        out[key] = max(out.get(key, 0.0), float(force))
    return dict(sorted(out.items()))


def near_reading(value: float, reading: float) -> bool:
    """Within READING_REL of a number the thesis gives as a reading."""
    return abs(value - reading) <= READING_REL * reading


def meets_figure_5_7(run: GraspRun) -> bool:
    """Figure 5-7's mean bird: fingers 1, 2, 4, 5 touch and the peak is finger
    4's, about 11 N."""
    return touching(run) == "1, 2, 4, 5" and peak_family(run) == "4" \
        and near_reading(run.summary["max_finger_force_N"], PEAK_MEAN)


def touched(run: GraspRun) -> set[str]:
    """Table 5-1's numbers of the fingers that touched."""
    return {k for k, force in family_peaks(run).items() if force > 0}


def touching(run: GraspRun) -> str:
    """The fingers that touched as text, e.g. '1, 2, 4, 5'."""
    return ", ".join(sorted(touched(run)))


def peak_family(run: GraspRun) -> str:
    return family(run, run.summary["max_finger_force_finger"])


def lift_x(run: GraspRun) -> float | None:
    """Centre X where the first N = 0 window starts, m (None: never lifted)."""
    windows = run.summary["hold_windows"]
    if not windows:
        return None
    t = np.array([r.t for r in run.trajectory.records])
    return float(np.interp(windows[0][0], t, _series(run, 0)))


def impulse_share(run: GraspRun, where) -> float:
    """Share of the fingers' force-time integral delivered where ``where(record)``."""
    recs = run.trajectory.records
    t = np.array([r.t for r in recs])
    force = np.array([sum(f.magnitude for f in r.fingers) for r in recs])
    inside = np.array([where(r) for r in recs], float)
    return float(np.trapezoid(force * inside, t) / np.trapezoid(force, t))


def net_lift(run: GraspRun) -> float:
    """Largest upward force of all fingers (both drums) on the bird less its
    weight, N: where the belt does not touch the bird, its mass times its
    upward acceleration."""
    recs = run.trajectory.records
    up = max(2 * sum(f.force[2] for f in r.fingers) for r in recs)
    return float(up - run.setup.bird.mass * G)


def peak_split(run: GraspRun) -> str:
    """The peak finger force in parts: world components (right drum; the
    left drum's mirror has Y reversed), and the push along the bird's
    surface normal against the friction along its surface."""
    _, y, state = run.peak()
    b = run.setup.bird
    rotation = rot_y(y[2])
    normal = rotation @ (state.body_point / np.array([b.eta, b.lam, b.gamma]) ** 2)
    push = -float(state.force @ normal / np.linalg.norm(normal))
    friction = float(np.sqrt(max(state.force @ state.force - push ** 2, 0.0)))
    fx, fy, fz = state.force
    return (f"{_peak(run)} = ({fx:+.1f}, {fy:+.1f}, {fz:+.1f}) N in X, Y, Z (+Y away from "
            f"its drum, towards the other), {push:.1f} N along the surface normal and "
            f"{friction:.1f} N of friction along the surface")


def sweep_friction(frictionless: GraspRun) -> str:
    """What the finger friction adds: the same run with frictionless fingers."""
    peaks = family_peaks(frictionless)
    share = impulse_share(frictionless, lambda r: abs(r.y[0]) <= DENSE)
    return (f" The drums sweep the fingers across the bird's surface, so each touching finger "
            f"slides and carries µ_f times its normal force as friction; with frictionless "
            f"fingers (the belt's friction kept) the peak is "
            f"{_peak(frictionless)}, finger 4's {peaks.get('4', 0.0):.1f} N, and {share:.0%} "
            f"of the force-time integral falls within ±1.5 in "
            f"(examples/validation/friction_sensitivity.py).")


def _peak(run: GraspRun) -> str:
    s = run.summary
    return f"{s['max_finger_force_N']:.1f} N at finger {s['max_finger_force_finger']}"


def mean_bird_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """Figures 5-7 and 5-9's mean bird, each group of rows computed only from
    runs that finished."""
    case = "Figure 5-7, mean bird (Table 5-3)"
    thesis = "fingers 1, 2, 4, 5; finger 4 about 11 N"
    # Figure 5-7's caption and legend compare soft (EI2) with hard (EI3) lower
    # fingers; Figure 5-6's captions number a constant-EI case 3: all three
    rows = []
    for name, label in ((SOFT, "soft lower fingers (case 2)"), (HARD, "hard lower fingers"),
                        (CONSTANT, "constant EI")):
        needs = [name, SOFT_FRICTIONLESS] if name == SOFT else [name]
        rows += unfinished(partial(_figure_5_7_rows, name=name, label=label), runs, needs, case,
                           f"fingers and forces, {label}", thesis)
    for name, label in ((SOFT_PLACED, "soft lower fingers (case 2)"),
                        (CONSTANT_PLACED, "constant EI")):
        rows += unfinished(partial(_placed_row, name=name, label=label), runs, [name], case,
                           f"Table 5-3's start as printed, {label}", thesis)
    rows += unfinished(_figure_5_9_row, runs, [HARD, SOFT], "Figure 5-9, mean bird",
                       "longest N = 0 window, hard minus soft lower fingers", "> 0")
    for name in (PLANAR_SOFT, PLANAR_HARD):
        rows += unfinished(partial(_planar_row, name=name), runs, [name], case,
                           f"the planar finger model ({name})", thesis)
    for name in (THESIS_SOFT, THESIS_CONSTANT, THESIS_HARD):
        rows += unfinished(partial(_own_model_row, name=name), runs, [name], case,
                           f"the thesis's own model ({name})", thesis)
    return rows


def _figure_5_7_rows(runs: dict[str, GraspRun], name: str, label: str) -> list[Row]:
    """Figure 5-7's statements on one arriving mean-bird run."""
    case = "Figure 5-7, mean bird (Table 5-3)"
    run = runs[name]
    s = run.summary
    share = impulse_share(run, lambda r: abs(r.y[0]) <= DENSE)
    return [
        claim(case, f"fingers touching the bird, {label}", "1, 2, 4, 5 ('no contact "
              "between finger #3 and the bird')", touching(run),
              touching(run) == "1, 2, 4, 5", "Criterion: the same fingers."),
        claim(case, f"finger with the peak force, {label}", "finger 4",
              f"finger {peak_family(run)}", peak_family(run) == "4",
              f"Ours: {_peak(run)}. Criterion: the same finger."),
        compare(case, f"peak finger force, {label}", "N", PEAK_MEAN, s["max_finger_force_N"],
                READING_REL * PEAK_MEAN, "'In the order of 11N' (two sides x 11 N is about "
                f"the bird's 17.7 N weight); tolerance 30 % for a reading. Ours: "
                f"{peak_split(run)}." + (sweep_friction(runs[SOFT_FRICTIONLESS])
                                         if name == SOFT else "")),
        claim(case, f"share of the finger force-time integral while |X| <= 38.1 mm, {label}",
              "most ('concentrate densely' from -1.5 to +1.5 in)", share, share > 0.5,
              "Criterion: more than half.", "1")]


def _placed_row(runs: dict[str, GraspRun], name: str, label: str) -> list[Row]:
    """Figure 5-7's statements with the bird placed on finger 4a at t = 0."""
    run = runs[name]
    share = impulse_share(run, lambda r: abs(r.y[0]) <= DENSE)
    return [claim(
        "Figure 5-7, mean bird (Table 5-3)", f"Table 5-3's start as printed, the bird placed on "
        f"finger 4a at t = 0, {label}", "fingers 1, 2, 4, 5 touch; the peak is finger 4's, "
        "about 11 N; forces concentrate within ±1.5 in", f"fingers {touching(run)}; "
        f"{_peak(run)}; {share:.0%} of the force-time integral within ±1.5 in",
        meets_figure_5_7(run) and share > 0.5,
        "The runs above let the bird arrive (one set period upstream); this one starts it "
        "where Table 5-3 prints, already held by finger 4a, as the thesis's 0.5 s run "
        "(Figure 5-5) seems to. Criterion: all three statements.")]


def _figure_5_9_row(runs: dict[str, GraspRun]) -> list[Row]:
    """Figure 5-9: hard lower fingers hold the mean bird longer than soft ones."""
    hard, soft = runs[HARD].summary, runs[SOFT].summary
    return [claim("Figure 5-9, mean bird", "longest N = 0 window, hard minus soft lower "
                  "fingers", "> 0 (hard fingers hold longer)",
                  hard["hold_time_s"] - soft["hold_time_s"],
                  hard["hold_time_s"] > soft["hold_time_s"],
                  f"Ours: {hard['hold_time_s']:.3f} s against {soft['hold_time_s']:.3f} s "
                  f"(peaks {_peak(runs[HARD])}, {_peak(runs[SOFT])}).", "s")]


def _planar_row(runs: dict[str, GraspRun], name: str) -> list[Row]:
    """The planar finger model on the arriving mean bird, with its validity."""
    run = runs[name]
    problems = validity_problems(run.summary["validity"])
    return [claim("Figure 5-7, mean bird (Table 5-3)", f"the planar finger model on the same "
                  f"run ({name})", "fingers 1, 2, 4, 5 touch; peak about 11 N at finger 4",
                  f"fingers {touching(run)}; {_peak(run)}", meets_figure_5_7(run),
                  "Outside its validity: " + ("; ".join(problems) or "none") +
                  ". Criterion: both statements.")]


def _own_model_row(runs: dict[str, GraspRun], name: str) -> list[Row]:
    """The thesis's own model (``planar-thesis``) on the arriving mean bird."""
    run = runs[name]
    return [claim(
        "Figure 5-7, mean bird (Table 5-3)", f"the thesis's own model: planar fingers with its "
        f"chapter III friction convention ({name.removesuffix(OWN)})",
        "fingers 1, 2, 4, 5 touch; peak about 11 N at finger 4",
        f"fingers {touching(run)}; {_peak(run)}", meets_figure_5_7(run),
        "Friction on each finger at µ, pointing tipwards whatever the sliding (as in "
        "Tables 3-2 to 3-5; its FEM, Table 3-6, follows the sliding instead): how the "
        "thesis computed its forces, not what our grasp runs use. Criterion: both "
        "statements.")]


def unfinished(rows_of, runs: dict[str, GraspRun], names: list[str], case: str, quantity: str,
               thesis: str) -> list[Row]:
    """``rows_of(runs)`` if every named run finished, else one row saying which
    did not (failed, or not within RUN_BUDGET s), with where the others went."""
    late = [f"{n}: {runs[n].summary['message']}" for n in names if stopped(runs[n])]
    if not late:
        return rows_of(runs)
    done = [f"{n}: {_motion(runs[n])}" for n in names if not stopped(runs[n])]
    return [claim(case, quantity, thesis, "not finished", False,
                  "Not computed: " + "; ".join(late) + "."
                  + (" Finished: " + "; ".join(done) + "." if done else ""))]


def _motion(run: GraspRun) -> str:
    s = run.summary
    return (f"X at {run.setup.duration:g} s {x_end(run):+.3f} m, backed off "
            f"{1e3 * back_off(run):.0f} mm, rise {1e3 * s['centre_rise_m']:.1f} mm, pitch up to "
            f"{np.degrees(s['max_pitch_rad']):.0f}°, peak {_peak(run)}")


def x_impulse(run: GraspRun, name: str | None = None) -> float:
    """Time integral of the fingers' X force on the bird, both drums (N s; <
    0 pushes it back): of the designed finger ``name``, or of all."""
    recs = run.trajectory.records
    families = [gf.design_name for gf in run.setup.grasper.fingers]
    fx = [2 * sum(f.force[0] for f, n in zip(r.fingers, families) if name in (None, n))
          for r in recs]
    return float(np.trapezoid(fx, [r.t for r in recs]))


def pushed_back(runs: dict[str, GraspRun], case: str, what: str, named: dict[str, str],
                finger: str | None = None, note: str = "") -> Row:
    """The thesis's 'pushed back at the first setting, passes at the others'
    (Figures 5-17, 5-18) against the runs ``named`` {setting label: run name};
    the explanation gives the fingers' X impulse in each (of ``finger`` if
    the setting is that finger's), any jam, then ``note`` if ours disagrees."""
    (first, head), *rest = named.items()
    others = " and ".join(label for label, _ in rest)
    statement = f"pushed back at {first}; passes at {others}"
    whose = f"finger {finger}'s" if finger else "all fingers'"
    impulses = ", ".join(f"{label} {x_impulse(runs[n], finger):+.3f} N s"
                         for label, n in named.items())
    jams = "; ".join(f"{label}: {_jam(runs[n])}" for label, n in named.items()
                     if runs[n].summary["jammed"])
    holds = not passes(runs[head]) and all(clears(runs[n]) for _, n in rest)
    return claim(case, f"{what}: {statement}", statement,
                 "; ".join(f"{label}: {_motion(runs[n])}" for label, n in named.items()),
                 holds, f"Criterion: {first} does not pass, {others} pass without a jam. Ours, "
                 f"{whose} X impulse on the ball (both drums, < 0 pushes it back): {impulses}."
                 + (f" Jams: {jams}." if jams else "") + ("" if holds else f" {note}").rstrip())


def football_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """§5.3's football: the experiment, the forces, the readings the thesis
    leaves open, and Figures 5-16 to 5-18."""
    case = "Figures 5-12 to 5-15, football (Table 5-4)"
    far = _far_runs()
    return (unfinished(_experiment_rows, runs, [FOOTBALL], case, "the experiment (rise, pitch, "
                       "passing)", "rise 18 mm, passes")
            + unfinished(_football_force_rows, runs, [FOOTBALL, far[0.4]], case,
                         "peak finger and force", "finger 4 about 8.5 N")
            + unfinished(_own_model_rows, runs, [FOOTBALL + OWN], case, "the thesis's own model",
                         "rise 18 mm, passes")
            + unfinished(_start_rows, runs, [FOOTBALL, far[1.16]], FIGURE_5_16,
                         "passes from X0 = -0.381 and -0.305 m", "both pass")
            + unfinished(_friction_rows, runs, [*far.values(), ONE_MU], FIGURE_5_17, "friction",
                         "pushed back at µ = 0; passes at 0.4 and 1.16")
            + unfinished(_mount_rows, runs, list(_phi_runs().values()), FIGURE_5_18,
                         "finger 3's φx", "pushed back at 45°, passes at 60° and 70°"))


def _far_runs() -> dict[float, str]:
    """Figure 5-17's runs from X0 = -0.381 m by finger µ."""
    return {m: football_far(f"finger µ = {m:g}") for m in (0.0, 0.4, 1.16)}


def _phi_runs() -> dict[float, str]:
    """Figure 5-18's runs from X0 = -0.381 m by finger 3's φx (deg)."""
    return {45.0: football_far("finger 3 φx = 45°"), 60.0: _far_runs()[1.16],
            70.0: football_far("finger 3 φx = 70°")}


def _experiment_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """What the football experiment measured (§5.3): rise, attitude, passing."""
    run = runs[FOOTBALL]
    fb = run.summary
    case = "Figures 5-12 to 5-15, football (Table 5-4)"
    return [
        compare(case, "maximum rise of the centre", "m", RISE_FOOTBALL, fb["centre_rise_m"],
                READING_REL * RISE_FOOTBALL, "'Around 0.018m', simulated and measured (Figure "
                "5-13, Z from the video); tolerance 30 % for a reading. Table 5-1's layout as "
                "printed (docs/MODEL.md, 'Finger layout'); the context row and the table 'spread "
                "over unprinted settings' show the rise over fingers 1 and 2's tilt and the drum "
                f"phase. Ours: "
                f"{_motion(run)}.", THESIS_MEASUREMENT),
        claim(case, "the ball does not turn over", "|pitch| < 90° (Figures 5-11, 5-12)",
              np.degrees(fb["max_pitch_rad"]), fb["max_pitch_rad"] < np.pi / 2,
              "The video's frames (Figures 5-11, 5-12). Criterion: |pitch| < 90° throughout.",
              "deg", THESIS_MEASUREMENT),
        claim(case, "the ball passes through the grasper", "passes (Figure 5-14)",
              _motion(run), clears(run), "The measured X velocity (Figure "
              f"5-14). Criterion: past the drum axis at the end, never more than "
              f"{1e3 * BACK_OFF:.0f} mm back, and no jam ({_jam(run)}).",
              basis=THESIS_MEASUREMENT)]


def _football_force_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """§5.3's simulated finger forces on the football, and the substitute
    quantity beside its 8.52 N."""
    run = runs[FOOTBALL]
    fb = run.summary
    case = "Figures 5-12 to 5-15, football (Table 5-4)"
    return [
        claim(case, "finger with the peak force", "finger 4 (carries the weight)",
              f"finger {peak_family(run)}", peak_family(run) == "4",
              f"Ours: {_peak(run)}. Criterion: the same finger."),
        compare(case, "peak finger force", "N", PEAK_FOOTBALL, fb["max_finger_force_N"],
                READING_REL * PEAK_FOOTBALL, "§5.3's estimate from the ball's inertia, 8.52 N, "
                "which it calls close to the simulation's largest finger force; tolerance 30 %. "
                f"Ours: {peak_split(run)}. At finger µ = 0.4 (Figure 5-17's run from -0.381 m) "
                f"the peak is {_peak(runs[_far_runs()[0.4]])}."),
        context(case, "largest upward force of the fingers less the ball's weight",
                PEAK_FOOTBALL, net_lift(run), "A substitute quantity, not counted: §5.3's 8.52 "
                "N = m A (2π/T)² is the ball's largest vertical inertial force (A 0.8 in, T 0.2 "
                "s, read off the simulated Z trace); ours is the fingers' Z forces (both drums) "
                "less the weight, which is that force only while the belt does not touch the "
                "ball.", "N")]


def _own_model_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """Context: the thesis's own model on the experiment."""
    own = runs[FOOTBALL + OWN]
    return [context(
        "Figures 5-12 to 5-15, football (Table 5-4)", "the thesis's own model (planar fingers, "
        "its chapter III friction convention) on the experiment", "rise around 0.018 m, passes "
        "(Figures 5-13, 5-14)", f"{_motion(own)}; {'passes' if passes(own) else 'does not pass'}"
        f"; {_jam(own)}", "Another finger model than the validation's (the model that meets the "
        "mean bird's force statements), shown on the experiment, not counted.")]


def _start_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """Figure 5-16: the two starts at one drum timing."""
    near, far = runs[FOOTBALL], runs[_far_runs()[1.16]]
    return [claim(
        FIGURE_5_16, "passes from X0 = -0.381 and -0.305 m (µ = 1.16, finger 3 at φx = 60°)",
        "both pass", f"-0.381 m: {_motion(far)}; {_jam(far)}. -0.305 m: {_motion(near)}; "
        f"{_jam(near)}", clears(far) and clears(near),
        "One drum timing for both (the designed phase of Table 5-4's -0.305 m start): the "
        "two runs differ only in where the ball starts, 0.076 m apart, so the -0.381 m ball "
        "meets the fingers later in their sweep. Criterion: both pass without a jam.")]


def _friction_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """Figure 5-17: the football's path against finger friction."""
    far = _far_runs()
    return [pushed_back(runs, FIGURE_5_17, "friction", {f"µ = {m:g}": n for m, n in far.items()},
                        note=UNRESOLVED),
            claim(FIGURE_5_17, "µ = 0 on fingers and belt (eq. 4.40 writes the belt's friction "
                  "with the same µ): pushed back", "pushed back", _motion(runs[ONE_MU]),
                  not passes(runs[ONE_MU]), "Table 5-4 prints one µ (rubber to rubber) and eq. "
                  "4.40 the belt's friction with it, so Figure 5-17's µ may be the belt's too; "
                  "the row above keeps the belt at 1.16. Criterion: does not pass.")]


def _mount_rows(runs: dict[str, GraspRun]) -> list[Row]:
    """Figure 5-18: the football's path against finger 3's φx."""
    return [pushed_back(runs, FIGURE_5_18, "finger 3's φx",
                        {f"{d:g}°": n for d, n in _phi_runs().items()}, "3",
                        UNRESOLVED)]


def spread_table(runs: dict[str, GraspRun]) -> list[dict]:
    """The football's rise over the quantities the thesis does not print:
    fingers 1 and 2's tilt against the drum phase (a distribution, not a pick)."""
    rows = []
    for tilt in SPREAD_TILTS:
        for phase in SPREAD_PHASES:
            run = runs[spread_name(tilt, phase)]
            rows.append({"upper_tilt_deg": tilt, "drum_phase_deg": phase,
                         "rise_within_30_percent_of_18_mm": near_reading(
                             run.summary["centre_rise_m"], RISE_FOOTBALL), **_run_facts(run)})
    return rows


def spread_row(table: list[dict]) -> Row:
    """A context row summing up :func:`spread_table`."""
    rises = [r["centre_rise_m"] for r in table]
    near = sum(r["rise_within_30_percent_of_18_mm"] for r in table)
    through = sum(bool(r["passes"]) and r["jam"] == "no jam" for r in table)
    return context(
        "Figures 5-12 to 5-15, football (Table 5-4)", "spread over unprinted settings: rise "
        f"with fingers 1, 2 at φy = {', '.join(f'{t:g}' for t in SPREAD_TILTS)}° x drum phase "
        f"{', '.join(f'{p:+g}' for p in SPREAD_PHASES)}° from the designed one",
        "around 0.018 m, passes", f"rise {1e3 * min(rises):.1f} to {1e3 * max(rises):.1f} mm; "
        f"{near} of {len(table)} within 30 % of 18 mm; {through} of {len(table)} pass without a "
        "jam",
        "The thesis prints no football layout and no drum phase; Table 5-1's tilt and the "
        "designed phase are the settings the counted rows use. The table 'spread over unprinted "
        "settings' gives each run: a distribution over what the thesis leaves open, not counted "
        "as agreement.")


def pallet_table(runs: dict[str, GraspRun]) -> list[dict]:
    """The mean bird (soft lower fingers) and the football on a solid belt and
    with finger 5 passing a slotted pallet: what the unknown pallet changes."""
    rows = []
    for label, solid, cut in (("mean bird, soft lower fingers", SOFT, SOFT_SLOTTED),
                              ("football", FOOTBALL, FOOTBALL_SLOTTED)):
        for belt, name in (("solid belt", solid), ("finger 5 through slots", cut)):
            rows.append({"object": label, "belt": belt, **_run_facts(runs[name])})
    return rows


def sizes_table(runs: dict[str, GraspRun]) -> list[dict]:
    """Table 5-5's five birds on the validated model, one row each."""
    return [{"bird": b, **_run_facts(runs[f"Table 5-5: {b}"])} for b in BIRDS]


def _run_facts(run: GraspRun) -> dict:
    """A run in one table row: fingers, peak, hold, rise, release, passing, jam,
    and whether it finished (a run that failed or that its wall-time budget
    stopped: as far as it got)."""
    s = run.summary
    end = run.trajectory.records[-1].t
    return {"fingers_touching": touching(run), "peak_force_N": s["max_finger_force_N"],
            "peak_finger": s["max_finger_force_finger"], "hold_time_s": s["hold_time_s"],
            "centre_rise_m": s["centre_rise_m"], "released": _released(run),
            "passes": None if stopped(run) else passes(run),
            "fingers_on_belt": ", ".join(s["belt_contacts"]) or "none", "jam": _jam(run),
            "run": "finished" if not stopped(run) else f"stopped by its budget at {end:.3f} s"
            if run.trajectory.out_of_time else f"failed at {end:.3f} s: {s['message']}"}


def _released(run: GraspRun) -> str:
    """Whether the bird is put back on the belt: 'yes', 'held at the end' or 'never lifted'."""
    windows = run.summary["hold_windows"]
    if not windows:
        return "never lifted"
    return "yes" if windows[-1][1] < run.trajectory.records[-1].t else "held at the end"


def _jam(run: GraspRun) -> str:
    """The run's jam reasons, or 'no jam'."""
    return "; ".join(run.summary["jam"]) or "no jam"


def sizes_rows(runs: dict[str, GraspRun]) -> list[Row]:
    return unfinished(_sizes_rows, runs, [f"Table 5-5: {b}" for b in BIRDS],
                      "Figure 5-19, Table 5-5 birds", "lift, height and support of five birds",
                      "the statements of §5.4")


def _sizes_rows(runs: dict[str, GraspRun]) -> list[Row]:
    size = {b: runs[f"Table 5-5: {b}"] for b in BIRDS}
    case = "Figure 5-19, Table 5-5 birds"
    rows = [compare(case, f"highest centre Z, {b}", "m", HEIGHT_MEAN, z_max(size[b]), HEIGHT_TOL,
                    f"'The grasper is able to lift the bird to the same height of 80mm' (1.66 "
                    f"to 2.05 kg), read as Figure 5-19(a)'s centre height; ours rises "
                    f"{1e3 * size[b].summary['centre_rise_m']:.1f} mm. Tolerance: half the "
                    "figure's 10 mm grid.")
            for b in ("mean_1_66kg", "mean_1_80kg", "large_2_05kg")]
    lifted = {b: lift_x(size[b]) for b in BIRDS}
    known = [x for x in lifted.values() if x is not None]
    spread = max(known) - min(known) if len(known) == len(BIRDS) else float("inf")
    small, mean = size["small_1_20kg"].summary, size["mean_1_80kg"].summary
    ends = [s["hold_windows"][0][1] if s["hold_windows"] else None for s in (small, mean)]
    rows += [
        claim(case, "X where the bird first leaves the belt", "about the same point for all",
              ", ".join("never" if x is None else f"{x:+.3f}" for x in lifted.values()),
              spread <= 0.025, f"Spread {spread:.3f} m. Criterion: all lifted, within 25 mm "
              "(a tenth of the figure's X range).", "m"),
        claim(case, "the small bird's support tails off sooner", "sooner than the mean bird's",
              f"first N = 0 window ends at {ends[0]} s, the 1.80 kg bird's at {ends[1]} s",
              None not in ends and ends[0] < ends[1], "Criterion: its first window ends "
              "earlier."),
        claim("Figure 5-20, Table 5-5 birds", "the 1.66 kg bird is lifted higher than the 1.80 kg",
              "higher", z_max(size["mean_1_66kg"]) - z_max(size["mean_1_80kg"]),
              z_max(size["mean_1_66kg"]) > z_max(size["mean_1_80kg"]),
              "Ours: difference of the highest centre Z. Criterion: > 0.", "m"),
        claim(case, "no bird turns over", "nutation within about ±60° (Figure 5-19(b))",
              ", ".join(f"{np.degrees(size[b].summary['max_pitch_rad']):.0f}°" for b in BIRDS),
              all(size[b].summary["max_pitch_rad"] < np.pi / 2 for b in BIRDS),
              "Criterion: |pitch| < 90° for every bird.", "deg"),
    ]
    return rows


SECTION_TEXT = (
    "Symmetric grasp (docs/MODEL.md), the Table 5-1 grasper as printed for every object (three "
    "finger sets 120° apart; fingers 1 and 2 at φy = -15°, the one setting §5.1 and §5.4 "
    "describe for the whole size range), spatial finger model (bending both ways and twist, "
    "friction against the sliding) unless a row says planar or the thesis's own model "
    "(planar, friction at µ tipwards on the finger as in chapter III), adaptive integrator. "
    "The belt is solid: a finger tip that reaches it rests on it and is dragged by it "
    "(finger 5's tip sits 7.3 mm below the belt at every drum angle); the thesis prints no "
    "pallet, so the table 'pallet readings' also runs finger 5 through slots. Mean bird: "
    "Table 5-3 (constant belt, legs k = 30 N/m, c = 1.5 N s/m), arriving: started one set "
    "period (1 s) upstream of X0 = -0.075 m, so that it reaches X0 as the next finger set "
    "stands at Table 5-1's angles, then 0.6 s; one row per case starts it at X0 as printed, "
    "on finger 4a. Football: Table 5-4 on the Figure 5-10 belt (2 m/s² assumed), finger 3 at "
    "φx = 60° as Figures 5-16 to 5-18 print, no legs, 1.6 s. Table 5-5 birds: X0 = -0.381 m, "
    "µ = 0.4, on the Figure 5-10 belt. The thesis prints no drum phase for these upstream "
    "starts: one drum timing serves every run on the Figure 5-10 belt, the one that brings a "
    "ball from Table 5-4's X0 = -0.305 m to Table 5-3's -0.075 m as the fingers reach their "
    "Table 5-1 angles (the mean bird's timing, the grasper as designed); a ball or bird from "
    "-0.381 m meets the same drums 0.076 m further back. The spread table turns the drums "
    "±20° and tilts fingers 1 and 2 ±10°. Evidence: the football experiment's rise and "
    "video are the motion target (thesis measurement); the thesis's simulated force levels "
    "and the trends of Figures 5-17 and 5-18 are compared as thesis simulations, and where "
    "ours disagrees with a trend the row names the candidate causes measured (docs/MODEL.md "
    "gives what each shows). Context rows and the tables are shown, not counted.")


def sections(runs: dict[str, GraspRun]) -> list[Section]:
    """The report's section for chapter V, with its tables and figures."""
    spread = spread_table(runs)
    return [Section("grasp", TITLE, SECTION_TEXT,
                    mean_bird_rows(runs) + football_rows(runs) + [spread_row(spread)]
                    + sizes_rows(runs), _figures(runs),
                    [("spread", "The football's spread over unprinted settings: fingers 1 and "
                      "2's tilt against the drums' phase from the designed one (rise within 30 "
                      "% of the thesis's 18 mm, passing without a jam, peak finger force). A "
                      "distribution over what the thesis leaves open, not counted.", spread),
                     ("sizes", "Table 5-5 on the validated model (spatial fingers, Table 5-1 "
                      "layout, solid belt, the football's drum timing): each bird's longest "
                      "hold it is put back from, peak finger force and where, centre rise, "
                      "release, passing, the fingers that pressed on the belt, and any jam.",
                      sizes_table(runs)),
                     ("pallet", "Pallet readings: the soft mean bird and the football on a "
                      "solid belt (finger 5 rests on it) and with finger 5 through slots cut "
                      "for it. The thesis prints no pallet; the solid belt is the default.",
                      pallet_table(runs))])]


def _figures(runs: dict[str, GraspRun]) -> list[tuple[object, str, str]]:
    """Chapter V's figures redrawn from the runs."""
    from design.report.grasp_figures import normal_force_figure

    fb = {f"µ = {m:g}": runs[n] for m, n in _far_runs().items()}
    sizes = {k.split(": ")[1]: r for k, r in runs.items() if k.startswith("Table 5-5")}
    return [
        (normal_force_figure({"hard lower fingers": runs[HARD],
                              "soft lower fingers": runs[SOFT]}), "grasp_normal_force",
         "Figure 5-9 redrawn: the belt's normal force on the mean bird, hard against soft "
         "lower fingers (shaded: N = 0 with soft fingers)."),
        (finger_force_x_figure({"soft": runs[SOFT], "constant EI": runs[CONSTANT]}, DENSE,
                               PEAK_MEAN),
         "grasp_finger_forces", "Figure 5-7 redrawn: each finger's force against the mean "
         "bird's X, soft lower fingers (solid) and constant EI (dashed)."),
        (path_figure(sizes, "Table 5-5 birds from X0 = -0.381 m", HEIGHT_MEAN),
         "grasp_bird_sizes", "Figure 5-19(a) redrawn: centre height against X."),
        (path_figure(fb, "Football from X0 = -0.381 m"), "grasp_football_friction",
         "Figure 5-17 redrawn: the football's centre path for finger µ = 0, 0.4, 1.16."),
        (path_figure({"X0 = -0.381 m": runs[_far_runs()[1.16]], "X0 = -0.305 m": runs[FOOTBALL]},
                     "Football from two starts, one drum timing"), "grasp_football_starts",
         "Figure 5-16 redrawn: the football's centre path from the two starts."),
        (transverse_figure({"Table 5-1, φy = -15°": runs[FOOTBALL].setup.grasper},
                           {"mean bird": runs[SOFT].setup.bird,
                            "football": runs[FOOTBALL].setup.bird}),
         "grasp_upper_tilt", "Figure 5-3 redrawn: the resting mean bird's and football's "
         "sections through the drum axes and the straight fingers 1 and 2 facing them at "
         "Table 5-1's tilt, which passes 5.2 mm above the mean bird and enters the football "
         "11.8 mm deep (tests/test_grasp_layout.py).")]
