"""The Wilson score interval of tools/agglo_stats.py against published values."""
import math

import pytest

from agglo_stats import Z_95, wilson_interval

# Newcombe, R. G. (1998), "Two-sided confidence intervals for the single proportion: comparison of
# seven methods", Statistics in Medicine 17:857-872, Table II, method 3 (Wilson score interval
# without continuity correction), 95% intervals printed to 4 decimals.
NEWCOMBE_1998_TABLE_II = [
    (81, 263, 0.2553, 0.3662),
    (15, 148, 0.0624, 0.1605),
    (0, 20, 0.0000, 0.1611),
    (1, 29, 0.0061, 0.1718),
]


@pytest.mark.parametrize("successes, trials, low, high", NEWCOMBE_1998_TABLE_II)
def test_wilson_matches_newcombe_1998(successes, trials, low, high):
    computed = wilson_interval(successes, trials)
    # The reference is rounded to 4 decimals: half a unit of the last digit.
    assert computed[0] == pytest.approx(low, abs=5e-5)
    assert computed[1] == pytest.approx(high, abs=5e-5)


def test_wilson_bounds_solve_the_score_equation():
    # Wilson (1927, J. Am. Stat. Assoc. 22:209): the bounds are the two roots p of
    # (k/n - p)^2 = z^2 p (1 - p) / n. Check the residual at both roots for a spread of cases.
    for successes, trials in [(3, 10), (37, 120), (119, 120), (1, 2), (500, 1000)]:
        observed = successes / trials
        for bound in wilson_interval(successes, trials):
            residual = (observed - bound) ** 2 - Z_95 ** 2 * bound * (1.0 - bound) / trials
            assert abs(residual) < 1e-14


def test_wilson_edges_and_symmetry():
    # k = 0 and k = n give the closed ends 0 and 1; swapping successes and failures mirrors the
    # interval about 1/2 (the score interval is equivariant under p -> 1 - p).
    assert wilson_interval(0, 120)[0] == 0.0
    assert wilson_interval(120, 120)[1] == 1.0
    low, high = wilson_interval(37, 120)
    mirrored = wilson_interval(83, 120)
    assert mirrored[0] == pytest.approx(1.0 - high, abs=1e-15)
    assert mirrored[1] == pytest.approx(1.0 - low, abs=1e-15)
    # The 0 of n upper bound has the closed form z^2 / (n + z^2).
    assert wilson_interval(0, 20)[1] == pytest.approx(Z_95 ** 2 / (20 + Z_95 ** 2), rel=1e-14)
    assert Z_95 == pytest.approx(1.959963984540054, abs=1e-15)   # Phi^{-1}(0.975)
    assert math.isclose(wilson_interval(5, 10)[0] + wilson_interval(5, 10)[1], 1.0, abs_tol=1e-15)


def test_wilson_refuses_impossible_counts():
    with pytest.raises(ValueError):
        wilson_interval(0, 0)
    with pytest.raises(ValueError):
        wilson_interval(5, 4)
