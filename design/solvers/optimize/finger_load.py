"""One finger's load on the bird as a differentiable CasADi function.

The same chain as the simulator (design/solvers/grasp/fingers.py): the finger's
frame on the drum, the ellipse in which its bending plane cuts the bird
(as a conic, smooth in the pose), the collocated contact equations solved by
a CasADi rootfinder, the force mapped back to the world and doubled for the
mirror finger. Built once per finger and contact mode; called at every stage
of the time grid.

Two finger models (the simulator's, design/solvers/grasp/fingers.py):
``planar``, the thesis's, whose section of the bird is an ellipse and
whose force lies in the finger's bending plane, and ``spatial``, the rod
bending both ways against the ellipsoid with regularised Coulomb friction
against the finger's sliding (a smooth function of the bird's state and
time, so that it needs no friction sense from the schedule).

Inputs (each stage model's ``sizes``): planar, the bird pose (X, Z, θ) (m, rad)
and the signed friction τµ; spatial, the bird's whole state (X, Z, θ and
their rates; the rates set the sliding); both, the time t (s), the
finger's design fp = (angle, height, drum radius, φx, φy, length) (rad,
m), the drums' g = (spacing, speed) (m, rad/s), the stiffness scale k and
the rootfinder's start z0. Outputs: the load on the bird from both drums
(Q_X, Q_Z, T_Y) (N, N, N m), the contact force's magnitude with the normal
force clipped at zero (N; a contact that would pull lets go) and the
contact's unknowns z (an output to read, declared not differentiable).

How it is evaluated: the function is three calls, the kinematics
x -> q (SX), the rootfinder (z0, q) -> z and the loads (x, z) -> outputs
(SX), and its Jacobian is given explicitly (``custom_jacobian``) by the
implicit-function theorem at the solution z it already has,

    d out/dx = ∂out/∂x + ∂out/∂z dz/dx = ∂out/∂x - λᵀ R_x,
    dz/dx = -R_z⁻¹ R_x,   λ = R_z⁻ᵀ (∂out/∂z)ᵀ   (R_x = ∂R/∂q ∂q/∂x),

one sparse QR of R_zᵀ with the four outputs as right-hand sides (the
adjoint λ) per stage, instead of CasADi's derivative of the rootfinder, which
solved the contact again inside every derivative call and carried every
seed through the kinematics' MX graph (``python -m benchmarks.solve`` times
the constraint Jacobian); the rootfinder is Newton with line search and
CasADi's sparse QR, with the residual's Jacobian compiled.

The NLP calls each finger and mode once per RK stage for all the intervals
in that contact (:meth:`FingerLoad.batch`: CasADi's map over the stages,
with the block-diagonal Jacobian of the stage Jacobians), and the batch
remembers the contacts it solved (:class:`_Roots`), so the Jacobian that
Ipopt asks for at the point whose constraints it has just evaluated solves
no contact again, and Ipopt's iterates are the same as without the memory.

The SX parts are generic in a constants vector c (the grasper's position
and tilt, the bird's semi-axes, the finger's reference rigidity, mesh and
stiffness parameters), so that one compiled library serves every finger
of a stiffness structure and every problem (design/solvers/compiled.py:
C code compiled once and cached on disk; interpreted when no compiler).
"""

from __future__ import annotations

import os

import casadi as ca
import numpy as np

from design.physics.bird import Bird
from design.physics.grasper import GraspFinger, Grasper
from design.physics.kinematics import finger_frame, rot_y, section
from design.solvers.beam.rod import RodStiffness
from design.solvers.compiled import compiled
from design.solvers.contact.belt_continuation import BELT_MODES
from design.solvers.contact.equations import MODES, contact_transcription
from design.solvers.contact.planar_belt_equations import planar_belt_transcription
from design.solvers.contact.robust import RobustContact
from design.solvers.contact.spatial import SpatialContact
from design.solvers.contact.spatial_belt_equations import belt_transcription, overhang_widths
from design.solvers.contact.spatial_equations import spatial_transcription
from design.solvers.grasp.fingers import FRICTION_SPEED, RATE_STEP

#: Newton tolerance and iteration limit inside the NLP
TOLERANCE, MAX_ITER = 1e-10, 30
#: the outputs of a finger's function; its inputs are the model's sizes, then z0
OUTPUTS = ["load", "force", "z"]
DIFFERENTIABLE = [True, True, False]


