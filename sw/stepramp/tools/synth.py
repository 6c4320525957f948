# SPDX-License-Identifier: MIT
"""Synthesis report: size and speed of the tops with open tools (`make synth`).

For each top: `ghdl synth` to Verilog, then yosys `synth_ice40` (iCE40 LUT4 / FF / carry counts), nextpnr-ice40
for HX8K and UP5K (maximum clock frequency; a top's HX8K figure is the median of nextpnr seeds 1, 2 and 3, each
listed as "fmax_seeds"), and yosys `synth_xilinx -family xc7` (LUT / FF counts; no Xilinx timing here). Every
entity is reported too, as the top instantiates it (its generics): yosys `synth_ice40 -noflatten` on the top's
netlist gives each module's cells, counted with the entities below it, and nextpnr-ice40 (seed 1) gives the fmax
of each entity that has a clock (wrapped like the top, see pnr_wrapper). Writes
build/synth/report.json as
    {"<top>": {"ice40_hx8k": {"lut4", "ff", "carry", "fmax_mhz", "fmax_seeds"}, "ice40_up5k": {...}, "xc7": {...},
               "entities": {"<entity>": {"lut4", "ff", "carry", "fmax_mhz"}}}}
and build/synth/report.md.

    python -m stepramp.tools.synth [--out DIR] [--no-pnr] [--record] [--docs] [TOP ...]

Both single-axis tops are reported in the exact ramp mode too (`stepramp_plb@exact`, `stepramp_axil@exact`: G_RAMP = 1).
The multi-axis top is reported at 1, 2 and 4 axes: `stepramp_multi_plb@N` is stepramp_multi_plb with G_AXES = N
(VARIANTS; each in a folder of its own under --out, no per-entity fmax), and the markdown ends with the cost of one
more axis, read off between the smallest and the largest count.

--record writes the iCE40 LUT4 / FF counts per entity (synth_ice40 -noflatten, with the entities below it) to
scripts/synth_baseline.json, the figures the regression's size test (tb/test_synth_size.py) holds every entity of
the PLB-like top to (it fails above +10 %). --docs rewrites the entity rows of the pages in docs/ (each page's
Resources table) from the PLB-like top's figures.
"""

from __future__ import annotations

import argparse
import fcntl
import hashlib
import json
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from stepramp.sim.runner import HDL_DIR, HDL_FILES, SYNTH_TOPS
from stepramp.tools.rtlcheck import analyse, synth

#: The recorded size the regression holds the tops to.
BASELINE = Path(__file__).resolve().parents[3] / "scripts" / "synth_baseline.json"

#: The multi-axis top at these axis counts, so that the cost of one more axis reads off the report.
MULTI_AXES = (1, 2, 4)

#: Report names of a top at other generics than SYNTH_TOPS's: name -> (entity, generics). `@exact`: the exact ramp
#: (G_RAMP = 1, docs/algorithm.md "Exact step times") beside the default AVR446 recurrence.
VARIANTS: dict[str, tuple[str, dict[str, int]]] = {
    "stepramp_plb@exact": ("stepramp_plb", {"G_RAMP": 1}),
    "stepramp_axil@exact": ("stepramp_axil", {"G_RAMP": 1}),
    **{f"stepramp_multi_plb@{n}": ("stepramp_multi_plb", {"G_AXES": n}) for n in MULTI_AXES},
}

#: The tops of the report (the peripheral as users instantiate it, in both ramp modes), then the multi-axis variants.
REPORT_TOPS = ("stepramp_plb", "stepramp_axil", *VARIANTS)

#: The clock nextpnr is asked for: the goal (issue 12). nextpnr stops improving timing once a design meets its
#: target, so a lower target reports a lower "Max frequency" for the same netlist.
TARGET_MHZ = 75

#: nextpnr seeds of a top's HX8K fmax: the figure is their median, and each is listed. One seed moves by about
#: 3 MHz from netlist to netlist (placement), so one seed alone can say more about the seed than about the design.
TOP_SEEDS = (1, 2, 3)

