"""The finger as a spatial rod: bending both ways and twist (Kirchhoff rod).

The thesis treats a finger as rigid out of its bending plane (§4.1,
assumption 2) and drops the contact force's component along that stiff
axis (eq. 4.26). Its own fingers are not that stiff: the base cone is
round (Table 2-2, section 1), and the elliptic tip sections are 2.0-8.0
times stiffer about their long axis, not infinitely. Where the bird's
surface normal at a contact leans out of the bending plane (a finger
sweeping along its stiff axis under the bird's belly), the in-plane model
turns most of the push into a force along the bending direction. The rod
below bends about both section axes and twists, so the contact force acts
along the surface normal and the finger yields in the direction it is
pushed.

Frames. Finger frame as for the planar finger: clamped at the origin, axis
along +x unloaded; y is the soft bending direction (the planar model's
plane is x-y), z the stiff one. The section's material frame (d1, d2, d3)
= R(q) (e_x, e_y, e_z), q a unit quaternion (w, x, y, z).

Equations (arc length s, internal moment m in the finger frame, N m; a
point force F (N) on the finger at s = L, so the internal force is F for
s < L and the rod is straight and unloaded beyond):

    r' = d1,    q' = ½ q ⊗ (0, k),    m' = -d1 × F,
    k = (m·d1 / GJ, m·d2 / EI_out, m·d3 / EI)      (twist, stiff, soft)
    r(0) = 0,   q(0) = 1,   m(L) = 0.

With q = (cos ψ/2, 0, 0, sin ψ/2) and F in the x-y plane this is the
planar elastica (design/physics/beam.py): k3 = ψ' = M/EI, M' = F_x sin ψ -
F_y cos ψ.

References
----------
Thesis §2.2, §4.1, Table 2-2; S. S. Antman, *Nonlinear Problems of
Elasticity* (Springer, 2005), ch. 8 (Kirchhoff rods).
"""

from __future__ import annotations

from design.physics.backend import ops

#: Poisson's ratio of rubber (nearly incompressible): G = E / (2 (1 + ν))
RUBBER_POISSON = 0.5


def quaternion_rotation(q):
    """Rotation matrix (3, 3) of the quaternion q = (w, x, y, z), normalised."""
    xp = ops(q)
    w, x, y, z = q[0], q[1], q[2], q[3]
    n = w * w + x * x + y * y + z * z
    return xp.matrix([
        [(w * w + x * x - y * y - z * z) / n, 2 * (x * y - w * z) / n, 2 * (x * z + w * y) / n],
        [2 * (x * y + w * z) / n, (w * w - x * x + y * y - z * z) / n, 2 * (y * z - w * x) / n],
        [2 * (x * z - w * y) / n, 2 * (y * z + w * x) / n, (w * w - x * x - y * y + z * z) / n]])


def quaternion_rate(q, k):
    """q' = ½ q ⊗ (0, k) for a body-frame rate k (3,): the material frame's
    rotation along the rod. Preserves |q|."""
    xp = ops(q, k)
    w, x, y, z = q[0], q[1], q[2], q[3]
    a, b, c = k[0], k[1], k[2]
    return xp.vector([-(x * a + y * b + z * c) / 2, (w * a + y * c - z * b) / 2,
                      (w * b + z * a - x * c) / 2, (w * c + x * b - y * a) / 2])


def cross(a, b):
    xp = ops(a, b)
    return xp.vector([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                      a[0] * b[1] - a[1] * b[0]])


def rod_rates(q, mu, kappa, ratios):
    """Non-dimensional rates (dq/du, dμ/du, d1) of the rod at one point.

    u = s/L, μ = m L / EI_r, κ = F L² / EI_r (3,), and ``ratios`` =
    (EI_r/GJ, EI_r/EI_out, EI_r/EI) at that point.
    """
    xp = ops(q, mu, kappa, ratios)
    R = quaternion_rotation(q)
    d = [R[:, j] for j in range(3)]
    k = xp.vector([(mu[0] * d[j][0] + mu[1] * d[j][1] + mu[2] * d[j][2]) * ratios[j]
                   for j in range(3)])
    return quaternion_rate(q, k), -cross(d[0], kappa), d[0]
