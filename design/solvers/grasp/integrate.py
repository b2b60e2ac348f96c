"""Integrating the grasp: an event-driven adaptive integrator (default) and the
thesis's fixed-step BDF-4 with frozen forces (baseline).

Adaptive (``adaptive``): scipy's steppers with error control (explicit
Runge-Kutta, DOP853 or RK45; or implicit, Radau or BDF, for stiff scenes),
one smooth ODE per conveyor mode (air, slip, stick). Mode switches are
events located on the step's dense output by a root finder: lift-off
(N = 0), touch-down (the lowest point reaches the belt, plastic impact),
stick/slip of the lowest point on the belt, the start and end of the
conveyor's deceleration, and a finger's friction reversing (its sliding
against its friction passing the reversal speed). Finger contacts are
evaluated at every stage with the friction of the last accepted instant;
each accepted instant settles it, and the stepper restarts when one turns. A
spatial finger's first touch of the bird is an event too: trials leave out a
finger that did not touch the bird at the last accepted instant, and a step
at whose end one touches it ends where its clearance crosses zero
(design/solvers/grasp/fingers.py). Located as an event, a reversal comes
where the sliding says, not up to a step late, so the hold and peak force do
not depend on where the steps fell (``python -m benchmarks.grasp``). A
finger's force maxima between accepted instants are located on the dense
output (design/solvers/grasp/peaks.py), so that the peak force does not
depend on the step either.

BDF-4 (``bdf4``, thesis §4.4): fixed step h, forces frozen over the step,
conveyor friction sign updated at the end of the step, the conveyor contact
dropped when N < 0 and restored when the body reaches the belt. Each step's
local error is estimated by Milne's device, (z - p) / (k + 2), z the
corrector, p the degree-k extrapolation of the last k + 1 states; the run
reports the largest and fails where one exceeds
``IntegratorSettings.max_local_error``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from math import comb

import numpy as np
from scipy.integrate import BDF, DOP853, RK45, Radau
from scipy.optimize import brentq

from design.physics.bird import G, BirdDynamics, Conveyor, Loads
from design.solvers.grasp.fingers import (ContactFailed, FingerForces, FingerState, Latest,
                                          OverBudget)
from design.solvers.grasp.peaks import PeakFinder, Span
from design.solvers.newton import damped_newton, forward_difference

#: scipy's steppers: explicit Runge-Kutta (rk45, dop853) and implicit, for
#: stiff scenes: Radau IIA of order 5 (radau) and variable-order BDF, orders
#: 1 to 5 (bdf; not the thesis's fixed-step ``bdf4`` integrator)
STEPPERS = {"dop853": DOP853, "rk45": RK45, "radau": Radau, "bdf": BDF}
#: the steppers that take the right-hand side's Jacobian (Grasp.jacobian)
IMPLICIT = ("radau", "bdf")
#: relative step of Grasp.jacobian's differences: sqrt of the double's epsilon
JACOBIAN_STEP = np.finfo(float).eps ** 0.5
INTEGRATORS = ("adaptive", "bdf4")


@dataclass(frozen=True)
class IntegratorSettings:
    """How to integrate: ``adaptive`` (rtol, atol in m, max_step s, stepper) or
    ``bdf4`` (step h in s); ``max_wall_time`` (s, None: no limit) stops a run
    that takes longer, as not ok, saying where it got to."""

    integrator: str = "adaptive"
    #: rtol 1e-4 / atol 1e-6 m: on the Pareto front of cost against hold and
    #: peak error, where tighter tolerances cost more for no better worst
    #: error (``design tradeoff`` on a grasp scene, ``python -m benchmarks.grasp``)
    rtol: float = 1e-4
    atol: float = 1e-6
    #: 10 ms, with the force maxima located between steps (peaks.py): the
    #: cheapest limit that keeps the hold and peak within the accuracy targets;
    #: at 20 ms the trajectory itself departs (``python -m benchmarks.grasp``,
    #: docs/performance.md)
    max_step: float = 1e-2
    stepper: str = "rk45"
    step: float = 5.6e-3
    max_wall_time: float | None = None
    #: ``bdf4`` has no error control: a step whose estimated local error in
    #: the bird's position (m) exceeds this ends the run, not ok (math.inf:
    #: the thesis's method as it ran, unchecked). 1 mm in one step is a tenth
    #: of the 10-20 mm lifts the thesis reports: a step size that meets the
    #: accuracy targets stays under it, the thesis's own steps do not
    #: (``python -m benchmarks.grasp``'s bdf4 rows, docs/performance.md).
    max_local_error: float = 1e-3
    #: a run whose belt continuations call Newton's method more than
    #: this per simulated second (of the whole run) stops, not ok, as soon as
    #: the count passes it (None: no limit). Unlike ``max_wall_time``, the
    #: count is the same on every machine.
    max_newton_solves: float | None = None

    def finer(self, factor: float = 4.0) -> "IntegratorSettings":
        """Settings at ``factor`` times finer resolution (a reference run)."""
        return IntegratorSettings(self.integrator, self.rtol / factor ** 4, self.atol / factor ** 4,
                                  self.max_step / factor, self.stepper, self.step / factor,
                                  self.max_wall_time, self.max_local_error)


@dataclass
class Record:
    """One instant of the run."""

    t: float
    y: np.ndarray
    mode: str
    normal: float
    friction: float
    belt_speed: float
    fingers: list[FingerState]


@dataclass
class Trajectory:
    records: list[Record] = field(default_factory=list)
    events: list[tuple[float, str]] = field(default_factory=list)
    steps: int = 0
    rejected: int = 0
    wall_time: float = 0.0
    message: str = ""
    ok: bool = True
    #: stopped by IntegratorSettings.max_wall_time (not ok, but no failure)
    out_of_time: bool = False
    #: finger index -> its largest force found between accepted instants,
    #: where it exceeds the records' (design/solvers/grasp/peaks.py's Peak)
    peaks: dict = field(default_factory=dict)
    #: fixed-step runs: (largest estimated local error of a step in the
    #: bird's position m, the time s at the end of that step)
    local_error: tuple[float, float] | None = None
    #: adaptive runs: the trajectory so far -> why to end the run at its last
    #: record ("": go on); it ends ``ok``, ``stopped`` saying why
    watch: Callable[["Trajectory"], str] | None = field(default=None, repr=False)
    stopped: str = ""

    def over_budget(self, started: float, budget: float | None, t: float, t_end: float) -> bool:
        """Stop (and say so) once the run has taken longer than ``budget`` s."""
        if budget is None or time.perf_counter() - started <= budget:
            return False
        self.ok, self.out_of_time = False, True
        self.message = (f"stopped by its wall-time budget of {budget:g} s at t = {t:.4f} s of "
                        f"{t_end:g} s, after {self.steps} steps")
        return True


class Grasp:
    """The bird, the conveyor and the fingers: the hybrid system to integrate."""

    def __init__(self, dynamics: BirdDynamics, conveyor: Conveyor, fingers: FingerForces):
        self.dyn, self.conveyor, self.fingers = dynamics, conveyor, fingers
        self.start: float | None = conveyor.start_time if conveyor.decelerates else None
        fingers.belt_speed = lambda t: self.belt(t)[0]
        self._belt = Latest(64)    # (t, start) -> the belt's motion

    def belt(self, t: float) -> tuple[float, float]:
        """The belt's speed (m/s) and acceleration (m/s²) at t: an integrator
        step asks at its few stage times again and again."""
        return self._belt.kept((t, self.start), lambda: self.conveyor.velocity(t, self.start))

    def solve_mode(self, t, y, mode, slip_sign, loads):
        v, v_dot = self.belt(t)
        acc, normal, friction = self.dyn.accelerations(y, loads, mode, v_dot, slip_sign)
        return acc, normal, friction

    def rhs(self, t, y, mode, slip_sign):
        loads, _ = self.fingers.evaluate(t, y)
        acc, _, _ = self.solve_mode(t, y, mode, slip_sign, loads)
        return np.concatenate([y[3:], acc])

    def jacobian(self, t, y, mode, slip_sign, threshold):
        """∂rhs/∂y by forward differences, column j stepped by sqrt(eps)
        max(|y_j|, ``threshold``) (scipy's first choice), each varied state's
        contacts continued from those at (t, y): a solve from a hair away
        instead of from the accepted state."""
        f = self.rhs(t, y, mode, slip_sign)
        out = np.empty((y.size, y.size))
        for j in range(y.size):
            h = JACOBIAN_STEP * max(abs(y[j]), threshold)
            varied = y.copy()
            varied[j] += h
            acc, _, _ = self.solve_mode(t, varied, mode, slip_sign,
                                        self.fingers.varied(t, varied, (t, y)))
            out[:, j] = (np.concatenate([varied[3:], acc]) - f) / (varied[j] - y[j])
        return out

    def record(self, t, y, mode, slip_sign, commit=True) -> Record:
        loads, states = self.fingers.evaluate(t, y, commit=commit)
        _, normal, friction = self.solve_mode(t, y, mode, slip_sign, loads)
        return Record(t, y.copy(), mode, normal, friction, self.belt(t)[0], states)


def integrate(grasp: Grasp, y0: np.ndarray, t_end: float, settings: IntegratorSettings,
              progress=None, watch=None) -> Trajectory:
    """Integrate from y0 over [0, t_end]. A finger contact that cannot be
    solved, or contact work past the settings' budget, ends the run there:
    ``ok`` false, the time (and finger) in ``message`` (the records so far
    are kept). ``watch``: see
    :attr:`Trajectory.watch`."""
    run = {"adaptive": _adaptive, "bdf4": _bdf4}[settings.integrator]
    t0 = time.perf_counter()
    traj = Trajectory(watch=watch)
    budget = settings.max_newton_solves
    grasp.fingers.budget = None if budget is None else (budget * t_end, budget)
    try:
        run(grasp, traj, y0, t_end, settings, progress)
    except (ContactFailed, OverBudget) as exc:
        traj.ok, traj.message = False, str(exc)
    traj.wall_time = time.perf_counter() - t0
    return traj


# ------------------------------------------------------------------ adaptive
#: the lowest point counts as on the belt within this height (m)
GAP_TOL = 1e-9
#: slip speeds (m/s) below this count as rolling with the belt
SLIP_TOL = 1e-9
#: an event fires only after its function exceeded this since the last switch
#: (N in newtons, slip in m/s, gap in m, times in s)
EVENT_ARM = {"lift-off": 1e-9, "slip": 1e-9, "stick": 1e-9, "touch-down": 0.0,
             "belt slows": 0.0, "belt steady": 0.0}
#: a friction reversal is committed where the reversal margin is at most
#: minus this (m/s), so that the contact solved again from the accepted
#: state agrees, to rounding, that it turns (1e-9 to 1e-7 s past the crossing)
REVERSAL_DEPTH = 1e-9
#: a finger's first touch of the bird is committed where the finger is at
#: least this far (m) inside it, so that the contact solved there starts
#: (1e-9 to 2e-9 m inside: a few nanoseconds past the crossing)
TOUCH_DEPTH = 1e-9
#: the event of a finger's first touch of the bird
TOUCHES = "a finger touches the bird"
#: this many events within a nanosecond is chattering: the run stops and says so
MAX_EVENTS_AT_ONCE = 20
#: a belt mode's normal force may dip below zero by this fraction of the
#: weight (event location to 1e-12 s); more is a belt pulling the bird down
SUPPORT_TOL = 1e-6


def decide_mode(grasp: Grasp, t: float, y: np.ndarray, landing: bool = False,
                on_belt: bool = False):
    """(mode, slip sign, state) consistent with (t, y).

    Off the belt: air (but ``on_belt``, where the bird's mode held it on the
    belt: a gap is then the drift of the constraint that mode integrates,
    settled here; a lift is the lift-off event). On it: air again if the
    free motion would lift the lowest point anyway; else stick if A rolls
    with the belt and the friction it needs is inside the cone, else slip in
    the direction A moves (or, from rest, the direction the friction cannot
    hold). If sliding would need a negative normal force (friction's
    Painlevé paradox), the belt holds A.
    """
    dyn = grasp.dyn
    if dyn.gap(y) > GAP_TOL and not (landing or on_belt):
        return "air", 0.0, y
    y = dyn.land(y) if landing else dyn.settle(y)
    loads, _ = grasp.fingers.evaluate(t, y)
    free, _, _ = grasp.solve_mode(t, y, "air", 0.0, loads)
    _, _, d1, d2 = dyn.support(y[2])
    if free[1] - d1 * free[2] - d2 * y[5] ** 2 > 0:
        return "air", 0.0, y
    _, normal, friction = grasp.solve_mode(t, y, "stick", 0.0, loads)
    s = dyn.slip(y, grasp.belt(t)[0])
    if normal > 0 and abs(s) <= SLIP_TOL and abs(friction) < dyn.mu * normal * (1 - 1e-9):
        return "stick", 0.0, y
    sign = float(np.sign(s)) if abs(s) > SLIP_TOL else -float(np.sign(friction)) or 1.0
    if grasp.solve_mode(t, y, "slip", sign, loads)[1] > 0:
        return "slip", sign, y
    return "stick", 0.0, y


def _events(grasp: Grasp, mode: str, slip_sign: float):
    """Event functions g(t, y) of a mode: a sign change from + to - is the event."""
    dyn = grasp.dyn
    ev = {}
    if mode in ("slip", "stick"):
        def lift(t, y):
            loads, _ = grasp.fingers.evaluate(t, y)
            return grasp.solve_mode(t, y, mode, slip_sign, loads)[1]
        ev["lift-off"] = lift
    if mode == "stick":
        def breakaway(t, y):
            loads, _ = grasp.fingers.evaluate(t, y)
            _, normal, friction = grasp.solve_mode(t, y, mode, slip_sign, loads)
            return dyn.mu * normal - abs(friction)
        ev["slip"] = breakaway
    if mode == "slip":
        ev["stick"] = lambda t, y: slip_sign * dyn.slip(y, grasp.belt(t)[0])
    if mode == "air":
        ev["touch-down"] = lambda t, y: dyn.gap(y) + GAP_TOL
    conv = grasp.conveyor
    if conv.decelerates and grasp.start is None and conv.start_position is not None:
        ev["belt slows"] = lambda t, y: conv.start_position - y[0]
    if grasp.start is not None and conv.decelerates:
        t_ramp = grasp.start + (conv.speed - conv.final_speed) / conv.rate
        ev["belt steady"] = lambda t, y: t_ramp - t
    return ev


def _after_event(grasp: Grasp, name: str, t: float, y: np.ndarray, mode: str, slip_sign: float):
    """New (mode, slip sign, state) after an event."""
    if name == "belt slows":
        grasp.start = t
    if name in ("belt slows", "belt steady", TOUCHES):
        return mode, slip_sign, y
    if name == "lift-off":
        return "air", 0.0, y
    if name == "slip":                        # the friction reached the cone: slip begins
        loads, _ = grasp.fingers.evaluate(t, y)
        _, _, friction = grasp.solve_mode(t, y, "stick", 0.0, loads)
        sign = -float(np.sign(friction)) or 1.0
        if grasp.solve_mode(t, y, "slip", sign, loads)[1] > 0:
            return "slip", sign, y
        # sliding would need N < 0: decide afresh (air, if the bird lifts)
    return decide_mode(grasp, t, y, landing=name == "touch-down", on_belt=mode != "air")


def _keep(grasp: Grasp, traj: Trajectory, record: Record) -> bool:
    """Append ``record``; False where the run ends there: its watch ends it
    (``stopped``), or it failed, saying where, because the belt would have to
    pull the bird down to keep it in its belt mode: a lift-off the events
    missed because the finger forces jumped (a contact changing branch
    between two evaluations), or friction's Painlevé paradox, which this
    model has no impulse to resolve."""
    traj.records.append(record)
    weight = grasp.dyn.bird.mass * G
    if record.mode == "air" or record.normal >= -SUPPORT_TOL * weight:
        if traj.watch is None or not (reason := traj.watch(traj)):
            return True
        traj.stopped, traj.message = reason, f"stopped at t = {record.t:.4f} s: {reason}"
        return False
    traj.ok = False
    traj.message = (f"the belt pulls the bird down at t = {record.t:.6f} s (N = "
                    f"{record.normal:.3g} N in mode {record.mode}): the run cannot go on "
                    f"consistently")
    return False


class _Found(Exception):
    """A time inside the band :func:`_locate` accepts, ending brentq early."""

    def __init__(self, t: float):
        super().__init__(t)
        self.t = t


def _locate(f, dense, t_old: float, t_new: float, depth: float = 0.0) -> float:
    """Where g(t) = f(t, dense(t)) crosses zero in [t_old, t_new]: the first
    time found with g ≤ -depth just past the crossing.

    With ``depth`` > 0, any time where -2 depth ≤ g ≤ -depth is taken as soon
    as it is found: past the crossing by depth / |g'| to 2 depth / |g'| (a
    reversal margin's slope is of order 1 m/s², so 1e-9 to 2e-9 s), without
    the evaluations brentq spends narrowing its bracket to 1e-12 s around a
    function whose values near zero are Newton-tolerance noise.

    Finger forces are continued from the latest solution, so g at the
    dense-output points may differ from the step's end values by the Newton
    tolerance: an end that has already crossed puts the event there.
    """
    g = lambda tt: f(tt, dense(tt))  # noqa: E731
    g_lo, g_hi = g(t_old), g(t_new)
    if g_lo <= -depth:
        return t_old
    if g_hi > -depth:
        return t_new

    def shifted(tt):
        value = g(tt) + depth
        if depth > 0 and -depth <= value <= 0:
            raise _Found(tt)
        return value

    try:
        tau, dt = brentq(shifted, t_old, t_new, xtol=1e-12), 1e-12
    except _Found as found:
        return found.t
    # brentq's answer lies within xtol of the crossing, on either side
    while tau < t_new and g(tau) > -depth:
        tau, dt = min(tau + dt, t_new), 2 * dt
    return tau


def _commit(grasp: Grasp, t: float, y: np.ndarray, mode: str, slip_sign: float):
    """Accept (t, y): the fingers' friction settles. Where one turned (a new
    smooth piece), or a contact starting here makes the belt pull (the trials
    that decided the mode left it out: a first touch not located, at another
    event), the belt contact is decided again under the new forces before
    the instant is recorded. Returns (record, mode, slip sign, state,
    whether a friction turned)."""
    before = [getattr(st, "tau_mu", None) for st in grasp.fingers.states]
    record = grasp.record(t, y, mode, slip_sign)
    after = [getattr(st, "tau_mu", None) for st in grasp.fingers.states]
    turned = any(a is not None and b is not None and a != b for a, b in zip(before, after))
    pulled = bool(grasp.fingers.touched) and \
        record.normal < -SUPPORT_TOL * grasp.dyn.bird.mass * G
    if (turned or pulled) and mode != "air":
        mode, slip_sign, y = decide_mode(grasp, t, y, on_belt=True)
        record = grasp.record(t, y, mode, slip_sign)
    return record, mode, slip_sign, y, turned


def _adaptive(grasp: Grasp, traj: Trajectory, y0, t_end, s: IntegratorSettings, progress):
    started = time.perf_counter()
    t = 0.0
    peaks = PeakFinder(grasp.fingers)
    traj.peaks = peaks.peaks
    mode, slip_sign, y = decide_mode(grasp, t, np.asarray(y0, float))
    if not _keep(grasp, traj, grasp.record(t, y, mode, slip_sign)):
        return traj
    last_report = 0.0
    while t < t_end - 1e-12:
        fun = (lambda m, sg: (lambda tt, yy: grasp.rhs(tt, yy, m, sg)))(mode, slip_sign)
        jac = {"jac": (lambda m, sg: (lambda tt, yy: grasp.jacobian(tt, yy, m, sg, s.atol)))(
            mode, slip_sign)} if s.stepper in IMPLICIT else {}
        stepper = STEPPERS[s.stepper](fun, t, y, t_end, rtol=s.rtol, atol=s.atol,
                                      max_step=s.max_step, **jac)
        events = _events(grasp, mode, slip_sign)
        restart = False
        while not restart and stepper.status == "running":
            t_old, y_old = stepper.t, stepper.y.copy()
            g_old = {k: f(t_old, y_old) for k, f in events.items()}
            before = grasp.fingers.snapshot()
            msg = stepper.step()
            if stepper.status == "failed":
                traj.ok, traj.message = False, f"integrator failed at t = {t_old:.4f} s: {msg}"
                return traj
            traj.steps += 1
            if traj.over_budget(started, s.max_wall_time, t_old, t_end):
                return traj
            dense = stepper.dense_output()
            t_new, y_new = stepper.t, stepper.y.copy()
            hits = []
            for name, f in events.items():
                # armed only once clearly positive: a switch leaves its new mode's
                # event functions at zero, and rounding must not switch back
                if g_old[name] > EVENT_ARM[name] and f(t_new, y_new) <= 0:
                    hits.append((_locate(f, dense, t_old, t_new), name))
            if hits:
                tau, name = min(hits)
                if grasp.fingers.touch_margin(tau, dense(tau)) <= -TOUCH_DEPTH:
                    # a finger touches the bird before the event: the step ends
                    # there instead, and the event is found again from it
                    touch = _locate(grasp.fingers.touch_margin, dense, t_old, tau, TOUCH_DEPTH)
                    if touch > t_old:
                        tau, name = touch, TOUCHES
                if len(traj.events) >= MAX_EVENTS_AT_ONCE and \
                        tau - traj.events[-MAX_EVENTS_AT_ONCE][0] < 1e-9:
                    traj.ok = False
                    traj.message = (f"modes chatter at t = {tau:.6f} s: "
                                    f"{', '.join(e[1] for e in traj.events[-5:])}")
                    return traj
                traj.events.append((float(tau), name))
                mode, slip_sign, y = _after_event(grasp, name, tau, dense(tau), mode, slip_sign)
                t = tau
                record, mode, slip_sign, y, _ = _commit(grasp, t, y, mode, slip_sign)
                if not _keep(grasp, traj, record):
                    return traj
                peaks.accepted(Span(t_old, t, dense, before), traj.records)
                restart = True
                continue
            snapshot = grasp.fingers.snapshot()
            t, committed = t_new, _commit(grasp, t_new, y_new, mode, slip_sign)
            if committed[4]:
                # a finger's friction turned within the step: it turns where its
                # reversal margin (with the friction it had) crosses zero
                grasp.fingers.restore(snapshot)
                t = _locate(grasp.fingers.reversal_margin, dense, t_old, t_new, REVERSAL_DEPTH)
                traj.events.append((float(t), "friction reverses"))
                committed = _commit(grasp, t, dense(t), mode, slip_sign)
                restart = True
            elif grasp.fingers.touched:
                # a finger touched the bird within the step, where the trials left
                # it out: the step ends where it first touches (a new smooth piece)
                grasp.fingers.restore(snapshot)
                t = _locate(grasp.fingers.touch_margin, dense, t_old, t_new, TOUCH_DEPTH)
                # inside already where the step began (its solve there found no
                # force): the contact starts where the step ends, as found
                t = t_new if t <= t_old else t
                traj.events.append((float(t), TOUCHES))
                committed = _commit(grasp, t, y_new if t == t_new else dense(t), mode, slip_sign)
                restart = True
            record, mode, slip_sign, y, _ = committed
            if not _keep(grasp, traj, record):
                return traj
            peaks.accepted(Span(t_old, t, dense, before), traj.records)
            if progress and t - last_report >= 0.1:
                progress(f"grasp: t = {t:.2f} s of {t_end:g} s, mode {mode}, "
                         f"{traj.steps} steps")
                last_report = t
    return traj


# ---------------------------------------------------------------------- BDF-4
#: the implicit step's Newton (forward-difference Jacobian, undamped as in
#: the thesis): step tolerance on the state (m, rad, m/s, rad/s), iterations
NEWTON_TOLERANCE, NEWTON_ITERATIONS = 1e-12, 20
_BDF = {1: ([1.0], 1.0), 2: ([4 / 3, -1 / 3], 2 / 3), 3: ([18 / 11, -9 / 11, 2 / 11], 6 / 11),
        4: ([48 / 25, -36 / 25, 16 / 25, -3 / 25], 12 / 25)}


def _local_error(history: list[np.ndarray], order: int, z: np.ndarray) -> float:
    """Milne's estimate of a BDF step's local error in the position (X, Z, m):
    |z - p| / (k + 2), z the accepted state (after the belt's projection or
    impact), p the degree-k extrapolation (k = order, fewer while the history
    is short) of the last k + 1 states to the new step; 0 at the first step."""
    k = min(order, len(history) - 1)
    if k < 1:
        return 0.0
    weights = [(-1) ** j * comb(k + 1, j + 1) for j in range(k + 1)]
    predicted = sum(w * history[-1 - j][:2] for j, w in enumerate(weights))
    return float(np.max(np.abs(z[:2] - predicted))) / (k + 2)


def _bdf4(grasp: Grasp, traj: Trajectory, y0, t_end, s: IntegratorSettings, progress):
    """Thesis §4.4: BDF of order 4 (lower orders to start), forces frozen."""
    dyn, h = grasp.dyn, s.step
    y = dyn.settle(np.asarray(y0, float))
    t = 0.0
    mode = "slip"
    history = [y.copy()]
    n_steps = int(np.ceil(t_end / h - 1e-9))
    rec = grasp.record(t, y, mode, 0.0)
    traj.records.append(rec)
    started = time.perf_counter()
    for n in range(n_steps):
        if traj.over_budget(started, s.max_wall_time, t, t_end):
            return traj
        loads, _ = grasp.fingers.evaluate(t, y)            # frozen over the step
        v, v_dot = grasp.belt(t)
        sign = float(np.sign(dyn.slip(y, v)))               # frozen friction sign
        if grasp.conveyor.decelerates and grasp.start is None and \
                grasp.conveyor.start_position is not None and y[0] >= grasp.conveyor.start_position:
            grasp.start = t
        order = min(len(history), 4)
        alphas, beta = _BDF[order]
        known = sum(a * history[-1 - j] for j, a in enumerate(alphas))

        def residual(z):
            acc, _, _ = dyn.accelerations(z, loads, mode, v_dot, sign)
            return z - known - h * beta * np.concatenate([z[3:], acc])

        step = damped_newton(forward_difference(residual), history[-1], NEWTON_TOLERANCE,
                             NEWTON_ITERATIONS, min_damping=1.0)
        if not step.converged:
            traj.ok = False
            traj.message = (f"BDF-4 step from t = {t:.4f} s failed: {step.message} (largest "
                            f"residual {np.max(np.abs(step.residual)):.3g})")
            return traj
        z = step.x
        t += h
        if mode != "air":
            _, normal, _ = dyn.accelerations(z, loads, mode, v_dot, sign)
            if normal < 0:
                mode = "air"
                traj.events.append((t, "lift-off"))
            else:
                z = dyn.settle(z)
        elif dyn.gap(z) < 0:
            z = dyn.land(z)
            mode = "slip"
            traj.events.append((t, "touch-down"))
        error = _local_error(history, order, z)
        if traj.local_error is None or error > traj.local_error[0]:
            traj.local_error = (error, t)
        if error > s.max_local_error:
            traj.ok = False
            traj.message = (f"BDF-4 step from t = {t - h:.4f} s: estimated local error "
                            f"{error:.3g} m in the bird's position, over max_local_error "
                            f"{s.max_local_error:g} m: the step of {h:g} s is too long for "
                            f"this scene (use a shorter step or the adaptive integrator)")
            return traj
        y = z
        history.append(y.copy())
        history = history[-5:]
        traj.steps += 1
        rec = grasp.record(t, y, mode, sign)
        traj.records.append(rec)
        if progress and n % 50 == 0:
            progress(f"grasp (BDF-4): t = {t:.2f} s of {t_end:g} s")
    return traj


__all__ = ["Grasp", "IntegratorSettings", "Trajectory", "integrate", "INTEGRATORS", "Loads"]
