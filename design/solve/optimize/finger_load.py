"""One finger's load on the bird as a differentiable CasADi function.

The same chain as the simulator (design/solve/grasp/fingers.py): the finger's
frame on the drum, the ellipse in which its bending plane cuts the bird
(as a conic, smooth in the pose), the collocated contact equations solved by
a CasADi rootfinder (derivatives by the implicit-function theorem), the
force mapped back to the world and doubled for the mirror finger. Built
once per finger and contact mode; called at every stage of the time grid.

Inputs: bird pose (X, Z, θ) (m, rad), time t (s), the finger's design
fp = (angle, height, drum radius, φx, φy, length) (rad, m), the drums'
g = (spacing, speed) (m, rad/s), the stiffness scale k, the signed friction
τµ and the rootfinder's start z0. Outputs: the load on the bird from both
drums (Q_X, Q_Z, T_Y) (N, N, N m), the contact force magnitude clipped at
zero (N; a contact that would pull lets go), the unclipped force (N) and z.
"""

from __future__ import annotations

import casadi as ca

from design.physics.bird import Bird
from design.physics.grasper import GraspFinger, Grasper
from design.physics.kinematics import finger_frame, section
from design.solve.contact.equations import MODES, contact_transcription
from design.solve.contact.robust import RobustContact

#: Newton tolerance and iteration limit inside the NLP
TOLERANCE, MAX_ITER = 1e-10, 30


class FingerLoad:
    """``functions[mode]`` for one finger (mode ``interior`` or ``tip``)."""

    def __init__(self, gf: GraspFinger, grasper: Grasper, bird: Bird, friction: float,
                 intervals: int, degree: int = 4):
        # the simulator's mesh and reference rigidity, so that its z are guesses here
        reference = RobustContact(gf.finger, friction, intervals, degree)
        self.ei_ref, self.widths = reference.ei_ref, reference.widths
        self.n_z = {}
        self.functions = {m: self._build(gf, grasper, bird, intervals, degree, m) for m in MODES}

    def _build(self, gf, grasper, bird, intervals, degree, mode) -> ca.Function:
        stiffness = gf.finger.stiffness
        tr = contact_transcription(stiffness, intervals, degree, mode, ellipse="conic")
        self.n_z[mode] = tr.n_z
        rf = tr.rootfinder(TOLERANCE, MAX_ITER, error_on_fail=True)
        pose, t = ca.MX.sym("pose", 3), ca.MX.sym("t")
        fp, g = ca.MX.sym("fp", 6), ca.MX.sym("g", 2)
        scale, tau_mu, z0 = ca.MX.sym("k"), ca.MX.sym("tau_mu"), ca.MX.sym("z0", tr.n_z)
        base, R = finger_frame(fp[0], fp[1], fp[2], fp[3], fp[4], g[0], g[1], t,
                               grasper.x, grasper.tilt)
        centre = ca.vertcat(pose[0], 0.0, pose[1])
        u0, B, _ = section((bird.eta, bird.lam, bird.gamma), (pose[0], 0.0, pose[1]), pose[2],
                           base, R)
        q = ca.vertcat(fp[5], self.ei_ref, u0, B[0, 0], B[0, 1], B[1, 1], tau_mu, self.widths,
                       stiffness.params)
        z = rf(z0, q)
        post = tr.post(z, q)[0]
        x_l, y_l, force, alpha = post[0], post[1], scale * post[3], post[4]
        pressing = ca.fmax(force, 0.0)
        plane = R[:, :2]
        f_w = plane @ ca.vertcat(pressing * ca.cos(alpha), -pressing * ca.sin(alpha))
        r = base + plane @ ca.vertcat(x_l, y_l) - centre
        load = 2 * ca.vertcat(f_w[0], f_w[2], r[2] * f_w[0] - r[0] * f_w[2])
        return ca.Function(f"finger_{gf.name}_{mode}", [pose, t, fp, g, scale, tau_mu, z0],
                           [load, pressing, force, z],
                           ["pose", "t", "fp", "g", "k", "tau_mu", "z0"],
                           ["load", "force", "raw_force", "z"])
