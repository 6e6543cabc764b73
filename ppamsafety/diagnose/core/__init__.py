"""The statistics shared by every record kind: noise levels, model-selection criteria and the
naming rule of a step, the linear forward selection, the parameter of a candidate, and the
:class:`~.result.Diagnosis` result."""
