-- SPDX-License-Identifier: MIT
-- stepramp_divider: iterative unsigned radix-4 divider that starts at the numerator's most significant bit pair
-- (floor(msb(N) / 2) + 1 iterations, no barrel shifter). Ports, latency and timing: docs/stepramp_divider.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_divider is
  generic (
    G_WIDTH     : positive := 32;
    G_DEN_WIDTH : positive := 32
  );
  port (
    clk         : in    std_logic;
    rst         : in    std_logic;
    start       : in    std_logic;
    numerator   : in    std_logic_vector(G_WIDTH - 1 downto 0);
    denominator : in    std_logic_vector(G_DEN_WIDTH - 1 downto 0);
    busy        : out   std_logic;
    done        : out   std_logic;
    div_zero    : out   std_logic;
    quotient    : out   std_logic_vector(G_WIDTH - 1 downto 0);
    remainder   : out   std_logic_vector(G_DEN_WIDTH - 1 downto 0)
  );
end entity stepramp_divider;

architecture rtl of stepramp_divider is

  constant C_IDX_W : positive := clog2(G_WIDTH);
  -- The numerator as bit pairs: padded to an even width.
  constant C_PAIRS : positive := (G_WIDTH + 1) / 2;
  -- The radix-4 step's trial differences (G_DEN_WIDTH + 3 bits) are carry-select subtractors (as
  -- stepramp_pkg's csel_sub_int), so that no borrow ripples through the whole width in the step (the divider's clock).
  constant C_TW : positive := G_DEN_WIDTH + 3;
  -- The subtractors' split: a low part of C_LO bits, whose borrow picks the high part (C_HI bits) computed without
  -- and with it. The parts are integers in the step (GHDL evaluates an integer in a few instructions, a vector bit
  -- by bit), converted from and to the registers' bits, which is wiring in hardware.
  constant C_LO : positive := (C_TW + 1) / 2;
  constant C_HI : positive := C_TW - C_LO;

  -- State encoding as constants (not an enum) so that GHDL's VPI shows it as a plain vector.
  constant C_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_ALIGN : std_logic_vector(1 downto 0) := "01";
  constant C_ITER  : std_logic_vector(1 downto 0) := "10";

  signal state  : std_logic_vector(1 downto 0);
  signal num_r  : unsigned(2 * C_PAIRS - 1 downto 0);
  signal den_r  : unsigned(G_DEN_WIDTH - 1 downto 0);
  signal den3_r : unsigned(G_DEN_WIDTH + 1 downto 0); -- 3 D
  signal rem_r  : unsigned(G_DEN_WIDTH - 1 downto 0);
  signal quo_r  : unsigned(G_WIDTH - 1 downto 0);
  -- One-hot: the bit pair this iteration takes (the last iteration takes pair 0).
  signal sel_r : std_logic_vector(C_PAIRS - 1 downto 0);
  -- The selected bit pair, fetched one clock ahead so that the AND-OR that picks it is off the subtractors' path.
  signal pair_r   : unsigned(1 downto 0);
  signal done_r   : std_logic;
  signal dz_r     : std_logic;
  signal num_msb  : std_logic_vector(C_IDX_W - 1 downto 0);
  signal num_zero : std_logic;
  -- The numerator's bits 2 i + 1 and 2 i at place i (wires: the pairs' high and low bits).
  signal num_odd  : std_logic_vector(C_PAIRS - 1 downto 0);
  signal num_even : std_logic_vector(C_PAIRS - 1 downto 0);
  -- D, 2 D and 3 D split as the trial is: the low part, the high part and its complement (not d = 2 ** C_HI - 1 - d:
  -- trial - d - 1 is trial + not d less 2 ** C_HI). Wires from den_r and den3_r, which change once per division.
  signal d1   : unsigned(C_TW - 1 downto 0);
  signal d2   : unsigned(C_TW - 1 downto 0);
  signal d3   : unsigned(C_TW - 1 downto 0);
  signal d1_l : natural range 0 to 2 ** C_LO - 1;
  signal d2_l : natural range 0 to 2 ** C_LO - 1;
  signal d3_l : natural range 0 to 2 ** C_LO - 1;
  signal d1_h : natural range 0 to 2 ** C_HI - 1;
  signal d2_h : natural range 0 to 2 ** C_HI - 1;
  signal d3_h : natural range 0 to 2 ** C_HI - 1;
  signal d1_n : natural range 0 to 2 ** C_HI - 1;
  signal d2_n : natural range 0 to 2 ** C_HI - 1;
  signal d3_n : natural range 0 to 2 ** C_HI - 1;

