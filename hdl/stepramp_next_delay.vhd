-- SPDX-License-Identifier: MIT
-- stepramp_next_delay: the ramp engine's next-delay unit. It answers "what is the ramp value at this index?" from
-- the value (and remainder) at the neighbouring index by one step of the AVR446 recurrence on stepramp_divider, or
-- loads a seed. Ports, recurrence and timing: docs/stepramp_engine.md, "stepramp_next_delay".

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_next_delay is
  generic (
    G_DIV_WIDTH : positive := 50
  );
  port (
    clk       : in    std_logic;
    rst       : in    std_logic;
    flush     : in    std_logic;
    req       : in    std_logic;
    req_seed  : in    std_logic;
    req_decel : in    std_logic;
    req_index : in    std_logic_vector(30 downto 0);
    req_value : in    std_logic_vector(47 downto 0);
    -- The numerator 2 * req_value + remainder, formed by the requester (from registers, off this unit's path).
    req_num   : in    std_logic_vector(G_DIV_WIDTH - 1 downto 0);
    busy      : out   std_logic;
    ans_valid : out   std_logic;
    ans_value : out   std_logic_vector(47 downto 0);
    ans_rem   : out   std_logic_vector(32 downto 0);
    ans_ovf   : out   std_logic
  );
end entity stepramp_next_delay;

architecture rtl of stepramp_next_delay is

  constant C_W : positive := G_DIV_WIDTH;
  -- The denominator 4 * index + 1 or + 3 of a 31-bit index: 33 bits (and so is the remainder, below it).
  constant C_DEN_W : positive := 33;

  signal pending     : std_logic;
  signal decel_r     : std_logic;
  signal value_r     : unsigned(47 downto 0);
  signal valid_r     : std_logic;
  signal ovf_r       : std_logic;
  signal ans_value_r : unsigned(47 downto 0);
  signal ans_rem_r   : unsigned(32 downto 0);

  signal accept    : std_logic;
  signal div_rst   : std_logic;
  signal div_start : std_logic;
  signal div_busy  : std_logic;
  signal div_done  : std_logic;
  signal div_zero  : std_logic;
  signal div_num   : std_logic_vector(C_W - 1 downto 0);
  signal div_den   : std_logic_vector(C_DEN_W - 1 downto 0);
  signal div_q     : std_logic_vector(C_W - 1 downto 0);
  signal div_r     : std_logic_vector(C_DEN_W - 1 downto 0);
  -- value -/+ quotient as a carry-select adder (the divider's last quotient digit -> the answer register and its
  -- range flag is a top path of the clock): the low C_SPLIT bits with the carry in, the bits above with and without
  -- the low part's carry, picked by it.
  constant C_SPLIT : positive := (C_W + 1) / 2;

  -- value + q (decel) or value - q = value + not q + 1 (accel), modulo 2^(C_W + 1) (one bit wider than the divider,
  -- so that a borrow or a carry out of 48 bits is visible), through one carry-select adder: the operand is q inverted
  -- when accelerating, and the + 1 enters as the carry of an extra low bit ('1' + '1'). Two adders for the bits above
  -- and a multiplexer in hardware, as if both were computed first; a simulator evaluates only the one it returns, and
  -- only at the edge that takes the answer (as concurrent statements they would follow the quotient at every clock
  -- of a division).
  function step_result (
    value : unsigned(47 downto 0);
    q     : unsigned(C_W - 1 downto 0);
    decel : std_logic
  ) return unsigned is

    variable value_x : unsigned(C_W downto 0);         -- the value, as wide as the sum
    variable q_op    : unsigned(C_W downto 0);         -- q, inverted when accelerating
    variable sum_lo  : unsigned(C_SPLIT + 1 downto 0); -- the low bits & the extra low bit, and the carry out

  begin

    value_x := resize(value, C_W + 1);
    q_op    := resize(q, C_W + 1) xor (C_W downto 0 => not decel);
    -- value + q_op + (not decel): the carry in rides on an extra low bit ('1' + carry in).
    sum_lo := ('0' & value_x(C_SPLIT - 1 downto 0) & '1') + ('0' & q_op(C_SPLIT - 1 downto 0) & not decel);

    if (sum_lo(C_SPLIT + 1) = '1') then
      return (value_x(C_W downto C_SPLIT) + q_op(C_W downto C_SPLIT) + 1) & sum_lo(C_SPLIT downto 1);
    end if;

    return (value_x(C_W downto C_SPLIT) + q_op(C_W downto C_SPLIT)) & sum_lo(C_SPLIT downto 1);

  end function step_result;

begin

  -- 2 * (2^48 - 1) + remainder (< 2^33) needs 50 bits; the divider itself stops at 64.
  assert G_DIV_WIDTH >= 50 and G_DIV_WIDTH <= 64
    report "stepramp_next_delay: G_DIV_WIDTH must be in 50 .. 64"
    severity failure;

  accept    <= req and not pending and not div_busy and not flush;
  div_start <= accept and not req_seed;
  -- flush resets the divider too: a division in flight is simply dropped.
  div_rst <= rst or flush;

  -- num = 2 * value + remainder comes with the request (req_num); den = 4 * index + 1 (accel) or 4 * index + 3
  -- (decel): just wiring.
  div_num <= req_num;
  div_den <= req_index & req_decel & '1';

  divider_inst : entity work.stepramp_divider
    generic map (
      G_WIDTH     => C_W,
      G_DEN_WIDTH => C_DEN_W
    )
    port map (
      clk         => clk,
      rst         => div_rst,
      start       => div_start,
      numerator   => div_num,
      denominator => div_den,
      busy        => div_busy,
      done        => div_done,
      div_zero    => div_zero,
      quotient    => div_q,
      remainder   => div_r
    );

  ctrl_proc : process (clk) is

    variable v_result : unsigned(C_W downto 0);

    -- The answer, valid for one clock: a ramp value (Q32.16), its remainder and the out-of-range flag.

    procedure answer (
      value     : unsigned(47 downto 0);
      remainder : unsigned(32 downto 0);
      overflow  : std_logic
    ) is
    begin

      valid_r     <= '1';
      ans_value_r <= value;
      ans_rem_r   <= remainder;
      ovf_r       <= overflow;

    end procedure answer;

  begin

    if rising_edge(clk) then
      valid_r <= '0';

      if (accept = '1') then
        decel_r <= req_decel;
        value_r <= unsigned(req_value);
        if (req_seed = '1') then
          answer(unsigned(req_value), (others => '0'), '0');
        else
          pending <= '1';
        end if;
      end if;

      if (pending = '1' and div_done = '1') then
        pending <= '0';
        -- The remainder is below den < 2^33. Out of the Q32.16 range (a borrow shows as the top bit): the engine
        -- stops with an error.
        v_result := step_result(value_r, unsigned(div_q), decel_r);
        answer(v_result(47 downto 0), unsigned(div_r), to_sl(v_result(C_W downto 48) /= 0 or div_zero = '1'));
      end if;

      if (rst = '1' or flush = '1') then
        pending <= '0';
        valid_r <= '0';
      end if;
    end if;

  end process ctrl_proc;

  busy      <= pending or div_busy;
  ans_valid <= valid_r;
  ans_value <= std_logic_vector(ans_value_r);
  ans_rem   <= std_logic_vector(ans_rem_r);
  ans_ovf   <= ovf_r;

end architecture rtl;
