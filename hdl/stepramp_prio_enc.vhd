-- SPDX-License-Identifier: MIT
-- stepramp_prio_enc: the index of the most significant '1' of data, and a zero flag; combinational.
-- Ports and timing: docs/stepramp_prio_enc.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_prio_enc is
  generic (
    G_WIDTH : positive := 32
  );
  port (
    data  : in    std_logic_vector(G_WIDTH - 1 downto 0);
    index : out   std_logic_vector(clog2(G_WIDTH) - 1 downto 0);
    zero  : out   std_logic
  );
end entity stepramp_prio_enc;

architecture rtl of stepramp_prio_enc is

  -- The input padded with zeros to a power of two: the tree below halves it level by level.
  constant C_LEVELS : positive := clog2(G_WIDTH);
  constant C_PAD    : positive := 2 ** C_LEVELS;

begin

  assert G_WIDTH >= 2 and G_WIDTH <= 1024
    report "stepramp_prio_enc: G_WIDTH must be in 2 .. 1024"
    severity failure;

  -- A binary tree, log2(width) levels deep (a loop where the last '1' wins would be a chain as long as the input):
  -- each node of level l covers 2^(l+1) bits and holds whether any is '1' and, below its top bit l, the index of the
  -- highest '1' within it. Node n of level l combines nodes 2n (low half) and 2n + 1 (high half) of level l - 1:
  -- the high half wins when it has a '1', and contributes index bit l.
  encode_proc : process (data) is

    type t_any is array (0 to C_PAD - 1) of std_logic;

    type t_idx is array (0 to C_PAD - 1) of unsigned(C_LEVELS - 1 downto 0);

    variable any_v : t_any;
    variable idx_v : t_idx;
    variable width : natural;

  begin

    for i in 0 to C_PAD - 1 loop

      idx_v(i) := (others => '0');

      if (i < G_WIDTH) then
        any_v(i) := data(i);
      else
        any_v(i) := '0';
      end if;

    end loop;

    width := C_PAD;

    for l in 0 to C_LEVELS - 1 loop

      width := width / 2;

      for n in 0 to C_PAD / 2 - 1 loop

        if (n < width) then
          if (any_v(2 * n + 1) = '1') then
            idx_v(n)    := idx_v(2 * n + 1);
            idx_v(n)(l) := '1';
          else
            idx_v(n) := idx_v(2 * n);
          end if;
          any_v(n) := any_v(2 * n) or any_v(2 * n + 1);
        end if;

      end loop;

    end loop;

    index <= std_logic_vector(idx_v(0));
    zero  <= not any_v(0);

  end process encode_proc;

end architecture rtl;
