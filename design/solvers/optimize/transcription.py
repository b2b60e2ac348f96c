"""The design NLP: multiple shooting over the schedule's phases, solved by Ipopt.

Unknowns: the scaled design d ∈ [0, 1]^n, the phase durations T_j and the
bird's state (X, Z, θ, Ẋ, Ż, θ̇) at every interval node. Each phase j is
cut into n_j equal intervals of T_j / n_j, integrated by one RK4 step whose
four stages each evaluate the belt mode's dynamics (design/physics/bird.py)
with the loads of the fingers in contact there (:mod:`finger_load`: the
collocated contact solved by an embedded rootfinder, so the constraint
Jacobian is exact). Constraints:

* continuity between nodes; between phases the event's jump (touch-down:
  the plastic impact) and the event condition at the switch (lift-off
  N = 0, touch-down gap = 0, stick→slip |F_c| = µN, slip→stick slip = 0);
* the mode holds at every node: stick N ≥ 0 and |F_c| ≤ µN, slip N ≥ 0 and
  the slip keeps its sign, air gap ≥ 0 (complementarity by phases);
* the bruise cap on every finger's force at every stage, and its fold force
  (scaled with its stiffness): a finger past it jams the bird;
* Σ T_j = the horizon, the start on the belt from the closed-form belt
  motion, the design rules, and the trust region around the current design.

Objective: maximise the hold phase's duration. The Hessian is approximated
by L-BFGS (the rootfinders' second derivatives are not worth their cost).
"""

from __future__ import annotations

import os
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from design.interrupt import checkpoint
from design.interrupt import requested as interrupt_requested
from design.physics.bird import BirdDynamics, Loads, belt_motion
from design.solvers.grasp.validity import fold_force
from design.solvers.reproducible import IPOPT_ORDERING
from design.solvers.optimize.finger_load import FingerLoad
from design.solvers.optimize.schedule import STAGES, Schedule
from design.solvers.optimize.variables import DesignSpace, parameters_of

#: the hold time enters the objective in units of this (s)
OBJECTIVE_SCALE = 0.1
#: no phase shorter than this (s)
MIN_DURATION = 1e-4
#: the NLP's bound on the bird's pitch (rad): the optimiser does not design tumbles
MAX_PITCH = 1.5
#: an iterate this feasible (largest violation, in the constraints' units) may
#: stand for a solve that ended infeasible (an iteration limit, a stall): the
#: best of them, by the objective, is its answer
FEASIBLE_ITERATE = 1e-4


@dataclass(frozen=True)
class NLPSettings:
    """Time grid (s), finger beam mesh, Ipopt limits and options.

    The 5 ms default is the coarsest grid on which the fixed-design NLP of
    the thesis design reproduces its simulation: on 10 ms it stays
    infeasible (`design tradeoff problems/hold_time.yaml`)."""

    time_step: float = 0.005
    beam_intervals: int = 6
    degree: int = 4
    max_iter: int = 60
    tol: float = 1e-6
    ipopt: dict = field(default_factory=dict)
    #: wall-clock limit of one Ipopt solve (s): a safety net only, far above a
    #: normal solve, since a binding limit makes results depend on machine load
    max_wall_time: float = 600.0
    #: stop when the constraint violation is above ``stall_violation`` and the
    #: last ``stall_iterations`` iterations have not lowered its best value by
    #: 10 % (0: never); deterministic, unlike a time limit
    stall_iterations: int = 0
    stall_violation: float = 0.0


@dataclass(frozen=True)
class Rules:
    """Design rules of §5.1 as constraints: drum spacing ≥ λ + σ_λ and ≥
    every finger's length (5.7); ``bird_spacing`` Δx (m) with ``finger_sets``
    n (None: the grasper's own number of sets) fixes the speed ratio
    v/ω = n Δx / (2π) (5.3-5.4)."""

    sigma_lambda: float = 0.0
    bird_spacing: float | None = None
    finger_sets: int | None = None


#: Ipopt's return statuses that end a solve on an error, not at an iterate it
#: judged (converged, stopped by a limit, or found infeasible): an exception
#: in an evaluation or a callback, a NaN at the iterate, an invalid problem
IPOPT_ERRORS = frozenset({
    "Not_Enough_Degrees_Of_Freedom", "Invalid_Problem_Definition", "Invalid_Option",
    "Invalid_Number_Detected", "Unrecoverable_Exception", "NonIpopt_Exception_Thrown",
    "Insufficient_Memory", "Internal_Error"})


