"""Where a design run's time goes: wall and CPU time per phase, Ipopt's
function evaluations, peak memory.

A :class:`Profile` is passed through the design loop (it is an attribute of
:class:`~design.solvers.optimize.trust_region.Outcome`) and of ``design
solve``'s run, which writes :meth:`Profile.summary` to result.json's
``profile`` and the report's table "Where the time went". The phases do not
overlap, so they add up to the run's wall time; what no phase covers (the
loop's bookkeeping, progress messages) is its own row, ``unaccounted``.
Each phase also has the process's CPU time (``process_time``), which
another process on the machine does not inflate as it does the wall time.

Phases (:data:`PHASES`): the problem's setup (which may simulate the
baseline once to time the belt's deceleration); the loop's simulations
(baseline, start, every candidate); for the optimiser's NLPs and for the
fixed-design views (the NLP with the design fixed, which must reproduce a
simulation), each of construction (the simulated schedule, the CasADi
graph, ``nlpsol`` with its derivative functions), Ipopt (the solver call
alone) and reading the solution back (the peak force at the solution, the
NLP's size); the verification simulations at 4x finer resolution (the
baseline's and each cap's design); and assembling the result. The report's
own rendering is outside the profile (it is drawn from it).

Inside each Ipopt phase, CasADi's statistics of every solve (``nlpsol``
with ``record_time``) are summed: wall and CPU time and call count of nlp_f,
nlp_g, nlp_grad_f, nlp_jac_g (and nlp_hess_l if an exact Hessian is used)
and of the iteration callback; what remains of the Ipopt phase is Ipopt's
own work (linear algebra, L-BFGS, line search) and CasADi's overhead.
The contact rootfinders embedded in the constraints have no statistics
CasADi accumulates over a solve (a rootfinder's ``stats()`` describe its
last call only), so their time is inside nlp_g and nlp_jac_g; the NLP
counts the stage contacts it solved (``rootfinder_solves``: an evaluation
at a point already evaluated, as the Jacobian after the constraints,
reuses the solutions; design/solvers/optimize/finger_load.py), else they are
counted as finger stages x evaluations of nlp_g and nlp_jac_g.

``compiled`` says whether the NLPs' finger functions ran as compiled C
(design/solvers/compiled.py) or interpreted, with the compiler command or the
reason (no compiler, a failed build, ``DESIGN_COMPILE=0``), and how many
libraries the run built (their wall time is inside NLP construction; the
compiler's CPU time, in child processes, is reported apart, not in the
run's CPU time) or loaded from the cache.

Peak memory is the process's peak resident set (``getrusage``'s
``ru_maxrss``) since it started, which includes whatever ran before the
design run in the same process.
"""

from __future__ import annotations

import os
import resource
import sys
import time
from contextlib import contextmanager
from dataclasses import dataclass, field

from design.solvers.compiled import status as compile_status

#: phase names in the order tables list them
SETUP = "problem setup"
SIMULATIONS = "loop simulations"
OPTIMISER, VIEWS = "optimiser NLPs", "fixed-design views"
CONSTRUCTION, IPOPT, READ_BACK = "construction", "Ipopt", "solution read-back"
VERIFICATION = "verification simulations (4x finer)"
RESULT = "result assembly"
#: waiting for the spatial model check's background runs (their own CPU
#: time is in result.json's model_check)
MODEL_CHECK = "spatial model check (wait)"
#: waiting for the robustness table's background runs (design/solvers/optimize/robustness.py)
ROBUSTNESS = "robustness scenes (wait)"
#: a study's cases while they run on Dask workers (their own phases are theirs)
STUDY = "study cases on workers"
#: a study run in this process: what its cases spend outside their own
#: phases (the case store's writes, each case's setup and result entry)
CASE_OVERHEAD = "study engine and case setup"
UNACCOUNTED = "unaccounted"
PHASES = [SETUP, SIMULATIONS,
          *(f"{group}: {step}" for group in (OPTIMISER, VIEWS)
            for step in (CONSTRUCTION, IPOPT, READ_BACK)),
          VERIFICATION, CASE_OVERHEAD, MODEL_CHECK, ROBUSTNESS, RESULT]
