"""One finger's load on the bird as a differentiable CasADi function.

The same chain as the simulator (design/solve/grasp/fingers.py): the finger's
frame on the drum, the ellipse in which its bending plane cuts the bird
(as a conic, smooth in the pose), the collocated contact equations solved by
a CasADi rootfinder, the force mapped back to the world and doubled for the
mirror finger. Built once per finger and contact mode; called at every stage
of the time grid.

Inputs: bird pose (X, Z, θ) (m, rad), time t (s), the finger's design
fp = (angle, height, drum radius, φx, φy, length) (rad, m), the drums'
g = (spacing, speed) (m, rad/s), the stiffness scale k, the signed friction
τµ and the rootfinder's start z0. Outputs: the load on the bird from both
drums (Q_X, Q_Z, T_Y) (N, N, N m), the contact force magnitude clipped at
zero (N; a contact that would pull lets go) and the contact's unknowns z
(an output to read, declared not differentiable).

How it is evaluated (issue 13): the function is three calls, the kinematics
x -> q (SX), the rootfinder (z0, q) -> z and the loads (x, z) -> outputs
(SX), and its Jacobian is given explicitly (``custom_jacobian``) by the
implicit-function theorem at the solution z it already has,

    d out/dx = ∂out/∂x + ∂out/∂z dz/dx = ∂out/∂x - λᵀ R_x,
    dz/dx = -R_z⁻¹ R_x,   λ = R_z⁻ᵀ (∂out/∂z)ᵀ   (R_x = ∂R/∂q ∂q/∂x),

one sparse QR of R_zᵀ with the four outputs as right-hand sides (the
adjoint λ) per stage, instead of CasADi's derivative of the rootfinder, which
solved the contact again inside every derivative call and carried every
seed through the kinematics' MX graph. Measured on the first NLP of
problems/hold_time.yaml (617 finger stages): one constraint Jacobian
0.31 -> 0.11 s CPU, the same to 9e-14 relative; the rootfinder is the
same (Newton with line search, CasADi's sparse QR), with the residual's
Jacobian compiled: the same iterates to the last bit.

The NLP calls each finger and mode once per RK stage for all the intervals
in that contact (:meth:`FingerLoad.batch`: CasADi's map over the stages,
with the block-diagonal Jacobian of the stage Jacobians), and the batch
remembers the contacts it solved (:class:`_Roots`), so the Jacobian that
Ipopt asks for at the point whose constraints it has just evaluated solves
no contact again: one Jacobian 0.106 -> 0.045 s CPU on the NLP above, the
Ipopt solution identical to the last bit.

The SX parts are generic in a constants vector c (the grasper's position
and tilt, the bird's semi-axes, the finger's reference rigidity, mesh and
stiffness parameters), so that one compiled library serves every finger
of a stiffness structure and every problem (design/solve/compiled.py:
C code compiled once and cached on disk; interpreted when no compiler).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from design.physics.bird import Bird
from design.physics.grasper import GraspFinger, Grasper
from design.physics.kinematics import finger_frame, section
from design.solve.compiled import compiled
from design.solve.contact.equations import MODES, contact_transcription
from design.solve.contact.robust import RobustContact

#: Newton tolerance and iteration limit inside the NLP
TOLERANCE, MAX_ITER = 1e-10, 30
#: the inputs and outputs of a finger's function
INPUTS = ["pose", "t", "fp", "g", "k", "tau_mu", "z0"]
OUTPUTS = ["load", "force", "z"]
DIFFERENTIABLE = [True, True, False]
#: sizes of the differentiable inputs (all but z0), in INPUTS' order
SIZES = {"pose": 3, "t": 1, "fp": 6, "g": 2, "k": 1, "tau_mu": 1}
#: index of the constants in c: grasper x, tilt, bird η, λ, γ, EI_ref, then widths, params
N_FIXED = 6


class StageFunctions:
    """The generic SX parts of one contact transcription (stiffness
    structure, mesh, mode): kinematics, loads and their Jacobian blocks, as
    functions of x = (pose, t, fp, g, k, τµ), z and the constants c; with
    the rootfinder that uses the (compiled) residual Jacobian."""

    def __init__(self, tr, n_c: int):
        self.tr = tr
        nx = sum(SIZES.values())
        x, z, c = ca.SX.sym("x", nx), ca.SX.sym("z", tr.n_z), ca.SX.sym("c", n_c)
        parts = dict(zip(SIZES, ca.vertsplit(x, np.cumsum([0, *SIZES.values()]).tolist())))
        pose, t, fp, g = parts["pose"], parts["t"], parts["fp"], parts["g"]
        scale, tau_mu = parts["k"], parts["tau_mu"]
        K = tr.beam.K
        gx, tilt, eta, lam, gamma, ei_ref = (c[i] for i in range(N_FIXED))
        widths, params = c[N_FIXED:N_FIXED + K], c[N_FIXED + K:]
        base, R = finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], t, gx, tilt)
        centre = ca.vertcat(pose[0], 0.0, pose[1])
        u0, B, _ = section((eta, lam, gamma), (pose[0], 0.0, pose[1]), pose[2], base, R)
        q = ca.vertcat(fp[5], ei_ref, u0, B[0, 0], B[0, 1], B[1, 1], tau_mu, widths, params)
        post = tr.post(z, q)[0]
        x_l, y_l, force, alpha = post[0], post[1], scale * post[3], post[4]
        pressing = ca.fmax(force, 0.0)
        plane = R[:, :2]
        f_w = plane @ ca.vertcat(pressing * ca.cos(alpha), -pressing * ca.sin(alpha))
        r = base + plane @ ca.vertcat(x_l, y_l) - centre
        load = 2 * ca.vertcat(f_w[0], f_w[2], r[2] * f_w[0] - r[0] * f_w[2])
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
        self.rootfinder = tr.rootfinder(TOLERANCE, MAX_ITER, error_on_fail=True)


_STAGES: dict = {}


def stage_functions(tr, n_c: int) -> StageFunctions:
    key = (id(tr), n_c)
    if key not in _STAGES:
        _STAGES[key] = StageFunctions(tr, n_c)
    return _STAGES[key]


class FingerLoad:
    """``functions[mode]`` for one finger (mode ``interior`` or ``tip``);
    ``compiled[mode]``: (whether its SX parts run compiled, the compiler
    command or why not)."""

    def __init__(self, gf: GraspFinger, grasper: Grasper, bird: Bird, friction: float,
                 intervals: int, degree: int = 4):
        # the simulator's mesh and reference rigidity, so that its z are guesses here
        reference = RobustContact(gf.finger, friction, intervals, degree)
        self.ei_ref, self.widths = reference.ei_ref, reference.widths
        self.n_z, self.transcriptions, self.compiled = {}, {}, {}
        self.constants = np.concatenate([[grasper.x, grasper.tilt, bird.eta, bird.lam,
                                          bird.gamma, self.ei_ref], self.widths,
                                         gf.finger.stiffness.params])
        self._jacobians: dict = {}
        self._stages: dict = {}
        self._batches: dict = {}
        self.functions = {m: self._build(gf, intervals, degree, m) for m in MODES}

    def _build(self, gf, intervals, degree, mode) -> ca.Function:
        tr = contact_transcription(gf.finger.stiffness, intervals, degree, mode, ellipse="conic")
        self.n_z[mode], self.transcriptions[mode] = tr.n_z, tr
        st = stage_functions(tr, self.constants.size)
        self.compiled[mode] = st.compiled, st.compile_reason
        self._stages[mode] = st
        c = ca.DM(self.constants)
        args = [ca.MX.sym(n, SIZES[n]) for n in SIZES]
        z0 = ca.MX.sym("z0", tr.n_z)
        x = ca.vertcat(*args)
        z = st.rootfinder(z0, st.pre(x, c))
        load, force = st.loads(x, z, c)
        # the Jacobian at the solution, by the adjoint of the contact: inputs,
        # then the nominal outputs (the solution z is the last)
        x_j = [ca.MX.sym(n, SIZES[n]) for n in SIZES]
        outs = [ca.MX.sym(f"out_{n}", s) for n, s in zip(OUTPUTS, (3, 1, tr.n_z))]
        r_z, r_x, o_z, o_x = st.blocks(ca.vertcat(*x_j), outs[-1], c)
        adjoint = ca.solve(r_z.T, o_z.T, "qr")
        d_out = o_x - ca.mtimes(adjoint.T, r_x)
        cuts = np.cumsum([0, *SIZES.values()]).tolist()
        blocks = []
        for row in ca.vertsplit(d_out, [0, 3, 4]):
            blocks += ca.horzsplit(row, cuts) + [ca.MX(row.size1(), tr.n_z)]
        # z is the contact's state, an output to read, not to differentiate
        blocks += [ca.MX(tr.n_z, n) for n in [*SIZES.values(), tr.n_z]]
        name = f"finger_{gf.name}_{mode}"
        jac = ca.Function(f"jac_{name}", [*x_j, ca.MX.sym("z0", tr.n_z), *outs], blocks,
                          [*INPUTS, *(f"out_{o}" for o in OUTPUTS)],
                          [f"jac_{o}_{i}" for o in OUTPUTS for i in INPUTS])
        self._jacobians[mode] = jac
        return ca.Function(name, [*args, z0], [load, force, z], INPUTS, OUTPUTS,
                           {"custom_jacobian": jac, "jac_penalty": 0, "enable_forward": False,
                            "enable_reverse": False,
                            "is_diff_out": DIFFERENTIABLE})

    @property
    def stage_solves(self) -> int:
        """Contacts solved so far by this finger's batches (stages x solves;
        the remembered ones not counted)."""
        return sum(roots.solves * roots.n for _, roots in self._batches.values())

    def batch(self, mode: str, n: int) -> ca.Function:
        """``functions[mode]`` at n stages in one call: every input and output
        with a column per stage (CasADi's map, a loop in C++ instead of n
        calls in the NLP's graph), and its Jacobian, block-diagonal over the
        stages, from the stage Jacobians of one mapped call."""
        key = (mode, n)
        if key not in self._batches:
            f, jac = self.functions[mode], self._jacobians[mode]
            name = f"{f.name()}_x{n}"
            ins = [ca.MX.sym(i, f.size1_in(k), n) for k, i in enumerate(INPUTS)]
            outs = [ca.MX.sym(f"out_{o}", f.size1_out(k), n) for k, o in enumerate(OUTPUTS)]
            blocks = jac.map(n)(*ins, *outs)
            # the stage blocks side by side hold the block-diagonal matrix's
            # nonzeros in its own (column-major) order: a cast, no copy
            diagonal = [ca.sparsity_cast(b, ca.diagcat(*[jac.sparsity_out(k)] * n))
                        for k, b in enumerate(blocks)]
            jac_n = ca.Function(f"jac_{name}", [*ins, *outs], diagonal, jac.name_in(),
                                jac.name_out())
            # the stages: kinematics, the contacts (solved once per point, see
            # _Roots), loads; the same operations as n calls of functions[mode]
            st, c = self._stages[mode], ca.DM(self.constants)
            ins_f = [ca.MX.sym(i, f.size1_in(k), n) for k, i in enumerate(INPUTS)]
            x = ca.vertcat(*ins_f[:len(SIZES)])
            roots = _Roots(f"{name}_roots", st.rootfinder.map(n), st.tr.n_q)
            z = roots(ins_f[-1], st.pre.map(n)(x, c))
            load, force = st.loads.map(n)(x, z, c)
            self._batches[key] = (ca.Function(
                name, ins_f, [load, force, z], INPUTS, OUTPUTS,
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

    def eval(self, arg):
        key = np.asarray(arg[0]).tobytes() + np.asarray(arg[1]).tobytes()
        if key in self._memory:
            self.reuses += 1
            self._memory[key] = z = self._memory.pop(key)      # most recent last
            return [z]
        z = self.rootfinder(arg[0], arg[1])
        self.solves += 1
        self._memory[key] = z
        if len(self._memory) > self.ENTRIES:
            del self._memory[next(iter(self._memory))]
        return [z]
