# SPDX-License-Identifier: MIT
# ipxact_registers.tcl: the registers of rdl/stepramp.xml (IP-XACT 1685-2014, written by PeakRDL from
# rdl/stepramp.rdl) as a Tcl list, for scripts/package_vivado.tcl. Plain Tcl (regexp over the generated file, no XML
# package), so that it runs in any Vivado and in tclsh: tb/test_vivado_tcl.py checks it against the register map.
#
# stepramp_ipxact_registers FILE -> {{name offset description {{field lsb width access reset description} ...}} ...}

proc stepramp_ipxact_tag {xml tag} {
  if {[regexp "<ipxact:${tag}>(\[^<\]*)</ipxact:${tag}>" $xml -> value]} {
    return [string map {&lt; < &gt; > &quot; \" &apos; ' &amp; &} $value]
  }
  return ""
}

proc stepramp_ipxact_number {text} {
  # IP-XACT numbers here are 'hXX (PeakRDL) or plain decimal.
  if {[regexp {^'h([0-9A-Fa-f]+)$} $text -> hex]} {
    scan $hex %llx value
    return $value
  }
  return $text
}

proc stepramp_ipxact_reset {field} {
  # The value inside <ipxact:resets> (an enumerated field also has <ipxact:value>s in its enumeration).
  if {[regexp {<ipxact:resets>(.*?)</ipxact:resets>} $field -> resets]} {
    return [stepramp_ipxact_number [stepramp_ipxact_tag $resets value]]
  }
  return 0
}

proc stepramp_ipxact_registers {path} {
  set fh [open $path r]
  set xml [read $fh]
  close $fh
  set regs {}
  foreach {-> reg} [regexp -all -inline {<ipxact:register>(.*?)</ipxact:register>} $xml] {
    set head $reg
    regexp {^(.*?)<ipxact:field>} $reg -> head
    set fields {}
    foreach {-> fld} [regexp -all -inline {<ipxact:field>(.*?)</ipxact:field>} $reg] {
      lappend fields [list [stepramp_ipxact_tag $fld name] [stepramp_ipxact_tag $fld bitOffset] \
        [stepramp_ipxact_tag $fld bitWidth] [stepramp_ipxact_tag $fld access] \
        [stepramp_ipxact_reset $fld] [stepramp_ipxact_tag $fld description]]
    }
    lappend regs [list [stepramp_ipxact_tag $head name] \
      [stepramp_ipxact_number [stepramp_ipxact_tag $head addressOffset]] \
      [stepramp_ipxact_tag $head description] $fields]
  }
  return $regs
}

if {[info exists argv0] && [file tail $argv0] eq "ipxact_registers.tcl"} {
  foreach reg [stepramp_ipxact_registers [lindex $argv 0]] {
    puts $reg
  }
}
