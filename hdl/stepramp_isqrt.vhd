-- SPDX-License-Identifier: MIT
-- stepramp_isqrt: iterative integer square root, rounded to the nearest integer, that starts at the radicand's most
-- significant bit pair (floor(msb(R) / 2) + 1 root bits, one per clock, no barrel shifter), optionally of R with
-- zero pairs appended below it (root(R 4^e), one clock per pair). Ports, algorithm and latency:
-- docs/stepramp_isqrt.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_isqrt is
  generic (
    G_WIDTH : positive := 80;
    -- The most zero pairs that can be appended below the radicand (the root of R 4^e, e = min(extra, G_EXTRA)).
    G_EXTRA : natural := 0
  );
  port (
    clk      : in    std_logic;
    rst      : in    std_logic;
    start    : in    std_logic;
    radicand : in    std_logic_vector(G_WIDTH - 1 downto 0);
    -- e, sampled with start: zero pairs appended below the radicand (values above G_EXTRA are taken as G_EXTRA).
    extra : in    std_logic_vector(3 downto 0);
    busy  : out   std_logic;
    done  : out   std_logic;
    -- One bit more than G_WIDTH / 2 + G_EXTRA: rounding can carry to 2^(G_WIDTH / 2 + G_EXTRA).
    root : out   std_logic_vector(G_WIDTH / 2 + G_EXTRA downto 0)
  );
end entity stepramp_isqrt;

architecture rtl of stepramp_isqrt is

  -- Bit pairs of the radicand. The iteration runs on 4 R (one zero pair more below them): its root t = isqrt(4 R)
  -- is 2 s + b, s = isqrt(R) and b = '1' exactly when R - s^2 > s, so the rounding decision is one more ordinary
  -- iteration and the rounded root (t + 1) / 2 = s + b one increment.
  constant C_PAIRS : positive := G_WIDTH / 2;
  constant C_IDX_W : positive := clog2(C_PAIRS);
  -- The root t < 2^(C_PAIRS + G_EXTRA + 1), and the remainder after a pair of the radicand or an appended zero pair
  -- is at most 2 s < 2^(C_PAIRS + G_EXTRA + 1) (the remainder after the last zero pair is not kept: only its sign
  -- is used).
  constant C_RW : positive := C_PAIRS + G_EXTRA + 1;
  -- The trial 4 rem + pair - (4 t + 1): both operands below 2^(C_RW + 2), one sign bit above them; a carry-select
  -- subtractor (stepramp_pkg's csel_sub's structure), as in the divider.
  constant C_TW : positive := C_RW + 3;
  -- The subtractor's split: a low part of C_LO bits, whose borrow picks the high part (C_HI bits) computed without
  -- and with it. Up to 60 bits (G_WIDTH / 2 + G_EXTRA <= 56) the parts are integers in the iteration (GHDL evaluates
  -- an integer in a few instructions, a vector bit by bit), converted from and to the registers' bits, which is
  -- wiring in hardware; wider, csel_sub itself (C_LO and C_HI are then 1, unused).
  constant C_INT : boolean := C_TW <= 60;

  function int_part (
    bits : positive
  ) return positive is
  begin

    if (C_INT) then
      return bits;
    end if;

    return 1;

  end function int_part;

  constant C_LO : positive := int_part((C_TW + 1) / 2);
  constant C_HI : positive := int_part(C_TW - (C_TW + 1) / 2);

  -- State encoding as constants (not an enum) so that GHDL's VPI shows it as a plain vector.
  constant C_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_ALIGN : std_logic_vector(1 downto 0) := "01";
  constant C_ITER  : std_logic_vector(1 downto 0) := "10";
  constant C_ROUND : std_logic_vector(1 downto 0) := "11";

  signal state : std_logic_vector(1 downto 0);
  signal rad_r : unsigned(G_WIDTH - 1 downto 0);
  signal rem_r : unsigned(C_RW - 1 downto 0);
  -- The root so far (t), then, after the increment, the rounded root.
  signal root_r : unsigned(C_RW - 1 downto 0);
  -- One-hot: the pair this iteration takes, of the pairs of 4 R and one zero pair above (pair 0 is the zero pair
  -- below the radicand, pair i + 1 the radicand's pair i). Shifted down one place per iteration: the last
  -- iteration is the one with bit 0 set.
  signal sel_r : std_logic_vector(C_PAIRS + 1 downto 0);
  -- The selected pair, fetched one clock ahead so that the AND-OR that picks it is off the subtractor's path.
  signal pair_r : unsigned(1 downto 0);
  -- The appended zero pairs still to come: the iteration stays on pair 0 (a zero pair) until they are done.
  signal ext_r  : unsigned(3 downto 0);
  signal done_r : std_logic;
  -- Which pairs hold a '1': the priority encoder then gives the top pair's index directly, at half the width.
  signal pair_any : std_logic_vector(C_PAIRS - 1 downto 0);
  signal top_pair : std_logic_vector(C_IDX_W - 1 downto 0);
  signal rad_zero : std_logic;
  -- The radicand's bits 2 j + 1 and 2 j at place j + 2 of the select (wires: the pairs' high and low bits).
  signal rad_odd  : std_logic_vector(C_PAIRS + 1 downto 0);
  signal rad_even : std_logic_vector(C_PAIRS + 1 downto 0);

