# SPDX-License-Identifier: MIT
"""Mutation check of the RTL: would the regression notice a broken line? (`make mutate`)

    python -m stepramp.tools.mutate [--sample 80] [--seed 1] [--jobs 2] [--list] [--only ID ...]

1. Every RTL file (stepramp.sim.runner.HDL_FILES) is scanned for mutation sites, outside comments and assertions:
   * ``rel``: a relational operator in a condition (if / elsif / while, or between when and else of a conditional
     assignment) replaced by its neighbour: = and /=, < and <=, > and >=;
   * ``logic``: and / or swapped in a condition or an assignment;
   * ``arith``: an integer literal added or subtracted in an assignment made one larger or one smaller;
   * ``bit``: a '0' / '1' literal flipped, or the last bit of a bit-string literal.
2. A seeded sample is drawn, spread over the files (round robin over each file's shuffled sites).
3. Each mutant is written into a copy of hdl/ and analysed with GHDL (--std=08, every file in order): a mutant that
   does not analyse is not valid and is not counted.
4. A valid mutant runs the quick RTL suite for its file (SUITES below: the file's own unit bench first, then the
   benches of the tops that hold it), with pytest -x: the first failing test kills it. The suite runs with
   STEPRAMP_HDL_DIR pointing at the mutant copy and a build folder of its own (STEPRAMP_SIM_BUILD), so --jobs
   mutants run side by side.

Prints killed / valid / total, the score (killed / valid) and every survivor; writes build/mutate/report.json.
Mutants shown equivalent (EQUIVALENT below, each with its reason) are listed, not run and not counted as valid.
Survivors get a test, or a written reason why they are equivalent (docs/verification.md, "Mutation check").
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path

from stepramp.sim.runner import HDL_DIR, HDL_FILES

REPO = HDL_DIR.parent
OUT = REPO / "build" / "mutate"

#: Quick RTL suite per file, cheapest and most specific first (pytest node ids, run with -x).
_ENGINE = [
    "tb/test_engine.py::test_engine_profiles[0]",
    "tb/test_engine.py::test_engine_error_codes",
    "tb/test_engine.py::test_engine_hard_stop",
    "tb/test_engine.py::test_engine_soft_stop[0]",
    "tb/test_engine.py::test_engine_profiles[1]",
    "tb/test_engine.py::test_engine_latency_budget",
    "tb/test_engine.py::test_engine_step_spacing",
    "tb/test_engine.py::test_engine_pos_load_and_start",
    "tb/test_engine.py::test_engine_reset",
    "tb/test_engine.py::test_engine_stop_combinations",
    "tb/test_engine.py::test_engine_counters_per_pulse",
    "tb/test_engine.py::test_engine_runs_the_loaded_move",
    "tb/test_engine.py::test_engine_start_without_load",
]
#: continuation segments (down heads, their soft stops) run from START on the engine bench
_SEGMENTS = [
    "tb/test_engine_segments.py::test_engine_segments_positioning",
    "tb/test_engine_segments.py::test_engine_segments_endless",
]
#: the exact ramp (G_RAMP = 1) on the engine bench: its segments, stops and parameter check
_EXACT = ["tb/test_engine_exact.py::test_exact_engine_segments"]
_PLB = [
    "tb/test_peripheral.py::test_registers[stepramp_plb]",
    "tb/test_peripheral.py::test_profiles[stepramp_plb-1]",
    "tb/test_core.py::test_core",
    "tb/test_faults.py",
]
_AXIL = [
    "tb/test_peripheral.py::test_registers[stepramp_axil]",
    "tb/test_peripheral.py::test_profiles[stepramp_axil-1]",
]
SUITES: dict[str, list[str]] = {
    "stepramp_pkg.vhd": [
        "tb/test_prio_enc.py",
        "tb/test_stepper.py::test_stepper",
        "tb/test_stepper.py::test_stepper_pwm_generics",
        *_ENGINE[:3],
        *_PLB[:1],
    ],
    "stepramp_regs_pkg.vhd": [*_PLB, *_ENGINE[:3]],
    "stepramp_prio_enc.vhd": ["tb/test_prio_enc.py", "tb/test_divider.py", *_ENGINE[:3]],
    "stepramp_divider.vhd": ["tb/test_divider.py", "tb/test_next_delay.py", *_ENGINE[:3]],
    "stepramp_timer.vhd": ["tb/test_timer.py", *_ENGINE[:3]],
    "stepramp_sched.vhd": ["tb/test_sched.py"],
    "stepramp_next_delay.vhd": ["tb/test_next_delay.py", *_ENGINE[:6]],
    "stepramp_isqrt.vhd": ["tb/test_isqrt.py", "tb/test_next_delay_exact.py"],
    "stepramp_next_delay_exact.vhd": ["tb/test_next_delay_exact.py"],
    "stepramp_precompute.vhd": ["tb/test_precompute.py", *_ENGINE, *_SEGMENTS, *_EXACT],
    "stepramp_engine.vhd": [*_ENGINE, *_SEGMENTS, *_EXACT, *_PLB[:1]],
    # (gate_wait serves only the multi-axis top's common start)
    "stepramp_stepper.vhd": ["tb/test_stepper.py", *_PLB, "tb/test_multi_rtl.py::test_multi_rtl[stepramp_multi_plb]"],
    "stepramp_regfile.vhd": ["tb/test_regfile.py", "tb/test_readback.py", *_PLB],
    "stepramp_core.vhd": [
        "tb/test_core.py::test_core",
        *_PLB,
        # (ESTOP's stop from the filtered level: the aimed pulses, one clock either side of F)
        "tb/test_inputs_rtl.py::test_inputs[stepramp_plb-estop_in_every_kind_of_motion]",
    ],
    "stepramp_plb.vhd": _PLB,
    "stepramp_axil.vhd": _AXIL,
    "stepramp_inputs.vhd": [
        "tb/test_inputs_rtl.py::test_inputs[stepramp_plb-filter_and_polarity]",
        "tb/test_inputs_rtl.py::test_inputs[stepramp_plb-position_latch]",
        "tb/test_inputs_rtl.py::test_inputs[stepramp_plb-estop_in_every_kind_of_motion]",
        *_PLB[:1],  # (the reset values of LATCH_POS and LATCH_TIME)
    ],
    "stepramp_multi_pkg.vhd": ["tb/test_multi_rtl.py"],
    "stepramp_multi.vhd": ["tb/test_multi_rtl.py"],
    # the bus slaves serve the single-axis tops (their suites first) and the multi-axis tops
    "stepramp_plb_slave.vhd": [*_PLB, "tb/test_multi_rtl.py::test_multi_rtl[stepramp_multi_plb]"],
    "stepramp_axil_slave.vhd": [*_AXIL, "tb/test_multi_rtl.py::test_multi_rtl[stepramp_multi_axil]"],
    "stepramp_multi_plb.vhd": ["tb/test_multi_rtl.py::test_multi_rtl[stepramp_multi_plb]"],
    "stepramp_multi_axil.vhd": ["tb/test_multi_rtl.py::test_multi_rtl[stepramp_multi_axil]"],
}


#: Mutants that change nothing the core does, with the reason (not run; not counted as valid). Keyed by Mutant.site:
#: the file, the line's code and the column in it, and the change, so that a verdict follows its line when lines
#: above it come or go, and lapses when the line itself changes.
EQUIVALENT: dict[str, str] = {
    "pkg: if (n <= 2) then @6 rel -> <": (
        "clog2(2): n < 2 fails, log2_ceil(2) = 1 is returned, the same as the early return"
    ),
    'regs_pkg: 1      => x"00000000", @11 bit -> "00000001"': (
        "C_REG_RESET(1) is CTRL's: it goes into mem(1) at reset, but CTRL is not a storage word (it reads back from "
        "its own flip-flops, tb/test_peripheral.py reset_values_and_id) and nothing reads mem(1)"
    ),
    "core: load <= start_req and not busy_any; @18 logic -> or": (
        "load = start_req or not busy_any: the engine also copies the staged move on every idle clock, but uses the "
        "copy only from a start, and the last copy before a start is taken at the START edge either way; while busy "
        "it loads on a second START, which the engine ignores while busy (start_while_busy_is_ignored stages another "
        "plan before such STARTs and sees the running move unchanged)"
    ),
    **{
        f'regs_pkg: {w:<7}=> x"00000000", @11 bit -> "00000001"': (
            f"word {w} (STATUS, POSITION, CUR_DELAY, STEP_COUNT, LATCH_POS .. TIME_HI) is not a storage word (mem is "
            "STEPS .. STOP_RATIO, DRIVE .. STEP_SPACE and SEGMENT .. INPUT_CFG): neither its RW mask nor its reset "
            "value is read (storage_mask and reset_value serve storage words only, the read-back RAM is written for "
            "storage words only); tb/test_regfile.py time_and_latch_registers writes the live words and reads their "
            "inputs back, tb/test_peripheral.py reset_values_and_id reads every register after reset"
        )
        for w in (2, 22, 23, 24, *range(38, 43))
    },
    "prio_enc: if (n < width) then @6 rel -> <=": (
        "n <= width also fills slot n = width of the level, from slots 2 width and 2 width + 1; the next level reads "
        "slots 2 n and 2 n + 1 with n < width / 2, so at most slot width - 1, and the result is slot 0: the extra "
        "slot is never read"
    ),
    "isqrt: if (unsigned(extra) > G_EXTRA) then @20 rel -> >=": (
        "extra = G_EXTRA takes the clamp instead of the value itself: both give ext_r = G_EXTRA"
    ),
    "plb_slave: rd_r     <= '0'; @12 bit -> '1'": (
        "rd_r's reset value is never seen: in reset and in the clock after it the register file's ack is '0' and its "
        "rdata is 0 (rdata_r and ram_sel_r are reset), so ip2bus_data, rdack and wrack are 0 with rd_r either way, "
        "and the first edge after reset loads rd_r from rd_s"
    ),
    "precompute: seed_wait   <= '0'; @15 bit -> '1'": (
        "seed_wait set at begin_move: setup (edge 1) sets it anyway, finish clears it, and only DECIDE reads it, "
        "which runs after setup; at edge 1 the answer clause may copy a stale answer into rec_val, which the seed's "
        "own answer overwrites before DECIDE can run (DECIDE waits for it)"
    ),
}


@dataclass(frozen=True)
class Mutant:
    """One change of one line: `original` at column `col` of line `line` (1-based) becomes `replacement`."""

    file: str
    line: int
    col: int
    kind: str
    original: str
    replacement: str
    #: The line as written (without its comment): what EQUIVALENT is keyed on, so that a line moving up or down the
    #: file keeps its verdict and a changed line loses it.
    source: str = ""

    @property
    def ident(self) -> str:
        new = re.sub(r"[^A-Za-z0-9/=<>+-]", "", self.replacement)
        return f"{Path(self.file).stem.removeprefix('stepramp_')}:{self.line}:{self.col}:{self.kind}:{new}"

    @property
    def site(self) -> str:
        """The key of EQUIVALENT: file, the line's code and the column in it (indentation stripped), the change."""
        code = self.source.strip()
        col = self.col - (len(self.source) - len(self.source.lstrip()))
        return f"{Path(self.file).stem.removeprefix('stepramp_')}: {code} @{col} {self.kind} -> {self.replacement}"

    def describe(self) -> str:
        return f"{self.file}:{self.line}: {self.kind} '{self.original}' -> '{self.replacement}'"

    def apply(self, text: str) -> str:
        lines = text.split("\n")
        row = lines[self.line - 1]
        assert row[self.col : self.col + len(self.original)] == self.original, f"{self.describe()}: site moved"
        lines[self.line - 1] = row[: self.col] + self.replacement + row[self.col + len(self.original) :]
        return "\n".join(lines)


