# SPDX-License-Identifier: MIT
"""The block models (priority encoder, divider, base timer) against their definitions."""

from __future__ import annotations

import random

import pytest

from stepramp.models.blocks import divide, divider_latency, iter_msb_pairs, msb, prio_enc, timer_ticks


def test_msb_matches_powers_of_two() -> None:
    for bit in range(64):
        assert msb(1 << bit) == bit
        assert msb((1 << (bit + 1)) - 1) == bit
    assert msb(0) == 0
    with pytest.raises(ValueError, match="negative"):
        msb(-1)


def test_prio_enc_flags_zero_and_rejects_overflow() -> None:
    assert prio_enc(0, 16) == (0, True)
    assert prio_enc(0x8000, 16) == (15, False)
    assert prio_enc(0x0101, 16) == (8, False)
    with pytest.raises(ValueError, match="does not fit"):
        prio_enc(1 << 16, 16)


def test_divide_satisfies_the_division_identity() -> None:
    rng = random.Random(7)
    for _ in range(5000):
        n, d = rng.getrandbits(32), rng.getrandbits(rng.randint(1, 32))
        res = divide(n, d, 32)
        if d == 0:
            assert res.div_zero
            assert (res.quotient, res.remainder) == ((1 << 32) - 1, n)
        else:
            assert res.quotient * d + res.remainder == n
            assert 0 <= res.remainder < d


def test_divider_latency_formula() -> None:
    # Trivial cases finish in the constant; otherwise one iteration per numerator bit pair from its msb down.
    assert divider_latency(5, 0) == 1
    assert divider_latency(0, 7) == 1
    assert divider_latency(1, 1) == 2
    assert divider_latency(3, 7) == 2  # N < D still iterates over N's bit pairs: quotient 0
    assert divider_latency(7, 7) == 3  # msb 2: pairs 1 and 0
    assert divider_latency(8, 7) == 3
    assert divider_latency(16, 7) == 4
    assert divider_latency((1 << 32) - 1, 1) == 17
    assert max(divider_latency(n, d) for n, d in iter_msb_pairs(32)) == 17
    # The iterations cover every bit pair of the quotient (and of the numerator).
    for n, d in iter_msb_pairs(16):
        if d and n:
            assert (n // d).bit_length() <= n.bit_length() <= 2 * (divider_latency(n, d) - 1) <= n.bit_length() + 1


def test_divide_narrow_denominator() -> None:
    # A 50-bit numerator over a 33-bit denominator (the next-delay unit's shape); D = 0 keeps N's low bits.
    assert divide((1 << 50) - 1, 5, 50, 33) == divide((1 << 50) - 1, 5, 50)
    assert divide(1 << 40, 0, 50, 33).remainder == 0
    assert divide((1 << 40) + 9, 0, 50, 33).remainder == 9
    with pytest.raises(ValueError, match="do not fit"):
        divide(1, 1 << 33, 50, 33)


def test_corner_pairs_cover_the_issue_list() -> None:
    pairs = set(iter_msb_pairs(32))
    top = (1 << 32) - 1
    for pair in [(0, 0), (1, 1), (top, top), (top, 1), (1, top), (1 << 31, 1 << 31), (5, 0)]:
        if pair != (5, 0):
            assert pair in pairs
    assert any(n < d for n, d in pairs)
    assert any(n == d for n, d in pairs)


def test_timer_ticks_spacing_and_change() -> None:
    assert timer_ticks([(0, 1)], 0, 5) == [1, 2, 3, 4, 5]
    assert timer_ticks([(0, 3)], 0, 10) == [3, 6, 9]
    assert timer_ticks([(10, 0)], 10, 3) == [11, 12, 13]
    # Change at edge 4 from 3 to 5: the tick at 3 reloads with 3 (value seen at edge 3), so 6, then 5s.
    assert timer_ticks([(0, 3), (4, 5)], 0, 20) == [3, 6, 11, 16]
    with pytest.raises(ValueError, match="restart"):
        timer_ticks([(5, 2)], 0, 10)
