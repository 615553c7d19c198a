"""Analyses of a structure and of a run's records: :mod:`~vtb.analysis.eigen` (the assembled
structure and its modes), :mod:`~vtb.analysis.track` (receptance, decay rate, modes),
:mod:`~vtb.analysis.spectra`, :mod:`~vtb.analysis.comfort`, :mod:`~vtb.analysis.contact`,
:mod:`~vtb.analysis.fesea` and :mod:`~vtb.analysis.plotting`."""