#: nextpnr devices: name -> (nextpnr device flag, package).
ICE40_DEVICES = {"ice40_hx8k": ("--hx8k", "ct256"), "ice40_up5k": ("--up5k", "sg48")}


def _run(cmd: list[str], cwd: Path, log: Path) -> str:
    """Run a tool in cwd. yosys reads its Verilog by name, relative to cwd (the output folder): the name goes into
    every cell's `src` attribute, so that the netlist nextpnr places does not depend on where the repository is
    checked out."""
    res = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, check=False)
    log.write_text(res.stdout + res.stderr)
    if res.returncode != 0:
        raise RuntimeError(f"{cmd[0]} failed (see {log}):\n{res.stderr[-2000:]}")
    return res.stdout + res.stderr


def _cells(stat: str) -> dict[str, int]:
    """Cell counts from the last `stat` in a yosys log."""
    block = stat[stat.rfind("Number of cells:") :]
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"^\s+(\S+)\s+(\d+)\s*$", block, re.M)}


def netlist(top: str, out: Path, generics: dict[str, int] | None = None) -> Path:
    """ghdl synth of a top to Verilog in out/ (no latch: synth refuses them) at its SYNTH_TOPS generics, or at
    `generics`; returns the .v path."""
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        errors = analyse("08", work) or synth(top, SYNTH_TOPS.get(top, {}) if generics is None else generics, work, out)
    if errors:
        raise RuntimeError("\n".join(errors))
    return out / f"{top}.v"


def ice40_cells(top: str, verilog: Path, out: Path) -> tuple[dict[str, int], Path]:
    """yosys synth_ice40: (cell counts, netlist json). Fails on a latch."""
    json_path = out / f"{top}_ice40.json"
    log = _run(
        ["yosys", "-p", f"read_verilog {verilog.name}; synth_ice40 -top {top} -json {json_path}; stat"],
        out,
        out / f"{top}_ice40.yosys.log",
    )
    cells = _cells(log)
    if any("LATCH" in name.upper() for name in cells):
        raise RuntimeError(f"{top}: latch cells after synth_ice40: {cells}")
    return cells, json_path


def _modules(stat: str) -> dict[str, dict[str, int]]:
    """Cell counts of every module from a yosys `stat` of a hierarchical design (the "=== name ===" sections)."""
    found: dict[str, dict[str, int]] = {}
    for m in re.finditer(r"^=== (\S+) ===\s*$(.*?)(?=^=== |\Z)", stat, re.M | re.S):
        if m.group(1) != "design":
            found[m.group(1)] = _cells(m.group(2))
    return found


def entity_of(module: str) -> str:
    """The VHDL entity of a ghdl synth module name (GHDL appends the generic values: stepramp_divider_50)."""
    names = sorted((Path(f).stem for f in HDL_FILES), key=len, reverse=True)
    return next((n for n in names if module == n or module.startswith(n + "_")), module)


def entity_cells(top: str, verilog: Path, out: Path) -> dict[str, dict[str, int]]:
    """iCE40 cells of every entity under top (synth_ice40 -noflatten), each with the entities it instantiates."""
    stat_file = out / f"{top}_entities.stat.txt"
    _run(
        ["yosys", "-p", f"read_verilog {verilog.name}; synth_ice40 -noflatten -top {top}; tee -o {stat_file} stat"],
        out,
        out / f"{top}_entities.yosys.log",
    )
    own = _modules(stat_file.read_text())

    def total(module: str) -> dict[str, int]:
        cells: dict[str, int] = {}
        for name, n in own[module].items():
            for cell, count in total(name).items() if name in own else [(name, 1)]:
                cells[cell] = cells.get(cell, 0) + n * count
        return cells

    result = {entity_of(m): total(m) for m in own}
    if any("LATCH" in name.upper() for cells in result.values() for name in cells):
        raise RuntimeError(f"{top}: latch cells after synth_ice40 -noflatten")
    return result