begin

  assert G_WIDTH >= 4 and G_WIDTH <= 128 and G_WIDTH mod 2 = 0
    report "stepramp_isqrt: G_WIDTH must be even and in 4 .. 128"
    severity failure;

  assert G_EXTRA <= 15
    report "stepramp_isqrt: G_EXTRA must be in 0 .. 15"
    severity failure;

  pairs_gen : for i in 0 to C_PAIRS - 1 generate
    pair_any(i)     <= rad_r(2 * i + 1) or rad_r(2 * i);
    rad_odd(i + 2)  <= rad_r(2 * i + 1);
    rad_even(i + 2) <= rad_r(2 * i);
  end generate pairs_gen;

  rad_odd(1 downto 0)  <= "00";
  rad_even(1 downto 0) <= "00";

  pair_enc_inst : entity work.stepramp_prio_enc
    generic map (
      G_WIDTH => C_PAIRS
    )
    port map (
      data  => pair_any,
      index => top_pair,
      zero  => rad_zero
    );

  sqrt_proc : process (clk) is

    variable sel   : std_logic_vector(C_PAIRS + 1 downto 0);
    variable first : natural range 0 to 2 ** C_IDX_W - 1;
    -- The next pair's high and low bit, one place per pair (all zero but the selected one).
    variable hi_v : std_logic_vector(C_PAIRS + 1 downto 0);
    variable lo_v : std_logic_vector(C_PAIRS + 1 downto 0);
    -- The trial 4 rem + pair and 4 t + 1, one spare bit above them: the sign of the difference.
    variable trial : unsigned(C_TW - 1 downto 0);
    variable sub   : unsigned(C_TW - 1 downto 0);
    variable d     : unsigned(C_TW - 1 downto 0);
    variable fits  : boolean; -- (unused: the difference's top bit is its sign)

  begin

    if rising_edge(clk) then
      done_r <= '0';

      case state is

        when C_IDLE =>

          if (start = '1') then
            rad_r <= unsigned(radicand);
            if (unsigned(extra) > G_EXTRA) then
              ext_r <= to_unsigned(G_EXTRA, 4);
            else
              ext_r <= unsigned(extra);
            end if;
            state <= C_ALIGN;
          end if;

        when C_ALIGN =>

          -- Start at the pair that holds the radicand's top bit: the root has no '1' above that pair's, and the
          -- remainder and root are 0 until it. The select starts one pair higher, at a zero pair, whose iteration
          -- changes nothing (0 - 1 < 0) and fetches the top pair through the AND-OR: a clock instead of a
          -- multiplexer over all pairs decoded from the index (85 LUT4 at 80 bits).
          sel   := (others => '0');
          first := to_integer(unsigned(top_pair));

          for i in 0 to C_PAIRS - 1 loop

            if (i = first) then
              sel(i + 2) := '1';
            end if;

          end loop;

          sel_r  <= sel;
          pair_r <= "00";
          rem_r  <= (others => '0');
          root_r <= (others => '0');
          if (rad_zero = '1') then
            done_r <= '1';
            state  <= C_IDLE;
          else
            state <= C_ITER;
          end if;

        when C_ITER =>

          -- One root bit per clock (restoring): the trial 4 rem + pair - (4 t + 1) fits when it is not negative.
          -- The next pair comes through an AND-OR of the one-hot select (a register), not a multiplexer decoded
          -- from a counter; the zero pair below the radicand has no term.
          hi_v := sel_r and rad_odd;
          lo_v := sel_r and rad_even;

          pair_r <= any(hi_v) & any(lo_v);

          -- A carry-select subtractor in hardware (both high parts side by side); a simulator computes only the high
          -- part the low part's borrow picks.
          trial := '0' & rem_r & pair_r;
          sub   := '0' & root_r & "01";
          if (C_INT) then
            csel_sub_int(to_integer(trial(C_LO - 1 downto 0)), to_integer(trial(C_LO + C_HI - 1 downto C_LO)),
                         to_integer(sub(C_LO - 1 downto 0)), to_integer(sub(C_LO + C_HI - 1 downto C_LO)),
                         to_integer(not sub(C_LO + C_HI - 1 downto C_LO)), C_LO, C_HI, d, fits);
          else
            d := csel_sub(trial, sub);
          end if;

          if (d(C_TW - 1) = '0') then
            rem_r  <= d(C_RW - 1 downto 0);
            root_r <= root_r(C_RW - 2 downto 0) & '1';
          else
            rem_r  <= rem_r(C_RW - 3 downto 0) & pair_r;
            root_r <= root_r(C_RW - 2 downto 0) & '0';
          end if;

          -- On pair 0 the select stays: the appended zero pairs (ext_r of them) and then the last zero pair, whose
          -- trial decides the rounding.
          if (sel_r(0) = '1') then
            if (ext_r = 0) then
              state <= C_ROUND;
            else
              ext_r <= ext_r - 1;
            end if;
          else
            sel_r <= '0' & sel_r(C_PAIRS + 1 downto 1);
          end if;

        when C_ROUND =>

          -- t = 2 s + b: the rounded root is s + b.
          root_r <= shift_right(root_r, 1) + root_r(0 downto 0);
          done_r <= '1';
          state  <= C_IDLE;

        when others =>

          state <= C_IDLE;

      end case;

      if (rst = '1') then
        state  <= C_IDLE;
        done_r <= '0';
        root_r <= (others => '0');
      end if;
    end if;

  end process sqrt_proc;

  busy <= '0' when state = C_IDLE else
          '1';
  done <= done_r;
  root <= std_logic_vector(root_r);

end architecture rtl;
