# SPDX-License-Identifier: MIT
"""The Vitis driver folder of the IP (drivers/stepramp_v1_0, completed with sw/c/src by stepramp.tools.vitis_driver
and by scripts/package_vivado.tcl), read the way a Vitis classic / SDK standalone BSP reads it:

- data/stepramp.mdd: its OPTION key = value lines (psf_version, the driver block's supported_peripherals, which
  must name the packaged IP, copyfiles, driver_state, VERSION matching the folder's _v1_0, NAME);
- data/stepramp.tcl: its `generate` proc run in tclsh with stand-ins of HSI's ::hsi::utils::define_include_file /
  define_canonical_xpars (and the older xdefine_include_file / xdefine_canonical_xpars) that write xparameters.h
  as HSI does for two stepramp_axil instances whose only address parameters are C_BASEADDR / C_HIGHADDR;
- src/: the BSP's `make include` and `make libs` with COMPILER=gcc ARCHIVER=ar (COMPILER_FLAGS with -c, as a
  BSP passes them) in a BSP-like tree, against that xparameters.h and a xil_io.h declaring the three accessors, then
  an application linked with the BSP's libxil.a that finds the core at XPAR_STEPRAMP_0_BASEADDR;
- scripts/package_vivado.tcl run in tclsh with every Vivado command stubbed: it puts the same folder in the IP and
  adds each of its files to the xilinx_softwaredriver file group.

Vitis itself is not installed here: the HSI stand-ins follow xillib_sw.tcl's naming (XPAR_<DRIVER>_NUM_INSTANCES,
XPAR_<INSTANCE>_<PARAM without C_>, XPAR_<DRIVER>_<n>_<PARAM>).
"""

from __future__ import annotations

import filecmp
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from stepramp.board import regmap
from stepramp.tools import vitis_driver

REPO = vitis_driver.REPO
DRIVER = vitis_driver.TEMPLATE.name  # stepramp_v1_0
IP_NAME = "stepramp_axil"
#: (instance, base, high) of the hardware design the HSI stand-ins describe: two cores of 4 KiB.
INSTANCES = [("stepramp_axil_0", 0x44A0_0000, 0x44A0_0FFF), ("stepramp_axil_1", 0x44A1_0000, 0x44A1_0FFF)]

HSI_STANDINS = r"""
namespace eval ::hsi::utils {}
set ::calls {}
proc xpar_name {s} { return [string toupper [regsub {^C_} $s {}]] }
proc xpar_value {inst arg id} {
  if {$arg eq "DEVICE_ID"} { return $id }
  if {![dict exists $inst CONFIG.$arg]} { error "stepramp_axil has no parameter $arg" }
  return [dict get $inst CONFIG.$arg]
}
proc ::hsi::utils::define_include_file {drv_handle file_name drv_string args} {
  lappend ::calls [list define_include_file $file_name $drv_string {*}$args]
  set fh [open [file join $::include_dir $file_name] a]
  if {"NUM_INSTANCES" in $args} {
    puts $fh "#define XPAR_[string toupper $drv_string]_NUM_INSTANCES [llength $::instances]"
  }
  set id 0
  foreach inst $::instances {
    foreach arg $args {
      if {$arg eq "NUM_INSTANCES"} continue
      puts $fh "#define XPAR_[string toupper [dict get $inst NAME]]_[xpar_name $arg] [xpar_value $inst $arg $id]"
    }
    incr id
  }
  close $fh
}
proc ::hsi::utils::define_canonical_xpars {drv_handle file_name drv_string args} {
  lappend ::calls [list define_canonical_xpars $file_name $drv_string {*}$args]
  set fh [open [file join $::include_dir $file_name] a]
  set id 0
  foreach inst $::instances {
    foreach arg $args {
      puts $fh "#define XPAR_[string toupper $drv_string]_${id}_[xpar_name $arg] [xpar_value $inst $arg $id]"
    }
    incr id
  }
  close $fh
}
proc xdefine_include_file {args} { ::hsi::utils::define_include_file {*}$args }
proc xdefine_canonical_xpars {args} { ::hsi::utils::define_canonical_xpars {*}$args }
"""

