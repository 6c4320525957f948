# SPDX-License-Identifier: MIT
"""Behaviour and latency of the exact mode's next-delay unit (docs/stepramp_isqrt.md): stepramp_isqrt and
stepramp_next_delay_exact.

The values come from stepramp.models.exact (plain integer arithmetic); the latencies from the formulas the page
documents, not from the RTL's clock-by-clock steps. The continuation rule (which request reuses the previous
square root) is the unit's contract, so it is modelled here; how the RTL keeps its state is not.
"""

from __future__ import annotations

from dataclasses import dataclass

from stepramp.models import exact
from stepramp.models.blocks import msb

#: The square root's radicand width in the next-delay unit: m * (x + 1) < 2^60 * 2^31 fits 92 bits.
ISQRT_WIDTH = exact.RADICAND_WIDTH

#: The zero pairs the unit's square root can append below its radicand (the scale e of the seed word, 0 .. 6).
ISQRT_EXTRA = exact.SCALE_MAX

#: The answer is root(C (x + 1)) - root(C x) <= sqrt(C) + 1 <= 2^36 for C < 2^72: 37 bits of each root give it
#: exactly; an answer of 2^36 or more (C above C_MAX, x = 0) does not fit Q32.16 and is answered with ans_ovf.
VALUE_Q4_BITS = 37


# ---------------------------------------------------------------------------------------------------------------
# stepramp_isqrt
# ---------------------------------------------------------------------------------------------------------------


def isqrt_iterations(radicand: int) -> int:
    """Root bits the square root computes: floor(msb(R) / 2) + 1, one per bit pair from the pair that holds R's top
    bit down; 0 for R = 0."""
    if radicand < 0:
        raise ValueError(f"negative radicand {radicand}")
    return 0 if radicand == 0 else msb(radicand) // 2 + 1


def isqrt_latency(radicand: int, extra: int = 0) -> int:
    """Clock edges from the edge that samples start to the edge after which done is '1': 1 for R = 0 (the align
    edge finds no '1'); else 1 (align) + 1 (the zero pair above the top pair, which fetches it) +
    isqrt_iterations(R) + extra (the zero pairs appended below R) + 1 (the zero pair below them, whose trial decides
    the rounding) + 1 (the rounding increment) = floor(msb(R) / 2) + extra + 5 = floor(msb(R 4^extra) / 2) + 5."""
    if radicand == 0:
        return 1
    return isqrt_iterations(radicand) + extra + 4


@dataclass(frozen=True)
class SquareRoot:
    """What stepramp_isqrt answers for one radicand."""

    root: int  # sqrt(R) rounded to the nearest integer (exact.root)
    latency: int  # clock edges from the one that samples start to the one that raises done


def isqrt(radicand: int, width: int = ISQRT_WIDTH, extra: int = 0, max_extra: int = 0) -> SquareRoot:
    """The rounded root of a width-bit radicand (width even) with extra zero pairs appended below it, root(R 4^e),
    and its latency; the unit's G_EXTRA = max_extra caps the pairs (e = min(extra, max_extra))."""
    if width % 2 or width < 4:
        raise ValueError(f"radicand width {width} is not an even number >= 4")
    if not 0 <= radicand < 1 << width:
        raise ValueError(f"radicand {radicand} does not fit {width} bits")
    if not 0 <= extra < 16:
        raise ValueError(f"extra {extra} does not fit 4 bits")
    pairs = min(extra, max_extra)
    return SquareRoot(exact.root(radicand << (2 * pairs)), isqrt_latency(radicand, pairs))


# ---------------------------------------------------------------------------------------------------------------
# stepramp_next_delay_exact
# ---------------------------------------------------------------------------------------------------------------


def unit_constant(seed: int) -> int:
    """The ramp constant the unit computes with for a seed word: m * 4^min(e, ISQRT_EXTRA) (the square root appends
    at most ISQRT_EXTRA zero pairs; the engine refuses a larger scale before it asks)."""
    m, e = exact.mantissa_scale(seed)
    return m << (2 * min(e, ISQRT_EXTRA))


def fresh_latency(constant: int, x: int) -> int:
    """A fresh request: msb(x) + 1 multiply steps (one, on a '0' bit, for x = 0), the last of which starts
    root(C x); root(C (x + 1)) starts in the edge after its done; the answer is registered in the edge after that
    one's done: msb(x) + L(C x) + L(C (x + 1)) + 3 (msb(0) = 0)."""
    return msb(x) + isqrt_latency(constant * x) + isqrt_latency(constant * (x + 1)) + 3


def continued_latency(constant: int, x: int, decel: bool) -> int:
    """A continued request: the new radicand (C (x + 1) accel, C x decel) is formed in the edge after the sampling
    edge, which starts its root; the answer is registered in the edge after its done: L(radicand) + 2."""
    return isqrt_latency(constant * x if decel else constant * (x + 1)) + 2


