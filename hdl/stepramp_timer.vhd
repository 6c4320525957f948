-- SPDX-License-Identifier: MIT
-- stepramp_timer: the base timer, a modulo counter that emits one registered tick every prescale clocks.
-- Ports and timing: docs/stepramp_timer.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

entity stepramp_timer is
  generic (
    G_WIDTH : positive := 16
  );
  port (
    clk      : in    std_logic;
    rst      : in    std_logic;
    restart  : in    std_logic;
    prescale : in    std_logic_vector(G_WIDTH - 1 downto 0);
    tick     : out   std_logic
  );
end entity stepramp_timer;

architecture rtl of stepramp_timer is

  -- The width of the down-counter's low part (bits 15 .. 0, or all of them) and of its high part (the bits above).

  function lo_width return natural is
  begin

    if (G_WIDTH < 16) then
      return G_WIDTH;
    end if;

    return 16;

  end function lo_width;

  constant C_LO_BITS : natural := lo_width;
  constant C_HI_BITS : natural := G_WIDTH - C_LO_BITS;

  signal reload    : unsigned(G_WIDTH - 1 downto 0);
  signal reload_lo : natural range 0 to 2 ** C_LO_BITS - 1;
  signal reload_hi : natural range 0 to 2 ** C_HI_BITS - 1;
  -- The down-counter, bits 15 .. 0 and the bits above, as integers: a simulator counts them natively (an unsigned
  -- count and compare call numeric_std's functions at every clock, a tenth of a bus top's simulation time).
  signal cnt_lo : natural range 0 to 2 ** C_LO_BITS - 1;
  signal cnt_hi : natural range 0 to 2 ** C_HI_BITS - 1;
  signal tick_r : std_logic;

  -- The high part of a count (0 when there is none).

  function hi_part (
    v : unsigned(G_WIDTH - 1 downto 0)
  ) return natural is
  begin

    if (C_HI_BITS = 0) then
      return 0;
    end if;

    return to_integer(v(G_WIDTH - 1 downto C_LO_BITS));

  end function hi_part;

begin

  assert G_WIDTH >= 1 and G_WIDTH <= 32
    report "stepramp_timer: G_WIDTH must be in 1 .. 32"
    severity failure;

  -- Down-counter reload value P - 1 (0 for P = 0 or 1), split as the counter is (concurrent statements: a simulator
  -- evaluates them when prescale changes, not every clock).
  reload <= (others => '0') when unsigned(prescale) = 0 else
            unsigned(prescale) - 1;

  reload_lo <= to_integer(reload(C_LO_BITS - 1 downto 0));
  reload_hi <= hi_part(reload);

  count_proc : process (clk) is
  begin

    if rising_edge(clk) then
      if (rst = '1' or restart = '1') then
        cnt_lo <= reload_lo;
        cnt_hi <= reload_hi;
        tick_r <= '0';
      elsif (cnt_lo = 0 and cnt_hi = 0) then
        cnt_lo <= reload_lo;
        cnt_hi <= reload_hi;
        tick_r <= '1';
      elsif (cnt_lo = 0) then
        -- (only with a high part: cnt_hi > 0 here)
        cnt_lo <= 2 ** C_LO_BITS - 1;
        if (C_HI_BITS > 0) then
          cnt_hi <= cnt_hi - 1;
        end if;
        tick_r <= '0';
      else
        cnt_lo <= cnt_lo - 1;
        tick_r <= '0';
      end if;
    end if;

  end process count_proc;

  tick <= tick_r;

end architecture rtl;
