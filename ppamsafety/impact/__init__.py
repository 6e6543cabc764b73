"""Impact analysis.

Modules: :mod:`.hic` (Head Injury Criterion, thesis eq. 6.1: exact fast evaluation of
sampled records and closed forms for half-sine and rectangular pulses).
"""