def _belt_function() -> ca.Function:
    """belt_motion (design/physics/bird.py) as an SX function of (t, speed,
    final speed, rate, start)."""
    args = [ca.SX.sym(n) for n in ("t", "speed", "final_speed", "rate", "start")]
    return ca.Function("belt", args, list(belt_motion(*args)),
                       ["t", "speed", "final_speed", "rate", "start"], ["v", "v_dot", "travel"])


_BELT = _belt_function()


class NLPFailed(RuntimeError):
    """Ipopt ended on an error (one of :data:`IPOPT_ERRORS`): no iterate to use."""


@dataclass
class NLPResult:
    d: np.ndarray
    durations: np.ndarray
    hold_time: float
    peak_force: float
    status: str
    success: bool
    iterations: int
    wall_time: float
    size: dict
    history: list
    #: the whole primal-dual solution (CasADi's signs: λ > 0 at an upper bound)
    x: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray
    #: the largest finger force (N) of each bird (default: one bird, ``peak_force``)
    peaks: np.ndarray | None = None
    #: the largest constraint violation at x (default: the last iteration's)
    violation: float | None = None
    #: the Ipopt iteration x is from (default: the last)
    iteration: int | None = None

    def __post_init__(self):
        if self.peaks is None:
            self.peaks = np.array([self.peak_force])
        if self.violation is None:
            self.violation = self.history[-1]["violation"] if self.history else np.inf
        if self.iteration is None:
            self.iteration = len(self.history) - 1


