# SPDX-License-Identifier: MIT
"""scripts/ipxact_registers.tcl (what scripts/package_vivado.tcl reads the IP-XACT with) gives the register map's
registers and fields, run in tclsh on rdl/stepramp.xml. Vivado itself is not available here (docs/integration.md)."""

from __future__ import annotations

import shutil
import subprocess

from stepramp.board import regmap
from stepramp.tools import regmap_gen

SCRIPT = regmap_gen.REPO / "scripts" / "ipxact_registers.tcl"
ACCESS = {regmap.RO: "read-only", regmap.RW: "read-write", regmap.W1C: "read-write", regmap.WS: "write-only"}


def test_tcl_reads_every_register_and_field() -> None:
    tclsh = shutil.which("tclsh")
    assert tclsh is not None, "tclsh is missing: scripts/bootstrap.sh installs Debian's tcl (make test runs it)"
    script = (
        f"source {SCRIPT}\n"
        f"foreach r [stepramp_ipxact_registers {regmap_gen.IPXACT}] {{\n"
        "  lassign $r n o d fs\n"
        '  foreach f $fs { lassign $f fn lsb w a rst fd; puts "$n $o $fn $lsb $w $a $rst" }\n'
        "}\n"
    )
    out = subprocess.run([tclsh], input=script, capture_output=True, text=True, check=True).stdout.split("\n")
    got = [tuple(line.split()) for line in out if line]
    want = [
        (r.name, str(r.offset), f.name, str(f.lsb), str(f.width), ACCESS[f.access], str(f.reset))
        for r in regmap.REGISTERS
        for f in r.fields
    ]
    assert got == want