begin

  assert G_WIDTH >= 3 and G_WIDTH <= 64
    report "stepramp_divider: G_WIDTH must be in 3 .. 64"
    severity failure;

  -- (At most 57: the step's parts, C_LO and C_HI bits, and their sums fit an integer.)
  assert G_DEN_WIDTH >= 1 and G_DEN_WIDTH <= G_WIDTH and G_DEN_WIDTH <= 57
    report "stepramp_divider: G_DEN_WIDTH must be in 1 .. G_WIDTH and at most 57"
    severity failure;

  pairs_proc : process (num_r) is
  begin

    for i in 0 to C_PAIRS - 1 loop

      num_odd(i)  <= num_r(2 * i + 1);
      num_even(i) <= num_r(2 * i);

    end loop;

  end process pairs_proc;

  d1   <= "000" & den_r;
  d2   <= "00" & den_r & '0';
  d3   <= '0' & den3_r;
  d1_l <= to_integer(d1(C_LO - 1 downto 0));
  d2_l <= to_integer(d2(C_LO - 1 downto 0));
  d3_l <= to_integer(d3(C_LO - 1 downto 0));
  d1_h <= to_integer(d1(C_TW - 1 downto C_LO));
  d2_h <= to_integer(d2(C_TW - 1 downto C_LO));
  d3_h <= to_integer(d3(C_TW - 1 downto C_LO));
  d1_n <= to_integer(not d1(C_TW - 1 downto C_LO));
  d2_n <= to_integer(not d2(C_TW - 1 downto C_LO));
  d3_n <= to_integer(not d3(C_TW - 1 downto C_LO));

  num_enc_inst : entity work.stepramp_prio_enc
    generic map (
      G_WIDTH => G_WIDTH
    )
    port map (
      data  => std_logic_vector(num_r(G_WIDTH - 1 downto 0)),
      index => num_msb,
      zero  => num_zero
    );

  div_proc : process (clk) is

    variable pair  : unsigned(1 downto 0);
    variable first : natural range 0 to 2 ** (C_IDX_W - 1) - 1;
    -- The selected pair's high and low bit, one place per pair (all zero but the selected one).
    variable hi_v : std_logic_vector(C_PAIRS - 1 downto 0);
    variable lo_v : std_logic_vector(C_PAIRS - 1 downto 0);
    -- 4 * remainder + pair, below 4 D, with one spare bit: the sign of the trial differences below.
    variable trial : unsigned(C_TW - 1 downto 0);
    variable t_lo  : natural range 0 to 2 ** C_LO - 1;
    variable t_hi  : natural range 0 to 2 ** C_HI - 1;
    -- trial - m D (stepramp_pkg's csel_sub_int): whether m D fits, and the difference.
    variable fits : boolean;
    variable diff : unsigned(C_TW - 1 downto 0);

  begin

    if rising_edge(clk) then
      done_r <= '0';

      case state is

        when C_IDLE =>

          if (start = '1') then
            num_r <= resize(unsigned(numerator), 2 * C_PAIRS);
            den_r <= unsigned(denominator);
            dz_r  <= '0';
            state <= C_ALIGN;
          end if;

        when C_ALIGN =>

          rem_r                                                <= (others => '0');
          quo_r                                                <= (others => '0');
          sel_r                                                <= (others => '0');
          sel_r(to_integer(shift_right(unsigned(num_msb), 1))) <= '1';
          -- The first pair: the one that holds the numerator's top bit (an AND-OR over the pairs, like the steps').
          pair  := "00";
          first := to_integer(unsigned(num_msb(C_IDX_W - 1 downto 1)));

          for i in 0 to C_PAIRS - 1 loop

            if (i = first) then
              pair := pair or num_r(2 * i + 1 downto 2 * i);
            end if;

          end loop;

          pair_r <= pair;
          den3_r <= ('0' & den_r & '0') + ("00" & den_r);
          if (den_r = 0) then
            quo_r  <= (others => '1');
            rem_r  <= num_r(G_DEN_WIDTH - 1 downto 0);
            dz_r   <= '1';
            done_r <= '1';
            state  <= C_IDLE;
          elsif (num_zero = '1') then
            done_r <= '1';
            state  <= C_IDLE;
          else
            state <= C_ITER;
          end if;

        when C_ITER =>

          -- One radix-4 step per clock, from the selected bit pair down to pair 0: the largest of 3 D, 2 D, D that
          -- fits. The pair of the next step comes through an AND-OR of the one-hot select shifted by one (a
          -- register), not a multiplexer decoded from a counter, and is registered in pair_r.
          hi_v := ('0' & sel_r(C_PAIRS - 1 downto 1)) and num_odd;
          lo_v := ('0' & sel_r(C_PAIRS - 1 downto 1)) and num_even;

          pair_r <= any(hi_v) & any(lo_v);

          -- The three trial differences are three subtractors side by side in hardware; a simulator computes
          -- trial - 2 D only when 3 D does not fit, and trial - D only when 2 D does not either.
          trial := '0' & rem_r & pair_r;
          t_lo  := to_integer(trial(C_LO - 1 downto 0));
          t_hi  := to_integer(trial(C_TW - 1 downto C_LO));
          csel_sub_int(t_lo, t_hi, d3_l, d3_h, d3_n, C_LO, C_HI, diff, fits);
          if (fits) then
            quo_r <= quo_r(G_WIDTH - 3 downto 0) & "11";
          else
            csel_sub_int(t_lo, t_hi, d2_l, d2_h, d2_n, C_LO, C_HI, diff, fits);
            if (fits) then
              quo_r <= quo_r(G_WIDTH - 3 downto 0) & "10";
            else
              csel_sub_int(t_lo, t_hi, d1_l, d1_h, d1_n, C_LO, C_HI, diff, fits);
              if (fits) then
                quo_r <= quo_r(G_WIDTH - 3 downto 0) & "01";
              else
                -- (nothing fits: the trial, below D, is the remainder)
                diff  := trial;
                quo_r <= quo_r(G_WIDTH - 3 downto 0) & "00";
              end if;
            end if;
          end if;
          rem_r <= diff(G_DEN_WIDTH - 1 downto 0);

          if (sel_r(0) = '1') then
            done_r <= '1';
            state  <= C_IDLE;
          else
            sel_r <= '0' & sel_r(C_PAIRS - 1 downto 1);
          end if;

        when others =>

          state <= C_IDLE;

      end case;

      if (rst = '1') then
        state  <= C_IDLE;
        done_r <= '0';
        dz_r   <= '0';
        quo_r  <= (others => '0');
        rem_r  <= (others => '0');
      end if;
    end if;

  end process div_proc;

  busy      <= '0' when state = C_IDLE else
               '1';
  done      <= done_r;
  div_zero  <= dz_r;
  quotient  <= std_logic_vector(quo_r);
  remainder <= std_logic_vector(rem_r);

end architecture rtl;