#: the contact modes the NLP can meet: the bird alone, or with the tip on the belt
#: (a finger on the belt alone loads nothing)
NLP_MODES = (*MODES, "tip+belt", "interior+belt")


def _belt_motion(fp, g, t, gx, tilt, v):
    """The belt in a finger frame at t: its upward normal (3,), offset e
    (n·r = e on its surface, m) and the belt's material velocity relative to
    the frame at r, v0 + G r (m/s; forward difference over RATE_STEP, as
    the simulator's design/solvers/grasp/fingers.py FingerForces.belt_contact)."""
    base, R = finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], t, gx, tilt)
    base2, R2 = finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], t + RATE_STEP, gx,
                             tilt)
    normal = R[2, :].T
    v0 = R2.T @ (base + ca.vertcat(v * RATE_STEP, 0.0, 0.0) - base2) / RATE_STEP
    G = (R2.T @ R - ca.DM.eye(3)) / RATE_STEP
    return normal, -base[2], v0, G


def _loads(f_w, r):
    """The load on the bird (Q_X, Q_Z, T_Y) of a finger and its mirror on
    the left drum (the same X and Z, Y mirrored) from the force on the bird
    ``f_w`` at ``r`` from its centre, both in the world frame."""
    return 2 * ca.vertcat(f_w[0], f_w[2], r[2] * f_w[0] - r[0] * f_w[2])


class PlanarStage:
    """The thesis's finger (design/solvers/grasp/fingers.py's PlanarFinger):
    the bending plane's section of the bird, the planar contact in it, the
    in-plane force with the schedule's friction sense τµ."""

    name = "planar"
    #: sizes of the differentiable inputs, in order (``belt``: its speed, m/s)
    sizes = {"pose": 3, "t": 1, "fp": 6, "g": 2, "k": 1, "tau_mu": 1, "belt": 1}
    #: constants c: grasper x, tilt, bird η, λ, γ, EI_ref, finger-belt µ, ε, then
    #: widths, stiffness params
    n_fixed = 8
    #: the implicit-function adjoint's linear solver (the residual Jacobian's sparsity)
    solver = "qr"
    #: its stages are cheap next to a thread's hand-off: serial
    threads = 1

    def __init__(self, gf: GraspFinger, grasper: Grasper, bird: Bird, friction: float,
                 belt_friction: float, intervals: int, degree: int):
        # the simulator's mesh and reference rigidity, so that its z are guesses here
        reference = RobustContact(gf.finger, friction, intervals, degree)
        self.stiffness, self.intervals, self.degree = gf.finger.stiffness, intervals, degree
        self.constants = np.concatenate([[grasper.x, grasper.tilt, bird.eta, bird.lam,
                                          bird.gamma, reference.ei_ref, belt_friction,
                                          FRICTION_SPEED], reference.widths,
                                         self.stiffness.params])

    def transcription(self, mode: str):
        if mode in BELT_MODES:
            return planar_belt_transcription(self.stiffness, self.intervals, self.degree, mode)
        return contact_transcription(self.stiffness, self.intervals, self.degree, mode,
                                     ellipse="conic")

    @classmethod
    def expressions(cls, tr, parts: dict, z, c):
        """(q, load, force) of one stage in SX."""
        pose, t, fp, g = parts["pose"], parts["t"], parts["fp"], parts["g"]
        K = tr.beam.K
        gx, tilt, eta, lam, gamma, ei_ref, mu_belt, eps = (c[i] for i in range(cls.n_fixed))
        widths, params = c[cls.n_fixed:cls.n_fixed + K], c[cls.n_fixed + K:]
        base, R = finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], t, gx, tilt)
        centre = ca.vertcat(pose[0], 0.0, pose[1])
        u0, B, _ = section((eta, lam, gamma), (pose[0], 0.0, pose[1]), pose[2], base, R)
        head = ca.vertcat(fp[5], ei_ref, u0, B[0, 0], B[0, 1], B[1, 1], parts["tau_mu"])
        if tr.mode in BELT_MODES:
            # the belt's line in the bending plane and its law (planar_belt_equations.py)
            normal, offset, v0, G = _belt_motion(fp, g, t, gx, tilt, parts["belt"])
            size = ca.norm_2(normal[:2])
            line = ca.vertcat(normal[:2] / size, offset / size)
            law = ca.vertcat(mu_belt, eps, -v0[:2], ca.vec((-G[:2, :2]).T))
            q = ca.vertcat(head, line, law, widths, ca.DM(overhang_widths()), params)
        else:
            q = ca.vertcat(head, widths, params)
        post = tr.post(z, q)[0]
        x_l, y_l, force, alpha = post[0], post[1], parts["k"] * post[3], post[4]
        pressing = ca.fmax(force, 0.0)
        # the force and point in the bending plane (the first two axes of R)
        plane = R[:, :2]
        f_w = plane @ ca.vertcat(pressing * ca.cos(alpha), -pressing * ca.sin(alpha))
        r = base + plane @ ca.vertcat(x_l, y_l) - centre
        return q, _loads(f_w, r), pressing