XIL_IO_H = """/* stand-in of the BSP's xil_io.h: the three accessors the driver uses */
#ifndef XIL_IO_H
#define XIL_IO_H
#include <stdint.h>
uint32_t Xil_In32(uintptr_t addr);
void Xil_Out32(uintptr_t addr, uint32_t value);
void Xil_Out8(uintptr_t addr, uint8_t value);
#endif
"""

APP_C = """#include <stdio.h>
#include "xparameters.h"
#include "stepramp.h"
/* the application's bus: the ID register of the core at XPAR_STEPRAMP_0_BASEADDR, everything else reads 0 */
static unsigned reads, writes;
uint32_t Xil_In32(uintptr_t addr)
{
    reads++;
    return addr == XPAR_STEPRAMP_0_BASEADDR + STEPRAMP_REG_ID ? STEPRAMP_ID_VALUE : 0u;
}
void Xil_Out32(uintptr_t addr, uint32_t value) { (void)addr; (void)value; writes++; }
void Xil_Out8(uintptr_t addr, uint8_t value) { (void)addr; (void)value; writes++; }
int main(void)
{
    stepramp_t motor;
    stepramp_plan_t plan;
    int rc = stepramp_init(&motor, XPAR_STEPRAMP_0_BASEADDR, 50e6, 400.0 * 16, 50);
    int rc_plan = stepramp_plan(&motor, &plan, 6400, 8000.0, 8000.0, 3200.0);
    int rc_move = stepramp_move(&motor, 6400, 8000.0, 8000.0, 3200.0);
    printf("%d %d %d %d %u %u %lu\\n", XPAR_STEPRAMP_NUM_INSTANCES, rc, rc_plan, rc_move, reads, writes,
           (unsigned long)(XPAR_STEPRAMP_0_HIGHADDR - XPAR_STEPRAMP_0_BASEADDR + 1u));
    return 0;
}
"""


def _tclsh() -> str:
    tclsh = shutil.which("tclsh")
    assert tclsh is not None, "tclsh is missing: scripts/bootstrap.sh installs Debian's tcl (make test runs it)"
    return tclsh


def _run(cmd: list[str], **kw: object) -> subprocess.CompletedProcess[str]:
    result = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=300, **kw)  # type: ignore[call-overload]
    assert result.returncode == 0, f"{' '.join(cmd)}:\n{result.stdout}\n{result.stderr}"
    return result


def parse_mdd(text: str) -> dict[str, dict[str, str]]:
    """The OPTION key = value; lines of an .mdd, by block: '' for the file's top level, the driver's name for its
    BEGIN driver .. END driver block (keys lower-cased, as the tools compare them)."""
    blocks: dict[str, dict[str, str]] = {"": {}}
    block = ""
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if m := re.fullmatch(r"BEGIN\s+driver\s+(\w+)", line, flags=re.I):
            block = m.group(1)
            blocks[block] = {}
        elif re.fullmatch(r"END\s+driver", line, flags=re.I):
            block = ""
        elif m := re.fullmatch(r"OPTION\s+(\w+)\s*=\s*(.+?)\s*;", line, flags=re.I):
            blocks[block][m.group(1).lower()] = m.group(2)
        else:
            raise AssertionError(f"not an .mdd line: {raw!r}")
    return blocks


