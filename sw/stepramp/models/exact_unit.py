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

#: The square root's radicand width in the next-delay unit: C * (x + 1) < 2^48 * 2^31 fits 80 bits.
ISQRT_WIDTH = exact.RADICAND_WIDTH

#: The answer is root(C (x + 1)) - root(C x) <= 2^24 for C < 2^48: 25 bits of each root give it exactly.
VALUE_Q4_BITS = 25


# ---------------------------------------------------------------------------------------------------------------
# stepramp_isqrt
# ---------------------------------------------------------------------------------------------------------------


def isqrt_iterations(radicand: int) -> int:
    """Root bits the square root computes: floor(msb(R) / 2) + 1, one per bit pair from the pair that holds R's top
    bit down; 0 for R = 0."""
    if radicand < 0:
        raise ValueError(f"negative radicand {radicand}")
    return 0 if radicand == 0 else msb(radicand) // 2 + 1


def isqrt_latency(radicand: int) -> int:
    """Clock edges from the edge that samples start to the edge after which done is '1': 1 for R = 0 (the align
    edge finds no '1'); else 1 (align) + 1 (the zero pair above the top pair, which fetches it) +
    isqrt_iterations(R) + 1 (the zero pair below R, whose trial decides the rounding) + 1 (the rounding increment)
    = floor(msb(R) / 2) + 5."""
    if radicand == 0:
        return 1
    return isqrt_iterations(radicand) + 4


@dataclass(frozen=True)
class SquareRoot:
    """What stepramp_isqrt answers for one radicand."""

    root: int  # sqrt(R) rounded to the nearest integer (exact.root)
    latency: int  # clock edges from the one that samples start to the one that raises done


def isqrt(radicand: int, width: int = ISQRT_WIDTH) -> SquareRoot:
    """The rounded root of a width-bit radicand (width even), and its latency."""
    if width % 2 or width < 4:
        raise ValueError(f"radicand width {width} is not an even number >= 4")
    if not 0 <= radicand < 1 << width:
        raise ValueError(f"radicand {radicand} does not fit {width} bits")
    return SquareRoot(exact.root(radicand), isqrt_latency(radicand))


# ---------------------------------------------------------------------------------------------------------------
# stepramp_next_delay_exact
# ---------------------------------------------------------------------------------------------------------------


def fresh_latency(constant: int, x: int) -> int:
    """A fresh request: msb(x) + 1 multiply steps (one, on a '0' bit, for x = 0), the last of which starts
    root(C x); root(C (x + 1)) starts in the edge after its done; the answer is registered in the edge after that
    one's done: msb(x) + L(C x) + L(C (x + 1)) + 3 (msb(0) = 0)."""
    return msb(x) + isqrt_latency(constant * x) + isqrt_latency(constant * (x + 1)) + 3


def continued_latency(constant: int, x: int, decel: bool) -> int:
    """A continued request: the new radicand (C (x + 1) accel, C x decel) is formed in the edge after the sampling
    edge, which starts its root; the answer is registered in the edge after its done: L(radicand) + 2."""
    return isqrt_latency(constant * x if decel else constant * (x + 1)) + 2


#: The worst cases for C < 2^48 and x < 2^31: every term grows with C and x, so they are at the top corner.
FRESH_WORST = fresh_latency((1 << exact.C_WIDTH) - 1, (1 << exact.INDEX_WIDTH) - 1)
CONTINUED_WORST = max(
    continued_latency((1 << exact.C_WIDTH) - 1, (1 << exact.INDEX_WIDTH) - 1, False),
    continued_latency((1 << exact.C_WIDTH) - 1, (1 << exact.INDEX_WIDTH) - 1, True),
)


@dataclass(frozen=True)
class ExactRequest:
    """One request to stepramp_next_delay_exact, as the requester drives it."""

    decel: bool
    x: int  # req_index
    c_head: int
    c_dec: int
    seed: bool = False
    alt: bool = False

    @property
    def constant(self) -> int:
        """C: c_dec for a decel request, else c_head (sampled with the request)."""
        return self.c_dec if self.decel else self.c_head


@dataclass(frozen=True)
class ExactAnswer:
    """The unit's answer to one request."""

    value: int  # Q32.16 (ans_value); ans_rem is 0 and ans_ovf '0'
    latency: int  # clock edges from the edge that samples req to the edge after which ans_valid is '1'
    continued: bool  # one square root (the kept run went on), else fresh (a multiply and two roots)


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

    def continues(self, req: ExactRequest) -> bool:
        """Whether the request would continue the kept run."""
        step = -1 if req.decel else 1
        return self.valid and not req.seed and not req.alt and req.decel == self.decel and req.x == self.x_lo + step

    def request(self, req: ExactRequest) -> ExactAnswer:
        """Answer one request and update the kept run."""
        constant = req.constant
        value = exact.value(constant, req.x)  # checks the ranges of C and x
        if not 0 <= req.c_head < 1 << exact.C_WIDTH or not 0 <= req.c_dec < 1 << exact.C_WIDTH:
            raise ValueError(f"{req}: a ramp constant does not fit {exact.C_WIDTH} bits")
        continued = self.continues(req)
        if continued and constant != self.constant:
            raise ValueError(
                f"{req}: continues the kept run with C = {constant:#x}, the run's is {self.constant:#x} "
                "(outside the contract: flush between segments)"
            )
        latency = continued_latency(constant, req.x, req.decel) if continued else fresh_latency(constant, req.x)
        if not req.alt:
            self.valid, self.decel, self.x_lo, self.constant = True, req.decel, req.x, constant
        return ExactAnswer(value, latency, continued)

    def flush(self) -> None:
        """A flush or a reset: the request in flight gives no answer, and the kept run is forgotten."""
        self.valid = False
