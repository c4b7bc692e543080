"""The one executor seam for s2r's parallel work (layout: ``local`` -> ``runner``).

Every stage that runs work in parallel (corner detection, validate's renders, check's matching, fleet checks) takes
its pool from here, so a new backend is added once: :mod:`s2r.executor.local` (local worker processes, the cores
this process may use, a child's environment), :mod:`s2r.executor.runner` (:func:`open_runner`: a
:class:`TaskRunner` over local processes or Dask distributed).
"""

from s2r.executor.local import (
    WorkersUnavailable,
    child_environment,
    children_search_no_relative_folder,
    local_pool,
    usable_cores,
)
from s2r.executor.runner import SCHEDULER_DEADLINE_S, SchedulerLost, TaskOutcome, TaskRunner, open_runner

__all__ = ["SCHEDULER_DEADLINE_S", "SchedulerLost", "TaskOutcome", "TaskRunner", "WorkersUnavailable",
           "child_environment", "children_search_no_relative_folder", "local_pool", "open_runner", "usable_cores"]
