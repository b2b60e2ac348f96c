"""Design studies: many independent (or chained) cases of one problem, run
one after another in this process or in parallel on Dask workers, each
finished case kept in an SQLite case store so a stopped study resumes.

:class:`Case` and :class:`StudyOptions` (cases.py) describe the study,
:func:`run_study` (engine.py) runs it, :class:`StudyProgress`
(progress.py) shows it; store.py holds the case store, cluster.py the
Dask cluster (``design cases`` lists a store: design/cli/cases.py).
"""

from design.study.cases import Case, StudyOptions
from design.study.engine import run_study
from design.study.progress import StudyProgress

__all__ = ["Case", "StudyOptions", "StudyProgress", "run_study"]
