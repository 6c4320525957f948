-- SPDX-License-Identifier: MIT
-- stepramp_inputs: the machine inputs of one axis (LIMIT_NEG, LIMIT_POS, HOME, ESTOP). Each pin passes a two-flop
-- synchroniser, its polarity and a filter: the filtered level follows the synchronised one once it has differed for
-- FILTER clocks in a row. The block also keeps the free-running 64-bit clock count (TIME) and the position latch.
-- Timing and the model of the filter: docs/stepramp_inputs.md and docs/algorithm.md, "Machine inputs".

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

entity stepramp_inputs is
  generic (
    -- Width of the filter counter: INPUT_FILTER holds up to 2^G_FILTER_BITS - 1 clocks (1 .. 31: the counters are
    -- integers).
    G_FILTER_BITS : positive := 20
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Pins, asynchronous: bit 0 LIMIT_NEG, 1 LIMIT_POS, 2 HOME, 3 ESTOP.
    pins : in    std_logic_vector(3 downto 0);
    -- Configuration: the filter length in clocks (0 acts as 1) and the polarity per pin (1: active low).
    filter : in    std_logic_vector(G_FILTER_BITS - 1 downto 0);
    pol    : in    std_logic_vector(3 downto 0);
    -- Filtered active levels, and one-clock strobes at the edge where a level became active (rise) or inactive
    -- (fall): level and strobe change at the same clock edge.
    level : out   std_logic_vector(3 downto 0);
    rise  : out   std_logic_vector(3 downto 0);
    fall  : out   std_logic_vector(3 downto 0);
    -- Position latch: the source (0 none, 1 HOME, 2 LIMIT_NEG, 3 LIMIT_POS) and its edges; latch_clr re-arms.
    latch_src     : in    std_logic_vector(1 downto 0);
    latch_active  : in    std_logic;
    latch_release : in    std_logic;
    latch_clr     : in    std_logic;
    position      : in    std_logic_vector(31 downto 0);
    latched       : out   std_logic;
    latch_pos     : out   std_logic_vector(31 downto 0);
    latch_time    : out   std_logic_vector(63 downto 0);
    -- Clock edges since reset: 0 in the cycle after the last reset edge, then one more per clock.
    time_count : out   std_logic_vector(63 downto 0)
  );
end entity stepramp_inputs;

