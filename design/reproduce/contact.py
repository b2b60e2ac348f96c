"""The thesis's contact results (Tables 3-1 to 3-6) recomputed.

Geometry of the pass (Tables 3-4, 3-5, 3-6, Figure 3-11): the drum turns at
20 rpm from φ = 180° while the ellipse (99 x 67 mm, centre height 184 mm)
moves at 0.508 m/s from X = -13 in: 18° of drum per 3 in of travel. Drum
radius 82.5 mm (Table 3-1): Table 3-4's "0.0762 m (2 inches)" is
inconsistent in itself, and with 82.5 mm our contact points match Table
3-5's within 1.3 mm while 76.2 mm moves them by up to 9 mm.
"""

from __future__ import annotations

import numpy as np

from design.io.fingers import read_finger
from design.physics.beam import Finger, PointLoad
from design.physics.contact import ContactSolution, FingerPose, Motion
from design.physics.ellipse import Ellipse
from design.physics.stiffness import UniformEI
from design.reproduce.grasp import load_model
from design.solvers.contact import AlgorithmI, AlgorithmII, RobustContact
from design.solvers.effective_ei import effective_ei

#: the thesis's soft finger: its I(s) from models/fingers/ (no other rigidity enters the plane)
SOFT = Finger(0.203, load_model(read_finger, "fingers", "thesis_nonuniform_soft.yaml").stiffness,
              "soft")
UNIFORM = Finger(0.203, UniformEI(0.08), "EI=0.08")
DRUM_RADIUS = 0.0825
OMEGA = 20 * 2 * np.pi / 60
SPEED = 0.508

#: Table 3-1 cases: ellipse centre (m), finger angle (deg), side (Figure 3-7
#: shows Case 2's contact at y_f ≈ -0.079 m: the finger is pulled, the
#: table's "0.040" is a misprint)
CASES = {1: ((-0.1016, 0.184), 126.0, "push"), 2: ((0.127, 0.184), 72.0, "pull")}
#: Tables 3-2 and 3-3: thesis results (point m, α deg, F N, ψ0 deg, L m)
THESIS_CASES = {
    (1, "Algorithm I"): ((0.104, 0.045), 85.39, 8.77, 35.6, 0.1188),
    (1, "Algorithm II"): ((0.103, 0.044), 44.33, 7.49, 34.4, 0.1158),
    (2, "Algorithm I"): ((0.0662, 0.040), 46.83, 18.72, 74.13, 0.1114),
}
#: Table 3-5: φ (deg) -> contact point (m), ψ0 (deg), |F| (N), α (deg)
THESIS_PASS = {
    144: ((0.1731, 0.032), 15.7, 1.685, 105.26), 126: ((0.1029, 0.046), 35.6, 8.77, 85.39),
    108: ((0.0662, 0.040), 46.1, 23.365, 74.88), 90: ((0.0673, 0.035), 41.1, 21.885, 79.87),
    72: ((0.0959, 0.029), 25.2, 8.055, 95.78), 54: ((0.1401, 0.031), 18.8, 2.975, 102.17),
    36: ((0.1901, 0.059), 25.7, 2.08, 95.30), 18: ((0.234, 0.119), 40.0, 1.795, 80.92),
}
#: Table 3-6: FEM contact force (N) against the ellipse's X (m)
FEM_PASS = {-0.254: 0.0, -0.1778: 0.665, -0.1016: 7.661, -0.0254: 31.797, 0.0508: 30.710,
            0.127: 7.718, 0.2032: 1.562, 0.254: 0.860, 0.2794: 0.676}


def pass_position(phi_deg: float) -> float:
    """Ellipse centre X (m) when the finger is at φ (deg) in the thesis's pass."""
    return -0.3302 + SPEED * np.radians(180.0 - phi_deg) / OMEGA


def pass_angle(x: float) -> float:
    return 180.0 - np.degrees((x + 0.3302) * OMEGA / SPEED)


def scene(phi_deg: float, center: tuple[float, float]) -> tuple[FingerPose, Ellipse]:
    return FingerPose(DRUM_RADIUS, np.radians(phi_deg)), Ellipse(0.099, 0.067, center)


def table_3_1() -> dict:
    """Cases 1 and 2 with every finger model and method: solutions by key."""
    out = {}
    for case, (center, phi, side) in CASES.items():
        pose, ell = scene(phi, center)
        ell = Ellipse(0.0991, 0.0673, center)
        soft = RobustContact(SOFT, 0.6).solve(pose, ell, side)
        out[(case, "robust, non-uniform soft")] = soft
        # the uniform stand-in whose load point matches the soft finger's under this contact load
        load = PointLoad(soft.force, soft.alpha, soft.arc_length)
        ei = effective_ei(SOFT, load).position_matched
        out[(case, f"robust, uniform effective EI = {ei:.4f}")] = \
            RobustContact(Finger(0.203, UniformEI(ei)), 0.6).solve(pose, ell, side)
        out[(case, "robust, uniform EI = 0.08")] = RobustContact(UNIFORM, 0.6).solve(pose, ell, side)
        step = 0.6 if case == 1 else 0.05        # the thesis's β (Table 3-2)
        out[(case, "Algorithm I (thesis), soft, effective EI")] = \
            AlgorithmI(SOFT, 0.6, step=step).solve(pose, ell, side)
        out[(case, "Algorithm II (thesis), soft, N = 155")] = \
            AlgorithmII(SOFT, 0.6, nodes=155).solve(pose, ell, side)
    return out


def thesis_pass(sliding: str = "push", step_deg: float = 6.0, friction: float = 0.6041,
                finger: Finger = UNIFORM) -> dict[float, ContactSolution]:
    """The Table 3-4 pass, φ from 180° to 0°, as one continued pass."""
    phis = np.arange(180.0, -0.1, -step_deg)
    poses, ells = zip(*(scene(p, (pass_position(p), 0.184)) for p in phis))
    sols = RobustContact(finger, friction).solve_pass(list(poses), list(ells), sliding,
                                                      Motion(OMEGA, (SPEED, 0.0)))
    return dict(zip(phis, sols))


def fine_passes(step_deg: float = 1.0) -> dict[str, dict[float, ContactSolution]]:
    """The pass at ``step_deg`` (deg) steps with the thesis's friction convention
    (``push``) and with friction from the sliding velocity (``auto``)."""
    return {"push": thesis_pass("push", step_deg), "auto": thesis_pass("auto", step_deg)}


def fem_pass(fine: dict[str, dict[float, ContactSolution]] | None = None
             ) -> dict[float, tuple[float, ContactSolution, ContactSolution]]:
    """Table 3-6's poses: ellipse X (m) -> (φ in deg, ours push, ours auto
    friction), taken from the 1° passes ``fine`` (every Table 3-6 pose is a
    whole degree)."""
    fine = fine or fine_passes()
    return {x: (pass_angle(x), fine["push"][float(round(pass_angle(x)))],
                fine["auto"][float(round(pass_angle(x)))]) for x in FEM_PASS}


def force_ratios(push: dict[float, ContactSolution]) -> list[float]:
    """Table 3-5's force over ours (push) at each listed φ where ours touches."""
    return [THESIS_PASS[k][2] / push[float(k)].force for k in THESIS_PASS
            if push[float(k)].contact]