_REL_SWAP = {"=": "/=", "/=": "=", "<": "<=", "<=": "<", ">": ">=", ">=": ">"}
_REL = re.compile(r"/=|<=|>=|=>|:=|=|<|>")
_LOGIC = re.compile(r"\b(and|or)\b", re.I)
_ARITH = re.compile(r"([+-])\s*(\d+)\b(?!\s*(downto|to)\b)")
_BIT = re.compile(r"'([01])'")
_BITSTR = re.compile(r'"([01]+)"')


def _code(line: str) -> str:
    """The line without its comment (VHDL's -- outside a string), comment blanked to keep columns."""
    in_str = False
    for i, ch in enumerate(line):
        if ch == '"':
            in_str = not in_str
        elif not in_str and line.startswith("--", i):
            return line[:i] + " " * (len(line) - i)
    return line


def _cond_spans(code: str, in_if: bool) -> tuple[list[tuple[int, int]], bool]:
    """Column spans of conditions on a line (if/elsif/while .. then/loop; when .. else), and whether an if's
    condition goes on past the line."""
    spans: list[tuple[int, int]] = []
    low = code.lower()
    pos = 0
    if in_if:
        end = re.search(r"\b(then|loop|generate)\b", low)
        if end is None:
            return [(0, len(code))], True
        spans.append((0, end.start()))
        pos = end.end()
        in_if = False
    for m in re.finditer(r"(?<!end )\b(if|elsif|while)\b", low[pos:]):
        start = pos + m.end()
        end = re.search(r"\b(then|loop|generate)\b", low[start:])
        if end is None:
            spans.append((start, len(code)))
            in_if = True
            break
        spans.append((start, start + end.start()))
    for m in re.finditer(r"\bwhen\b", low):
        rest = low[m.end() :]
        stop = re.search(r"\belse\b|=>", rest)
        if stop is not None and stop.group(0) == "else":
            spans.append((m.end(), m.end() + stop.start()))
    return spans, in_if


