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

  signal cnt    : unsigned(G_WIDTH - 1 downto 0);
  signal tick_r : std_logic;
  signal reload : unsigned(G_WIDTH - 1 downto 0);

begin

  assert G_WIDTH >= 1 and G_WIDTH <= 32
    report "stepramp_timer: G_WIDTH must be in 1 .. 32"
    severity failure;

  -- Down-counter reload value P - 1 (0 for P = 0 or 1).
  reload <= (others => '0') when unsigned(prescale) = 0 else
            unsigned(prescale) - 1;

  count_proc : process (clk) is
  begin

    if rising_edge(clk) then
      if (rst = '1' or restart = '1') then
        cnt    <= reload;
        tick_r <= '0';
      elsif (cnt = 0) then
        cnt    <= reload;
        tick_r <= '1';
      else
        cnt    <= cnt - 1;
        tick_r <= '0';
      end if;
    end if;

  end process count_proc;

  tick <= tick_r;

end architecture rtl;
