-- SPDX-License-Identifier: MIT
-- stepramp_next_delay_exact: the next-delay unit of the exact ramp arithmetic. It answers "what is the ramp value at
-- this index?" as root(C (x + 1)) - root(C x) (rounded square roots, on one stepramp_isqrt), C = m 4^e given as
-- a seed word (mantissa m, scale e), and continues a run of neighbouring indices with one square root per answer.
-- Ports, algorithm and latency: docs/stepramp_isqrt.md, "stepramp_next_delay_exact".

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_next_delay_exact is
  port (
    clk       : in    std_logic;
    rst       : in    std_logic;
    flush     : in    std_logic;
    req       : in    std_logic;
    req_seed  : in    std_logic;
    req_decel : in    std_logic;
    req_alt   : in    std_logic;
    req_index : in    std_logic_vector(30 downto 0);
    c_head    : in    std_logic_vector(63 downto 0);
    c_dec     : in    std_logic_vector(63 downto 0);
    busy      : out   std_logic;
    ans_valid : out   std_logic;
    ans_value : out   std_logic_vector(47 downto 0);
    ans_rem   : out   std_logic_vector(32 downto 0);
    ans_ovf   : out   std_logic
  );
end entity stepramp_next_delay_exact;

architecture rtl of stepramp_next_delay_exact is

  constant C_X_W : positive := 31;
  -- A seed word: the mantissa m in bits 59:0, the scale e in bits 63:60; C = m 4^e.
  constant C_C_W : positive := 60;
  -- The radicands are m x and m (x + 1) < 2^60 * 2^31: 91 bits; the square root takes bit pairs, and appends e zero
  -- pairs below them (at most C_E_MAX: the root of C x = m x 4^e).
  constant C_R_W   : positive := 92;
  constant C_E_MAX : natural  := 6;
  -- root(C (x + 1)) - root(C x) <= sqrt(C) + 1 / 2 + 1 / 2 < 2^36 + 1 (C < 2^72): the answer is at most 2^36, so
  -- 37 bits of each root give it exactly (the difference modulo 2^37); only those are kept.
  constant C_D_W : positive := 37;
  -- The roots are Q.4 ticks, the answer Q32.16.
  constant C_SHIFT : positive := 12;

  -- State encoding as constants (not an enum) so that GHDL's VPI shows it as a plain vector. Bit 0 is '1' in MUL
  -- only: the adder's doubling reads that flip-flop alone, one LUT level less in front of its carry chain.
  constant C_IDLE : std_logic_vector(2 downto 0) := "000";
  constant C_MUL  : std_logic_vector(2 downto 0) := "001"; -- C x, one bit of x per clock
  constant C_SQ1  : std_logic_vector(2 downto 0) := "010"; -- root(C x) of a fresh request
  constant C_CONT : std_logic_vector(2 downto 0) := "100"; -- a continued request's radicand
  constant C_SQ2  : std_logic_vector(2 downto 0) := "110"; -- the last (or only) root

  signal state   : std_logic_vector(2 downto 0);
  signal c_r     : unsigned(C_C_W - 1 downto 0);
  signal e_r     : std_logic_vector(3 downto 0);
  signal x_r     : unsigned(C_X_W - 1 downto 0);
  signal decel_r : std_logic;
  signal alt_r   : std_logic;
  signal cont_r  : std_logic;
  -- One-hot: the bit of x that the multiply step takes (its value in bit_r, fetched one clock ahead). Outside the
  -- multiply bit_r is '1': C enters the adder.
  signal sel_r : std_logic_vector(C_X_W - 1 downto 0);
  signal bit_r : std_logic;
  -- The adder subtracts C: a continued decel request.
  signal sub_r : std_logic;
  -- The working radicand: C x during the multiply, then the radicand of the request's last root.
  signal acc : unsigned(C_R_W - 1 downto 0);
  -- The other root of the answer (low C_D_W bits): the first root of a fresh request, the kept one of a continued.
  signal other_r : unsigned(C_D_W - 1 downto 0);

  -- The continuation state of the last request that was not an alternative: what the next index of the same kind
  -- needs, the radicand and root at the end of the pair it moves towards (accel: C (x + 1), decel: C x), the index
  -- that continues (x + 1 or x - 1, one bit wider so that 2^31 and -1 match no index) and the kind.
  signal kept_valid : std_logic;
  signal kept_decel : std_logic;
  signal kept_next  : unsigned(C_X_W downto 0);
  signal kept_rad   : unsigned(C_R_W - 1 downto 0);
  signal kept_root  : unsigned(C_D_W - 1 downto 0);

  signal ans_valid_r : std_logic;
  signal ans_r       : unsigned(C_D_W - 1 downto 0);

  signal busy_i   : std_logic;
  signal accept   : std_logic;
  signal cont     : std_logic;
  signal x_msb    : std_logic_vector(4 downto 0);
  signal x_zero   : std_logic;
  signal x_sel    : std_logic_vector(C_X_W - 1 downto 0);
  signal x_step   : unsigned(C_X_W downto 0);
  signal x_next   : unsigned(C_X_W downto 0);
  signal next_bit : std_logic;

  -- The one adder of the radicands (in units of 4^e: m x, m (x + 1)): acc * 2 + bit * m (multiply step), acc + m (the
  -- second root of a fresh request), acc +/- m (a continued request). The subtraction is acc + not m + 1, the + 1 the
  -- carry of an extra low bit. 92 bits in one carry chain would be the clock's path: a carry-select adder, the low
  -- C_SPLIT bits one chain, the bits above computed with and without the low part's carry, picked by it.
  constant C_SPLIT : positive := C_R_W / 2;

  signal add_a   : unsigned(C_R_W - 1 downto 0);
  signal c_op    : unsigned(C_C_W - 1 downto 0);           -- C, 0 or not C
  signal add_b   : unsigned(C_R_W - 1 downto 0);
  signal sum_lo  : unsigned(C_SPLIT + 1 downto 0);         -- the low bits & the extra low bit, and the carry out
  signal sum_hi0 : unsigned(C_R_W - C_SPLIT - 1 downto 0); -- the bits above without a carry from below
  signal sum_hi1 : unsigned(C_R_W - C_SPLIT - 1 downto 0); -- and with one
  signal rad     : unsigned(C_R_W - 1 downto 0);

  -- The answer root - other, or (a continued decel request: the root just computed is the lower one)
  -- other - root = not (root + not other): one adder, its carry in and an inversion picked by swap.
  signal swap     : std_logic;
  signal diff     : unsigned(C_D_W downto 0);
  signal ans_next : unsigned(C_D_W - 1 downto 0);

  signal sq_rst   : std_logic;
  signal sq_start : std_logic;
  signal sq_done  : std_logic;
  signal sq_root  : std_logic_vector(C_R_W / 2 + C_E_MAX downto 0);
  signal sq_low   : unsigned(C_D_W - 1 downto 0);