def sites(path: Path) -> list[Mutant]:
    """Every mutation site of an RTL file."""
    name = path.name
    found: list[Mutant] = []
    in_assert = False
    in_if = False
    for number, raw in enumerate(path.read_text().split("\n"), start=1):
        code = _code(raw)
        low = code.lower().strip()
        if in_assert or low.startswith(("assert", "report", "severity")):
            in_assert = not low.endswith(";")
            continue
        spans, in_if = _cond_spans(code, in_if)

        def inside(col: int, spans: list[tuple[int, int]] = spans) -> bool:
            return any(a <= col < b for a, b in spans)

        for m in _REL.finditer(code):
            op = m.group(0)
            if op in _REL_SWAP and inside(m.start()):
                found.append(Mutant(name, number, m.start(), "rel", op, _REL_SWAP[op], code))
        is_assignment = ("<=" in code or ":=" in code) and not re.match(
            r"\s*(signal|constant|variable|type|subtype|generic|port)\b", code, re.I
        )
        for m in _LOGIC.finditer(code):
            if inside(m.start()) or is_assignment:
                word = m.group(1)
                swap = {"and": "or", "or": "and"}[word.lower()]
                found.append(Mutant(name, number, m.start(), "logic", word, swap, code))
        if is_assignment:
            for m in _ARITH.finditer(code):
                value = int(m.group(2))
                for new in (value + 1, value - 1):
                    if new >= 0:
                        text = m.group(0)
                        found.append(Mutant(name, number, m.start(), "arith", text, f"{m.group(1)} {new}", code))
        for m in _BIT.finditer(code):
            flipped = "1" if m.group(1) == "0" else "0"
            found.append(Mutant(name, number, m.start(), "bit", m.group(0), f"'{flipped}'", code))
        for m in _BITSTR.finditer(code):
            bits = m.group(1)
            flipped = bits[:-1] + ("1" if bits[-1] == "0" else "0")
            found.append(Mutant(name, number, m.start(), "bit", m.group(0), f'"{flipped}"', code))
    return found