def entity_cells_cached(top: str, folder: Path) -> dict[str, dict[str, int]]:
    """entity_cells of top's ghdl synth netlist, once per content: kept in folder under a key of the RTL's and this
    module's contents and the yosys version, computed under a file lock (so that the size check's tests, whichever
    xdist worker runs them, and `make test`'s prefetch during the bootstrap share one yosys run). Raises on a latch
    (nothing is kept then)."""
    digest = hashlib.sha256()
    for path in (*(HDL_DIR / name for name in HDL_FILES), Path(__file__)):
        digest.update(path.read_bytes())
    digest.update(subprocess.run(["yosys", "-V"], capture_output=True, text=True, check=False).stdout.encode())
    folder.mkdir(parents=True, exist_ok=True)
    cache = folder / f"{top}-{digest.hexdigest()[:20]}.json"
    with (folder / "lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if cache.exists():
            cells: dict[str, dict[str, int]] = json.loads(cache.read_text())
            return cells
        out = Path(tempfile.mkdtemp(prefix="synth_size_"))
        cells = entity_cells(top, netlist(top, out), out)
        cache.write_text(json.dumps(cells))
        return cells


def ice40_summary(cells: dict[str, int]) -> dict[str, int]:
    return {
        "lut4": cells.get("SB_LUT4", 0),
        "ff": sum(n for name, n in cells.items() if name.startswith("SB_DFF")),
        "carry": cells.get("SB_CARRY", 0),
        # 4 kbit block RAMs (the register file's read-back copy)
        "ebr": sum(n for name, n in cells.items() if name.startswith("SB_RAM40")),
    }


#: LUT sites of the xc7 distributed-RAM cells (a RAM32M is four LUT6 in a SLICEM, and so on).
XC7_LUTRAM_SITES = {"RAM32M": 4, "RAM64M": 4, "RAM32X1D": 2, "RAM64X1D": 2, "RAM32X1S": 1, "RAM64X1S": 1}


_PORT = re.compile(r"(input|output)\s+(?:\[(\d+):(\d+)\]\s+)?(\w+)")


def pnr_wrapper(top: str, verilog: Path, clock: str) -> str:
    """A Verilog wrapper with three pins for place and route: the clock, a serial input, a serial output.

    The IP's bus has ~110 ports, more than an UP5K package has pins, and an IP core's ports are not pins anyway.
    Every input comes from a shift register fed by one pin; every output is registered and XOR-reduced to one pin,
    so no logic is optimised away and every path of the core is timed between flip-flops. The wrapper adds about
    one flip-flop per port; the area figures come from the core alone.
    """
    text = verilog.read_text()
    header = re.search(rf"module {top}\s*\((.*?)\);", text, re.S)
    if header is None:
        raise RuntimeError(f"module {top} not found in {verilog}")
    ins: list[tuple[str, int]] = []
    outs: list[tuple[str, int]] = []
    for kind, msb, lsb, name in _PORT.findall(header.group(1)):
        width = int(msb) - int(lsb) + 1 if msb else 1
        if name != clock:
            (ins if kind == "input" else outs).append((name, width))
    n_in = sum(w for _, w in ins)
    n_out = sum(w for _, w in outs)
    lines = [
        f"module {top}_pnr (input {clock}, input sdi, output sdo);",
        f"  reg [{n_in - 1}:0] sh;",
        f"  always @(posedge {clock}) sh <= {{sh[{n_in - 2}:0], sdi}};",
        f"  wire [{n_out - 1}:0] o;",
        f"  reg [{n_out - 1}:0] oq;",
        f"  always @(posedge {clock}) oq <= o;",
        "  assign sdo = ^oq;",
    ]
    conns = [f".{clock}({clock})"]
    pos = 0
    for name, width in ins:
        conns.append(f".{name}(sh[{pos + width - 1}:{pos}])")
        pos += width
    pos = 0
    for name, width in outs:
        conns.append(f".{name}(o[{pos + width - 1}:{pos}])")
        pos += width
    lines.append(f"  {top} core ({', '.join(conns)});")
    lines.append("endmodule")
    return "\n".join(lines) + "\n"


_ENTITY_FMAX: dict[str, float | None] = {}
"""fmax per module name (entity and generics) once measured: the second top has the same entities."""


def entity_fmax(module: str, verilog: Path, out: Path) -> float | None:
    """HX8K fmax of one module of a netlist, wrapped like a top; None when it has no clock (combinational)."""
    if module in _ENTITY_FMAX:
        return _ENTITY_FMAX[module]
    _ENTITY_FMAX[module] = _entity_fmax(module, verilog, out)
    return _ENTITY_FMAX[module]


def _entity_fmax(module: str, verilog: Path, out: Path) -> float | None:
    text = verilog.read_text()
    header = re.search(rf"module {module}\s*\((.*?)\);", text, re.S)
    if header is None or not re.search(r"input\s+clk\b", header.group(1)):
        return None
    wrapper = out / f"{module}_pnr.v"
    wrapper.write_text(pnr_wrapper(module, verilog, "clk"))
    wrapped = out / f"{module}_pnr_ice40.json"
    _run(
        ["yosys", "-p", f"read_verilog {verilog.name} {wrapper.name}; synth_ice40 -top {module}_pnr -json {wrapped}"],
        out,
        out / f"{module}_pnr.yosys.log",
    )
    return fmax(module, wrapped, "ice40_hx8k", out)


def fmax(top: str, json_path: Path, device: str, out: Path, seed: int = 1) -> float:
    flag, package = ICE40_DEVICES[device]
    log_name = f"{top}_{device}.nextpnr.log" if seed == 1 else f"{top}_{device}_seed{seed}.nextpnr.log"
    log = _run(
        [
            "nextpnr-ice40",
            flag,
            "--package",
            package,
            "--json",
            str(json_path),
            "--freq",
            str(TARGET_MHZ),
            "--seed",
            str(seed),
            "--timing-allow-fail",
        ],
        out,
        out / log_name,
    )
    found = re.findall(r"Max frequency for clock\s+'[^']*':\s+([\d.]+) MHz", log)
    if not found:
        raise RuntimeError(f"no Max frequency line in {out / log_name}")
    return float(found[-1])


def fmax_seeds(top: str, json_path: Path, device: str, out: Path) -> dict[int, float]:
    """fmax for each of TOP_SEEDS, the place-and-route runs side by side (nextpnr uses one core each)."""
    with ThreadPoolExecutor(max_workers=len(TOP_SEEDS)) as pool:
        runs = {seed: pool.submit(fmax, top, json_path, device, out, seed) for seed in TOP_SEEDS}
        return {seed: run.result() for seed, run in runs.items()}


def xc7(top: str, verilog: Path, out: Path) -> dict[str, int]:
    log = _run(
        ["yosys", "-p", f"read_verilog {verilog.name}; synth_xilinx -family xc7 -top {top}; stat"],
        out,
        out / f"{top}_xc7.yosys.log",
    )
    cells = _cells(log)
    return {
        "lut": sum(n for name, n in cells.items() if re.fullmatch(r"LUT\d", name)),
        "ff": sum(n for name, n in cells.items() if re.fullmatch(r"FD[A-Z]*", name)),
        # LUTs used as memory (not in "lut"; Vivado's "Slice LUTs" counts both)
        "lutram": sum(XC7_LUTRAM_SITES.get(name, 0) * n for name, n in cells.items()),
    }


def report_top(
    top: str, out: Path, pnr: bool = True, generics: dict[str, int] | None = None, entity_pnr: bool = True
) -> dict[str, Any]:
    """One top's entry of the report (at `generics`, else its SYNTH_TOPS generics); entity_pnr: the HX8K fmax of each
    entity too."""
    verilog = netlist(top, out, generics)
    cells, _ = ice40_cells(top, verilog, out)
    entry: dict[str, Any] = {}
    wrapped: Path | None = None
    if pnr:
        clock = "aclk" if re.search(rf"module {top}\s*\(\s*input\s+aclk", verilog.read_text()) else "clk"
        wrapper = out / f"{top}_pnr.v"
        wrapper.write_text(pnr_wrapper(top, verilog, clock))
        wrapped = out / f"{top}_pnr_ice40.json"
        _run(
            ["yosys", "-p", f"read_verilog {verilog.name} {wrapper.name}; synth_ice40 -top {top}_pnr -json {wrapped}"],
            out,
            out / f"{top}_pnr.yosys.log",
        )
    for device in ICE40_DEVICES:
        entry[device] = dict(ice40_summary(cells))
        if wrapped is not None:
            try:
                if device == "ice40_hx8k":
                    seeds = fmax_seeds(top, wrapped, device, out)
                    entry[device]["fmax_mhz"] = statistics.median(seeds.values())
                    entry[device]["fmax_seeds"] = {str(k): v for k, v in seeds.items()}
                else:
                    entry[device]["fmax_mhz"] = fmax(top, wrapped, device, out)
            except RuntimeError as exc:  # e.g. more logic cells than the device has: no fmax, said so
                entry[device]["fmax_mhz"] = None
                entry[device]["pnr_error"] = str(exc).splitlines()[-1][:200]
    entry["xc7"] = xc7(top, verilog, out)
    entities = entity_cells(top, verilog, out)
    modules = {entity_of(m): m for m in re.findall(r"^module (\w+)", verilog.read_text(), re.M)}
    entry["entities"] = {}
    for name, cells in sorted(entities.items(), key=lambda kv: -kv[1].get("SB_LUT4", 0)):
        row: dict[str, Any] = dict(ice40_summary(cells))
        if pnr and entity_pnr and name != top:
            try:
                row["fmax_mhz"] = entity_fmax(modules[name], verilog, out)
            except RuntimeError as exc:
                row["fmax_mhz"] = None
                row["pnr_error"] = str(exc).splitlines()[-1][:200]
        entry["entities"][name] = row
    return entry


def report_entry(name: str, out: Path, pnr: bool = True) -> dict[str, Any]:
    """A report top (REPORT_TOPS) by its name: a variant (VARIANTS) in out/<name with @ as _x>, without the
    entities' fmax (they are the single-axis top's), or a top of SYNTH_TOPS in out."""
    if name in VARIANTS:
        top, generics = VARIANTS[name]
        folder = out / name.replace("@", "_x")
        folder.mkdir(parents=True, exist_ok=True)
        return report_top(top, folder, pnr=pnr, generics=generics, entity_pnr=False)
    return report_top(name, out, pnr=pnr)


def axis_cost(report: dict[str, Any]) -> dict[str, float] | None:
    """iCE40 LUT4 and FF (flattened, HX8K figures) of one more axis of the multi-axis top: the difference between
    the largest and the smallest axis count of the report, per axis; None with fewer than two counts."""
    counts = sorted(n for n in MULTI_AXES if f"stepramp_multi_plb@{n}" in report)
    if len(counts) < 2:
        return None
    low, high = (report[f"stepramp_multi_plb@{n}"]["ice40_hx8k"] for n in (counts[0], counts[-1]))
    span = counts[-1] - counts[0]
    return {key: (high[key] - low[key]) / span for key in ("lut4", "ff", "carry")}


def _fmax(entry: dict[str, Any]) -> str:
    if "pnr_error" in entry:
        return "does not place"
    seeds = entry.get("fmax_seeds")
    if seeds:
        listed = ", ".join(f"{v}" for v in seeds.values())
        return f"{entry['fmax_mhz']} (median of seeds {', '.join(seeds)}: {listed})"
    return str(entry.get("fmax_mhz", "-"))


def markdown(report: dict[str, Any]) -> str:
    lines = [
        "| top | iCE40 HX8K LUT4 | FF | carry | EBR | HX8K fmax (MHz) | UP5K fmax (MHz) | xc7 LUT | xc7 LUTRAM | "
        "xc7 FF |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for top, e in report.items():
        hx, up, x = e["ice40_hx8k"], e["ice40_up5k"], e["xc7"]
        lines.append(
            f"| {top} | {hx['lut4']} | {hx['ff']} | {hx['carry']} | {hx.get('ebr', 0)} | {_fmax(hx)} | {_fmax(up)} | "
            f"{x['lut']} | {x.get('lutram', 0)} | {x['ff']} |"
        )
    cost = axis_cost(report)
    if cost is not None:
        lines += [
            "",
            f"One more axis of stepramp_multi_plb (iCE40, flattened): {cost['lut4']:.0f} LUT4, {cost['ff']:.0f} FF, "
            f"{cost['carry']:.0f} carry.",
        ]
    for top, e in report.items():
        lines += [
            "",
            f"Entities of {top} (iCE40, synth_ice40 -noflatten, each with the entities it instantiates; fmax on HX8K):",
            "",
            "| entity | LUT4 | FF | carry | fmax (MHz) |",
            "|---|---|---|---|---|",
        ]
        for name, row in e.get("entities", {}).items():
            f = "-" if row.get("fmax_mhz") is None else str(row["fmax_mhz"])
            lines.append(f"| {name} | {row['lut4']} | {row['ff']} | {row['carry']} | {f} |")
    return "\n".join(lines) + "\n"


#: An entity's row on its page: | `stepramp_x` | LUT4 | FF | carry | fmax |
_DOC_ROW = re.compile(r"^\| `(stepramp_\w+)` \| [\d,]+ \| [\d,]+ \| [\d,]+ \| [^|]+ \|$", re.M)

#: The pages whose entity rows --docs rewrites.
DOC_PAGES = Path(__file__).resolve().parents[3] / "docs"


def _thousands(n: int) -> str:
    return f"{n:,}"


def update_docs(report: dict[str, Any], top: str = "stepramp_plb", pages: Path = DOC_PAGES) -> list[Path]:
    """Rewrite every entity row of the docs pages (`| stepramp_x | LUT4 | FF | carry | fmax |`, the name in
    backquotes) with the figures of `top` in report (an entity only another top has, such as that top itself, from
    that top); returns the pages changed. Entities missing from the report keep their row."""
    entities = {name: e for other in report.values() for name, e in other.get("entities", {}).items()}
    entities.update(report[top]["entities"])  # the PLB-like top's figures first; the other tops add their own

    def row(m: re.Match[str]) -> str:
        e = entities.get(m.group(1))
        if e is None:
            return m.group(0)
        f = "-" if e.get("fmax_mhz") is None else f"{e['fmax_mhz']:.2f}"
        return f"| `{m.group(1)}` | {_thousands(e['lut4'])} | {_thousands(e['ff'])} | {_thousands(e['carry'])} | {f} |"

    changed = []
    for page in sorted(pages.glob("*.md")):
        text = page.read_text()
        new = _DOC_ROW.sub(row, text)
        if new != text:
            page.write_text(new)
            changed.append(page)
    return changed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=Path("build/synth"))
    parser.add_argument("--no-pnr", action="store_true", help="skip nextpnr (no fmax)")
    parser.add_argument("--record", action="store_true", help=f"record the iCE40 sizes in {BASELINE.name}")
    parser.add_argument("--docs", action="store_true", help="rewrite the entity rows of docs/*.md from the report")
    parser.add_argument(
        "--size-cache",
        type=Path,
        default=None,
        help="only the per-entity iCE40 cells of each top into this cache folder (tb/test_synth_size.py's), then stop",
    )
    parser.add_argument("tops", nargs="*", default=list(REPORT_TOPS))
    args = parser.parse_args(argv)
    if args.size_cache is not None:
        for top in args.tops:
            entity_cells_cached(top, args.size_cache.resolve())
        return 0
    missing = [t for t in ("yosys", *(() if args.no_pnr else ("nextpnr-ice40",))) if shutil.which(t) is None]
    if missing:
        print(f"synth: {', '.join(missing)} not found (Debian: apt-get install yosys nextpnr-ice40)", file=sys.stderr)
        return 1
    out: Path = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    report = {top: report_entry(top, out, pnr=not args.no_pnr) for top in args.tops}
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
    (out / "report.md").write_text(markdown(report))
    if args.record:
        sizes = {
            top: {name: {k: row[k] for k in ("lut4", "ff")} for name, row in e["entities"].items()}
            for top, e in report.items()
        }
        BASELINE.write_text(json.dumps(sizes, indent=2) + "\n")
        print(f"recorded: {BASELINE}")
    if args.docs and "stepramp_plb" in report:
        for page in update_docs(report):
            print(f"updated: {page}")
    print(markdown(report), end="")
    print(f"written: {out / 'report.json'}, {out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
