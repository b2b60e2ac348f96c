"""Compiled CasADi functions (design/solvers/compiled.py): the same outputs as
the interpreted ones, a cache that builds once, the interpreted fallback
when there is no compiler or it fails; and the optimiser's finger function
(design/solvers/optimize/finger_load.py), whose explicit Jacobian must equal
CasADi's derivative of the rootfinder it replaces."""

import casadi as ca
import numpy as np
import pytest

from design.solvers import compiled as comp


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder; the compiler settings of the environment unset."""
    monkeypatch.setenv("DESIGN_CACHE_DIR", str(tmp_path))
    for variable in ("DESIGN_COMPILE", "CC", "DESIGN_CFLAGS"):
        monkeypatch.delenv(variable, raising=False)
    return tmp_path


def small_function(name="small"):
    x, p = ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    y = ca.vertcat(ca.sin(x[0]) * ca.exp(p[0] * x[1]), ca.sqrt(1 + x[2] ** 2) / (2 + p[1]),
                   ca.atan2(x[1], x[0] + 3) + ca.fmax(x[2], 0.1))
    return ca.Function(name, [x, p], [y, ca.jacobian(y, x)], ["x", "p"], ["y", "J"])


needs_compiler = pytest.mark.skipif(comp.compiler()[0] is None,
                                    reason="no C compiler: the fallback is tested below")


@needs_compiler
def test_compiled_equals_interpreted_and_is_cached(cache):
    f = small_function()
    done = comp.compiled([f])
    g, = done.functions
    assert done.compiled and "External" in str(g) and "gcc" in done.reason
    rng = np.random.default_rng(1)
    for _ in range(20):
        x, p = rng.normal(size=3), rng.normal(size=2)
        for a, b in zip(f(x, p), g(x, p)):
            a, b = np.asarray(a), np.asarray(b)
            assert np.allclose(a, b, rtol=1e-12, atol=1e-300), (a, b)
    start = len(comp.status.libraries) - 1
    assert comp.status.libraries[-1]["built"]
    assert len(list(cache.glob("*.so"))) == 1
    # the second time (as in the next run) the library is loaded, not built
    h, = comp.compiled([small_function()]).functions
    assert not comp.status.libraries[-1]["built"]
    assert np.array_equal(np.asarray(h([1, 2, 3], [0.1, 0.2])[0]),
                          np.asarray(g([1, 2, 3], [0.1, 0.2])[0]))
    # a different function is a different library
    comp.compiled([small_function("other")])
    assert comp.status.libraries[-1]["built"] and len(list(cache.glob("*.so"))) == 2
    summary = comp.status.summary(start)
    assert summary["libraries_loaded"] == 3 and summary["libraries_built"] == 2


@needs_compiler
def test_a_broken_cached_library_is_built_again(cache):
    f = small_function("broken")
    comp.compiled([f])
    library, = cache.glob("*.so")
    library.write_bytes(b"not a library")
    done = comp.compiled([small_function("broken")])
    assert done.compiled and comp.status.libraries[-1]["built"]
    assert np.allclose(np.asarray(done.functions[0]([1, 2, 3], [0.1, 0.2])[0]),
                       np.asarray(f([1, 2, 3], [0.1, 0.2])[0]), rtol=1e-12)


def test_missing_compiler_falls_back_to_interpreted(cache, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-here")
    f = small_function()
    done = comp.compiled([f])
    assert done.functions[0] is f
    assert not done.compiled and "not found" in done.reason
    assert not list(cache.glob("*.so"))


def test_failing_compiler_and_switch_fall_back(cache, monkeypatch):
    monkeypatch.setenv("CC", "false")            # a compiler that always fails
    f = small_function()
    done = comp.compiled([f])
    assert done.functions[0] is f
    assert not done.compiled and "compilation failed" in done.reason
    monkeypatch.delenv("CC")
    monkeypatch.setenv("DESIGN_COMPILE", "0")
    done = comp.compiled([f])
    assert done.functions[0] is f and "DESIGN_COMPILE=0" in done.reason


def pressing_contact(setup, finger: int, t: float):
    """A light interior contact of the setup's finger at time t: the bird
    (level, centred under the finger's point at 0.8 of its length) raised
    until that part of the finger is 1.5 % inside its cut, solved by the
    simulator's contact solver in the finger's frame. Returns the finger
    function's inputs (pose, t, fp, g, k, τµ, belt speed, z0) and the force (N)."""
    from design.physics.contact import FingerPose
    from design.physics.ellipse import Ellipse
    from design.physics.kinematics import finger_frame, section
    from design.solvers.contact.robust import RobustContact
    from design.solvers.optimize.variables import parameters_of

    v, gf, bird = parameters_of(setup), setup.grasper.fingers[finger], setup.bird
    key = f"fingers.{gf.design_name}."
    fp = np.array([v[key + "angle"] + gf.phase, v[key + "height"], gf.mount.radius,
                   v[key + "phi_x"], v[key + "phi_y"], v[key + "length"]])
    g = np.array([v["spacing"], v["drum_speed"]])
    base, R = (np.asarray(a, float) for a in finger_frame(*fp[:5], *g, t, setup.grasper.x,
                                                          setup.grasper.tilt))
    x_bird = float((base.ravel() + R[:, 0] * 0.8 * fp[5])[0])
    s = np.linspace(0.3, 1.0, 300) * fp[5]

    def cut(z_bird):
        u0, B, _ = section((bird.eta, bird.lam, bird.gamma), (x_bird, 0.0, z_bird), 0.0,
                           base.ravel(), R)
        return np.asarray(u0, float).ravel(), np.asarray(B, float)

    def deepest(z_bird):                        # the finger's lowest level (p-c)'B(p-c)
        u0, B = cut(z_bird)
        d = np.stack([s - u0[0], np.full_like(s, -u0[1])])
        return np.min(np.einsum("in,ij,jn->n", d, B, d))

    lo, hi = bird.gamma, bird.gamma + 0.1
    assert deepest(lo) > 1 > deepest(hi)
    for _ in range(40):
        lo, hi = ((lo + hi) / 2, hi) if deepest((lo + hi) / 2) > 0.985 else (lo, (lo + hi) / 2)
    u0, B = cut(lo)
    eig, vec = np.linalg.eigh(B)
    ellipse = Ellipse(1 / np.sqrt(eig[0]), 1 / np.sqrt(eig[1]), (u0[0], u0[1]),
                      float(np.arctan2(vec[1, 0], vec[0, 0])))
    sol = RobustContact(gf.finger, setup.finger_friction, 4).solve(FingerPose(0.0, 0.0),
                                                                    ellipse, "push")
    assert sol.contact and sol.converged and sol.extras["mode"] == "interior"
    inputs = [np.array([x_bird, lo, 0.0]), t, fp, g, 1.0, sol.extras["friction_ratio"],
              setup.conveyor.speed, sol.extras["z"]]
    return inputs, sol.force


def test_finger_jacobian_is_the_rootfinders_derivative(monkeypatch):
    """The finger function's explicit Jacobian (the adjoint of the contact at
    its solution) against CasADi's derivative of the same chain through the
    rootfinder (the optimiser's former finger function), at a light contact
    of the short test grasp."""
    monkeypatch.setenv("DESIGN_COMPILE", "0")     # the formula, not the compiler
    from design.solvers.optimize.finger_load import SIZES, FingerLoad, StageFunctions
    from tests.design_cases import short_setup

    setup = short_setup()
    gf = setup.grasper.fingers[0]
    fl = FingerLoad(gf, setup.grasper, setup.bird, setup.finger_friction, 4)
    F = fl.function("interior")
    inputs, force = pressing_contact(setup, 0, 0.5)
    load, pressing, z = F(*inputs)
    assert float(pressing) == pytest.approx(force, rel=1e-8) and force > 0.05
    # the reference: the same chain, differentiated by CasADi through the rootfinder
    st = StageFunctions(fl.transcriptions["interior"], fl.constants.size)
    x = ca.MX.sym("x", sum(SIZES.values()))
    z0 = ca.MX.sym("z0", fl.n_z["interior"])
    c = ca.DM(fl.constants)
    root = st.tr.rootfinder(1e-10, 30, True)(z0, st.pre(x, c))
    out = ca.vertcat(*st.loads(x, root, c))
    reference = ca.Function("reference", [x, z0], [out, ca.jacobian(out, x)])
    x0 = ca.vertcat(*[ca.DM(v) for v in inputs[:len(SIZES)]])
    ref_out, ref_jac = reference(x0, inputs[-1])
    assert np.allclose(np.asarray(ref_out).ravel(),
                       np.concatenate([np.asarray(load).ravel(), np.asarray(pressing).ravel()]), rtol=1e-12,
                       atol=1e-14)
    blocks = F.jacobian()(*inputs, load, pressing, z)
    n_in = len(F.name_in())
    ours = ca.vertcat(*[ca.horzcat(*blocks[o * n_in:o * n_in + len(SIZES)]) for o in (0, 1)])
    scale = float(ca.mmax(ca.fabs(ref_jac)))
    assert scale > 0
    assert float(ca.mmax(ca.fabs(ca.densify(ours) - ref_jac))) <= 1e-9 * scale
    # z is an output to read (the next guess), not differentiated
    assert F.jacobian().sparsity_out(2 * n_in).nnz() == 0


def test_finger_batch_is_the_stages_one_by_one(monkeypatch):
    """A batch of stages (one call for the NLP) gives each stage's loads and
    its block of the Jacobian as a call per stage does, and evaluating it
    again at the same point (the Jacobian after the constraints) solves no
    contact again."""
    monkeypatch.setenv("DESIGN_COMPILE", "0")
    from design.solvers.optimize.finger_load import FingerLoad
    from tests.design_cases import short_setup

    setup = short_setup()
    fl = FingerLoad(setup.grasper.fingers[0], setup.grasper, setup.bird,
                    setup.finger_friction, 4)
    F = fl.function("interior")
    base, _ = pressing_contact(setup, 0, 0.5)
    stages = []
    for dz in (0.0, 2e-4, 4e-4):                 # the bird a little higher: pressing harder
        inputs = list(base)
        inputs[0] = base[0] + np.array([0.0, dz, 0.0])
        stages.append(inputs)
    B = fl.batch("interior", 3)
    columns = [ca.horzcat(*[ca.DM(s[k]) for s in stages]) for k in range(len(base))]
    load, force, z = B(*columns)
    solved = fl.stage_solves
    assert solved == 3
    forces = []
    for n, inputs in enumerate(stages):
        one = F(*inputs)
        assert np.array_equal(np.asarray(load[:, n]), np.asarray(one[0]))
        assert np.array_equal(np.asarray(force[:, n]), np.asarray(one[1]))
        forces.append(float(one[1]))
    assert forces[0] < forces[1] < forces[2]
    # the Jacobian: stage n's block is the stage's own Jacobian, nothing between stages
    x = [ca.MX.sym(f"x{k}", *columns[k].shape) for k in range(len(base))]
    out = B(*x)
    jacobian = ca.Function("j", x, [ca.jacobian(ca.vertcat(ca.vec(out[0]), ca.vec(out[1])),
                                                x[0])])(*columns)
    assert fl.stage_solves == solved                    # the same point: remembered
    J = np.asarray(ca.densify(jacobian))
    for n, inputs in enumerate(stages):
        own = F.jacobian()(*inputs, *F(*inputs))
        rows = [3 * n, 3 * n + 1, 3 * n + 2, 9 + n]
        expected = np.vstack([np.asarray(ca.densify(own[0])),
                              np.asarray(ca.densify(own[len(base)]))])
        assert np.allclose(J[np.ix_(rows, range(3 * n, 3 * n + 3))], expected,
                           rtol=1e-12, atol=1e-12 * np.abs(expected).max())
        others = [c for c in range(9) if c // 3 != n]
        assert not np.any(J[np.ix_(rows, others)])


def test_buffered_calls_equal_the_function_s_and_do_not_share_outputs():
    """design.solvers.buffers.Buffered: the same numbers as Function.__call__
    (column-major matrices), fresh arrays per call (a state kept from one
    call must not change at the next), a sparse output and a wrong input
    size named."""
    from design.solvers.buffers import Buffered
    sparse = small_function()
    with pytest.raises(ValueError, match="small: output 1 is sparse"):
        Buffered(sparse)
    X, P = ca.SX.sym("x", 3), ca.SX.sym("p", 2)
    y, J = sparse(X, P)
    f = ca.Function("dense", [X, P], [y, ca.densify(J)])
    call = Buffered(f)
    rng = np.random.default_rng(2)
    x1, x2, p = rng.normal(size=3), rng.normal(size=3), rng.normal(size=2)
    y1, J1 = call(x1, p)
    y2, J2 = call(x2, p)
    for (y, J), x in (((y1, J1), x1), ((y2, J2), x2)):
        want_y, want_J = f(x, p)
        assert np.array_equal(y, np.asarray(want_y)) and np.array_equal(J, np.asarray(want_J))
    assert not np.array_equal(y1, y2)
    with pytest.raises(ValueError, match="input 0 has 2 values, needs 3"):
        call(x1[:2], p)


@needs_compiler
def test_a_rootfinder_with_the_compiled_jacobian_takes_the_same_iterates(cache):
    """design.solvers.newton.NewtonCache with its Jacobian compiled (the
    planar contact's rootfinder by default, design/solvers/contact/
    equations.py) lands on the interpreted rootfinder's root to the last
    bit, from starts that need several damped steps."""
    from design.solvers.newton import NewtonCache, compiled_jacobian
    z, q = ca.SX.sym("z", 3), ca.SX.sym("q", 3)
    r = ca.vertcat(z[0] ** 3 + z[1] - q[0], ca.sin(z[1]) + z[0] * z[2] - q[1],
                   ca.exp(z[2]) - z[0] - q[2])
    residual = ca.Function("cubic", [z, q], [r])
    cache_ = NewtonCache("cubic_newton", residual, "lapacklu",
                         lambda: compiled_jacobian(residual, "cubic_jac_z"))
    own = cache_.get(1e-12, 30, False, use_jacobian=False)
    given = cache_.get(1e-12, 30, False)
    assert "External" in str(cache_._jacobian)
    rng = np.random.default_rng(3)
    for _ in range(10):
        z0, q0 = rng.normal(size=3), rng.normal(size=3)
        a, b = np.asarray(own(z0, q0)).ravel(), np.asarray(given(z0, q0)).ravel()
        assert np.array_equal(a, b), (a, b)
        assert own.stats()["iter_count"] == given.stats()["iter_count"]
