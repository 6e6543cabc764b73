"""The compiled control laws: each controller's declared rows (parameters, state, internals,
scratch) and its step kernel.

They sit below the controller classes (:mod:`ppamsafety.control.pid`, ...), which validate
gains and pack the parameter row, and below :mod:`ppamsafety.control.dispatch`, the one
compiled entry point that calls the law of every kind; :meth:`Controller.step
<ppamsafety.control.base.Controller.step>` and the closed-loop runner both call it.
"""