begin

  busy_i <= '0' when state = C_IDLE else
            '1';
  accept <= req and not busy_i and not flush;

  -- A request continues the kept run when it asks for the neighbouring index in the run's direction, of the same
  -- kind, and is neither a seed (a new run) nor an alternative (answered fresh, the run kept for later).
  -- (The index compare is the predefined "=" of std_logic_vector: kept_next is not reset, and numeric_std's "="
  -- would warn about it on every request until the first answer.)
  cont <= kept_valid and not req_seed and not req_alt and not (req_decel xor kept_decel) and
          to_sl(('0' & req_index) = std_logic_vector(kept_next));

  -- The multiply starts at x's top '1' (msb(x) + 1 steps; one step with bit 0 for x = 0), found on the request.
  x_enc_inst : entity work.stepramp_prio_enc
    generic map (
      G_WIDTH => C_X_W
    )
    port map (
      data  => req_index,
      index => x_msb,
      zero  => x_zero
    );

  x_sel_proc : process (x_msb) is
  begin

    for i in 0 to C_X_W - 1 loop

      x_sel(i) <= to_sl(to_unsigned(i, 5) = unsigned(x_msb));

    end loop;

  end process x_sel_proc;

  -- The next bit of x: an AND-OR of the one-hot select shifted by one (a register), not a multiplexer.
  next_bit_proc : process (sel_r, x_r) is

    variable any : std_logic;

  begin

    any := '0';

    for i in 0 to C_X_W - 2 loop

      any := any or (sel_r(i + 1) and x_r(i));

    end loop;

    next_bit <= any;

  end process next_bit_proc;

  -- Only the multiply doubles acc (state(0): MUL); C enters every step but a multiply step on a '0' bit.
  add_a   <= acc(C_R_W - 2 downto 0) & '0' when state(0) = '1' else
             acc;
  c_op    <= (c_r and (C_C_W - 1 downto 0 => bit_r)) xor (C_C_W - 1 downto 0 => sub_r);
  add_b   <= (C_R_W - 1 downto C_C_W => sub_r) & c_op;
  sum_lo  <= ('0' & add_a(C_SPLIT - 1 downto 0) & '1') + ('0' & add_b(C_SPLIT - 1 downto 0) & sub_r);
  sum_hi0 <= add_a(C_R_W - 1 downto C_SPLIT) + add_b(C_R_W - 1 downto C_SPLIT);
  sum_hi1 <= add_a(C_R_W - 1 downto C_SPLIT) + add_b(C_R_W - 1 downto C_SPLIT) + 1;
  rad     <= sum_hi1 & sum_lo(C_SPLIT downto 1) when sum_lo(C_SPLIT + 1) = '1' else
             sum_hi0 & sum_lo(C_SPLIT downto 1);

  -- The square root samples the adder's result: at the last multiply step (C x), in the first root's done cycle
  -- (C x + C), and in CONT (the kept radicand +/- C). flush drops a root in flight.
  sq_start <= '1' when (state = C_MUL and sel_r(0) = '1') or (state = C_SQ1 and sq_done = '1') or state = C_CONT else
              '0';
  sq_rst   <= rst or flush;

  isqrt_inst : entity work.stepramp_isqrt
    generic map (
      G_WIDTH => C_R_W,
      G_EXTRA => C_E_MAX
    )
    port map (
      clk      => clk,
      rst      => sq_rst,
      start    => sq_start,
      radicand => std_logic_vector(rad),
      extra    => e_r,
      busy     => open,
      done     => sq_done,
      root     => sq_root
    );

  sq_low   <= unsigned(sq_root(C_D_W - 1 downto 0));
  swap     <= cont_r and decel_r;
  diff     <= (sq_low & '1') + (not other_r & not swap);
  ans_next <= diff(C_D_W downto 1) xor (C_D_W - 1 downto 0 => swap);

  -- The index that continues the run after this request: x + 1 (accel) or x - 1 (decel), x - 1 = x + all ones.
  x_step <= (C_X_W downto 1 => decel_r) & '1';
  x_next <= ('0' & x_r) + x_step;

  ctrl_proc : process (clk) is
  begin

    if rising_edge(clk) then
      ans_valid_r <= '0';

      if (rst = '1' or flush = '1') then
        -- Nothing in flight survives, and the kept run is forgotten: the next request is fresh.
        state      <= C_IDLE;
        kept_valid <= '0';
      else

        case state is

          when C_IDLE =>

            if (accept = '1') then
              if (req_decel = '1') then
                c_r <= unsigned(c_dec(C_C_W - 1 downto 0));
                e_r <= c_dec(63 downto C_C_W);
              else
                c_r <= unsigned(c_head(C_C_W - 1 downto 0));
                e_r <= c_head(63 downto C_C_W);
              end if;
              x_r     <= unsigned(req_index);
              decel_r <= req_decel;
              alt_r   <= req_alt;
              cont_r  <= cont;
              sub_r   <= cont and req_decel;
              if (cont = '1') then
                acc     <= kept_rad;
                other_r <= kept_root;
                bit_r   <= '1';
                state   <= C_CONT;
              else
                acc   <= (others => '0');
                sel_r <= x_sel;
                bit_r <= not x_zero;
                state <= C_MUL;
              end if;
            end if;

          when C_MUL =>

            acc   <= rad;
            bit_r <= next_bit;
            sel_r <= '0' & sel_r(C_X_W - 1 downto 1);
            if (sel_r(0) = '1') then
              bit_r <= '1';
              state <= C_SQ1;
            end if;

          when C_SQ1 =>

            -- root(C x) is done; root(C x + C) starts. The run keeps C (x + 1) after an accel request, C x after a
            -- decel one (its root is this one: kept now, valid only with the answer).
            if (sq_done = '1') then
              other_r <= sq_low;
              if (decel_r = '0') then
                acc <= rad;
              elsif (alt_r = '0') then
                kept_root <= sq_low;
              end if;
              state <= C_SQ2;
            end if;

          when C_CONT =>

            acc   <= rad;
            state <= C_SQ2;

          when C_SQ2 =>

            if (sq_done = '1') then
              ans_r       <= ans_next;
              ans_valid_r <= '1';
              state       <= C_IDLE;
              if (alt_r = '0') then
                kept_valid <= '1';
                kept_decel <= decel_r;
                kept_next  <= x_next;
                kept_rad   <= acc;
                if (decel_r = '0' or cont_r = '1') then
                  kept_root <= sq_low;
                end if;
              end if;
            end if;

          when others =>

            state <= C_IDLE;

        end case;

      end if;

      if (rst = '1') then
        ans_r <= (others => '0');
      end if;
    end if;

  end process ctrl_proc;

  busy      <= busy_i;
  ans_valid <= ans_valid_r;
  ans_value <= std_logic_vector(shift_left(resize(ans_r(C_D_W - 2 downto 0), 48), C_SHIFT));
  -- Exact: no remainder. An answer of 2^36 Q.4 ticks or more does not fit Q32.16 (only x = 0 with C above
  -- 2^72 - 2^36, which the driver never writes).
  ans_rem <= (others => '0');
  ans_ovf <= ans_r(C_D_W - 1);

end architecture rtl;
