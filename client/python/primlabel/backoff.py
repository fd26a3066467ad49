"""Exponential backoff with jitter between retries, as the C++ client (client/src/backoff.cpp)."""

from __future__ import annotations

import random
from dataclasses import dataclass


@dataclass(frozen=True)
class BackoffPolicy:
    initial: float = 0.2  # seconds before the first retry
    multiplier: float = 2.0
    maximum: float = 5.0  # cap of any one delay
    # Each delay is drawn from [d * (1 - jitter), d * (1 + jitter)], then capped, so clients that
    # lost the server together do not come back in lockstep.
    jitter: float = 0.2


class Backoff:
    """The delays of successive retries: the n-th (from 0) is initial * multiplier**n, capped."""

    def __init__(self, policy: BackoffPolicy = BackoffPolicy(), seed: int | None = None):
        self._policy = policy
        self._rng = random.Random(seed)
        self.retries = 0

    def nominal(self, n: int) -> float:
        """The delay before retry n without jitter (the centre of the jitter window)."""
        p = self._policy
        try:
            grown = p.initial * max(1.0, p.multiplier) ** n
        except OverflowError:  # a huge n: the cap applies anyway
            grown = p.maximum
        return min(p.maximum, grown)

    def next(self) -> float:
        centre = self.nominal(self.retries)
        self.retries += 1
        jitter = min(max(self._policy.jitter, 0.0), 1.0)
        return min(self._policy.maximum, centre * self._rng.uniform(1.0 - jitter, 1.0 + jitter))

    def reset(self) -> None:
        self.retries = 0