#: the rootfinders' row (their time is inside nlp_g and nlp_jac_g)
ROOTFINDERS = "contact rootfinder solves"


def peak_memory_mib() -> float:
    """The process's peak resident set so far (MiB)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / 1024 ** 2 if sys.platform == "darwin" else peak / 1024   # bytes / KiB


def clocks() -> tuple[float, float]:
    """(wall, CPU) time (s) now: ``perf_counter`` and this process's
    ``process_time`` (every thread's CPU time, so robust to other processes
    on the machine, and above the wall time when threads run in parallel)."""
    return time.perf_counter(), time.process_time()


@dataclass
class NLPTotals:
    """CasADi's statistics summed over the solves of one group of NLPs."""

    solves: int = 0
    ipopt_iterations: int = 0
    #: Python's wall and CPU time around the solver calls (s)
    wall_time: float = 0.0
    cpu_time: float = 0.0
    #: CasADi's own total of the solver calls (s)
    casadi_total: float = 0.0
    #: function name -> [wall time (s), calls, CPU time (s)]
    functions: dict = field(default_factory=dict)
    rootfinder_solves: int = 0

    def add(self, timings: dict) -> None:
        stats = timings.get("stats") or {}
        self.solves += 1
        self.ipopt_iterations += int(stats.get("iter_count", 0))
        self.wall_time += timings.get("solve_s", 0.0)
        self.cpu_time += timings.get("solve_cpu_s", 0.0)
        self.casadi_total += float(stats.get("t_wall_total", 0.0))
        for key, value in stats.items():
            if key.startswith("n_call_") and key != "n_call_total":
                name = key[len("n_call_"):]
                calls = int(value)
                if calls:
                    entry = self.functions.setdefault(name, [0.0, 0, 0.0])
                    entry[0] += float(stats.get(f"t_wall_{name}", 0.0))
                    entry[1] += calls
                    entry[2] += float(stats.get(f"t_proc_{name}", 0.0))
        if "rootfinder_solves" in timings:
            self.rootfinder_solves += int(timings["rootfinder_solves"])
        else:                   # every evaluation of g or its Jacobian solves every stage
            evaluations = int(stats.get("n_call_nlp_g", 0)) + \
                int(stats.get("n_call_nlp_jac_g", 0))
            self.rootfinder_solves += int(timings.get("finger_stages", 0)) * evaluations

    def merge(self, other: NLPTotals) -> None:
        self.solves += other.solves
        self.ipopt_iterations += other.ipopt_iterations
        self.wall_time += other.wall_time
        self.cpu_time += other.cpu_time
        self.casadi_total += other.casadi_total
        self.rootfinder_solves += other.rootfinder_solves
        for name, values in other.functions.items():
            entry = self.functions.setdefault(name, [0.0, 0, 0.0])
            for k, v in enumerate(values):
                entry[k] += v

    def summary(self) -> dict:
        """The group's totals; ``ipopt_internal``: Ipopt's own work and
        CasADi's overhead, the solver calls' time less every function
        evaluation and callback."""
        evaluations = [sum(f[k] for f in self.functions.values()) for k in (0, 2)]
        return {"solves": self.solves, "ipopt_iterations": self.ipopt_iterations,
                "ipopt_wall_time_s": self.wall_time, "ipopt_cpu_time_s": self.cpu_time,
                "casadi_total_wall_time_s": self.casadi_total,
                "ipopt_internal_wall_time_s": max(self.wall_time - evaluations[0], 0.0),
                "ipopt_internal_cpu_time_s": max(self.cpu_time - evaluations[1], 0.0),
                "functions": {name: {"wall_time_s": wall, "cpu_time_s": cpu, "calls": calls}
                              for name, (wall, calls, cpu) in self.functions.items()},
                "rootfinder_solves": self.rootfinder_solves}


