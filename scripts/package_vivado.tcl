# SPDX-License-Identifier: MIT
# package_vivado.tcl: package stepramp_axil (the stepramp core with an AXI4-Lite slave) as a Vivado IP, for the
# IP integrator (block design with MicroBlaze on AXI).
#
# UNTESTED: Vivado is not installed where stepramp is developed and verified, so this script has never been run.
# It is a small, standard IP packager script (Vivado Tcl reference UG835, IP packager UG1118); check the result in
# the IP packager (Tools > Edit in IP Packager on build/vivado_ip/stepramp_axil/component.xml) the first time.
#
# Usage (from the repository root or anywhere else):
#   vivado -mode batch -source scripts/package_vivado.tcl
# Result: build/vivado_ip/stepramp_axil/ (component.xml, hdl/, xgui/, drivers/stepramp_v1_0/), VLNV stepramp:ip:stepramp_axil:<version>
# with the version of the ID register (hdl/stepramp_regs_pkg.vhd, C_ID_VALUE: 0x53520002 -> 0.2). Add
# build/vivado_ip to the IP repositories of the Vivado project (Settings > IP > Repository).
#
# hdl/ holds two bus tops (stepramp_plb, stepramp_axil), so the sources go into an in-memory project with the top
# set explicitly and `ipx::package_project` packages that (what "Package your current project" does); letting
# `ipx::infer_core` pick the top from the folder could pick stepramp_plb.

set root   [file normalize [file join [file dirname [info script]] ..]]
set ip_dir [file join $root build vivado_ip stepramp_axil]

# Version from the ID register: bits 15:8 major, 7:0 minor.
set fh [open [file join $root hdl stepramp_regs_pkg.vhd] r]
set pkg [read $fh]
close $fh
if {![regexp {C_ID_VALUE\s*:[^:]*:=\s*x"([0-9A-Fa-f]{8})"} $pkg -> id_hex]} {
  error "C_ID_VALUE not found in hdl/stepramp_regs_pkg.vhd"
}
scan $id_hex %x id_value
set version "[expr {($id_value >> 8) & 0xFF}].[expr {$id_value & 0xFF}]"

# Sources: every RTL file (plain VHDL, no vendor primitives; Vivado orders them itself). Copied into the IP.
file delete -force $ip_dir
file mkdir $ip_dir
create_project -in_memory stepramp_package
add_files -norecurse [lsort [glob [file join $root hdl *.vhd]]]
set_property top stepramp_axil [current_fileset]
update_compile_order -fileset sources_1

ipx::package_project -root_dir $ip_dir -vendor stepramp -library ip -taxonomy /UserIP -import_files \
  -set_current true
set core [ipx::current_core]
set_property name          stepramp_axil $core
set_property version       $version $core
set_property core_revision 1 $core
set_property display_name  "stepramp stepper-motor ramp (AXI4-Lite)" $core
set_property description   "Linear speed ramps for stepper motors (AVR446 recurrence), STEP/DIR outputs" $core

# Interfaces. The packager infers them from the port names (s_axil_*, aclk, aresetn); make sure of each.
proc ensure_interface {core name vlnv} {
  if {[llength [ipx::get_bus_interfaces $name -of_objects $core]] == 0} {
    ipx::infer_bus_interface $name $vlnv $core
  }
}

if {[llength [ipx::get_bus_interfaces s_axil -of_objects $core]] == 0} {
  ipx::infer_bus_interfaces xilinx.com:interface:aximm_rtl:1.0 $core
}
ensure_interface $core aclk    xilinx.com:signal:clock_rtl:1.0
ensure_interface $core aresetn xilinx.com:signal:reset_rtl:1.0
ensure_interface $core irq     xilinx.com:signal:interrupt_rtl:1.0

proc set_bus_parameter {core busif name value} {
  set intf [ipx::get_bus_interfaces $busif -of_objects $core]
  set param [ipx::get_bus_parameters $name -of_objects $intf]
  if {[llength $param] == 0} {
    set param [ipx::add_bus_parameter $name $intf]
  }
  set_property value $value $param
}

set_bus_parameter $core aresetn POLARITY    ACTIVE_LOW
set_bus_parameter $core irq     SENSITIVITY LEVEL_HIGH
ipx::associate_bus_interfaces -busif s_axil -clock aclk $core
ipx::associate_bus_interfaces -clock aclk -reset aresetn $core

# Memory map: the registers sit in the low 256 bytes (8 address bits) and repeat in the rest of the 4 KiB block.
set mmap [ipx::add_memory_map s_axil $core]
set_property slave_memory_map_ref s_axil [ipx::get_bus_interfaces s_axil -of_objects $core]
set block [ipx::add_address_block reg0 $mmap]
set_property base_address 0 $block
set_property range 4096 $block
set_property width 32 $block
set_property usage register $block

# Registers and fields from the IP-XACT that rdl/stepramp.rdl generates (python -m stepramp.tools.regmap_gen), so
# that the address editor and the hardware handoff see them. reset_value is set where this Vivado has it.
source [file join $root scripts ipxact_registers.tcl]
foreach reg [stepramp_ipxact_registers [file join $root rdl stepramp.xml]] {
  lassign $reg name offset description fields
  set r [ipx::add_register $name $block]
  set_property address_offset $offset $r
  set_property size 32 $r
  set_property description $description $r
  foreach fld $fields {
    lassign $fld fname lsb width access reset fdescription
    set f [ipx::add_field $fname $r]
    set_property bit_offset $lsb $f
    set_property bit_width $width $f
    set_property access $access $f
    set_property description $fdescription $f
    catch {set_property reset_value $reset $f}
  }
}

# The Vitis (classic / SDK standalone BSP) driver beside the IP: drivers/stepramp_v1_0 with data/stepramp.mdd,
# data/stepramp.tcl and src/Makefile from the repository's drivers/stepramp_v1_0, and the driver's sources
# (sw/c/src/*.c, *.h) in src/ -- the folder `python -m stepramp.tools.vitis_driver` writes (checked by
# sw/tests/test_vitis_driver.py). A BSP made from a design with this IP picks the driver for stepramp_axil.
set drv_name stepramp_v1_0
set drv_dir  [file join $ip_dir drivers $drv_name]
file mkdir [file join $drv_dir data] [file join $drv_dir src]
foreach f [lsort [glob [file join $root drivers $drv_name data *]]] {
  file copy -force $f [file join $drv_dir data]
}
file copy -force [file join $root drivers $drv_name src Makefile] [file join $drv_dir src]
foreach f [lsort [glob [file join $root sw c src *.c] [file join $root sw c src *.h]]] {
  file copy -force $f [file join $drv_dir src]
}
ipx::add_file_group -type software_driver {} $core
set drv_group [ipx::get_file_groups xilinx_softwaredriver -of_objects $core]
foreach f [lsort [glob -directory $drv_dir -tails data/* src/*]] {
  set fobj [ipx::add_file drivers/$drv_name/$f $drv_group]
  switch -glob -- $f {
    *.mdd   {set_property type mdd $fobj}
    *.tcl   {set_property type tclSource $fobj}
    *.c     -
    *.h     {set_property type cSource $fobj}
    default {set_property type unknown $fobj}
  }
}

# The generic G_MICROSTEPS keeps its default (16) unless it is exposed with ipx::add_user_parameter.
ipx::create_xgui_files $core
ipx::update_checksums $core
ipx::check_integrity $core
ipx::save_core $core
close_project
puts "stepramp: packaged stepramp:ip:stepramp_axil:$version in $ip_dir"
