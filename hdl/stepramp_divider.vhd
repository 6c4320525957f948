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
  -- The radix-4 step's trial differences (G_DEN_WIDTH + 3 bits) are carry-select subtractors (stepramp_pkg's
  -- csel_sub), so that no borrow ripples through the whole width in the step (the divider's clock).
  constant C_TW : positive := G_DEN_WIDTH + 3;

  -- State encoding as constants (not an enum) so that GHDL's VPI shows it as a plain vector.
  constant C_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_ALIGN : std_logic_vector(1 downto 0) := "01";
  constant C_ITER  : std_logic_vector(1 downto 0) := "10";

  -- No bit pair selected (the select's AND-OR of the step is zero).
  constant C_NO_PAIR : std_logic_vector(C_PAIRS - 1 downto 0) := (others => '0');

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

begin

  assert G_WIDTH >= 3 and G_WIDTH <= 64
    report "stepramp_divider: G_WIDTH must be in 3 .. 64"
    severity failure;

  assert G_DEN_WIDTH >= 1 and G_DEN_WIDTH <= G_WIDTH
    report "stepramp_divider: G_DEN_WIDTH must be in 1 .. G_WIDTH"
    severity failure;

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

    variable pair : unsigned(1 downto 0);
    -- The selected pair's high and low bit, one place per pair (all zero but the selected one).
    variable hi_v : std_logic_vector(C_PAIRS - 1 downto 0);
    variable lo_v : std_logic_vector(C_PAIRS - 1 downto 0);
    -- 4 * remainder + pair, below 4 D, with one spare bit: the sign of the trial differences below.
    variable trial : unsigned(C_TW - 1 downto 0);
    variable d1    : unsigned(C_TW - 1 downto 0); -- trial - D
    variable d2    : unsigned(C_TW - 1 downto 0); -- trial - 2 D
    variable d3    : unsigned(C_TW - 1 downto 0); -- trial - 3 D

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
          pair := "00";

          for i in 0 to C_PAIRS - 1 loop

            if (to_unsigned(i, C_IDX_W - 1) = unsigned(num_msb(C_IDX_W - 1 downto 1))) then
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
          for i in 0 to C_PAIRS - 2 loop

            hi_v(i) := sel_r(i + 1) and num_r(2 * i + 1);
            lo_v(i) := sel_r(i + 1) and num_r(2 * i);

          end loop;

          hi_v(C_PAIRS - 1) := '0';
          lo_v(C_PAIRS - 1) := '0';

          pair := "00";
          if (hi_v /= C_NO_PAIR) then
            pair(1) := '1';
          end if;
          if (lo_v /= C_NO_PAIR) then
            pair(0) := '1';
          end if;
          pair_r <= pair;

          -- The three trial differences are three subtractors side by side in hardware; a simulator computes
          -- trial - 2 D only when 3 D does not fit, and trial - D only when 2 D does not either.
          trial := '0' & rem_r & pair_r;
          d3    := csel_sub(trial, '0' & den3_r);
          if (d3(G_DEN_WIDTH + 2) = '0') then
            rem_r <= d3(G_DEN_WIDTH - 1 downto 0);
            quo_r <= quo_r(G_WIDTH - 3 downto 0) & "11";
          else
            d2 := csel_sub(trial, "00" & den_r & '0');
            if (d2(G_DEN_WIDTH + 2) = '0') then
              rem_r <= d2(G_DEN_WIDTH - 1 downto 0);
              quo_r <= quo_r(G_WIDTH - 3 downto 0) & "10";
            else
              d1 := csel_sub(trial, "000" & den_r);
              if (d1(G_DEN_WIDTH + 2) = '0') then
                rem_r <= d1(G_DEN_WIDTH - 1 downto 0);
                quo_r <= quo_r(G_WIDTH - 3 downto 0) & "01";
              else
                rem_r <= trial(G_DEN_WIDTH - 1 downto 0);
                quo_r <= quo_r(G_WIDTH - 3 downto 0) & "00";
              end if;
            end if;
          end if;

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
