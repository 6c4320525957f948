-- SPDX-License-Identifier: MIT
-- stepramp_sched: the shared ramp computer's scheduler (issue 35): which waiting axis the computer serves next, round
-- robin. Ports, timing and the bound it guarantees: docs/stepramp_sched.md; the rule: docs/ramp_computer.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

entity stepramp_sched is
  generic (
    G_AXES : positive := 4
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Axis i waits for a service (held until the edge that grants it).
    req : in    std_logic_vector(G_AXES - 1 downto 0);
    -- The computer can start a service at this edge.
    free : in    std_logic;
    -- The axis whose service starts at this edge (one-hot, all '0' when none): the first waiting axis after the
    -- one served last, cyclically (axis 0 first after reset). Combinational from req, free and the last grant.
    grant     : out   std_logic_vector(G_AXES - 1 downto 0);
    grant_idx : out   std_logic_vector(2 downto 0)
  );
end entity stepramp_sched;

architecture rtl of stepramp_sched is

  -- The axis served last (G_AXES - 1 after reset, so that axis 0 comes first).
  signal last : natural range 0 to G_AXES - 1;
  -- This edge's choice.
  signal pick   : natural range 0 to G_AXES - 1;
  signal pick_v : std_logic;

begin

  assert G_AXES <= 8
    report "stepramp_sched: G_AXES must be in 1 .. 8"
    severity failure;

  -- The rotating priority: axes last + 1, last + 2, ... last (modulo G_AXES); the first that waits.
  pick_proc : process (req, last) is

    variable v_axis : natural range 0 to 2 * G_AXES - 1;

  begin

    pick   <= 0;
    pick_v <= '0';

    for k in G_AXES downto 1 loop

      -- (last + k) modulo G_AXES, as a compare and a subtraction on a few bits: no divider.
      v_axis := last + k;

      if (v_axis >= G_AXES) then
        v_axis := v_axis - G_AXES;
      end if;

      if (req(v_axis) = '1') then
        pick   <= v_axis;
        pick_v <= '1';
      end if;

    end loop;

  end process pick_proc;

  grant_proc : process (pick, pick_v, free) is
  begin

    grant <= (others => '0');

    if (pick_v = '1' and free = '1') then
      grant(pick) <= '1';
    end if;

  end process grant_proc;

  grant_idx <= std_logic_vector(to_unsigned(pick, 3));

  last_proc : process (clk) is
  begin

    if rising_edge(clk) then
      if (pick_v = '1' and free = '1') then
        last <= pick;
      end if;

      if (rst = '1') then
        last <= G_AXES - 1;
      end if;
    end if;

  end process last_proc;

end architecture rtl;
