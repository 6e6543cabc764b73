"""Diagnosis of arm records (open loop, closed loop, static sawtooth): block residuals per
subsystem, the arm's candidate library, forward selection with its bootstrap, the pipeline,
the hidden-effect generator, the fit of effects to summary statistics (Table 5.2) and the
joint fit of the as-built arm to every printed measurement of the thesis (``as_built``)."""