@pytest.fixture(scope="module")
def bsp(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A BSP-like tree: include/, lib/, libsrc/stepramp_v1_0 (the driver folder as vitis_driver writes it)."""
    root = tmp_path_factory.mktemp("bsp")
    (root / "include").mkdir()
    (root / "lib").mkdir()
    vitis_driver.write(root / "libsrc" / DRIVER)
    return root


@pytest.fixture(scope="module")
def xparameters(bsp: Path) -> tuple[Path, list[list[str]]]:
    """The driver's generate proc run with the HSI stand-ins: include/xparameters.h and the calls it made."""
    instances = " ".join(
        f"{{NAME {name} CONFIG.C_BASEADDR 0x{base:08X} CONFIG.C_HIGHADDR 0x{high:08X}}}"
        for name, base, high in INSTANCES
    )
    script = (
        f"{HSI_STANDINS}\nset ::include_dir {{{bsp / 'include'}}}\nset ::instances [list {instances}]\n"
        f"source {{{bsp / 'libsrc' / DRIVER / 'data' / 'stepramp.tcl'}}}\n"
        "generate drv_handle_0\nforeach c $::calls { puts $c }\n"
    )
    out = _run([_tclsh()], input=script).stdout
    return bsp / "include" / "xparameters.h", [line.split() for line in out.splitlines()]


def test_mdd_names_the_packaged_ip(bsp: Path) -> None:
    mdd = parse_mdd((bsp / "libsrc" / DRIVER / "data" / "stepramp.mdd").read_text())
    assert mdd[""] == {"psf_version": "2.1"}
    assert set(mdd) == {"", "stepramp"}
    opts = mdd["stepramp"]
    assert opts["supported_peripherals"] == f"({IP_NAME})"
    assert opts["name"] == "stepramp"
    assert opts["copyfiles"] == "all" and opts["driver_state"] == "ACTIVE"
    # the folder is <name>_v<major>_<minor> of the driver's VERSION
    assert f"{opts['name']}_v{opts['version'].replace('.', '_')}" == DRIVER
    # the name the IP is packaged under (its VLNV's name) and its top entity
    package = (REPO / "scripts" / "package_vivado.tcl").read_text()
    assert re.search(rf"set_property name\s+{IP_NAME} \$core", package)
    assert re.search(rf"set_property top {IP_NAME} ", package)
    assert (REPO / "hdl" / f"{IP_NAME}.vhd").is_file()


def test_src_is_sw_c_src_and_the_makefile(bsp: Path) -> None:
    src = bsp / "libsrc" / DRIVER / "src"
    want = {p.name for p in vitis_driver.driver_files()}
    assert {"stepramp.c", "stepramp.h", "stepramp_regs.h", "stepramp_plan.c"} <= want
    assert {p.name for p in src.iterdir()} == want | {"Makefile"}
    for p in vitis_driver.driver_files():
        assert filecmp.cmp(p, src / p.name, shallow=False), p.name
    assert filecmp.cmp(vitis_driver.TEMPLATE / "src" / "Makefile", src / "Makefile", shallow=False)


def test_tcl_defines_the_xparameters(xparameters: tuple[Path, list[list[str]]]) -> None:
    header, calls = xparameters
    params = ["DEVICE_ID", "C_BASEADDR", "C_HIGHADDR"]
    assert calls == [
        ["define_include_file", "xparameters.h", "STEPRAMP", "NUM_INSTANCES", *params],
        ["define_canonical_xpars", "xparameters.h", "STEPRAMP", *params],
    ]
    defines = dict(re.findall(r"#define (\w+) (\S+)", header.read_text()))
    assert defines["XPAR_STEPRAMP_NUM_INSTANCES"] == str(len(INSTANCES))
    for n, (name, base, high) in enumerate(INSTANCES):
        for prefix in (f"XPAR_{name.upper()}", f"XPAR_STEPRAMP_{n}"):
            assert int(defines[f"{prefix}_BASEADDR"], 16) == base
            assert int(defines[f"{prefix}_HIGHADDR"], 16) == high
            assert defines[f"{prefix}_DEVICE_ID"] == str(n)
    # the name the driver's own usage example (stepramp.h) uses
    assert "XPAR_STEPRAMP_0_BASEADDR" in (vitis_driver.DRIVER_SOURCES / "stepramp.h").read_text()


def test_src_builds_in_a_bsp_and_links_an_application(
    bsp: Path, xparameters: tuple[Path, list[list[str]]], tmp_path: Path
) -> None:
    (bsp / "include" / "xil_io.h").write_text(XIL_IO_H)
    src = bsp / "libsrc" / DRIVER / "src"
    make = [
        "make",
        "-C",
        str(src),
        "COMPILER=gcc",
        "ARCHIVER=ar",
        "COMPILER_FLAGS=-c -O2",
        "EXTRA_COMPILER_FLAGS=-std=c99 -Wall -Wextra -Werror -pedantic",
    ]
    _run([*make, "include"])
    _run([*make, "libs"])
    headers = {p.name for p in vitis_driver.driver_files() if p.suffix == ".h"}
    assert headers <= {p.name for p in (bsp / "include").iterdir()}
    members = _run(["ar", "t", str(bsp / "lib" / "libxil.a")]).stdout.split()
    assert sorted(members) == sorted(p.stem + ".o" for p in vitis_driver.driver_files() if p.suffix == ".c")
    assert not list(src.glob("*.o")), "make libs leaves no objects behind (its clean)"
    app = tmp_path / "app.c"
    app.write_text(APP_C)
    exe = tmp_path / "app"
    inc = str(bsp / "include")
    _run(
        [
            "gcc",
            "-std=c99",
            "-Wall",
            "-Werror",
            "-I",
            inc,
            "-o",
            str(exe),
            str(app),
            "-L",
            str(bsp / "lib"),
            "-lxil",
            "-lm",
        ]
    )
    n, rc, rc_plan, rc_move, reads, writes, span = (int(v) for v in _run([str(exe)]).stdout.split())
    assert (n, rc, rc_plan, rc_move) == (len(INSTANCES), 0, 0, 0)
    assert reads >= 1 and writes > 0
    assert span >= 1 << regmap.ADDR_BITS  # the core's register window fits the address range


def test_package_vivado_puts_the_folder_in_the_ip(tmp_path: Path) -> None:
    """scripts/package_vivado.tcl in tclsh, every Vivado command logged by `unknown`, on a copy of the tree's layout
    (so that its build/ is under tmp_path): the IP's drivers/stepramp_v1_0 is the folder vitis_driver writes, and
    each of its files is added to the xilinx_softwaredriver file group with a type."""
    root = tmp_path / "repo"
    (root / "scripts").mkdir(parents=True)
    for name in ("package_vivado.tcl", "ipxact_registers.tcl"):
        shutil.copy2(REPO / "scripts" / name, root / "scripts" / name)
    for name in ("hdl", "rdl", "drivers", "sw"):
        (root / name).symlink_to(REPO / name)
    script = (
        "set ::log {}\n"
        'proc unknown {args} { lappend ::log $args; return "obj[llength $::log]" }\n'
        f"source {{{root / 'scripts' / 'package_vivado.tcl'}}}\n"
        "foreach c $::log { puts [join $c { }] }\n"
    )
    log = _run([_tclsh()], input=script).stdout.splitlines()
    ip_driver = root / "build" / "vivado_ip" / IP_NAME / "drivers" / DRIVER
    want = vitis_driver.write(tmp_path / "want" / DRIVER)
    cmp = filecmp.dircmp(ip_driver, want)
    files = sorted(f"{d}/{f}" for d in ("data", "src") for f in sorted(p.name for p in (want / d).iterdir()))
    assert not cmp.left_only and not cmp.right_only
    for f in files:
        assert filecmp.cmp(ip_driver / f, want / f, shallow=False), f
    assert any(line.startswith("ipx::add_file_group -type software_driver") for line in log)
    assert any(line.startswith("ipx::get_file_groups xilinx_softwaredriver") for line in log)
    added = [line.split()[1] for line in log if line.startswith("ipx::add_file ")]
    assert added == [f"drivers/{DRIVER}/{f}" for f in files]
    types = [line.split()[2] for line in log if line.startswith("set_property type ")]
    assert types == [
        "mdd"
        if f.endswith(".mdd")
        else "tclSource"
        if f.endswith(".tcl")
        else "unknown"
        if f.endswith("Makefile")
        else "cSource"
        for f in files
    ]
