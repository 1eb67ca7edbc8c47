"""The statistics of a sweep's report: success rates with Wilson intervals, distance per
failure with an exact Poisson interval, empirical CDFs. Pure functions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

#: The normal quantile of a two-sided 95 % interval.
Z_95 = 1.959963984540054


@dataclass(frozen=True, slots=True)
class Rate:
    """Successes out of trials, with an interval.

    Attributes:
        successes: count.
        trials: count (0: no estimate).
        low, high: the interval's ends, in [0, 1].
    """

    successes: int
    trials: int
    low: float
    high: float

    @property
    def value(self) -> float:
        """successes / trials (nan without trials)."""
        return self.successes / self.trials if self.trials else math.nan


def wilson_interval(successes: int, trials: int, z: float = Z_95) -> Rate:
    """The Wilson score interval of a binomial proportion (Wilson 1927; Brown, Cai and
    DasGupta 2001, eq. 4): centre (p + z²/2n) / (1 + z²/n), half-width
    z / (1 + z²/n) * sqrt(p (1 - p) / n + z² / 4n²).

    Args:
        successes: in [0, trials].
        trials: >= 0; 0 gives the whole [0, 1].
        z: the normal quantile (1.96: 95 %).

    Raises:
        ValueError: counts out of range.
    """
    if not 0 <= successes <= trials:
        raise ValueError(f"wilson_interval: need 0 <= successes <= trials, got {successes}, "
                         f"{trials}")
    if trials == 0:
        return Rate(0, 0, 0.0, 1.0)
    p = successes / trials
    z2 = z * z
    denominator = 1.0 + z2 / trials
    centre = (p + z2 / (2 * trials)) / denominator
    half = z / denominator * math.sqrt(p * (1 - p) / trials + z2 / (4 * trials * trials))
    return Rate(successes, trials, max(0.0, centre - half), min(1.0, centre + half))


@dataclass(frozen=True, slots=True)
class DistancePerFailure:
    """Distance driven per failure (km per intervention), with an interval.

    Attributes:
        distance_km: the distance driven in all the runs, km.
        failures: the runs that needed an intervention.
        value_km: distance_km / failures (inf without failures).
        low_km, high_km: the 95 % interval's ends (high_km is inf without failures).
    """

    distance_km: float
    failures: int
    value_km: float
    low_km: float
    high_km: float


def distance_per_failure(distance_km: float, failures: int,
                         confidence: float = 0.95) -> DistancePerFailure:
    """Failures as a Poisson process along the distance driven: the exact (Garwood 1936)
    interval of the rate, chi2(a/2, 2k)/2 .. chi2(1 - a/2, 2k + 2)/2 failures per
    ``distance_km``, inverted into km per failure.

    Raises:
        ValueError: a negative distance or count.
    """
    from scipy.stats import chi2

    if distance_km < 0 or failures < 0:
        raise ValueError(f"distance_per_failure: need distance >= 0 and failures >= 0, got "
                         f"{distance_km}, {failures}")
    alpha = 1.0 - confidence
    rate_high = chi2.ppf(1 - alpha / 2, 2 * failures + 2) / 2
    rate_low = chi2.ppf(alpha / 2, 2 * failures) / 2 if failures else 0.0
    return DistancePerFailure(
        distance_km=distance_km, failures=failures,
        value_km=distance_km / failures if failures else math.inf,
        low_km=distance_km / rate_high,
        high_km=distance_km / rate_low if rate_low > 0 else math.inf)


def empirical_cdf(values: npt.ArrayLike) -> tuple[npt.NDArray[np.float64],
                                                   npt.NDArray[np.float64]]:
    """(sorted values, fraction of values <= each): the steps of the empirical CDF."""
    x = np.sort(np.asarray(values, dtype=np.float64))
    return x, np.arange(1, len(x) + 1, dtype=np.float64) / max(1, len(x))