class DesignNLP:
    """The NLP for one schedule, cap and trust region ``box`` (bounds on d).

    ``objective``: ``hold`` maximises the hold phase's duration; ``track``
    stays closest to the simulated phase durations (for a fixed design, whose
    events pin its timing: the optimiser's own view of a simulated design).
    """

    def __init__(self, space: DesignSpace, schedule: Schedule, run, cap: float,
                 settings: NLPSettings, rules: Rules = Rules(), box=None, progress=None,
                 objective: str = "hold"):
        self.space, self.schedule, self.settings = space, schedule, settings
        self.progress = progress
        setup = self.setup = space.baseline
        self.dyn = BirdDynamics(setup.bird, setup.legs, setup.conveyor_friction)
        used = {i for p in schedule.phases for iv in p.contacts for st in iv
                for i, c in enumerate(st) if c is not None}
        self.fingers = {i: FingerLoad(setup.grasper.fingers[i], setup.grasper, setup.bird,
                                      setup.finger_friction, settings.beam_intervals,
                                      settings.degree, setup.finger_model,
                                      setup.finger_belt_friction)
                        for i in sorted(used)}
        self._modes = {}
        self.objective = objective
        self._build(run, cap, rules, box)
        #: (whether every finger function's SX parts run compiled, the reasons)
        states = [m for f in self.fingers.values() for m in f.compiled.values()]
        self.compiled = (all(c for c, _ in states),
                         sorted({reason for _, reason in states}))

    # ------------------------------------------------------------ model
    def _mode_function(self, mode: str, sign: float) -> ca.Function:
        """(y, loads, v̇) -> (ẏ, N, F_c) of one belt mode."""
        key = (mode, sign)
        if key not in self._modes:
            y, q, vd = ca.SX.sym("y", 6), ca.SX.sym("q", 3), ca.SX.sym("vd")
            acc, normal, friction = self.dyn.accelerations(y, Loads(q[0], q[1], q[2]), mode, vd,
                                                           sign)
            self._modes[key] = ca.Function(f"bird_{mode}", [y, q, vd],
                                           [ca.vertcat(y[3:], acc), normal, friction])
        return self._modes[key]

    def _runge_kutta(self, grid, values) -> dict:
        """The RK4 stages of every interval: (j, k) -> (the summed finger
        loads at each stage, the stage derivatives k_s, the finger forces in
        stage then finger order, each with its finger's index). Built stage
        by stage across all intervals (stage s needs stage s-1 of its own
        interval only), so that each
        finger and contact mode is one batched call per stage
        (FingerLoad.batch) instead of a call per interval."""
        sch, grasper = self.schedule, self.setup.grasper
        g = ca.vertcat(values["spacing"], values["drum_speed"])
        design = {}
        for i in self.fingers:
            gf = grasper.fingers[i]
            key = f"fingers.{gf.design_name}."
            design[i] = (ca.vertcat(values[key + "angle"] + gf.phase, values[key + "height"],
                                    gf.mount.radius, values[key + "phi_x"],
                                    values[key + "phi_y"], values[key + "length"]),
                         values[f"groups.{gf.group}.stiffness_scale"])
        cells = [(j, k) for j, phase in enumerate(sch.phases) for k in range(phase.intervals)]
        out = {cell: ([], [], []) for cell in cells}
        for s, c in enumerate(STAGES):
            states, times, calls = {}, {}, {}
            for j, k in cells:
                nodes, h, t_phase = grid[j]
                y, ks = nodes[:, k], out[j, k][1]
                t = t_phase + k * h
                times[j, k] = t + c * h
                states[j, k] = y if s == 0 else y + c * h * ks[-1] if s < 3 else y + h * ks[-1]
                for i, contact in enumerate(sch.phases[j].contacts[k][s]):
                    if contact is not None:
                        calls.setdefault((i, contact.mode), []).append((j, k, contact))
            results = {}
            for (i, mode), group in calls.items():
                f = self.fingers[i].batch(mode, len(group))
                fp, scale = design[i]
                state = ca.horzcat(*[states[j, k] for j, k, _ in group])
                stage_times = ca.horzcat(*[times[j, k] for j, k, _ in group])
                given = {"pose": state[:3, :], "state": state, "t": stage_times,
                         "belt": self._belt(stage_times, values)[0],
                         "fp": ca.repmat(fp, 1, len(group)), "g": ca.repmat(g, 1, len(group)),
                         "k": ca.repmat(scale, 1, len(group)),
                         "tau_mu": ca.DM([[cc.tau_mu for _, _, cc in group]]),
                         "z0": ca.DM(np.column_stack([cc.z for _, _, cc in group]))}
                load, force, _ = f(*(given[name] for name in self.fingers[i].inputs))
                for n, (j, k, _) in enumerate(group):
                    results[j, k, i] = load[:, n], force[0, n]
            for j, k in cells:
                phase = sch.phases[j]
                total = ca.MX.zeros(3)
                for i, contact in enumerate(phase.contacts[k][s]):
                    if contact is not None:
                        load, force = results[j, k, i]
                        total += load
                        out[j, k][2].append((force, i))
                out[j, k][0].append(total)
                _, v_dot, _ = self._belt(times[j, k], values)
                mode_f = self._mode_function(phase.mode, phase.sign)
                out[j, k][1].append(mode_f(states[j, k], total, v_dot)[0])
        return out

    def _belt(self, t, values):
        """Belt speed, acceleration and travel at t: one call of an SX function
        (the closed form's twenty-odd operations as one node of the NLP's
        graph, not twenty: a third of the NLP's construction time)."""
        c = self.setup.conveyor
        return _BELT(t, c.speed, values["conveyor.final_speed"], values["conveyor.rate"],
                     values["conveyor.start_time"])

    # ------------------------------------------------------------ NLP
    def _build(self, run, cap, rules, box):
        sch, space, dyn = self.schedule, self.space, self.dyn
        n = space.size
        d = ca.MX.sym("d", n)
        durations = ca.MX.sym("T", len(sch.phases))
        values = space.values(d)
        w, w0, lbw, ubw = [d, durations], [], [], []
        lo, hi = (np.zeros(n), np.ones(n)) if box is None else box
        d0 = space.scale(run_values(run, space))
        w0 += [d0, [p.duration for p in sch.phases]]
        lbw += [lo, np.full(len(sch.phases), MIN_DURATION)]
        ubw += [hi, np.full(len(sch.phases), sch.t_end - sch.t_start)]
        g, lbg, ubg, tags = [], [], [], []

        def constrain(expr, lower, upper, tag):
            g.append(expr)
            size = expr.numel()
            lbg.append(np.full(size, lower))
            ubg.append(np.full(size, upper))
            tags.extend([tag] * size)

        forces: list = []
        mu = dyn.mu
        t0 = self.setup.start_x
        # on the belt, untouched, until t_start: the closed-form belt motion (a
        # belt that slows must not start before then: it would roll the bird;
        # one that keeps its speed may 'start' when it likes)
        v_a, _, travel = self._belt(sch.t_start, values)
        if isinstance(values["conveyor.start_time"], ca.MX):
            slowing = self.setup.conveyor.speed - values["conveyor.final_speed"]
            constrain((values["conveyor.start_time"] - sch.t_start) * slowing, 0.0, np.inf,
                      "belt start")
        bird = self.setup.bird
        start_state = ca.vertcat(t0 + travel, bird.gamma, 0.0, v_a, 0.0, 0.0)
        grid = []                       # per phase: (nodes, interval h, start time)
        t_phase = sch.t_start
        for j, phase in enumerate(sch.phases):
            h = durations[j] / phase.intervals
            nodes = ca.MX.sym(f"y{j}", 6, phase.intervals)
            w.append(ca.vec(nodes))
            pitch = np.abs(phase.states[:, 2])
            if pitch.max() > MAX_PITCH:
                k = int(np.argmax(pitch))
                at = phase.t0 + k * phase.duration / phase.intervals
                raise ValueError(
                    f"the simulated bird turns over inside the optimiser's window (pitch "
                    f"{phase.states[k, 2]:+.2f} rad at t = {at:.3f} s; the NLP keeps |pitch| "
                    f"<= {MAX_PITCH} rad): no design can start from it")
            w0.append(phase.states.ravel())
            lbw.append(np.tile([-np.inf, 0.0, -MAX_PITCH, -np.inf, -np.inf, -np.inf],
                               phase.intervals))
            ubw.append(np.tile([np.inf, 0.5, MAX_PITCH, np.inf, np.inf, np.inf], phase.intervals))
            grid.append((nodes, h, t_phase))
            t_phase = t_phase + durations[j]
        stages = self._runge_kutta(grid, values)
        previous_end = None
        for j, (phase, (nodes, h, t_phase)) in enumerate(zip(sch.phases, grid)):
            mode_f = self._mode_function(phase.mode, phase.sign)
            first = nodes[:, 0]
            if previous_end is None:
                constrain(first - start_state, 0.0, 0.0, "start")
            else:
                prev = sch.phases[j - 1]
                jumped = dyn.land(previous_end) if prev.end == "touch-down" and prev.exact \
                    else previous_end
                constrain(first - jumped, 0.0, 0.0, "continuity")
            for k in range(phase.intervals):
                y = nodes[:, k]
                t = t_phase + k * h
                stage_loads, ks, stage_forces = stages[j, k]
                forces += stage_forces
                end = y + h / 6 * (ks[0] + 2 * ks[1] + 2 * ks[2] + ks[3])
                # the mode holds at the node (its stage-1 loads)
                _, v_dot, _ = self._belt(t, values)
                _, normal, friction = mode_f(y, stage_loads[0], v_dot)
                if k == 0 and j > 0:
                    self._event(sch.phases[j - 1], y, t, stage_loads[0], values, constrain)
                if phase.mode == "air":
                    constrain(y[1] - dyn.support(y[2])[1], 0.0, np.inf, "gap")
                else:
                    constrain(normal, 0.0, np.inf, "normal")
                    if phase.mode == "stick":
                        constrain(mu * normal - friction, 0.0, np.inf, "friction cone")
                        constrain(mu * normal + friction, 0.0, np.inf, "friction cone")
                    else:
                        v, _, _ = self._belt(t, values)
                        constrain(phase.sign * (y[3] - y[5] * dyn.support(y[2])[1] - v), 0.0,
                                  np.inf, "slip sign")
                if k < phase.intervals - 1:
                    constrain(nodes[:, k + 1] - end, 0.0, 0.0, "continuity")
                else:
                    previous_end = end
                    if phase.end == "touch-down":
                        constrain(end[1] - dyn.support(end[2])[1], 0.0, 0.0, "touch-down")
        constrain(ca.sum1(durations), sch.t_end - sch.t_start, sch.t_end - sch.t_start, "horizon")
        self.force = ca.vertcat(*[f for f, _ in forces])
        if forces:
            constrain(self.force, -np.inf, cap, "cap")
            # no finger past its fold force (a jam, design/solvers/grasp/validity.py):
            # the fold force scales with the finger's stiffness
            grasper = self.setup.grasper.fingers
            fold = ca.vertcat(*[fold_force(grasper[i].finger) *
                                values[f"groups.{grasper[i].group}.stiffness_scale"]
                                for _, i in forces])
            constrain(self.force - fold, -np.inf, 0.0, "fold force")
        for expr, tag in rule_constraints(values, self.setup, rules):
            constrain(expr, 0.0, np.inf, tag)
        x = ca.vertcat(*[ca.vec(v) for v in w])
        self.x0 = np.concatenate([np.ravel(v) for v in w0])
        self.lbx, self.ubx = np.concatenate(lbw), np.concatenate(ubw)
        self.g = ca.vertcat(*g)
        self.lbg, self.ubg = np.concatenate(lbg), np.concatenate(ubg)
        self.tags = tags
        self._cap_rows = np.array([t == "cap" for t in tags], bool)
        self._size, self._solver = None, None
        self.n_design, self.n_phases = n, len(sch.phases)
        #: where the objective's hold time (s) sits in x
        self.hold_index = n + sch.hold
        if self.objective == "hold":
            self.f = -durations[sch.hold] / OBJECTIVE_SCALE
        else:       # "track": the simulated phase durations, where events leave slack
            simulated = np.array([p.duration for p in sch.phases])
            self.f = ca.sumsqr((durations - simulated) / self.settings.time_step)
        self.x = x
        self.functions = ca.Function("nlp", [x], [self.f, self.g, self.force])

    def _event(self, phase, y, t, loads, values, constrain):
        """The condition that ended ``phase`` at its last state y (time t):
        an equation for a located event, for a re-decision only that the old
        mode is over (the finger forces may jump there)."""
        if phase.end in ("touch-down", "end"):
            return
        mode_f = self._mode_function(phase.mode, phase.sign)
        _, v_dot, _ = self._belt(t, values)
        _, normal, friction = mode_f(y, loads, v_dot)
        if phase.end == "lift-off":                  # the belt stops pushing
            margin, tag = normal, "lift-off"
        elif phase.end == "slip":                    # friction reached the cone edge
            margin, tag = self.dyn.mu * normal - ca.fabs(friction), "slip starts"
        else:                                        # the slip came to zero
            v, _, _ = self._belt(t, values)
            slip = y[3] - y[5] * self.dyn.support(y[2])[1] - v
            margin, tag = (slip if phase.exact else phase.sign * slip), "stick starts"
        constrain(margin, 0.0 if phase.exact else -np.inf, 0.0, tag)

    def restart_contacts(self) -> None:
        """Every finger stage starts its next solve from the simulation's guess."""
        for finger in self.fingers.values():
            finger.restart()

    @property
    def stage_solves(self) -> int:
        """Finger contacts solved so far in this NLP's functions."""
        return sum(f.stage_solves for f in self.fingers.values())

    @property
    def size(self) -> dict:
        if self._size is None:
            self._size = {
                "variables": int(self.x.numel()), "constraints": int(self.g.numel()),
                "jacobian_nonzeros": int(ca.jacobian_sparsity(self.g, self.x).nnz()),
                "design_variables": self.n_design, "phases": self.n_phases,
                "intervals": self.schedule.intervals, "finger_stages": int(self.force.numel())}
        return dict(self._size)

    def rebound(self, cap: float, box=None) -> DesignNLP:
        """The same NLP (schedule, graph, solver) with another cap (N) and
        trust region ``box``: what the design loop needs after a rejected
        candidate, whose schedule, the best design's, has not changed.
        Solving it gives what a new NLP with these bounds gives."""
        lo, hi = (np.zeros(self.n_design), np.ones(self.n_design)) if box is None else box
        self.lbx[:self.n_design], self.ubx[:self.n_design] = lo, hi
        self.ubg[self._cap_rows] = cap
        return self

    def solve(self) -> NLPResult:
        """Ipopt from the simulated design's states. Records ``self.timings``
        (also when it raises, from the point reached): wall and CPU time
        (s) of ``build`` (nlpsol with its derivative functions), ``solve``
        (the solver call) and ``post`` (reading the solution back) as
        ``build_s``, ``build_cpu_s`` and so on, CasADi's ``stats`` and the
        number of ``finger_stages``, the contacts solved during the solve
        (``rootfinder_solves``) and whether the finger functions run
        ``compiled`` (design/solvers/optimize/profile.py)."""
        history: list = []
        self.timings = {"finger_stages": int(self.force.numel()), "compiled": self.compiled}
        with self._timed("build"):
            if self._solver is None:           # built once, solved again after rebound()
                callback = _Progress(self, history, self.progress)
                self._solver = callback, self._nlpsol(callback)
            callback, solver = self._solver
            callback.restart(history)
        self.restart_contacts()
        solves = self.stage_solves
        try:
            with self._timed("solve"), _casadi_output_muted() as streams:
                callback.streams = streams
                sol = solver(x0=self.x0, lbx=self.lbx, ubx=self.ubx, lbg=self.lbg,
                             ubg=self.ubg)
        finally:
            self.timings["stats"] = _stats(solver)
            self.timings["rootfinder_solves"] = self.stage_solves - solves
        with self._timed("post"):
            return self._result(sol, solver.stats(), self.timings["solve_s"], history, callback)

    def _nlpsol(self, callback) -> ca.Function:
        s = self.settings
        opts = {"ipopt": {"hessian_approximation": "limited-memory", "max_iter": s.max_iter,
                          "tol": s.tol, "acceptable_tol": 1e-4, "print_level": 0, "sb": "yes",
                          "max_wall_time": s.max_wall_time,
                          "mu_strategy": "adaptive", **IPOPT_ORDERING, **s.ipopt},
                "print_time": False, "iteration_callback": callback,
                # each function's wall and CPU time and calls in stats(), for the run's profile
                "record_time": True,
                # a rootfinder that fails at a trial point makes Ipopt shorten its step
                "show_eval_warnings": False}
        return ca.nlpsol("design", "ipopt", {"x": self.x, "f": self.f, "g": self.g}, opts)

    @contextmanager
    def _timed(self, step: str):
        """Record the block's wall and CPU time (s) as ``timings[step_s]`` and
        ``timings[step_cpu_s]``, also when it raises."""
        wall, cpu = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.timings[f"{step}_s"] = time.perf_counter() - wall
            self.timings[f"{step}_cpu_s"] = time.process_time() - cpu

    def _result(self, sol, stats, wall, history, callback) -> NLPResult:
        checkpoint(f"in Ipopt, iteration {stats['iter_count']} of an NLP")
        if callback.error is not None:
            raise NLPFailed(f"Ipopt's iteration callback failed: {callback.error!r}") \
                from callback.error
        if stats["return_status"] in IPOPT_ERRORS:
            raise NLPFailed(f"Ipopt ended on an error, {stats['return_status']}, after "
                            f"{stats['iter_count']} iterations")
        x = np.asarray(sol["x"]).ravel()
        violation, iteration = (history[-1]["violation"], len(history) - 1) if history else \
            (np.inf, -1)
        if violation > FEASIBLE_ITERATE and callback.best is not None:
            # an iteration limit or a stall left Ipopt infeasible after a feasible
            # iterate: that one is the solve's answer
            iteration, x = callback.best
            violation = history[iteration]["violation"]
        try:
            with _casadi_output_muted():
                force = np.asarray(self.functions(x)[2]).ravel()
        except RuntimeError:          # Ipopt stopped at a point a contact cannot reach
            force = np.full(self.force.numel(), np.inf)
        peaks = self.peaks(force)
        return NLPResult(x[:self.n_design], self.durations(x), float(x[self.hold_index]),
                         float(peaks.max()), stats["return_status"],
                         bool(stats["success"]), int(stats["iter_count"]), wall, self.size,
                         history, x, np.asarray(sol["lam_g"]).ravel(),
                         np.asarray(sol["lam_x"]).ravel(), peaks, violation, iteration)

    def durations(self, x: np.ndarray) -> np.ndarray:
        """The phase durations (s) in the solution x."""
        return x[self.n_design:self.n_design + self.n_phases]

    def peaks(self, force: np.ndarray) -> np.ndarray:
        """The largest finger force (N) of each bird, from every stage's forces."""
        return np.array([force.max() if force.size else 0.0])


