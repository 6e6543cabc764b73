"""The one diagnosis pipeline of every record kind: its steps, in their order, written once.

Every record kind reduces to one linear design (:mod:`.linear_selection`), and every kind
diagnoses it by the same steps in the same order (:data:`STAGES`):

1. ``design`` -- the record, its noise level, the whitened residual and the candidate columns;
2. ``selection`` -- the naming rule: forward selection, the search over every small subset,
   the look-alikes;
3. ``stability`` -- the selection rerun on halves of the record (and the bootstrap);
4. ``covariance`` -- the covariance of the final fit (HAC, cluster-robust, half-sample
   inflation);
5. ``intervals`` -- the parameters with their 95 % intervals, widened for the candidates the
   record holds a hint of (:mod:`.omitted`);
6. ``explained`` -- whether the fitted model brings the residual down to the noise, and each
   member of the fit named, partial or confounded;
7. ``detection`` -- the detection limits of the record (:mod:`.power`);
8. ``consistency`` -- the constancy of each named effect across the record;
9. ``gates`` -- the one rule for "high" (:mod:`.gates`) with the kind's thresholds;
10. ``regions`` -- the residual by operating region (:mod:`.regions`);

then ``result``: the :class:`~.result.Diagnosis`.

This module knows no physics.  A kind supplies its steps as a :class:`Steps` subclass whose
methods carry the stages' names and keep the record's state on the instance (worked example:
the muscle on the test bench, :class:`ppamsafety.diagnose.bench.pipeline.MuscleSteps`; the
arm, :class:`ppamsafety.diagnose.arm.pipeline.ArmSteps`).
"""

from __future__ import annotations

import time

#: The steps of a diagnosis, in their order (module docstring).
STAGES = ("design", "selection", "stability", "covariance", "intervals", "explained",
          "detection", "consistency", "gates", "regions")


class Steps:
    """One record's diagnosis, step by step: a record kind implements every stage of
    :data:`STAGES` and :meth:`result`; :func:`run_steps` calls them in order.

    The state of the diagnosis lives on the instance: each stage reads what the earlier ones
    left there and adds its own.
    """

    def design(self) -> None:
        """The record, its noise level, the whitened residual and the candidate columns."""
        raise NotImplementedError(f"{type(self).__name__} does not define design()")

    def selection(self) -> None:
        """The naming rule on the design: the final fit and the look-alikes."""
        raise NotImplementedError(f"{type(self).__name__} does not define selection()")

    def stability(self) -> None:
        """The selection rerun on halves of the record."""
        raise NotImplementedError(f"{type(self).__name__} does not define stability()")

    def covariance(self) -> None:
        """The covariance of the final fit."""
        raise NotImplementedError(f"{type(self).__name__} does not define covariance()")

    def intervals(self) -> None:
        """The parameters of the final fit with their (widened) intervals."""
        raise NotImplementedError(f"{type(self).__name__} does not define intervals()")

    def explained(self) -> None:
        """Whether the residual is at the noise; the fit's members named, partial or
        confounded."""
        raise NotImplementedError(f"{type(self).__name__} does not define explained()")

    def detection(self) -> None:
        """The detection limits of the record."""
        raise NotImplementedError(f"{type(self).__name__} does not define detection()")

    def consistency(self) -> None:
        """The constancy of each named effect across the record."""
        raise NotImplementedError(f"{type(self).__name__} does not define consistency()")

    def gates(self) -> None:
        """Every gate of the kind's rule for "high" on each named effect."""
        raise NotImplementedError(f"{type(self).__name__} does not define gates()")

    def regions(self) -> None:
        """The final residual by operating region."""
        raise NotImplementedError(f"{type(self).__name__} does not define regions()")

    def result(self, seconds: dict):
        """The :class:`~.result.Diagnosis`.

        Parameters
        ----------
        seconds : dict
            Stage -> wall time [s] (every stage of :data:`STAGES`, in order).
        """
        raise NotImplementedError(f"{type(self).__name__} does not define result()")


def run_steps(steps: Steps):
    """Run a record kind's steps in the order of :data:`STAGES`; its diagnosis.

    Parameters
    ----------
    steps : Steps
        One record's steps, built with its options (validated when built).

    Returns
    -------
    Diagnosis
    """
    if not isinstance(steps, Steps):
        raise TypeError(f"steps must be a Steps, got {type(steps).__name__}")
    seconds = {}
    t = time.perf_counter()
    for stage in STAGES:
        getattr(steps, stage)()
        now = time.perf_counter()
        seconds[stage] = now - t
        t = now
    return steps.result(seconds)


__all__ = ["STAGES", "Steps", "run_steps"]
