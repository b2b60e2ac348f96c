"""The bird in every finger's frame, for all of a grasper's fingers in one call.

:class:`~design.solvers.grasp.fingers.FrameViews` needs, at each evaluation of
the finger forces, the bird's quadric in each finger's frame, the straight
finger's level in it and the bird surface's motion relative to the frame.
In numpy that is some twenty small array operations, about 50 µs an
evaluation, a tenth of a spatial grasp run; here it is one CasADi function
of the frames and the bird's two poses, compiled (design/solvers/compiled.py).

Inputs (flat, C order): the bird's rotation and its rotation dt later (3, 3),
its centre and its centre dt later (3,), its matrix's diagonal (3,), dt (s),
the fingers' bases (n, 3) and rotations (n, 3, 3) at t and at t + dt, and
their lengths (n,). Outputs (flat, C order): the bird's centre in each frame
(n, 3), its matrix there (n, 3, 3), the straight finger's level (n,), and
the surface's motion v0 (n, 3) and gradient (n, 3, 3) (a point p of the
finger frame moves at v0 + G p, forward differences over dt).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from design.solvers.buffers import Buffered
from design.solvers.compiled import compiled


def _matrix(flat: ca.SX) -> ca.SX:
    """A 3x3 matrix from its 9 entries in C order."""
    return ca.reshape(flat, 3, 3).T


def _flat(m: ca.SX) -> ca.SX:
    """A matrix's entries in C order."""
    return ca.vec(m.T)


def views_function(n: int) -> ca.Function:
    """The views of ``n`` fingers as a CasADi function (see the module docstring)."""
    rot, rot2 = ca.SX.sym("rot", 9), ca.SX.sym("rot2", 9)
    centre, centre2, diag = ca.SX.sym("centre", 3), ca.SX.sym("centre2", 3), ca.SX.sym("diag", 3)
    dt = ca.SX.sym("dt")
    bases, rotations = ca.SX.sym("bases", 3 * n), ca.SX.sym("R", 9 * n)
    bases2, rotations2 = ca.SX.sym("bases2", 3 * n), ca.SX.sym("R2", 9 * n)
    lengths = ca.SX.sym("lengths", n)
    B, B2 = _matrix(rot), _matrix(rot2)
    outs: list[list[ca.SX]] = [[], [], [], [], []]
    for k in range(n):
        base, base2 = bases[3 * k:3 * k + 3], bases2[3 * k:3 * k + 3]
        R, R2 = _matrix(rotations[9 * k:9 * k + 9]), _matrix(rotations2[9 * k:9 * k + 9])
        c = R.T @ (centre - base)
        Rb = R.T @ B
        M = Rb @ ca.diag(diag) @ Rb.T
        # the straight finger's deepest point x* = c·Q e_x / Q00, clipped to it
        x = ca.fmin(ca.fmax(ca.dot(M[0, :].T, c) / M[0, 0], 0.0), lengths[k])
        d = ca.vertcat(x - c[0], -c[1], -c[2])
        turn = R2.T @ B2 @ B.T
        outs[0].append(c)
        outs[1].append(_flat(M))
        outs[2].append(ca.dot(d, M @ d) - 1.0)
        outs[3].append((R2.T @ (centre2 - base2) + turn @ (base - centre)) / dt)
        outs[4].append(_flat((turn @ R - ca.SX.eye(3)) / dt))
    return ca.Function(f"finger_views_{n}",
                       [rot, rot2, centre, centre2, diag, dt, bases, rotations, bases2,
                        rotations2, lengths], [ca.vertcat(*o) for o in outs])


@lru_cache(maxsize=None)
def views_call(n: int) -> Buffered:
    """:func:`views_function` compiled (or interpreted where it cannot be),
    through a buffer (built once per finger count and process)."""
    return Buffered(compiled([views_function(n)]).functions[0])


def finger_views(body, later, dt: float, frames, frames_later, lengths: np.ndarray):
    """(centres (n, 3), matrices (n, 3, 3), levels (n,), v0 (n, 3), gradients
    (n, 3, 3)) of the bird ``body`` and ``later`` (dt on) in the frames
    (bases (n, 3), rotations (n, 3, 3)) at t and at t + dt."""
    n = lengths.size
    call = views_call(n)
    values = (body.rotation, later.rotation, body.center, later.center, np.diag(body.matrix),
              dt, frames[0], frames[1], frames_later[0], frames_later[1], lengths)
    for buffer, value in zip(call.inputs, values):
        buffer[:] = np.ravel(value)
    centres, matrices, levels, v0, gradients = (out.copy() for out in call.run())
    return (centres.reshape(n, 3), matrices.reshape(n, 3, 3), levels, v0.reshape(n, 3),
            gradients.reshape(n, 3, 3))
