"""Running configurations: :mod:`~vtb.run.simulate` (one run, and batches in the core),
:mod:`~vtb.run.scaleout` (batches on executors and Dask), :mod:`~vtb.run.synthesis` (the cached
modal reduction the synthesis engine runs on), :mod:`~vtb.run.tables` (results as tables and
Parquet) and :mod:`~vtb.run.indices` (what Python knows about the core's index names)."""
