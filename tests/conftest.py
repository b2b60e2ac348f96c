"""Session settings for the test suite.

One BLAS thread. The toolkit's linear algebra is on small matrices (the
contact rootfinders' Jacobians, about 100 x 100, least squares in the
sliding velocity, Ipopt's KKT systems), where OpenBLAS's default of one
thread per core only adds hand-offs between threads, and on a shared
2-core machine with the other core busy each hand-off waits for the
scheduler: a 103 x 103 ``numpy.linalg.lstsq`` took 21 ms with two threads
against 1.5 ms with one, and test_reproduction_contact's FEM-peak test
8-38 s against 2.5 s. The variables must be set before numpy, scipy and
CasADi load their OpenBLAS copies, so here, before any test module is
imported; subprocesses (the ``design`` command in the CLI and interrupt
tests) inherit them. A value set by the caller is kept."""

import os
import sys
import warnings

import pytest

for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

# numpy reads the variable when it loads its OpenBLAS: if a plugin imported it
# first, the setting above is ignored in this process (not in subprocesses)
if "numpy" in sys.modules:
    warnings.warn("numpy was imported before tests/conftest.py set one BLAS thread; "
                  "set OPENBLAS_NUM_THREADS=1 in the environment for the full speed")


def pytest_collection_modifyitems(items):
    """Tests marked ``both_cores`` (a browser's processes) run last: alone
    on the machine once the prefetch worker is done, they take about half
    the time they take beside it."""
    items.sort(key=lambda item: item.get_closest_marker("both_cores") is not None)


def pytest_collection_finish(session):
    """Start the prefetch worker (tests/prefetch.py) on the simulations and
    references the selected tests will ask for, in the order they will."""
    from tests import prefetch
    if not prefetch.enabled() or len(session.items) < 2:
        return
    try:
        prefetch.start(_prefetch_jobs(session))
    except Exception as exc:                 # noqa: BLE001  the tests compute it all themselves
        warnings.warn(f"no prefetch worker: {exc!r}")


