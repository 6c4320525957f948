# SPDX-License-Identifier: MIT
"""stepramp.sim.netlist.restore_case_defaults without a simulator: GHDL 2.0's Verilog `case` without `default`
gets the default its VHDL writer printed for the same net, module by module; anything it cannot translate raises."""

from __future__ import annotations

import pytest

from stepramp.sim.netlist import restore_case_defaults

VERILOG = """module leaf
  (input  [1:0] s,
   output o);
  reg n5_o;
  reg [2:0] n6_o;
  always @*
    case (s)
      2'b10: n5_o <= a;
      2'b01: n5_o <= b;
    endcase
  always @*
    case (s)
      2'b10: n6_o <= c;
      default: n6_o <= 3'b111;
    endcase
endmodule

module top
  (input  [1:0] s);
  reg [3:0] n9_o;
  always @*
    case (s)
      2'b01: n9_o <= d;
    endcase
endmodule
"""

VHDL = """entity leaf is
end entity;
entity top is
end entity;
architecture rtl of leaf is
begin
  with s select n5_o <=
    a when "10",
    b when "01",
    '0' when others;
end rtl;

architecture rtl of top is
begin
  with s select n9_o <=
    d when "01",
    "1010" when others;
end rtl;
"""


def test_each_missing_default_comes_from_the_vhdl_netlist() -> None:
    out = restore_case_defaults(VERILOG, VHDL)
    assert "2'b01: n5_o <= b;\n      default: n5_o <= 1'b0;\n    endcase" in out
    assert "2'b01: n9_o <= d;\n      default: n9_o <= 4'b1010;\n    endcase" in out
    # A case that has its default keeps it, and only it.
    assert out.count("default: n6_o") == 1 and "default: n6_o <= 3'b111;" in out


def test_a_net_default_copied_from_another_net() -> None:
    vhdl = VHDL.replace("'0' when others;", "num_r when others;")
    assert "default: n5_o <= num_r;" in restore_case_defaults(VERILOG, vhdl)


def test_no_default_in_the_vhdl_raises() -> None:
    vhdl = VHDL.replace("n9_o", "n10_o")
    with pytest.raises(RuntimeError, match="top: no default for n9_o"):
        restore_case_defaults(VERILOG, vhdl)


def test_an_expression_default_raises() -> None:
    vhdl = VHDL.replace("'0' when others;", "x(3 downto 0) when others;")
    with pytest.raises(RuntimeError, match="cannot translate"):
        restore_case_defaults(VERILOG, vhdl)


def test_an_unknown_default_stays_unknown() -> None:
    # GHDL gives a multiplexer whose selector covers every value (a constant table) the default 'X'.
    vhdl = VHDL.replace("'0' when others;", "'X' when others;").replace('"1010" when others;', '"10X1" when others;')
    out = restore_case_defaults(VERILOG, vhdl)
    assert "default: n5_o <= 1'bx;" in out
    assert "default: n9_o <= 4'b10x1;" in out