@dataclass
class Profile:
    """Wall and CPU time (s) and count per phase, CasADi's statistics per NLP
    group, from its creation (the run's start) on."""

    started: tuple = field(default_factory=clocks)
    cpus: int | None = field(default_factory=os.cpu_count)
    load_average: tuple = field(default_factory=os.getloadavg)
    #: phase -> [wall time (s), count, CPU time (s)]
    phases: dict = field(default_factory=dict)
    #: group (OPTIMISER, VIEWS) -> NLPTotals
    nlps: dict = field(default_factory=dict)
    #: compiled libraries loaded in this process before the run
    libraries_before: int = field(default_factory=lambda: len(compile_status.libraries))
    #: per NLP: (its finger functions run compiled, the compiler or why not)
    compiled: list = field(default_factory=list)

    def add(self, phase: str, seconds: float, count: int = 1, cpu: float = 0.0) -> None:
        entry = self.phases.setdefault(phase, [0.0, 0, 0.0])
        entry[0] += seconds
        entry[1] += count
        entry[2] += cpu

    @contextmanager
    def phase(self, name: str):
        """Time the block as one call of ``name`` (also when it raises)."""
        wall, cpu = clocks()
        try:
            yield
        finally:
            now = clocks()
            self.add(name, now[0] - wall, 1, now[1] - cpu)

    def add_nlp(self, group: str, timings: dict | None) -> None:
        """One NLP solve's ``timings`` (DesignNLP.timings: wall and CPU time
        ``build_s``/``build_cpu_s`` of nlpsol, ``solve_s``/``solve_cpu_s``,
        ``post_s``/``post_cpu_s``, CasADi's ``stats``, ``finger_stages``);
        None (the NLP was not built or not solved): nothing to add."""
        if not timings:
            return
        if "compiled" in timings:
            self.compiled.append(timings["compiled"])
        self.add(f"{group}: {CONSTRUCTION}", timings.get("build_s", 0.0), 0,
                 timings.get("build_cpu_s", 0.0))
        if "solve_s" in timings:
            self.add(f"{group}: {IPOPT}", timings["solve_s"], 1, timings.get("solve_cpu_s", 0.0))
            self.nlps.setdefault(group, NLPTotals()).add(timings)
        if "post_s" in timings:
            self.add(f"{group}: {READ_BACK}", timings["post_s"], 1,
                     timings.get("post_cpu_s", 0.0))

    def timed(self) -> tuple[float, float]:
        """Wall and CPU time (s) of all phases so far."""
        return (sum(p[0] for p in self.phases.values()),
                sum(p[2] for p in self.phases.values()))

    def merge(self, other: Profile) -> None:
        """Add another profile's phases and NLP statistics (not its clock)."""
        for name, (wall, count, cpu) in other.phases.items():
            self.add(name, wall, count, cpu)
        for group, totals in other.nlps.items():
            self.nlps.setdefault(group, NLPTotals()).merge(totals)
        self.compiled += other.compiled

    def compiled_summary(self) -> dict:
        """Whether the NLPs' finger functions ran compiled (None: no NLP was
        built), the compiler command or why not, and the libraries built or
        loaded during the run."""
        reasons = sorted({r for _, rs in self.compiled for r in rs})
        return {"compiled": all(c for c, _ in self.compiled) if self.compiled else None,
                "reason": "; ".join(reasons),
                **compile_status.summary(self.libraries_before)}

    def summary(self) -> dict:
        """result.json's ``profile``: the phases in order with the unaccounted
        rest, each NLP group's CasADi statistics, peak memory, the machine."""
        now = clocks()
        total, total_cpu = now[0] - self.started[0], now[1] - self.started[1]
        order = PHASES + [p for p in self.phases if p not in PHASES]
        phases = [{"phase": p, "wall_time_s": self.phases[p][0],
                   "cpu_time_s": self.phases[p][2], "calls": self.phases[p][1]}
                  for p in order if p in self.phases]
        phases.append({"phase": UNACCOUNTED,
                       "wall_time_s": max(total - sum(p["wall_time_s"] for p in phases), 0.0),
                       "cpu_time_s": max(total_cpu - sum(p["cpu_time_s"] for p in phases), 0.0),
                       "calls": None})
        return {"wall_time_s": total, "cpu_time_s": total_cpu, "phases": phases,
                "nlp": {group: totals.summary() for group, totals in self.nlps.items()},
                "peak_memory_MiB": peak_memory_mib(),
                "compiled": self.compiled_summary(),
                "machine": {"cpus": self.cpus, "load_average_at_start": list(self.load_average),
                            # BLAS threads change the linear algebra's speed on 2 shared cores
                            "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS")}}