class SpatialStage:
    """The finger as a spatial rod (design/solvers/grasp/fingers.py's
    SpatialFinger): the bird's ellipsoid as a quadric in the finger frame,
    the friction law from the rigid finger's sliding over the bird (the
    simulator's forward difference over RATE_STEP, so the same numbers),
    the force along the surface normal plus friction."""

    name = "spatial"
    sizes = {"state": 6, "t": 1, "fp": 6, "g": 2, "k": 1, "belt": 1}
    #: constants c: grasper x, tilt, bird η, λ, γ, EI_ref, µ, ε, finger-belt µ, then
    #: widths, stiffness params
    n_fixed = 9
    #: dense LU, as the spatial rootfinder's (spatial_equations.py: its Jacobian is
    #: over a third full)
    solver = "lapacklu"
    #: the stages' contacts and Jacobian blocks over this many threads (at most the
    #: cores): the spatial stages are costly enough to gain from a second core, and
    #: every iterate stays the same (``python -m benchmarks.solve`` profiles nlp_g)
    threads = 2

    def __init__(self, gf: GraspFinger, grasper: Grasper, bird: Bird, friction: float,
                 belt_friction: float, intervals: int, degree: int):
        reference = SpatialContact(gf.finger, intervals, degree)
        self.stiffness = RodStiffness.of(gf.finger)
        self.intervals, self.degree = intervals, degree
        self.constants = np.concatenate([[grasper.x, grasper.tilt, bird.eta, bird.lam,
                                          bird.gamma, reference.ei_ref, friction,
                                          FRICTION_SPEED, belt_friction], reference.widths,
                                         self.stiffness.params])

    def transcription(self, mode: str):
        if mode in BELT_MODES:
            return belt_transcription(self.stiffness, self.intervals, self.degree, mode)
        return spatial_transcription(self.stiffness, self.intervals, self.degree, mode)

    @classmethod
    def expressions(cls, tr, parts: dict, z, c):
        state, t, fp, g = parts["state"], parts["t"], parts["fp"], parts["g"]
        K = tr.rod.K
        gx, tilt, eta, lam, gamma, ei_ref, mu, eps, mu_belt = (c[i] for i in range(cls.n_fixed))
        widths, params = c[cls.n_fixed:cls.n_fixed + K], c[cls.n_fixed + K:]
        def frame(time):
            return finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], time, gx, tilt)

        base, R = frame(t)
        base2, R2 = frame(t + RATE_STEP)
        centre = ca.vertcat(state[0], 0.0, state[1])
        centre2 = centre + RATE_STEP * ca.vertcat(state[3], 0.0, state[4])
        Rb, Rb2 = rot_y(state[2]), rot_y(state[2] + RATE_STEP * state[5])
        body = ca.diag(ca.vertcat(1 / eta ** 2, 1 / lam ** 2, 1 / gamma ** 2))
        c_f, Q_f = R.T @ (centre - base), R.T @ Rb @ body @ Rb.T @ R
        # the bird's material velocity relative to the finger frame at p (finger
        # frame): v(p) = (R2ᵀ (centre2 + Rb2 Rbᵀ (base + R p - centre) - base2) - p) / dt
        # = v0 + G p; the law takes the finger's sliding over the bird, -v
        carry = Rb2 @ Rb.T
        v0 = R2.T @ (centre2 + carry @ (base - centre) - base2) / RATE_STEP
        G = (R2.T @ carry @ R - ca.DM.eye(3)) / RATE_STEP
        law = ca.vertcat(ca.DM.zeros(3), mu, eps, -v0, ca.vec((-G).T))
        quadric = ca.vertcat(c_f, Q_f[0, 0], Q_f[0, 1], Q_f[0, 2], Q_f[1, 1], Q_f[1, 2],
                             Q_f[2, 2])
        if tr.mode in BELT_MODES:
            normal, offset, v0, G = _belt_motion(fp, g, t, gx, tilt, parts["belt"])
            belt = ca.vertcat(ca.DM.zeros(3), mu_belt, eps, -v0, ca.vec((-G).T))
            q = ca.vertcat(fp[5], ei_ref, quadric, law, normal, offset, belt, widths,
                           ca.DM(overhang_widths()), params)
        else:
            q = ca.vertcat(fp[5], ei_ref, quadric, law, widths, params)
        post = tr.post(z, q)[0]
        point, normal_force, direction = post[0:3], post[3], post[7:10] + post[16:19]
        pressing = ca.fmax(parts["k"] * normal_force, 0.0)
        load = _loads(R @ (-pressing * direction), base + R @ point - centre)
        return q, load, pressing * ca.norm_2(direction)


