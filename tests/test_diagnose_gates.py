"""One rule for "high" (``diagnose.core.gates``): every record kind's gates are data."""

import itertools
import math

import pytest

from ppamsafety.diagnose.arm.gates import ARM_RULE
from ppamsafety.diagnose.bench.campaign import CAMPAIGN_RULE, GAIN_HIGH, P_HIGH
from ppamsafety.diagnose.bench.gates import MUSCLE_RULE as BENCH_RULE
from ppamsafety.diagnose.core.gates import HIGH_WEIGHT, judge, level


def test_kinds_share_the_inclusion_threshold_and_keep_their_own_gates():
    assert ARM_RULE.weight == BENCH_RULE.weight == HIGH_WEIGHT == 0.95
    assert len(ARM_RULE.gates) == 9 and "not_compensating" in ARM_RULE.gates
    assert len(BENCH_RULE.gates) == 10 and {"reversals", "pressure_levels"} <= set(BENCH_RULE.gates)
    assert "weight" not in CAMPAIGN_RULE.gates                # a campaign has no BIC weight
    # the residual limit grows as the equations get fewer (noise alone varies more)
    assert ARM_RULE.rho_high(21) > ARM_RULE.rho_high(1200) > ARM_RULE.rho_factor


def test_campaign_rule_is_its_former_inline_conjunction():
    """Every combination of the campaign's evidence: the rule says "high" exactly when all of
    stability, significance, held-out gain, admissibility, grid edge and mid-stroke pass."""
    for stab, freq, p, gain, ok, edge, mid in itertools.product(
            (True, False), (1.0, 0.8), (1e-9, 1e-3, math.nan), (0.5, 0.01), (True, False),
            (True, False), (True, False)):
        expected = bool(stab and freq >= 1.0 and p < P_HIGH and gain >= GAIN_HIGH and ok
                        and not edge and mid)
        g = judge(CAMPAIGN_RULE, stability=freq if stab else None, p_value=p, cv_gain=gain,
                  admissible=ok, not_at_edge=not edge, mid_stroke=mid)
        assert (level(g) == "high") == expected


def test_missing_evidence_names_the_gate():
    with pytest.raises(TypeError, match="mid_stroke"):
        judge(CAMPAIGN_RULE, stability=1.0, p_value=0.0, cv_gain=1.0, admissible=True,
              not_at_edge=True)