architecture rtl of stepramp_inputs is

  -- The largest filter count, 2^G_FILTER_BITS - 1 (written so that 2^31 is never formed).
  constant C_CNT_MAX : natural := 2 ** (G_FILTER_BITS - 1) - 1 + 2 ** (G_FILTER_BITS - 1);

  -- The filter counters are integers: one signal each for a simulator (a vector is one per bit, each assigned at every
  -- clock), the same registers and comparators in hardware.

  type cnt_array_t is array (0 to 3) of natural range 0 to C_CNT_MAX;

  signal pins_pol : std_logic_vector(3 downto 0);
  signal sync1    : std_logic_vector(3 downto 0);
  signal sync2    : std_logic_vector(3 downto 0);
  signal level_r  : std_logic_vector(3 downto 0);
  signal rise_r   : std_logic_vector(3 downto 0);
  signal fall_r   : std_logic_vector(3 downto 0);
  signal cnt      : cnt_array_t;
  signal last     : natural range 0 to C_CNT_MAX;
  signal last_c   : natural range 0 to C_CNT_MAX;
  -- TIME counts every clock: its low 4 bits and the 12 above them are integers (a simulator adds them natively and
  -- converts 4 bits at each clock, 12 at every 16th), the high 48 bits step when the 16 below wrap (a 64-bit counter
  -- in hardware all the same).
  signal time_lo   : natural range 0 to 15;
  signal time_mid  : natural range 0 to 2 ** 12 - 1;
  signal time_hi   : unsigned(47 downto 0);
  signal latched_r : std_logic;
  signal lpos_r    : std_logic_vector(31 downto 0);
  signal ltime_r   : unsigned(63 downto 0);

  -- The 4-bit vector of each count 0 .. 15 (a table read, where to_unsigned converts bit by bit at each clock; wires
  -- in hardware).

  type t_nibbles is array (0 to 15) of std_logic_vector(3 downto 0);

  function make_nibbles return t_nibbles is

    variable v : t_nibbles;

  begin

    for i in v'range loop

      v(i) := std_logic_vector(to_unsigned(i, 4));

    end loop;

    return v;

  end function make_nibbles;

  constant C_NIBBLE : t_nibbles := make_nibbles;

  -- FILTER - 1, and 0 for FILTER 0 and 1 (and for an undefined FILTER, before the register file's reset).

  function last_count (
    f : std_logic_vector(G_FILTER_BITS - 1 downto 0)
  ) return natural is

    variable n : natural range 0 to C_CNT_MAX;

  begin

    n := to_integer(unsigned(f));

    if (n = 0) then
      return 0;
    end if;

    return n - 1;

  end function last_count;

begin

  -- The ASYNC_REG-style pair: sync1 is the only flip-flop that sees a pin.
  sync_proc : process (clk) is
  begin

    if rising_edge(clk) then
      if (rst = '1') then
        sync1 <= (others => '0');
        sync2 <= (others => '0');
      else
        sync1 <= pins_pol;
        sync2 <= sync1;
      end if;
    end if;

  end process sync_proc;

  -- The pins made active high (a concurrent statement: a simulator evaluates it when a pin or POL changes).
  pins_pol <= pins xor pol;

  -- The count a mismatch must reach: FILTER - 1 (0 for FILTER 0 and 1), registered off the compare's path (the
  -- subtraction a concurrent statement, which a simulator evaluates when FILTER changes, not every clock).
  last_c <= last_count(filter);

  -- (No reset: the filter does not read it until its synchronisers, which are reset, can differ from the filtered
  -- level, two clocks after reset, and by then it follows FILTER's reset value.)
  last_proc : process (clk) is
  begin

    if rising_edge(clk) then
      last <= last_c;
    end if;

  end process last_proc;

  -- The filter: a synchronised level that differs from the filtered one for FILTER edges in a row replaces it; any
  -- sample that agrees restarts the count (a bounce).
  filter_proc : process (clk) is
  begin

    if rising_edge(clk) then
      rise_r <= (others => '0');
      fall_r <= (others => '0');

      for i in 0 to 3 loop

        if (sync2(i) /= level_r(i)) then
          if (cnt(i) >= last) then
            level_r(i) <= sync2(i);
            rise_r(i)  <= sync2(i);
            fall_r(i)  <= not sync2(i);
            cnt(i)     <= 0;
          else
            cnt(i) <= cnt(i) + 1;
          end if;
        else
          cnt(i) <= 0;
        end if;

      end loop;

      if (rst = '1') then
        level_r <= (others => '0');
        rise_r  <= (others => '0');
        fall_r  <= (others => '0');

        for i in 0 to 3 loop

          cnt(i) <= 0;

        end loop;

      end if;
    end if;

  end process filter_proc;

  -- TIME and the latch: the first selected edge of the source since the last clear takes POSITION and TIME, both as
  -- they are in the clock after the filtered level changed (docs/stepramp_inputs.md, "Latch timing").
  latch_proc : process (clk) is

    variable hit : std_logic;

  begin

    if rising_edge(clk) then
      if (time_lo /= 15) then
        time_lo <= time_lo + 1;
      elsif (time_mid /= 2 ** 12 - 1) then
        time_lo  <= 0;
        time_mid <= time_mid + 1;
      else
        time_lo  <= 0;
        time_mid <= 0;
        time_hi  <= time_hi + 1;
      end if;
      hit := '0';

      case latch_src is

        when "01" =>

          hit := (rise_r(2) and latch_active) or (fall_r(2) and latch_release);

        when "10" =>

          hit := (rise_r(0) and latch_active) or (fall_r(0) and latch_release);

        when "11" =>

          hit := (rise_r(1) and latch_active) or (fall_r(1) and latch_release);

        when others =>

          hit := '0';

      end case;

      if (latch_clr = '1') then
        latched_r <= '0';
      end if;

      -- (a clear and an edge in the same clock: the edge is latched)
      if (hit = '1' and (latched_r = '0' or latch_clr = '1')) then
        latched_r <= '1';
        lpos_r    <= position;
        ltime_r   <= time_hi & to_unsigned(time_mid, 12) & to_unsigned(time_lo, 4);
      end if;

      if (rst = '1') then
        time_lo   <= 0;
        time_mid  <= 0;
        time_hi   <= (others => '0');
        latched_r <= '0';
        lpos_r    <= (others => '0');
        ltime_r   <= (others => '0');
      end if;
    end if;

  end process latch_proc;

  level      <= level_r;
  rise       <= rise_r;
  fall       <= fall_r;
  latched    <= latched_r;
  latch_pos  <= lpos_r;
  latch_time <= std_logic_vector(ltime_r);
  -- TIME to the port in three parts, so that a simulator converts and assigns 4 bits at each clock, the 12 above them
  -- at every 16th and the high 48 bits only when they step.
  time_count(3 downto 0)   <= C_NIBBLE(time_lo);
  time_count(15 downto 4)  <= std_logic_vector(to_unsigned(time_mid, 12));
  time_count(63 downto 16) <= std_logic_vector(time_hi);

  assert G_FILTER_BITS >= 1 and G_FILTER_BITS <= 31
    report "stepramp_inputs: G_FILTER_BITS must be 1 .. 31"
    severity failure;

end architecture rtl;
