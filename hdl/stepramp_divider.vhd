-- SPDX-License-Identifier: MIT
-- stepramp_divider: iterative unsigned divider, operands aligned by two priority encoders.
--
-- A restoring divider normally runs G_WIDTH iterations. Here the divisor is first shifted left so that its
-- most significant '1' lines up with the numerator's (the shift comes from two priority encoders), so only
-- msb(N) - msb(D) + 1 iterations are needed. The ramp's quotients are small, so a division usually takes a
-- handful of cycles.
--
-- Latency, from the rising edge that samples start to the rising edge that raises done:
--   1                           when D = 0 (div_zero = '1'), or msb(N) < msb(D) (N < D: quotient 0, remainder N;
--                               also N = 0)
--   1 + msb(N) - msb(D) + 1     otherwise (at most G_WIDTH + 1; N < D with msb(N) = msb(D) takes this path: 2)
-- The alignment compares only the two msb indices (no wide comparator), and each iteration is one subtraction whose
-- borrow decides the quotient bit.
-- start is sampled only when busy = '0'. done is a one-cycle strobe; quotient, remainder and div_zero are valid
-- from done on and held until the next start. On D = 0: quotient all ones, remainder = N.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_divider is
  generic (
    G_WIDTH : positive := 32
  );
  port (
    clk         : in    std_logic;
    rst         : in    std_logic;
    start       : in    std_logic;
    numerator   : in    std_logic_vector(G_WIDTH - 1 downto 0);
    denominator : in    std_logic_vector(G_WIDTH - 1 downto 0);
    busy        : out   std_logic;
    done        : out   std_logic;
    div_zero    : out   std_logic;
    quotient    : out   std_logic_vector(G_WIDTH - 1 downto 0);
    remainder   : out   std_logic_vector(G_WIDTH - 1 downto 0)
  );
end entity stepramp_divider;

architecture rtl of stepramp_divider is

  constant C_IDX_W : positive := clog2(G_WIDTH);

  -- State encoding as constants (not an enum) so that GHDL's VPI shows it as a plain vector.
  constant C_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_ALIGN : std_logic_vector(1 downto 0) := "01";
  constant C_ITER  : std_logic_vector(1 downto 0) := "10";

  signal state    : std_logic_vector(1 downto 0);
  signal num_r    : unsigned(G_WIDTH - 1 downto 0);
  signal den_r    : unsigned(G_WIDTH - 1 downto 0);
  signal rem_r    : unsigned(G_WIDTH - 1 downto 0);
  signal dsh_r    : unsigned(G_WIDTH - 1 downto 0);
  signal quo_r    : unsigned(G_WIDTH - 1 downto 0);
  signal cnt_r    : unsigned(C_IDX_W - 1 downto 0);
  signal done_r   : std_logic;
  signal dz_r     : std_logic;
  signal num_msb  : std_logic_vector(C_IDX_W - 1 downto 0);
  signal den_msb  : std_logic_vector(C_IDX_W - 1 downto 0);
  signal num_zero : std_logic;
  signal den_zero : std_logic;

begin

  assert G_WIDTH >= 2 and G_WIDTH <= 64
    report "stepramp_divider: G_WIDTH must be in 2 .. 64"
    severity failure;

  num_enc_inst : entity work.stepramp_prio_enc
    generic map (
      G_WIDTH => G_WIDTH
    )
    port map (
      din   => std_logic_vector(num_r),
      index => num_msb,
      zero  => num_zero
    );

  den_enc_inst : entity work.stepramp_prio_enc
    generic map (
      G_WIDTH => G_WIDTH
    )
    port map (
      din   => std_logic_vector(den_r),
      index => den_msb,
      zero  => den_zero
    );

  div_proc : process (clk) is

    variable shift : unsigned(C_IDX_W - 1 downto 0);
    variable diff  : unsigned(G_WIDTH downto 0);

  begin

    if rising_edge(clk) then
      done_r <= '0';

      case state is

        when C_IDLE =>

          if (start = '1') then
            num_r <= unsigned(numerator);
            den_r <= unsigned(denominator);
            dz_r  <= '0';
            state <= C_ALIGN;
          end if;

        when C_ALIGN =>

          if (den_zero = '1') then
            quo_r  <= (others => '1');
            rem_r  <= num_r;
            dz_r   <= '1';
            done_r <= '1';
            state  <= C_IDLE;
          elsif (num_zero = '1' or unsigned(num_msb) < unsigned(den_msb)) then
            -- N < D (also N = 0): nothing to iterate.
            quo_r  <= (others => '0');
            rem_r  <= num_r;
            done_r <= '1';
            state  <= C_IDLE;
          else
            -- msb(N) >= msb(D) (D > 0), so the shifted divisor still fits in G_WIDTH bits.
            shift := unsigned(num_msb) - unsigned(den_msb);
            dsh_r <= shift_left(den_r, to_integer(shift));
            rem_r <= num_r;
            quo_r <= (others => '0');
            cnt_r <= shift;
            state <= C_ITER;
          end if;

        when C_ITER =>

          -- One restoring step per clock, from the aligned position down to bit 0: the borrow of rem - dsh decides.
          diff := ('0' & rem_r) - ('0' & dsh_r);
          if (diff(G_WIDTH) = '0') then
            rem_r <= diff(G_WIDTH - 1 downto 0);
            quo_r <= quo_r(G_WIDTH - 2 downto 0) & '1';
          else
            quo_r <= quo_r(G_WIDTH - 2 downto 0) & '0';
          end if;

          dsh_r <= shift_right(dsh_r, 1);

          if (cnt_r = 0) then
            done_r <= '1';
            state  <= C_IDLE;
          else
            cnt_r <= cnt_r - 1;
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