def _stats(solver) -> dict:
    """The solver's statistics for the profile; none if it has none."""
    try:
        return solver.stats()
    except RuntimeError:
        return {}


@contextmanager
def _casadi_output_muted():
    """CasADi writes through Python's sys.stdout/sys.stderr; mute them while
    Ipopt runs (CasADi dumps every input of a rootfinder call that fails at a
    trial point, and Ipopt then shortens its step: expected, not news).
    Yields the real streams, for the progress reports."""
    streams = sys.stdout, sys.stderr
    with open(os.devnull, "w") as sink:
        sys.stdout = sys.stderr = sink
        try:
            yield streams
        finally:
            sys.stdout, sys.stderr = streams


def run_values(run, space: DesignSpace) -> dict:
    """The parameter values of the simulated design."""
    values = parameters_of(run.setup)
    for gf_base, gf in zip(space.baseline.grasper.fingers, run.setup.grasper.fingers):
        values[f"groups.{gf.group}.stiffness_scale"] = _scale_of(gf_base, gf)
    return values


def _scale_of(base, finger) -> float:
    return float(finger.finger.stiffness.ei(np.array([0.0]))[0] /
                 base.finger.stiffness.ei(np.array([0.0]))[0])


def rule_margins(values: dict, setup, rules: Rules) -> list:
    """(margin ≥ 0 when the rule holds, name) of the design rules, numbers or
    CasADi expressions as the values are."""
    out = [(values["spacing"] - setup.bird.lam - rules.sigma_lambda, "rule 5.7: d >= lambda")]
    for name in dict.fromkeys(gf.design_name for gf in setup.grasper.fingers):
        out.append((values["spacing"] - values[f"fingers.{name}.length"],
                    f"rule 5.7: d >= l ({name})"))
    if rules.bird_spacing is not None:
        sets = rules.finger_sets or len({gf.phase for gf in setup.grasper.fingers})
        ratio = sets * rules.bird_spacing / (2 * np.pi)
        gap = values["conveyor.speed"] / values["drum_speed"] - ratio
        out += [(gap + 1e-6, "rule 5.3: v/omega"), (1e-6 - gap, "rule 5.3: v/omega")]
    return out