def profile_rows(profile: dict) -> list[dict]:
    """The table "Where the time went": every phase with its wall time (s),
    share of the total wall time (%), CPU time (s) and calls, each Ipopt
    phase followed by its breakdown (rows marked ↳, not to be added again),
    then the total."""
    total = profile["wall_time_s"]

    def row(name, wall, cpu, calls):
        return {"phase": name, "wall time (s)": wall,
                "share of total (%)": None if wall is None else 100 * wall / total if total > 0
                else 0.0, "CPU time (s)": cpu, "calls": calls}

    rows = []
    for p in profile["phases"]:
        rows.append(row(p["phase"], p["wall_time_s"], p.get("cpu_time_s"), p["calls"]))
        group, _, step = p["phase"].partition(": ")
        if step != IPOPT or group not in profile["nlp"]:
            continue
        n = profile["nlp"][group]
        for name, f in sorted(n["functions"].items(), key=lambda kv: -kv[1]["wall_time_s"]):
            rows.append(row(f"↳ {name}", f["wall_time_s"], f.get("cpu_time_s"), f["calls"]))
        rows.append(row(f"↳ Ipopt itself and CasADi overhead ({n['ipopt_iterations']} "
                        "iterations)", n["ipopt_internal_wall_time_s"],
                        n.get("ipopt_internal_cpu_time_s"), n["solves"]))
        rows.append(row(f"↳ {ROOTFINDERS} (time inside nlp_g, nlp_jac_g)", None, None,
                        n["rootfinder_solves"]))
    rows.append(row("total", total, profile.get("cpu_time_s"), None))
    return rows


def profile_text(profile: dict) -> str:
    """:func:`profile_rows` as a plain-text table, with peak memory and the
    machine's cores and load."""
    def cell(value, spec):
        return "-" if value is None else format(value, spec)

    lines = [f"{'phase':62} {'wall s':>8} {'share %':>7} {'CPU s':>8} {'calls':>7}"]
    for r in profile_rows(profile):
        lines.append(f"{r['phase']:62} {cell(r['wall time (s)'], '8.2f'):>8} "
                     f"{cell(r['share of total (%)'], '7.1f'):>7} "
                     f"{cell(r['CPU time (s)'], '8.2f'):>8} "
                     f"{'' if r['calls'] is None else r['calls']:>7}")
    m = profile["machine"]
    load = ", ".join(f"{x:.2f}" for x in m["load_average_at_start"])
    lines.append(f"peak memory {profile['peak_memory_MiB']:.0f} MiB; {m['cpus']} cores, load "
                 f"average {load} at the start")
    c = profile.get("compiled")
    if c and c["compiled"] is not None:
        lines.append(f"contact functions {'compiled' if c['compiled'] else 'interpreted'} "
                     f"({c['reason']}); {c['libraries_built']} of {c['libraries_loaded']} "
                     f"libraries built in this run ({c['compile_wall_time_s']:.1f} s wall, "
                     f"{c.get('compiler_cpu_time_s', 0.0):.1f} s CPU in the compiler)")
    return "\n".join(lines)
