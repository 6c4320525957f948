# SPDX-License-Identifier: MIT
"""The exact mode's next-delay unit model (stepramp.models.exact_unit) against its definitions: the rounded root
against math.isqrt, the latency formulas on hand-computed cases, the worst cases the engine's budget reads, and the
continuation rule."""

from __future__ import annotations

import math
import random

import pytest

from stepramp.models import exact
from stepramp.models.exact_unit import (
    CONTINUED_WORST,
    CONTINUED_WORST_NARROW,
    FRESH_WORST,
    FRESH_WORST_NARROW,
    VALUE_Q4_BITS,
    ExactRequest,
    NextDelayExact,
    continued_latency,
    fresh_latency,
    isqrt,
    isqrt_iterations,
    isqrt_latency,
    unit_constant,
)

X_MAX = (1 << exact.INDEX_WIDTH) - 1
SEED_TOP = exact.seed_word((1 << exact.MANT_WIDTH) - 1, exact.SCALE_MAX)
"""The largest seed word the unit computes with: C = (2^60 - 1) 4^6, just below 2^72."""
C_TOP = ((1 << exact.MANT_WIDTH) - 1) << (2 * exact.SCALE_MAX)
C_NARROW_TOP = (1 << 48) - 1


def random_seed(rng: random.Random) -> int:
    """A seed word of a random constant below 2^72 (every bit length, encoded as the driver does: the smallest
    scale), about one in eight a scale of 7 .. 15 (the unit takes 6)."""
    c = rng.getrandbits(rng.randint(0, 72))
    e = 0
    while c >> (2 * e) >= 1 << exact.MANT_WIDTH:
        e += 1
    if rng.random() < 0.125:
        return exact.seed_word(rng.getrandbits(60), rng.randint(7, 15))
    return exact.seed_word(c >> (2 * e), e)


def test_extra_pairs_root_the_scaled_radicand() -> None:
    """isqrt with e zero pairs appended is root(R 4^e) (capped at max_extra), its latency floor(msb(R 4^e) / 2) + 5;
    the unit's constant of a seed word is m 4^min(e, 6)."""
    rng = random.Random(6)
    for _ in range(3000):
        r, e = rng.getrandbits(rng.randint(0, 92)), rng.randint(0, 15)
        got = isqrt(r, 92, e, 6)
        used = min(e, 6)
        assert got.root == exact.root(r << (2 * used))
        assert got.latency == (1 if r == 0 else isqrt_latency(r << (2 * used)))
    assert isqrt(1, 4, 3, 6).latency == 0 // 2 + 3 + 5
    assert unit_constant(exact.seed_word(5, 3)) == 5 * 4**3
    assert unit_constant(exact.seed_word(5, 9)) == 5 * 4**6


