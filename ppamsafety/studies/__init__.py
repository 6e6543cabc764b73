"""Former name of :mod:`ppamsafety.sections`, kept so that existing imports keep working.

The report-section modules were renamed "sections" so that "study" means one thing: a
sweep study (a TOML study file run by ``ppamsafety sweep``, :mod:`ppamsafety.study_files`).
``from ppamsafety.studies import responses`` still gives the section module
:mod:`ppamsafety.sections.responses`; new code imports :mod:`ppamsafety.sections`.
"""

import importlib

from ..sections import (REGISTRY, Section, SectionResult, main, run_section, section_module,
                        write_artifact, write_section)

#: Former names of :func:`ppamsafety.sections.run_section`, ``section_module`` and
#: :class:`~ppamsafety.sections.SectionResult`.
run_study, study_module, StudyResult = run_section, section_module, SectionResult


def __getattr__(name):
    # a section module by its old path: `from ppamsafety.studies import responses`
    if name in REGISTRY:
        return importlib.import_module(f"ppamsafety.sections.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["REGISTRY", "Section", "SectionResult", "StudyResult", "main", "run_section", "run_study",
           "section_module", "study_module", "write_artifact", "write_section"]