#: the stage models by name (a grasp scene's ``finger_model``)
STAGE_MODELS = {m.name: m for m in (PlanarStage, SpatialStage)}
#: the planar model's inputs, for callers that build its stages by hand
SIZES = PlanarStage.sizes


class StageFunctions:
    """The generic SX parts of one contact transcription (finger model,
    stiffness structure, mesh, mode): kinematics, loads and their Jacobian
    blocks, as functions of x (the model's differentiable inputs), z and the
    constants c; with the transcription's rootfinder."""

    def __init__(self, tr, n_c: int, model=PlanarStage):
        self.tr, self.model = tr, model
        sizes = model.sizes
        x, z, c = ca.SX.sym("x", sum(sizes.values())), ca.SX.sym("z", tr.n_z), \
            ca.SX.sym("c", n_c)
        parts = dict(zip(sizes, ca.vertsplit(x, np.cumsum([0, *sizes.values()]).tolist())))
        q, load, pressing = model.expressions(tr, parts, z, c)
        out = ca.vertcat(load, pressing)
        name = tr.residual.name()
        self.pre = ca.Function(f"{name}_q", [x, c], [q], ["x", "c"], ["q"])
        self.loads = ca.Function(f"{name}_loads", [x, z, c], [load, pressing],
                                 ["x", "z", "c"], ["load", "force"])
        # the implicit-function blocks at a solution z: R_z, ∂R/∂x, ∂out/∂z, ∂out/∂x
        res = tr.residual(z, q)
        self.blocks = ca.Function(
            f"{name}_blocks", [x, z, c],
            [ca.jacobian(res, z), ca.jacobian(res, x), ca.jacobian(out, z), ca.jacobian(out, x)],
            ["x", "z", "c"], ["R_z", "R_x", "out_z", "out_x"])
        done = compiled([self.pre, self.loads, self.blocks])
        self.pre, self.loads, self.blocks = done.functions
        #: whether the SX parts run compiled, and the compiler or why not
        self.compiled, self.compile_reason = done.compiled, done.reason
        # the transcription's own Newton (its residual Jacobian compiled the same way)
        self.rootfinder = tr.rootfinder(TOLERANCE, MAX_ITER, error_on_fail=True,
                                        compiled_jacobian=True)


_STAGES: dict = {}


def stage_functions(tr, n_c: int, model=PlanarStage) -> StageFunctions:
    key = (id(tr), n_c, model.name)
    if key not in _STAGES:
        _STAGES[key] = StageFunctions(tr, n_c, model)
    return _STAGES[key]