def sample(all_sites: dict[str, list[Mutant]], n: int, seed: int) -> list[Mutant]:
    """n mutants spread over the files: round robin over each file's sites, shuffled with the seed."""
    rng = random.Random(seed)
    pools = {f: rng.sample(s, len(s)) for f, s in all_sites.items() if s}
    chosen: list[Mutant] = []
    while len(chosen) < n and any(pools.values()):
        for pool in pools.values():
            if pool and len(chosen) < n:
                chosen.append(pool.pop())
    return chosen


@dataclass
class Outcome:
    mutant: Mutant
    status: str  # "killed", "survived", "invalid", "equivalent"
    by: str  # the test that killed it, or why it is invalid
    seconds: float


def _analyses(hdl: Path, work: Path) -> str | None:
    """None if every file analyses under --std=08, else GHDL's first error."""
    work.mkdir(parents=True, exist_ok=True)
    for name in HDL_FILES:
        result = subprocess.run(
            ["ghdl", "-a", "--std=08", f"--workdir={work}", str(hdl / name)],
            capture_output=True,
            text=True,
            check=False,
        )
        if result.returncode != 0:
            return (result.stderr.strip().splitlines() or ["?"])[0]
    return None


def _run_group(cmd: list[str], env: dict[str, str], timeout_s: float) -> tuple[int | None, str]:
    """Run a mutant's suite in a process group of its own; (return code, stdout), return code None after a timeout.
    Whatever the suite leaves running is killed with the group (a mutant can keep a simulator spinning in delta
    cycles after pytest has given up on it; seed 2 left one running for 45 minutes)."""
    proc = subprocess.Popen(
        cmd, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True
    )
    try:
        stdout, _ = proc.communicate(timeout=timeout_s)
        returncode: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        stdout, returncode = "", None
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    return returncode, stdout


