"""The bridge engineer's check of EN 1991-2 §6.4.6: load trains (:mod:`.load_trains`), the
code's damping (:mod:`.damping`), speed scans (:mod:`.scan`), the checks with their clauses
(:mod:`.checks`) and the report (:mod:`.report`). docs/bridge-check.md describes the method."""