def test_root_rounds_to_nearest_on_the_edges() -> None:
    """root(R) = s + 1 exactly when R - s^2 > s (s = isqrt(R)): at s^2, s^2 + s it is s, at s^2 + s + 1 s + 1."""
    rng = random.Random(1)
    roots = [0, 1, 2, 3, (1 << 20) - 1, 1 << 20, (1 << 40) - 1, *(rng.getrandbits(40) for _ in range(200))]
    for s in roots:
        assert isqrt(s * s).root == s
        assert isqrt(s * s + s).root == s
        if s >= 2:
            assert isqrt(s * s - 1).root == s  # (s - 1)^2 + 2 (s - 1): above (s - 1)^2 + (s - 1)
        if (s + 1) ** 2 <= (1 << 80) - 1:
            assert isqrt(s * s + s + 1).root == s + 1
    # all ones: the rounding carries to 2^(width / 2), the root port's extra bit
    for width in (4, 12, 16, 80, 128):
        assert isqrt((1 << width) - 1, width).root == 1 << (width // 2)


def test_root_is_the_nearest_integer() -> None:
    """|root(R) - sqrt(R)| < 1/2, checked in integers: (2 root - 1)^2 < 4 R < (2 root + 1)^2."""
    rng = random.Random(2)
    values = list(range(5000)) + [rng.getrandbits(rng.randint(1, 80)) for _ in range(5000)]
    for r in values:
        q = isqrt(r).root
        assert (2 * q - 1) ** 2 < 4 * r < (2 * q + 1) ** 2 or (r == 0 and q == 0)


def test_root_from_the_zero_pair() -> None:
    """The RTL's rounding: t = isqrt(4 R) = 2 s + b, b = 1 exactly when R - s^2 > s, and root = (t + 1) // 2."""
    rng = random.Random(3)
    for r in [*range(4096), *(rng.getrandbits(rng.randint(1, 80)) for _ in range(5000))]:
        t = math.isqrt(4 * r)
        assert (t + 1) // 2 == exact.root(r) == isqrt(r).root


def test_isqrt_latency_by_hand() -> None:
    assert isqrt_iterations(0) == 0 and isqrt_latency(0) == 1
    # R = 1 .. 3: one pair (msb 0 or 1): align, the fetch of the top pair, one root bit, the zero pair, the increment
    assert [isqrt_latency(r) for r in (1, 2, 3)] == [5, 5, 5]
    assert [isqrt_latency(r) for r in (4, 15)] == [6, 6]  # msb 2, 3: two pairs
    assert isqrt_latency(16) == 7
    assert isqrt_latency((1 << 79) - 1) == 39 + 5  # msb 78: 40 pairs
    assert isqrt_latency((1 << 80) - 1) == 39 + 5  # msb 79: the same pair
    with pytest.raises(ValueError, match="negative"):
        isqrt_iterations(-1)
    with pytest.raises(ValueError, match="does not fit"):
        isqrt(1 << 16, 16)
    with pytest.raises(ValueError, match="even"):
        isqrt(3, 15)


def test_isqrt_iterations_cover_the_root() -> None:
    """One iteration per root bit: the unrounded root has exactly isqrt_iterations(R) bits."""
    for r in [*range(1, 4096), *(1 << k for k in range(80)), *((1 << k) - 1 for k in range(1, 81))]:
        assert math.isqrt(r).bit_length() == isqrt_iterations(r)


def test_next_delay_latency_by_hand() -> None:
    # x = 0, C = 1: msb 0, L(0) = 1, L(1) = 5
    assert fresh_latency(1, 0) == 0 + 1 + 5 + 3
    # x = 5 (msb 2), C = 3: R_lo = 15 (L 6), R_hi = 18 (msb 4, L 7)
    assert fresh_latency(3, 5) == 2 + 6 + 7 + 3
    # continued: accel takes the root of C (x + 1), decel of C x
    assert continued_latency(3, 5, decel=False) == isqrt_latency(18) + 2 == 9
    assert continued_latency(3, 5, decel=True) == isqrt_latency(15) + 2 == 8
    assert continued_latency(3, 0, decel=True) == 1 + 2  # root(0)
    # the page's example: C = 16, x = 2: R_lo = 32 (msb 5, L 7), R_hi = 48 (L 7); root(48) - root(32) = 7 - 6
    assert fresh_latency(16, 2) == 1 + 7 + 7 + 3 == 18
    assert exact.value(16, 2) == 1 << 12
    # C = 0: every radicand 0
    assert fresh_latency(0, X_MAX) == 30 + 1 + 1 + 3


def test_worst_cases_fit_the_budget() -> None:
    """The worst cases (C < 2^72, x < 2^31) are at the top corner: 30 + 56 + 56 + 3 and 56 + 2; for C < 2^48
    30 + 44 + 44 + 3 and 44 + 2."""
    assert FRESH_WORST == 145
    assert CONTINUED_WORST == 58
    assert FRESH_WORST_NARROW == 121
    assert CONTINUED_WORST_NARROW == 46
    rng = random.Random(4)
    for _ in range(3000):
        c, x = unit_constant(random_seed(rng)), rng.getrandbits(rng.randint(0, 31))
        decel = rng.random() < 0.5
        assert fresh_latency(c, x) <= FRESH_WORST
        assert continued_latency(c, x, decel) <= CONTINUED_WORST
        if c < 1 << 48:
            assert fresh_latency(c, x) <= FRESH_WORST_NARROW
            assert continued_latency(c, x, decel) <= CONTINUED_WORST_NARROW


def test_values_fit_37_bits_and_telescope() -> None:
    """Every answer is below 2^37 in Q.4 (the largest, 2^36, at x = 0 with the largest C: ans_ovf, as it does not fit
    Q32.16), at most 2^36 - 1 for C <= C_MAX, and a run of answers sums to the difference of two roots."""
    assert exact.value_q4(C_TOP, 0) == 1 << 36
    assert exact.value_q4(C_TOP, 0) < 1 << VALUE_Q4_BITS
    assert NextDelayExact().request(ExactRequest(False, 0, SEED_TOP, 0)).ovf
    assert not NextDelayExact().request(ExactRequest(False, 1, SEED_TOP, 0)).ovf
    assert exact.value_q4(exact.C_MAX, 0) == (1 << 36) - 1
    assert exact.value_q4(exact.C_MAX + 1, 0) == 1 << 36
    assert exact.value_q4(C_NARROW_TOP, 0) == 1 << 24
    rng = random.Random(5)
    for _ in range(2000):
        c, x = unit_constant(random_seed(rng)), rng.getrandbits(rng.randint(0, 31))
        assert 0 <= exact.value_q4(c, x) <= math.isqrt(c) + 1 <= 1 << 36
    for seed in (1, 12345, C_NARROW_TOP, exact.ramp_constant(3e9), exact.seed_word((1 << 60) - (1 << 24), 6)):
        c = exact.constant_of(seed)
        lo = rng.randrange(1000)
        unit = NextDelayExact()
        total = sum(unit.request(ExactRequest(False, x, seed, 0)).value for x in range(lo, lo + 300))
        assert (
            total == exact.ramp_sum_q16(seed, lo, lo + 300) == (exact.root(c * (lo + 300)) - exact.root(c * lo)) << 12
        )


def test_continuation_rule() -> None:
    c = 1000
    unit = NextDelayExact()
    head = ExactRequest(False, 10, c, 7)
    a = unit.request(head)
    assert not a.continued and a.latency == fresh_latency(c, 10) and a.value == exact.value(c, 10)
    # the next accel index continues, with one root: C (x + 1)
    b = unit.request(ExactRequest(False, 11, c, 7))
    assert b.continued and b.latency == continued_latency(c, 11, False)
    # an alternative in between is fresh and leaves the run: 12 still continues
    alt = unit.request(ExactRequest(True, 11, 5, 5, alt=True))
    assert not alt.continued and alt.value == exact.value(5, 11)
    assert unit.request(ExactRequest(False, 12, c, 7)).continued
    # a gap, a repeat, the other kind or a seed is fresh
    for req in (
        ExactRequest(False, 14, c, 7),
        ExactRequest(False, 14, c, 7),
        ExactRequest(True, 13, c, c),
    ):
        assert not unit.request(req).continued
    # the decel run (13) goes down; a seed restarts it, and the run goes on from the seed's index
    assert unit.request(ExactRequest(True, 12, 0, c)).continued
    assert not unit.request(ExactRequest(True, 11, 0, c, seed=True)).continued
    assert unit.request(ExactRequest(True, 10, 0, c)).continued
    # a flush forgets it
    unit.flush()
    assert not unit.request(ExactRequest(True, 9, 0, c)).continued
    assert unit.request(ExactRequest(True, 8, 0, c)).continued


def test_continuation_stops_at_the_ends_of_the_index_range() -> None:
    c = 3
    unit = NextDelayExact()
    unit.request(ExactRequest(False, X_MAX, c, 0))
    assert not unit.request(ExactRequest(False, 0, c, 0)).continued  # x_lo + 1 = 2^31 is no index (no wrap)
    unit.request(ExactRequest(True, 1, 0, c))
    assert unit.request(ExactRequest(True, 0, 0, c)).continued
    assert not unit.request(ExactRequest(True, X_MAX, 0, c)).continued  # x_lo - 1 = -1 is no index (no wrap)


def test_contract_violations_are_refused() -> None:
    unit = NextDelayExact()
    unit.request(ExactRequest(False, 5, 100, 0))
    with pytest.raises(ValueError, match="flush between segments"):
        unit.request(ExactRequest(False, 6, 101, 0))
    with pytest.raises(ValueError, match="ramp index"):
        unit.request(ExactRequest(False, 1 << 31, 100, 0))
    with pytest.raises(ValueError, match="64 bits"):
        unit.request(ExactRequest(False, 1, 1 << 64, 0))
    with pytest.raises(ValueError, match="64 bits"):
        unit.request(ExactRequest(False, 1, 1, 1 << 64))