class FingerLoad:
    """:meth:`function` (mode) for one finger of the finger model ``model``
    (:data:`STAGE_MODELS`), in the contact modes of :data:`NLP_MODES`, each
    built when first asked for; ``compiled[mode]``: (whether its SX parts
    run compiled, the compiler command or why not)."""

    def __init__(self, gf: GraspFinger, grasper: Grasper, bird: Bird, friction: float,
                 intervals: int, degree: int = 4, model: str = "planar",
                 belt_friction: float = 0.0):
        self.model = STAGE_MODELS[model](gf, grasper, bird, friction, belt_friction, intervals,
                                         degree)
        self.gf = gf
        self.sizes = self.model.sizes
        #: the function's inputs, in order
        self.inputs = [*self.sizes, "z0"]
        self.n_z, self.transcriptions, self.compiled = {}, {}, {}
        self.constants = self.model.constants
        self._jacobians: dict = {}
        self._stages: dict = {}
        self._batches: dict = {}
        self._functions: dict = {}

    def function(self, mode: str) -> ca.Function:
        """The finger's load in contact mode ``mode`` (built on first use)."""
        if mode not in self._functions:
            self._functions[mode] = self._build(self.gf, mode)
        return self._functions[mode]

    def _build(self, gf, mode) -> ca.Function:
        tr = self.model.transcription(mode)
        self.n_z[mode], self.transcriptions[mode] = tr.n_z, tr
        st = stage_functions(tr, self.constants.size, type(self.model))
        self.compiled[mode] = st.compiled, st.compile_reason
        self._stages[mode] = st
        sizes, inputs = self.sizes, self.inputs
        c = ca.DM(self.constants)
        args = [ca.MX.sym(n, sizes[n]) for n in sizes]
        z0 = ca.MX.sym("z0", tr.n_z)
        x = ca.vertcat(*args)
        z = st.rootfinder(z0, st.pre(x, c))
        load, force = st.loads(x, z, c)
        # the Jacobian at the solution, by the adjoint of the contact: inputs,
        # then the nominal outputs (the solution z is the last)
        x_j = [ca.MX.sym(n, sizes[n]) for n in sizes]
        outs = [ca.MX.sym(f"out_{n}", s) for n, s in zip(OUTPUTS, (3, 1, tr.n_z))]
        r_z, r_x, o_z, o_x = st.blocks(ca.vertcat(*x_j), outs[-1], c)
        adjoint = ca.solve(r_z.T, o_z.T, self.model.solver)
        d_out = o_x - ca.mtimes(adjoint.T, r_x)
        cuts = np.cumsum([0, *sizes.values()]).tolist()
        blocks = []
        for row in ca.vertsplit(d_out, [0, 3, 4]):
            blocks += ca.horzsplit(row, cuts) + [ca.MX(row.size1(), tr.n_z)]
        # z is the contact's state, an output to read, not to differentiate
        blocks += [ca.MX(tr.n_z, n) for n in [*sizes.values(), tr.n_z]]
        name = f"finger_{gf.name}_{mode.replace('+', '_')}"
        jac = ca.Function(f"jac_{name}", [*x_j, ca.MX.sym("z0", tr.n_z), *outs], blocks,
                          [*inputs, *(f"out_{o}" for o in OUTPUTS)],
                          [f"jac_{o}_{i}" for o in OUTPUTS for i in inputs])
        self._jacobians[mode] = jac
        return ca.Function(name, [*args, z0], [load, force, z], inputs, OUTPUTS,
                           {"custom_jacobian": jac, "jac_penalty": 0, "enable_forward": False,
                            "enable_reverse": False,
                            "is_diff_out": DIFFERENTIABLE})

    def _mapped(self, f: ca.Function, n: int) -> ca.Function:
        """f over n stages: serial, or over the machine's cores for a model
        whose stages are worth it (``threads``): every column is the same
        computation either way, so the results are identical."""
        threads = min(self.model.threads, os.cpu_count() or 1)
        return f.map(n, "thread", threads) if threads > 1 and n > 1 else f.map(n)

    def restart(self) -> None:
        """Forget the contacts the batches solved: the next solve starts every
        stage from the simulation's guess again (a rebound NLP then solves as
        a new one)."""
        for _, roots in self._batches.values():
            roots.restart()

    @property
    def stage_solves(self) -> int:
        """Contacts solved so far by this finger's batches (stages x solves;
        the remembered ones not counted)."""
        return sum(roots.solves * roots.n for _, roots in self._batches.values())

    def batch(self, mode: str, n: int) -> ca.Function:
        """:meth:`function` at n stages in one call: every input and output
        with a column per stage (CasADi's map, a loop in C++ instead of n
        calls in the NLP's graph), and its Jacobian, block-diagonal over the
        stages, from the stage Jacobians of one mapped call."""
        key = (mode, n)
        if key not in self._batches:
            f = self.function(mode)
            jac = self._jacobians[mode]
            name = f"{f.name()}_x{n}"
            ins = [ca.MX.sym(i, f.size1_in(k), n) for k, i in enumerate(self.inputs)]
            outs = [ca.MX.sym(f"out_{o}", f.size1_out(k), n) for k, o in enumerate(OUTPUTS)]
            blocks = self._mapped(jac, n)(*ins, *outs)
            # the stage blocks side by side hold the block-diagonal matrix's
            # nonzeros in its own (column-major) order: a cast, no copy
            diagonal = [ca.sparsity_cast(b, ca.diagcat(*[jac.sparsity_out(k)] * n))
                        for k, b in enumerate(blocks)]
            jac_n = ca.Function(f"jac_{name}", [*ins, *outs], diagonal, jac.name_in(),
                                jac.name_out())
            # the stages: kinematics, the contacts (solved once per point, see
            # _Roots), loads; the same operations as n calls of function(mode)
            st, c = self._stages[mode], ca.DM(self.constants)
            ins_f = [ca.MX.sym(i, f.size1_in(k), n) for k, i in enumerate(self.inputs)]
            x = ca.vertcat(*ins_f[:len(self.sizes)])
            roots = _Roots(f"{name}_roots", self._mapped(st.rootfinder, n), st.tr.n_q)
            z = roots(ins_f[-1], st.pre.map(n)(x, c))
            load, force = st.loads.map(n)(x, z, c)
            self._batches[key] = (ca.Function(
                name, ins_f, [load, force, z], self.inputs, OUTPUTS,
                {"custom_jacobian": jac_n, "jac_penalty": 0, "enable_forward": False,
                 "enable_reverse": False, "is_diff_out": DIFFERENTIABLE}), roots)
        return self._batches[key][0]


