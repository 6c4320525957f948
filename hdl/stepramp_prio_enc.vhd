-- SPDX-License-Identifier: MIT
-- stepramp_prio_enc: index of the most significant '1' of din, and a zero flag.
-- Purely combinational. index is 0 when din is all zeros (zero = '1' then).

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
    din   : in    std_logic_vector(G_WIDTH - 1 downto 0);
    index : out   std_logic_vector(clog2(G_WIDTH) - 1 downto 0);
    zero  : out   std_logic
  );
end entity stepramp_prio_enc;

architecture rtl of stepramp_prio_enc is

begin

  assert G_WIDTH >= 2 and G_WIDTH <= 1024
    report "stepramp_prio_enc: G_WIDTH must be in 2 .. 1024"
    severity failure;

  encode_proc : process (din) is

    variable idx : unsigned(index'range);

  begin

    -- Scan from the LSB up so that the last '1' seen (the most significant) wins.
    idx := (others => '0');

    for i in 0 to G_WIDTH - 1 loop

      if (din(i) = '1') then
        idx := to_unsigned(i, idx'length);
      end if;

    end loop;

    index <= std_logic_vector(idx);

  end process encode_proc;

  zero <= '1' when unsigned(din) = 0 else
          '0';

end architecture rtl;