def rule_constraints(values: dict, setup, rules: Rules):
    """The rules that depend on design variables, as NLP constraints (the
    others cannot change; the run reports whether they hold)."""
    return [(e, tag) for e, tag in rule_margins(values, setup, rules) if isinstance(e, ca.MX)]


class _Progress(ca.Callback):
    """Ipopt iteration callback: records and reports objective and violation;
    stops Ipopt when the view has stalled or Ctrl-C was pressed."""

    def __init__(self, nlp: DesignNLP, history: list, progress):
        ca.Callback.__init__(self)
        self.nx, self.ng = nlp.x.numel(), nlp.g.numel()
        self.lbg, self.ubg = nlp.lbg, nlp.ubg
        self.history, self.report = history, progress
        self.hold_index = nlp.hold_index
        self.stall = nlp.settings.stall_iterations, nlp.settings.stall_violation
        self.streams = sys.stdout, sys.stderr
        #: an exception in the callback, which ends the solve as an error
        self.error: Exception | None = None
        #: (iteration, x) of the best iterate within FEASIBLE_ITERATE (the least f)
        self.best: tuple[int, np.ndarray] | None = None
        self._best_f = np.inf
        self.construct("progress", {})

    def restart(self, history: list) -> None:
        """For a new solve: record into ``history``, no error yet, no best iterate."""
        self.history, self.error, self.best, self._best_f = history, None, None, np.inf

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        try:
            self._record(arg)
        except Exception as exc:      # noqa: BLE001  CasADi would take it for a stop request
            self.error = exc
            return [1]
        # non-zero: Ipopt stops (User_Requested_Stop)
        return [int(self.stalled() or interrupt_requested())]

    def _record(self, arg) -> None:
        g = np.asarray(arg[ca.nlpsol_out().index("g")]).ravel()
        x = arg[ca.nlpsol_out().index("x")]
        hold = float(x[self.hold_index])
        violation = float(np.max(np.concatenate([[0.0], self.lbg - g, g - self.ubg])))
        f = float(arg[ca.nlpsol_out().index("f")])
        if violation <= FEASIBLE_ITERATE and f < self._best_f:
            self.best, self._best_f = (len(self.history), np.asarray(x).ravel().copy()), f
        self.history.append({"iteration": len(self.history), "hold_time_s": hold,
                             "violation": violation})
        if self.report:
            muted = sys.stdout, sys.stderr
            sys.stdout, sys.stderr = self.streams
            try:
                self.report(f"ipopt iteration {len(self.history) - 1}: hold "
                            f"{hold:.4f} s, constraint violation {violation:.2e}")
            finally:
                sys.stdout, sys.stderr = muted

    def stalled(self) -> bool:
        n, floor = self.stall
        v = [h["violation"] for h in self.history]
        return bool(n) and len(v) > n and v[-1] > floor and min(v[-n:]) > 0.9 * min(v[:-n])
