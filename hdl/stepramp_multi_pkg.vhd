-- SPDX-License-Identifier: MIT
-- stepramp_multi_pkg: the address map of the multi-axis top stepramp_multi (its global window and the axis
-- windows). Registers and timing: docs/stepramp_multi.md; the Python and C copies (stepramp.board.multi,
-- sw/c/src/stepramp_multi.h) are checked against this file by sw/tests/test_multi.py.

library ieee;
  use ieee.std_logic_1164.all;

package stepramp_multi_pkg is

  -- Decoded address bits: 16 windows of 256 bytes; window 0 is global, window i + 1 is axis i.
  constant C_MULTI_ADDR_BITS : natural := 12;
  constant C_MULTI_MAX_AXES  : natural := 8;

  -- ID bits 31:16 ('SM') and 15:8; bits 7:0 hold G_AXES.
  constant C_MULTI_ID_MAGIC   : std_logic_vector(15 downto 0) := x"534D";
  constant C_MULTI_ID_VERSION : std_logic_vector(7 downto 0)  := x"01";

  -- Byte offsets in the global window.
  constant C_MREG_ID             : natural := 16#00#;
  constant C_MREG_SYNC_START     : natural := 16#04#;
  constant C_MREG_AXES_STATUS    : natural := 16#08#;
  constant C_MREG_IRQ_MASK       : natural := 16#0C#;
  constant C_MREG_SYNC_SOFT_STOP : natural := 16#10#;

  -- AXES_STATUS fields: bit i of each is axis i.
  constant C_AXES_STATUS_BUSY_LSB : natural := 0;
  constant C_AXES_STATUS_DONE_LSB : natural := 8;
  constant C_AXES_STATUS_IRQ_LSB  : natural := 16;

end package stepramp_multi_pkg;