def run_one(mutant: Mutant, index: int, timeout_s: float) -> Outcome:
    """Write, analyse and test one mutant in build/mutate/m<index>."""
    t0 = time.monotonic()
    if mutant.site in EQUIVALENT:
        return Outcome(mutant, "equivalent", EQUIVALENT[mutant.site], 0.0)
    root = OUT / f"m{index}"
    shutil.rmtree(root, ignore_errors=True)
    hdl = root / "hdl"
    shutil.copytree(HDL_DIR, hdl)
    target = hdl / mutant.file
    target.write_text(mutant.apply(target.read_text()))
    error = _analyses(hdl, root / "work")
    if error is not None:
        shutil.rmtree(root, ignore_errors=True)
        return Outcome(mutant, "invalid", error, time.monotonic() - t0)
    env = {
        **os.environ,
        "STEPRAMP_HDL_DIR": str(hdl),
        "STEPRAMP_SIM_BUILD": str(root / "sim"),
        "STEPRAMP_COVERAGE_DIR": "",
    }
    env.setdefault("GHDL_BACKEND", "llvm" if Path("/usr/bin/ghdl-llvm").exists() else "mcode")
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *SUITES[mutant.file]]
    returncode, stdout = _run_group(cmd, env, timeout_s)
    shutil.rmtree(root, ignore_errors=True)
    if returncode is None:
        return Outcome(mutant, "killed", f"suite over {timeout_s:.0f} s (a hang)", time.monotonic() - t0)
    if returncode == 0:
        return Outcome(mutant, "survived", "", time.monotonic() - t0)
    failed = re.findall(r"^FAILED (\S+)", stdout, re.M)
    errors = re.findall(r"^ERROR (\S+)", stdout, re.M)
    by = (failed or errors or [f"pytest exit {returncode}"])[0]
    return Outcome(mutant, "killed", by, time.monotonic() - t0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sample", type=int, default=80, help="how many mutants (default 80)")
    ap.add_argument("--seed", type=int, default=1, help="the sample's seed (default 1)")
    ap.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 2)), help="mutants run side by side")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds a mutant's suite may take (a hang)")
    ap.add_argument("--list", action="store_true", help="print the sites per file and the sample, run nothing")
    ap.add_argument("--only", nargs="*", default=None, help="run only these mutant ids (from an earlier report)")
    args = ap.parse_args(argv)

    all_sites = {name: sites(HDL_DIR / name) for name in HDL_FILES}
    chosen = sample(all_sites, args.sample, args.seed)
    if args.only is not None:
        wanted = set(args.only)
        chosen = [m for sites_ in all_sites.values() for m in sites_ if m.ident in wanted]
    print(f"mutate: seed {args.seed}, {len(chosen)} mutants of {sum(len(s) for s in all_sites.values())} sites")
    for name, found in all_sites.items():
        kinds = {k: sum(1 for m in found if m.kind == k) for k in ("rel", "logic", "arith", "bit")}
        picked = sum(1 for m in chosen if m.file == name)
        print(f"  {name:26} {len(found):4} sites {kinds}  sampled {picked}")
    if args.list:
        for m in chosen:
            print(f"  {m.ident:32} {m.describe()}")
        return 0

    OUT.mkdir(parents=True, exist_ok=True)
    outcomes: list[Outcome] = []
    t0 = time.monotonic()
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_one, m, i, args.timeout) for i, m in enumerate(chosen)]
        for n, future in enumerate(futures, start=1):
            out = future.result()
            outcomes.append(out)
            print(f"  [{n:3}/{len(chosen)}] {out.status:8} {out.seconds:6.1f} s  {out.mutant.describe()}  {out.by}")
            sys.stdout.flush()
    killed = sum(o.status == "killed" for o in outcomes)
    valid = sum(o.status in ("killed", "survived") for o in outcomes)
    equivalent = [o for o in outcomes if o.status == "equivalent"]
    survivors = [o for o in outcomes if o.status == "survived"]
    score = 100.0 * killed / valid if valid else 0.0
    print(f"mutate: killed {killed} / valid {valid} / total {len(outcomes)}: {score:.1f} % killed")
    print(f"mutate: wall time {time.monotonic() - t0:.0f} s with {args.jobs} jobs")
    for o in equivalent:
        print(f"  equivalent {o.mutant.ident}: {o.mutant.describe()}: {o.by}")
    for o in survivors:
        print(f"  survivor {o.mutant.ident}: {o.mutant.describe()}")
    report = {
        "seed": args.seed,
        "sample": args.sample,
        "killed": killed,
        "valid": valid,
        "total": len(outcomes),
        "equivalent": len(equivalent),
        "score_percent": round(score, 1),
        "outcomes": [
            {**asdict(o.mutant), "id": o.mutant.ident, **{k: getattr(o, k) for k in ("status", "by")}} for o in outcomes
        ],
    }
    (OUT / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