#: The worst cases for C < 2^72 and x < 2^31: every term grows with C and x, so they are at the top corner
#: (a mantissa of 2^60 - 1 at scale 6; the latency of C x is that of its radicand m x with e zero pairs appended).
_C_TOP = ((1 << exact.MANT_WIDTH) - 1) << (2 * exact.SCALE_MAX)
FRESH_WORST = fresh_latency(_C_TOP, (1 << exact.INDEX_WIDTH) - 1)
CONTINUED_WORST = max(
    continued_latency(_C_TOP, (1 << exact.INDEX_WIDTH) - 1, False),
    continued_latency(_C_TOP, (1 << exact.INDEX_WIDTH) - 1, True),
)
#: The same for constants below 2^48 (scale 0): the engine's shorter budget (MIN_INTERVAL_CLKS_EXACT).
_C_NARROW_TOP = exact.C_NARROW - 1
FRESH_WORST_NARROW = fresh_latency(_C_NARROW_TOP, (1 << exact.INDEX_WIDTH) - 1)
CONTINUED_WORST_NARROW = continued_latency(_C_NARROW_TOP, (1 << exact.INDEX_WIDTH) - 1, False)


@dataclass(frozen=True)
class ExactRequest:
    """One request to stepramp_next_delay_exact, as the requester drives it."""

    decel: bool
    x: int  # req_index
    c_head: int  # seed words (scale in bits 63:60, mantissa in 59:0)
    c_dec: int
    seed: bool = False
    alt: bool = False

    @property
    def constant(self) -> int:
        """C of the seed word c_dec for a decel request, else of c_head (sampled with the request; unit_constant)."""
        return unit_constant(self.c_dec if self.decel else self.c_head)


@dataclass(frozen=True)
class ExactAnswer:
    """The unit's answer to one request."""

    value: int  # Q32.16 (ans_value, its low 48 bits); ans_rem is 0
    latency: int  # clock edges from the edge that samples req to the edge after which ans_valid is '1'
    continued: bool  # one square root (the kept run went on), else fresh (a multiply and two roots)
    ovf: bool = False  # ans_ovf: the value is 2^48 or more (Q.4: 2^36 or more; C above C_MAX at x = 0)


@dataclass
class NextDelayExact:
    """The unit's contract: answers, latencies and the continuation rule.

    The unit keeps the run of its last request that was not an alternative (req_alt): its kind, its index x_lo and
    its constant. A request continues that run when it is not a seed and not an alternative, has the same kind, the
    run is valid, and x = x_lo + 1 (accel) or x = x_lo - 1 (decel); every other request is fresh. A seed starts a
    new run, an alternative leaves the run as it was, a flush (or reset) forgets it. The run's constant must not
    change while it continues (the engine flushes between segments): request() raises if a request would continue
    with another constant, as the unit then answers from the kept radicand with the new C.
    """

    valid: bool = False
    decel: bool = False
    x_lo: int = 0
    constant: int = 0
    word: int = 0  # the seed word the run's constant came in

    def continues(self, req: ExactRequest) -> bool:
        """Whether the request would continue the kept run."""
        step = -1 if req.decel else 1
        return self.valid and not req.seed and not req.alt and req.decel == self.decel and req.x == self.x_lo + step

    def request(self, req: ExactRequest) -> ExactAnswer:
        """Answer one request and update the kept run."""
        if not 0 <= req.c_head < 1 << exact.SEED_WIDTH or not 0 <= req.c_dec < 1 << exact.SEED_WIDTH:
            raise ValueError(f"{req}: a seed word does not fit {exact.SEED_WIDTH} bits")
        if not 0 <= req.x < 1 << exact.INDEX_WIDTH:
            raise ValueError(f"ramp index {req.x} is not in 0 .. 2^31 - 1")
        constant = req.constant
        value_q4 = exact.value_q4(constant, req.x)
        continued = self.continues(req)
        if continued and constant != self.constant:
            raise ValueError(
                f"{req}: continues the kept run with C = {constant:#x}, the run's is {self.constant:#x} "
                "(outside the contract: flush between segments)"
            )
        latency = continued_latency(constant, req.x, req.decel) if continued else fresh_latency(constant, req.x)
        if not req.alt:
            self.valid, self.decel, self.x_lo, self.constant = True, req.decel, req.x, constant
            self.word = req.c_dec if req.decel else req.c_head
        value = (value_q4 << (16 - exact.FRAC_EXACT)) & ((1 << 48) - 1)
        return ExactAnswer(value, latency, continued, value_q4 >= 1 << 36)

    def flush(self) -> None:
        """A flush or a reset: the request in flight gives no answer, and the kept run is forgotten."""
        self.valid = False
