"""Studies: :mod:`~vtb.studies.grid` (any fields × any indices, journaled and resumable),
:mod:`~vtb.studies.journal` (the journals) and :mod:`~vtb.studies.optimize` (the generic
optimiser: a problem over fields and indices, solved through an evaluator).

``vtb.studies`` keeps every name of the former module of that name (now :mod:`vtb.studies.grid`).
"""

from .grid import ALIASES, StudyResult, case_config, get_field, index_names, plan, read_journal, result_of, rows_of, set_field, study

__all__ = ["ALIASES", "StudyResult", "case_config", "get_field", "index_names", "plan", "read_journal", "result_of", "rows_of", "set_field", "study"]