class _Roots(ca.Callback):
    """The contacts of a batch of stages, (z0, q) -> z (the rootfinder mapped
    over the columns), remembering its last calls: Ipopt evaluates the
    constraints at a point and then their Jacobian at the same point, whose
    nominal evaluation would solve every contact again. Same inputs, same
    outputs: the solve is deterministic, so a remembered z is the z a new
    solve would give, to the last bit. A batch may serve several RK stages
    (the same finger, mode and count), hence a few entries. The rootfinder's
    failure (Ipopt then shortens its step) is raised as before and nothing is
    remembered."""

    #: calls remembered: the four RK stages of the current point, twice
    ENTRIES = 8

    def __init__(self, name: str, rootfinder: ca.Function, n_q: int):
        ca.Callback.__init__(self)
        self.rootfinder, self.n_q = rootfinder, n_q
        self.n_z, self.n = rootfinder.size1_in(0), rootfinder.size2_in(0)
        self._memory: dict = {}
        #: the last solution for each guess (the stages a call serves), to start from
        self._last: dict = {}
        self.solves = self.reuses = 0
        self.construct(name, {"enable_fd": False})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.n_z if i == 0 else self.n_q, self.n)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(self.n_z, self.n)

    def has_jac_sparsity(self, oind, iind):
        return True

    def get_jac_sparsity(self, oind, iind, symmetric):
        """Stage by stage: each column's z depends on its own q (and not, as
        a converged root, on its start z0)."""
        if iind == 0:
            return ca.Sparsity(self.n_z * self.n, self.n_z * self.n)
        return ca.diagcat(*[ca.Sparsity.dense(self.n_z, self.n_q)] * self.n)

    def restart(self) -> None:
        self._memory.clear()
        self._last.clear()

    def eval(self, arg):
        guess = np.asarray(arg[0]).tobytes()
        key = guess + np.asarray(arg[1]).tobytes()
        if key in self._memory:
            self.reuses += 1
            self._memory[key] = z = self._memory.pop(key)      # most recent last
            return [z]
        # from these stages' last solution, the nearest in the design; from the
        # simulation's guess where that does not converge
        last = self._last.get(guess)
        z = None
        if last is not None:
            try:
                z = self.rootfinder(last, arg[1])
            except RuntimeError:
                z = None
        if z is None:
            z = self.rootfinder(arg[0], arg[1])
        self.solves += 1
        self._last[guess] = z
        self._memory[key] = z
        if len(self._memory) > self.ENTRIES:
            del self._memory[next(iter(self._memory))]
        return [z]
