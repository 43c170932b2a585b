"""Studies at scale: an axis (or several) sampled over what varies, each sample tuned,
verified, or analysed as a task on dask.distributed, every row written as it completes.

>>> from servotune.study import DISTRIBUTIONS
>>> sorted(DISTRIBUTIONS)
['lognormal', 'loguniform', 'normal', 'triangular', 'uniform']
"""

from .runner import StudyFolderError, StudyRun, read_rows, run_study, study_folder
from .spec import (
    COMPUTE,
    DISTRIBUTIONS,
    Sample,
    Study,
    StudyFormatError,
    Variation,
    apply_values,
    load_study,
)
from .spread import FrictionSpreadSamples, spread_from_study
from .summary import StudySummary, summarise, summary_html, write_summary
from .tasks import run_sample
from .validate import check_study, read_axis_tables

__all__ = [
    "Study", "Variation", "Sample", "StudyFormatError", "load_study", "apply_values",
    "COMPUTE", "DISTRIBUTIONS", "check_study", "read_axis_tables",
    "run_sample",
    "StudyRun", "StudyFolderError", "run_study", "study_folder", "read_rows",
    "StudySummary", "summarise", "summary_html", "write_summary",
    "spread_from_study", "FrictionSpreadSamples",
]
