# SPDX-License-Identifier: MIT
"""GTKWave save files (.gtkw) that lay out a waveform of stepramp_plb, stepramp_axil or stepramp_engine for a reader.

Groups, top to bottom: the bus (or the engine's move inputs), the ramp FSM (state by name, busy, done, error), the
current delay (as a number and as an analog trace, which draws the ramp), the step counter and the position,
STEP/DIR/ENABLE, and the windings. `LAYOUTS` names each signal by its path below the top and its width; every engine
and bus simulation checks that each of them exists with that width (`missing_in`), so a layout cannot silently drift
from the RTL.

GTKWave reads GHDL's GHW with one facility per bit (`top.<top>.<path>[i]`), so vectors are written as GTKWave's
concatenations `#{name} bit bit ...`, which every GTKWave 3.x loads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stepramp.board.regmap import ADDR_BITS

# GTKWave trace flags (gtkwave's analyzer.h).
_HEX, _DEC, _BIN, _RJUSTIFY, _SIGNED = 0x2, 0x4, 0x8, 0x20, 0x400
_ANALOG_STEP, _ANALOG_BLANK_STRETCH = 0x8000, 0x20000
_GRP_BEGIN, _GRP_END, _BLANK = 0x800000, 0x1000000, 0x200

FORMATS = {
    "bit": _BIN | _RJUSTIFY,
    "hex": _HEX | _RJUSTIFY,
    "dec": _DEC | _RJUSTIFY,
    "signed": _SIGNED | _DEC | _RJUSTIFY,
    "analog": _ANALOG_STEP | _DEC | _RJUSTIFY,
    "text": _BIN | _RJUSTIFY,  # an enumeration: GTKWave shows the GHW literal
}


@dataclass(frozen=True)
class Trace:
    path: str  # below the top entity, dotted through instance labels
    width: int = 1  # 1 for std_logic and for enumerations
    fmt: str = "bit"
    label: str | None = None  # the name shown for a vector (default: its path)
    rows: int = 0  # extra height for an analog trace


Layout = list[tuple[str, list[Trace]]]


def _engine_groups(prefix: str) -> Layout:
    """The ramp engine's groups; prefix: the engine's path below the top ("" for the engine itself)."""
    return [
        (
            "Ramp FSM",
            [
                Trace(prefix + "state_name", 1, "text", "state"),
                Trace(prefix + "busy"),
                Trace(prefix + "done"),
                Trace(prefix + "error"),
                Trace(prefix + "err_code", 5, "dec", "err_code"),
            ],
        ),
        (
            "Current delay (ticks between steps)",
            [
                Trace(prefix + "cur_delay", 32, "dec", "cur_delay"),
                Trace(prefix + "cur_delay", 32, "analog", "cur_delay (analog)", rows=6),
            ],
        ),
        (
            "Step counter and position",
            [
                Trace(prefix + "step_count", 31, "dec", "step_count"),
                Trace(prefix + "position", 32, "signed", "position"),
            ],
        ),
    ]


_PINS: Layout = [
    ("STEP / DIR outputs", [Trace("step"), Trace("dir"), Trace("enable")]),
    ("Windings (H-bridge inputs)", [Trace("a1"), Trace("a2"), Trace("b1"), Trace("b2")]),
]


def _axil_channel(name: str, *payload: tuple[str, int, str]) -> list[Trace]:
    return [
        Trace(f"s_axil_{name}valid"),
        Trace(f"s_axil_{name}ready"),
        *(Trace(f"s_axil_{field}", width, fmt) for field, width, fmt in payload),
    ]


#: A layout per top: the bus, the engine (FSM state by name, delay, counters) and the pins.
LAYOUTS: dict[str, Layout] = {
    "stepramp_plb": [
        (
            "Bus: PLB IPIF (the soft CPU's accesses)",
            [
                Trace("clk"),
                Trace("rst"),
                Trace("bus2ip_cs"),
                Trace("bus2ip_rnw"),
                Trace("bus2ip_addr", 32, "hex"),
                Trace("bus2ip_be", 4, "bit"),
                Trace("bus2ip_data", 32, "hex"),
                Trace("ip2bus_wrack"),
                Trace("ip2bus_rdack"),
                Trace("ip2bus_data", 32, "hex"),
                Trace("ip2bus_error"),
                Trace("irq"),
            ],
        ),
        *_engine_groups("core_inst.engine_inst."),
        *_PINS,
    ],
    "stepramp_axil": [
        (
            "Bus: AXI4-Lite (the soft CPU's accesses)",
            [
                Trace("aclk"),
                Trace("aresetn"),
                # each channel: valid, ready, then its payload
                *_axil_channel("aw", ("awaddr", ADDR_BITS, "hex")),
                *_axil_channel("w", ("wdata", 32, "hex"), ("wstrb", 4, "bit")),
                *_axil_channel("b", ("bresp", 2, "bit")),
                *_axil_channel("ar", ("araddr", ADDR_BITS, "hex")),
                *_axil_channel("r", ("rdata", 32, "hex"), ("rresp", 2, "bit")),
                Trace("irq"),
            ],
        ),
        *_engine_groups("core_inst.engine_inst."),
        *_PINS,
    ],
    "stepramp_engine": [
        (
            "Move inputs",
            [
                Trace("clk"),
                Trace("rst"),
                Trace("start"),
                Trace("soft_stop"),
                Trace("hard_stop"),
                Trace("steps", 31, "dec", "steps"),
                Trace("direction"),
                Trace("prescale", 16, "dec", "prescale"),
            ],
        ),
        *_engine_groups(""),
        ("STEP / DIR", [Trace("step"), Trace("dir")]),
    ],
}

#: The layout of the demo and shell waveforms (stepramp_plb).
LAYOUT: Layout = LAYOUTS["stepramp_plb"]


def signal_paths(layout: Layout = LAYOUT) -> list[tuple[str, int]]:
    """Every (path, width) the layout uses, once each."""
    seen: dict[str, int] = {}
    for _, traces in layout:
        for t in traces:
            seen.setdefault(t.path, t.width)
    return list(seen.items())


def missing_in(dut: Any, paths: list[tuple[str, int]] | list[list[Any]]) -> list[str]:
    """Inside a simulation: which of these (path, width) signals the design below `dut` does not have (a vector:
    or not with that width)."""
    out = []
    for path, width in paths:
        handle = dut
        try:
            for part in path.split("."):
                handle = getattr(handle, part)
        except AttributeError:
            out.append(path)
            continue
        if width > 1 and len(handle) != width:
            out.append(f"{path} (width {len(handle)}, not {width})")
    return out


def zoom_for(duration_s: float) -> float:
    """GTKWave's zoom that shows duration_s across the wave pane of a [size] 1500 1000 window.

    The visible span is 2^-zoom times a constant; measured with GTKWave 3.3.118 on a GHW file (femtoseconds):
    Zoom Full on a 795 ms dump gives -47.42, so the constant is 4.2 fs.
    """
    return -math.log2(max(duration_s * 1e15 / 4.2, 1.0))


def write_gtkw(
    path: Path,
    dumpfile: Path,
    top: str = "stepramp_plb",
    duration_s: float | None = None,
    marker_s: float | None = None,
    title: str = "stepramp",
    layout: Layout | None = None,
) -> Path:
    """Write the save file; `gtkwave SAVEFILE` opens the laid-out view.

    duration_s: the span to show (default: GTKWave's own zoom); marker_s: where to put the marker (its values show
    beside the names).
    """
    lines = [
        "[*]",
        f"[*] {title}",
        "[*] written by stepramp.sim.waves: open with  gtkwave " + path.name,
        "[*]",
        f'[dumpfile] "{dumpfile.resolve()}"',
        f'[savefile] "{path.resolve()}"',
        "[timestart] 0",
        "[size] 1500 1000",
        "[pos] -1 -1",
    ]
    if duration_s is not None:
        marker = round((marker_s or 0.0) * 1e15)
        lines.append(f"*{zoom_for(duration_s):.6f} {marker} " + " ".join(["-1"] * 26))
    lines += ["[sst_width] 180", "[signals_width] 330", "[sst_expanded] 1", "[sst_vpaned_height] 250"]
    for group, traces in layout if layout is not None else LAYOUTS[top]:
        lines += [f"@{_GRP_BEGIN | _BLANK:x}", f"-{group}"]
        for t in traces:
            lines.append(f"@{FORMATS[t.fmt]:x}")
            name = f"top.{top}.{t.path}"
            if t.width == 1:
                lines.append(f"+{{{t.label}}} {name}" if t.label else name)
            else:
                bits = " ".join(f"{name}[{i}]" for i in reversed(range(t.width)))
                lines.append(f"#{{{t.label or t.path}}} {bits}")
            if t.rows:
                lines.append(f"@{_ANALOG_BLANK_STRETCH:x}")
                lines += ["-"] * t.rows
        lines += [f"@{_GRP_END | _BLANK:x}", f"-{group}"]
    path.write_text("\n".join(lines) + "\n")
    return path
