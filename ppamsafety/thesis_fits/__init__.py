"""Fits of the thesis's own numbers: not a diagnosis of a record.

* :mod:`.as_built` -- the as-built arm: the effect library fitted jointly to every printed
  measurement of the thesis (Table 5.2, Table 6.1, fig. 3.1 and §5.3.5's statements);
* :mod:`.summary_fit` -- which single effect brings the simulated Table 5.2 (tracking-error
  summary statistics) onto the thesis's, and how much such a table can identify.

Both simulate the thesis arm with the hidden-effect generator of the diagnosis
(:mod:`ppamsafety.diagnose.arm.synthesize`) and compare with published numbers; the
diagnosis of a measured record (:func:`ppamsafety.diagnose.diagnose`) does not use them.
The report's sections ``as_built`` and ``diagnose_cases`` show them.
"""
