"""Diagnosis of arm records (open loop, closed loop, static sawtooth): block residuals per
subsystem, the arm's candidate library, forward selection with its bootstrap, the pipeline,
the hidden-effect generator and the arm's record-kind adapter.  The fits of the thesis's own
numbers (the as-built arm, the summary-statistics fit) live in :mod:`ppamsafety.thesis_fits`."""