def _prefetch_jobs(session) -> list:
    """(key, function, arguments, needs) of what the selected tests will ask
    for, roughly in the order they will (the tests take over what the worker
    has not reached); what none of them asks for is left out."""
    from tests.design_cases import (COMPILE, SINGLE_BIRD, compile_finger_loads, prefetch_jobs,
                                    prefetched_simulation, single_bird_optimum)
    from tests.test_contact_poses import REFERENCES, imposed_side_references
    from tests.test_fit_bench import CLAMP_TAPER, MOULDED, clamp_taper_fit, moulded_fit
    from tests.test_grasp import HARD, HARD_FINE, hard_run
    from tests.test_peaks import RUNS, peak_runs
    from tests.test_population import TWINS, solve_twins
    from tests.test_profile import PROFILED, solve_profiled
    from tests.test_reports import DESIGN_RUN, solve_short_design
    from tests.test_reproduce_command import QUICK, reproduce_quick
    from tests.test_spatial_nlp import ON_THE_BELT, PLACED_HOLD, on_the_belt, placed_hold
    from tests.test_tradeoff import BEAM_STUDY, GRASP_WINDOW, beam_study, grasp_window_study
    from tests.test_validation import (FOOTBALL, MEAN_CONSTANT, MEAN_HARD, MEAN_SOFT,
                                       PLACED_HARD, THESIS_SOFT, football_run, mean_bird_run,
                                       placed_run)

    def asked(users: list[str]) -> bool:
        return any(item.nodeid.startswith(tuple(users)) for item in session.items)

    def fixture_used(name: str) -> bool:
        return any(name in getattr(item, "fixturenames", ()) for item in session.items)

    folder = session.config._tmp_path_factory.mktemp
    jobs = []
    if asked(["tests/test_compiled_nlp.py", "tests/test_design_solve.py",
              "tests/test_population.py", "tests/test_run_status.py"]):
        # first: what it compiles, the tests load from the cache instead
        jobs.append((COMPILE, compile_finger_loads, (), ()))
    if asked(["tests/test_contact_poses.py::test_imposed_side_matches"]):
        jobs.append((REFERENCES, imposed_side_references, (), ()))
    simulations = prefetch_jobs()
    jobs += [(key, prefetched_simulation, inputs, ()) for key, inputs, users in simulations
             if asked(users)]
    if asked(["tests/test_design_solve.py::test_kkt"]):
        # after the short grasp's baseline at the loop's tolerance, which it
        # uses; before the twins, which reuse it in the worker
        jobs.append((SINGLE_BIRD, single_bird_optimum, (), (simulations[0][0],)))
    if asked(["tests/test_profile.py::"]):
        jobs.append((PROFILED, solve_profiled, (folder("profile"),), (simulations[0][0],)))
    if fixture_used("moulded_finger"):
        jobs.append((MOULDED, moulded_fit, (folder("moulded"),), ()))
    if fixture_used("clamp_taper"):
        jobs.append((CLAMP_TAPER, clamp_taper_fit, (folder("clamp_taper"),), ()))
    # tests/test_grasp.py's two runs, asked for before test_reports' design run
    if fixture_used("hard_fine"):
        jobs.append((HARD_FINE, hard_run, (4.0,), ()))
    if fixture_used("hard"):
        jobs.append((HARD, hard_run, (), ()))
    if asked(["tests/test_peaks.py::test_locat"]):
        jobs.append((RUNS, peak_runs, (), ()))
    if fixture_used("twins"):
        # after the short grasp's baseline at the loop's tolerance, which it uses
        jobs.append((TWINS, solve_twins, (), (simulations[0][0],)))
    if fixture_used("design_run"):
        # after the loop's and the verification's baseline runs, which it uses
        jobs.append((DESIGN_RUN, solve_short_design, (folder("design"),),
                     tuple(key for key, _, _ in simulations[:2])))
    if fixture_used("quick"):
        jobs.append((QUICK, reproduce_quick, (folder("reproduction"),), ()))
    if fixture_used("beam"):
        jobs.append((BEAM_STUDY, beam_study, (folder("tradeoff") / "out",), ()))
    if asked(["tests/test_tradeoff.py::test_grasp_window_keeps"]):
        jobs.append((GRASP_WINDOW, grasp_window_study, (), ()))
    if asked(["tests/test_spatial_nlp.py::test_the_nlp_calls_the_spatial_finger"]):
        jobs.append((PLACED_HOLD, placed_hold, (), ()))
    if fixture_used("finger_5a_on_the_belt"):
        jobs.append((ON_THE_BELT, on_the_belt, (), ()))
    if fixture_used("football"):
        jobs.append((FOOTBALL, football_run, (), ()))
    if fixture_used("mean_soft"):
        jobs.append((MEAN_SOFT, mean_bird_run, ("soft",), ()))
    if fixture_used("mean_hard"):
        jobs.append((MEAN_HARD, mean_bird_run, ("hard",), ()))
    if fixture_used("mean_constant"):
        jobs.append((MEAN_CONSTANT, mean_bird_run, ("constant",), ()))
    if fixture_used("thesis_soft"):
        jobs.append((THESIS_SOFT, mean_bird_run, ("soft", "planar-thesis"), ()))
    if fixture_used("placed_hard"):
        jobs.append((PLACED_HARD, placed_run, (), ()))
    return jobs


@pytest.fixture(scope="session")
def design_run(tmp_path_factory):
    """tests/test_reports.py's :func:`solve_short_design`: its status, output
    folder and the designs it handed the model check; run ahead by the
    session's prefetch worker (tests/prefetch.py) into the folder it was
    given, or here. Shared by the report and animation tests."""
    from tests import prefetch
    from tests.test_reports import DESIGN_RUN, solve_short_design

    tmp = prefetch.folder(DESIGN_RUN, lambda: tmp_path_factory.mktemp("design"))
    status, checked = prefetch.result(DESIGN_RUN, solve_short_design, tmp)
    return status, tmp / "out", checked


def pytest_sessionfinish(session):
    from tests import prefetch
    prefetch.stop()
