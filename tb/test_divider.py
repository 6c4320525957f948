# SPDX-License-Identifier: MIT
"""stepramp_divider: quotient, remainder, div_zero and latency in cycles against the reference model.

Width 8: all 65,536 operand pairs. Width 32, and the next-delay unit's 50-bit numerator over a 33-bit
denominator: every corner pair (0, 1, max, powers of two, all-ones, N = D, N < D) and random pairs, at least
20,000 in all.
"""

from __future__ import annotations

import random

import pytest
from cocotb.triggers import FallingEdge, RisingEdge, SimTimeoutError, with_timeout

from stepramp.models.blocks import divide, iter_msb_pairs
from stepramp.sim.runner import run_cocotb
from tbutil import CLK_PERIOD_NS, build_dir, cocotb, env_int, now_cycles, start_clock_and_reset


def operand_pairs(width: int, den_width: int, n_random: int, seed: int) -> list[tuple[int, int]]:
    """Exhaustive for small widths; corners plus random pairs of varied magnitude otherwise."""
    if width <= 8:
        return [(n, d) for n in range(1 << width) for d in range(1 << den_width)]
    rng = random.Random(seed)
    pairs = [(n, d) for n, d in iter_msb_pairs(width) if d < 1 << den_width]
    while len(pairs) < n_random:
        # Random bit lengths, so that every quotient length is exercised, not only huge/huge.
        n = rng.getrandbits(rng.randint(0, width))
        d = rng.getrandbits(rng.randint(0, den_width))
        pairs.append((n, d))
    return pairs


#: A backstop for the widest divider (64 bits) and the pairs asked for; the body holds each wait to a tighter,
#: width-exact limit.
BACKSTOP_US = 2 * env_int("N_PAIRS", 20000) * (64 + 2) * CLK_PERIOD_NS // 1000 + 100


@cocotb.test(timeout_time=BACKSTOP_US, timeout_unit="us")
async def divider_against_model(dut) -> None:
    """Back-to-back divisions with start held high: each result and latency checked against the model."""
    width, den_width = len(dut.numerator), len(dut.denominator)
    pairs = operand_pairs(width, den_width, env_int("N_PAIRS", 20000), env_int("PAIR_SEED", 1))
    dut.start.value = 0
    dut.numerator.value = 0
    dut.denominator.value = 0
    await start_clock_and_reset(dut.clk, dut.rst)

    failures: list[str] = []
    latencies: list[int] = []
    n, d = pairs[0]
    dut.numerator.value = n
    dut.denominator.value = d
    dut.start.value = 1
    await RisingEdge(dut.clk)
    sample_edge = now_cycles()  # this edge samples start (the divider is idle)
    # Limit: every pair at the worst latency (1 + ceil(width / 2) clocks, asserted below) plus its sampling clock,
    # +50%.
    worst = 1 + (width + 1) // 2
    limit_ns = 3 * len(pairs) * (worst + 1) * CLK_PERIOD_NS // 2
    index = 0

    async def divide_all() -> None:
        # One limit for the whole run, not a with_timeout per division: each costs ten times the simulation of the
        # division (stepramp.sim.wake).
        nonlocal index, sample_edge
        for index, (n, d) in enumerate(pairs):
            await RisingEdge(dut.done)
            done_edge = now_cycles()
            expect = divide(n, d, width, den_width)
            got = (int(dut.quotient.value), int(dut.remainder.value), bool(int(dut.div_zero.value)))
            latency = done_edge - sample_edge
            latencies.append(latency)
            if got != (expect.quotient, expect.remainder, expect.div_zero) or latency != expect.latency:
                failures.append(f"{n}/{d}: got q,r,dz={got} lat={latency}, expected {expect}")
                if len(failures) > 20:
                    return
            if index + 1 < len(pairs):
                # The divider is idle in the done cycle, so the next edge samples the next operands.
                dut.numerator.value, dut.denominator.value = pairs[index + 1]
            else:
                dut.start.value = 0
            sample_edge = done_edge + 1

    try:
        await with_timeout(divide_all(), limit_ns, "ns")
    except SimTimeoutError:
        n, d = pairs[index]
        raise AssertionError(f"no done for pair {index} ({n}/{d}) within the limit of {limit_ns} ns") from None
    await FallingEdge(dut.clk)
    assert not failures, "\n".join(failures)
    assert max(latencies) == worst
    mean = sum(latencies) / len(latencies)
    dut._log.info("width %d: %d divisions, latency mean %.3f max %d", width, len(pairs), mean, max(latencies))


@cocotb.test(timeout_time=2, timeout_unit="us")  # measured 0.4 us at width 32
async def divider_ignores_start_while_busy(dut) -> None:
    """Every output is 0 after reset (docs/stepramp_divider.md, "Ports"). A start pulse during a division changes
    nothing: the first result comes out, then the divider idles."""
    width = len(dut.numerator)
    top = (1 << width) - 1
    dut.start.value = 0
    await start_clock_and_reset(dut.clk, dut.rst)
    await FallingEdge(dut.clk)
    outputs = {n: int(getattr(dut, n).value) for n in ("busy", "done", "div_zero", "quotient", "remainder")}
    assert not any(outputs.values()), f"after reset: {outputs}"
    dut.numerator.value = top
    dut.denominator.value = 1
    dut.start.value = 1
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.numerator.value = 5
    dut.denominator.value = 7  # would give q=0 at once if it were sampled
    await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.start.value = 0
    await RisingEdge(dut.done)
    assert int(dut.quotient.value) == top
    assert int(dut.remainder.value) == 0
    await FallingEdge(dut.clk)
    for _ in range(5):
        await RisingEdge(dut.clk)
        await FallingEdge(dut.clk)
        assert int(dut.busy.value) == 0, "a start sampled while busy must not queue a division"
        assert int(dut.done.value) == 0


@pytest.mark.parametrize(("width", "den_width"), [(8, 8), (32, 32), (50, 33)])
def test_divider(width: int, den_width: int) -> None:
    run_cocotb(
        "stepramp_divider",
        "test_divider",
        build_dir(f"divider_w{width}_{den_width}"),
        parameters={"G_WIDTH": width, "G_DEN_WIDTH": den_width},
        extra_env={"N_PAIRS": "20000", "PAIR_SEED": "2026"},
    )
