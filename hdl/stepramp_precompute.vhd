-- SPDX-License-Identifier: MIT
-- stepramp_precompute: the ramp engine's precompute. While an interval counts down in the sequencer
-- (stepramp_engine), it keeps the next two ready (nxt_* and a second slot behind it) and, when a soft stop request
-- is armed, the soft-stop alternative of the pulse that decides it (alt_*).
-- Ports, timing and latency budget: docs/stepramp_engine.md, "stepramp_precompute" and "Latency budget".

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;
  use work.stepramp_regs_pkg.all;

entity stepramp_precompute is
  generic (
    G_DIV_WIDTH : positive := 50;
    -- The ramp arithmetic: 0 the AVR446 recurrence, 1 the exact ramp (docs/algorithm.md, "Exact step times").
    G_RAMP : natural := 0
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Control strobes from the sequencer.
    latch      : in    std_logic;
    begin_move : in    std_logic;
    setup      : in    std_logic;
    -- A take-over (with latch): the segment's interval 1 is prepared next, from c_first and the fraction carried.
    take     : in    std_logic;
    advance  : in    std_logic;
    take_alt : in    std_logic;
    finish   : in    std_logic;
    -- A soft stop request is armed: it is decided at the pulse that ends the interval now counting, so that
    -- pulse's alternative is prepared (without one, none is: docs/algorithm.md, "Soft stop").
    stop_armed : in    std_logic;
    -- The move (the engine's active copy).
    l          : in    std_logic_vector(30 downto 0);
    sa         : in    std_logic_vector(30 downto 0);
    sd         : in    std_logic_vector(30 downto 0);
    c_first    : in    std_logic_vector(47 downto 0);
    c_last     : in    std_logic_vector(47 downto 0);
    c_sa       : in    std_logic_vector(47 downto 0);
    c_sd       : in    std_logic_vector(47 downto 0);
    accel_seed : in    std_logic_vector(63 downto 0);
    -- Taken at latch, like c_first and accel_seed (the segment's head: docs/algorithm.md, "Changes while moving").
    head_index : in    std_logic_vector(30 downto 0);
    head_prod  : in    std_logic_vector(47 downto 0);
    decel_seed : in    std_logic_vector(63 downto 0);
    cruise     : in    std_logic_vector(63 downto 0);
    stop_ratio : in    std_logic_vector(31 downto 0);
    -- The rest of the segment: all 0 for a move from rest to rest.
    head_down : in    std_logic;
    endless   : in    std_logic;
    run_stop  : in    std_logic_vector(30 downto 0);
    -- The next interval, ready to be copied at the pulse edge.
    nxt_ok    : out   std_logic;
    nxt_d     : out   std_logic_vector(32 downto 0);
    nxt_state : out   std_logic_vector(1 downto 0);
    nxt_last  : out   std_logic;
    nxt_code  : out   std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    -- The soft-stop alternative of the next interval, and whether a soft stop is in effect.
    alt_ok    : out   std_logic;
    alt_kind  : out   std_logic_vector(1 downto 0);
    alt_d     : out   std_logic_vector(32 downto 0);
    alt_one   : out   std_logic;
    alt_code  : out   std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    stop_mode : out   std_logic
  );
end entity stepramp_precompute;

architecture rtl of stepramp_precompute is

  -- Ramp phases of an interval (the same encoding as the engine's state port).
  constant C_ST_ACCEL : std_logic_vector(1 downto 0) := "01";
  constant C_ST_RUN   : std_logic_vector(1 downto 0) := "10";
  constant C_ST_DECEL : std_logic_vector(1 downto 0) := "11";

  -- Precompute of the next interval (constants, not an enum, so that GHDL's VPI shows a plain vector).
  constant C_PC_IDLE   : std_logic_vector(2 downto 0) := "000";
  constant C_PC_TAKE   : std_logic_vector(2 downto 0) := "001";
  constant C_PC_DECIDE : std_logic_vector(2 downto 0) := "010";
  constant C_PC_WAIT   : std_logic_vector(2 downto 0) := "011";
  constant C_PC_ADD    : std_logic_vector(2 downto 0) := "100";
  -- The soft-stop alternative of the next interval.
  constant C_PC_ALT_WAIT : std_logic_vector(2 downto 0) := "101";
  constant C_PC_ALT_ADD  : std_logic_vector(2 downto 0) := "110";

  -- What a soft stop decided at the pulse ending the current interval does (alt_kind; stepramp_engine reads it).
  constant C_ALT_IGNORE : std_logic_vector(1 downto 0) := "00"; -- nothing: DECEL, last pulse, or p + m >= L
  constant C_ALT_LOAD   : std_logic_vector(1 downto 0) := "10"; -- m >= 1: the next interval is the alternative
  constant C_ALT_END    : std_logic_vector(1 downto 0) := "01"; -- m = 0: the move ends with this pulse

  constant C_Q16_PAD : unsigned(15 downto 0) := (others => '0');

  -- The head counter one interval on: + 1 in an up head (the accel index n0 + j), - 1 in a down head (K - j).
  function step_head (
    ctr  : unsigned(30 downto 0);
    down : std_logic
  ) return unsigned is
  begin

    if (down = '1') then
      return ctr - 1;
    end if;

    return ctr + 1;

  end function step_head;

  -- The fractional-carry accumulator step s = acc + v (the one adder of C_PC_ADD and C_PC_ALT_ADD), with "s >> 32 = 0"
  -- (no ticks) on top: zero & s. Carry-select: the fraction's sum and the integer part + 1 side by side, the
  -- fraction's carry picking the integer part, so no carry ripples through all 65 bits; the zero flag follows from
  -- the same carry and v's integer part. An incrementer, a zero test and multiplexers in hardware, as if all were
  -- computed first; a simulator computes only the branch the carry picks, and only at the edge that keeps the
  -- interval (as concurrent statements they would follow every change of v_r and acc).
  function acc_step (
    v        : unsigned(63 downto 0);
    fraction : unsigned(31 downto 0)
  ) return unsigned is

    variable frac_sum : unsigned(32 downto 0); -- the fraction's sum and its carry

  begin

    frac_sum := ('0' & v(31 downto 0)) + ('0' & fraction);

    if (frac_sum(32) = '1') then
      return '0' & (('0' & v(63 downto 32)) + 1) & frac_sum(31 downto 0);
    end if;

    return to_sl(v(63 downto 32) = 0) & '0' & v(63 downto 32) & frac_sum(31 downto 0);

  end function acc_step;

  -- The move, as numbers.
  signal p_l          : unsigned(30 downto 0);
  signal p_sa         : unsigned(30 downto 0);
  signal p_sd         : unsigned(30 downto 0);
  signal p_c_last     : unsigned(47 downto 0);
  signal p_c_sa       : unsigned(47 downto 0);
  signal p_c_sd       : unsigned(47 downto 0);
  signal p_decel_seed : unsigned(63 downto 0);
  signal p_cruise     : unsigned(63 downto 0);
  signal p_stop_ratio : unsigned(31 downto 0);

  -- The accumulator fraction after the interval now counting.
  signal acc : unsigned(31 downto 0);

  -- The prepared intervals, two deep: slot A (nxt_*, what the next pulse loads) and slot B (nx2_*, the one after
  -- it; B is only full when A is). Each holds its ticks, the accumulator fraction after it, its error flags, its
  -- phase, whether it is the last, and what a soft stop decided at the pulse before it would do (alt kind, m = 1).
  signal nxt_ok_r    : std_logic;
  signal nxt_d_r     : unsigned(32 downto 0);
  signal nxt_acc     : unsigned(31 downto 0);
  signal nxt_range   : std_logic; -- nxt_code RANGE
  signal nxt_zero    : std_logic; -- nxt_code ZERO_TICKS (when not RANGE)
  signal nxt_state_r : std_logic_vector(1 downto 0);
  signal nxt_last_r  : std_logic;
  signal nxt_altk    : std_logic_vector(1 downto 0);
  signal nx2_ok      : std_logic;
  signal nx2_d       : unsigned(32 downto 0);
  signal nx2_acc     : unsigned(31 downto 0);
  signal nx2_range   : std_logic;
  signal nx2_zero    : std_logic;
  signal nx2_state   : std_logic_vector(1 downto 0);
  signal nx2_last    : std_logic;
  signal nx2_altk    : std_logic_vector(1 downto 0);
  -- The interval being prepared (pc_j): its phase and last flag, set in DECIDE, copied into its slot in ADD.
  signal pd_state : std_logic_vector(1 downto 0);
  signal pd_last  : std_logic;
  -- There is an interval after pc_j to prepare (pc_j is not the last).
  signal pc_more : std_logic;

  -- pc_j is the index of the interval being prepared, pc_m = L - pc_j.
  signal pc_state  : std_logic_vector(2 downto 0);
  signal seed_wait : std_logic; -- the accel seed load of this move is not answered yet
  signal pc_j      : unsigned(30 downto 0);
  -- Where pc_j stands against sa and sd, as flags (pc_j only ever grows by one, so no magnitude compare is needed):
  -- le_sa = (pc_j <= sa) and le_sd = (pc_j <= sd) until the DECIDE of pc_j, (pc_j < sa) and (pc_j < sd) after it;
  -- eq_sa and eq_sd are the equalities of pc_j, set in IDX and read in DECIDE.
  signal le_sa       : std_logic;
  signal le_sd       : std_logic;
  signal eq_sa       : std_logic;
  signal eq_sd       : std_logic;
  signal lt_sa       : std_logic;
  signal lt_sd       : std_logic;
  signal pc_m        : unsigned(30 downto 0);
  signal pc_m_zero   : std_logic; -- pc_m = 0, set in IDX for DECIDE
  signal dec_started : std_logic;
  -- The head ramp (intervals before sa): head_ctr is the up head's accel index n0 + pc_j, or the down head's
  -- K - pc_j (the decel index of interval pc_j's value, and the m of a soft stop decided at pulse pc_j).
  -- head_started: the down head's first value (the seed itself, interval 2) has been prepared. nxt_head_r: the
  -- interval pc_j is a head interval; prev_head and prev_state: interval pc_j - 1 is one, and its phase (taken in
  -- IDX; DECIDE judges a soft stop decided at pulse pc_j - 1 with them: in a down head, whose phase is DECEL,
  -- prev_head lets it act).
  signal head_ctr     : unsigned(30 downto 0);
  signal head_started : std_logic;
  signal nxt_head_r   : std_logic;
  signal prev_head    : std_logic;
  signal prev_state   : std_logic_vector(1 downto 0);
  -- The alternative prepared is the down head going on (alt_kind LOAD in a down head): the head's next value, or
  -- where that is c_sa, the head's own step.
  signal alt_cont : std_logic;
  -- Recurrence state: A_{j-2} while accelerating, D_{L-j+1} while decelerating (never both in one move).
  signal rec_val : unsigned(47 downto 0);
  signal rec_rem : unsigned(32 downto 0);
  signal v_r     : unsigned(63 downto 0); -- Q32.32 value of interval pc_j (then of the alternative)
  signal v_range : std_logic;             -- v_r came from a recurrence value out of the Q32.16 range (code RANGE)

  -- Soft stop. stop_mode: a soft stop is in effect; the precompute then follows the stop's decel ramp,
  -- pc_m = L' - pc_j. DECIDE of interval c + 1 judges a soft stop decided at pulse c (c in ACCEL or RUN): alt_kind
  -- (what it does), kept in c + 1's slot. When a request is armed (stop_armed: it is decided at the pulse ending the
  -- interval now counting, c) and slot A holds c + 1, nothing more is prepared until that pulse, and for alt kind
  -- LOAD the alternative is: the value of interval c + 1 in the stop (c_last when m = 1, else D_(m-1) from
  -- D_m := D), through the same accumulator step as a normal value. D is the normal value of interval c + 1, the
  -- last one prepared (A_c or c_sa in ACCEL, cruise in RUN), truncated to Q32.16: v_r still holds it when the unit
  -- takes the request. So the alternative costs one division in the interval before its pulse, whether slot A was
  -- ready at the arming pulse (two ahead) or was still being prepared (one ahead: the alternative follows it).
  signal stop_mode_r : std_logic;
  -- (n0 + c) * stop_ratio, Q47.16, for the ACCEL interval c = pc_j - 1 (stepped in IDX while c <= sa): its low 47
  -- bits, and prod_big, set once it reaches 2^47 (it only grows, so a sticky bit tells m >= 2^31 as well as the 16
  -- upper bits did).
  signal cur_prod : unsigned(46 downto 0);
  signal prod_big : std_logic;
  -- cur_prod + stop_ratio and its sticky bit, registered every clock (cur_prod changes only in IDX, and the next IDX
  -- is at least four clocks later), so that IDX copies a register instead of waiting for the adder;
  -- the register as two numbers, bits 23 .. 0 and 46 .. 24 (a simulator's transaction each, not one per bit).
  signal prod_next_lo  : natural range 0 to 2 ** 24 - 1;
  signal prod_next_hi  : natural range 0 to 2 ** 23 - 1;
  signal prod_next_big : std_logic;
  signal prod_step     : std_logic;                    -- pc_j <= sa: the next IDX adds stop_ratio to cur_prod
  signal first_pend    : std_logic;                    -- the segment's first pulse has not come yet (no IDX before it)
  signal stop_m        : unsigned(30 downto 0);        -- m of a soft stop decided at pulse pc_j - 1 (set in IDX)
  signal stop_big      : std_logic;                    -- m >= 2^31
  signal alt_kind_r    : std_logic_vector(1 downto 0); -- of interval pc_j (DECIDE), copied into its slot in ADD
  signal alt_one_r     : std_logic;                    -- m = 1
  signal alt_go        : std_logic;                    -- the alternative of the armed request is being prepared or ready
  signal stop_mm1      : unsigned(30 downto 0);        -- m - 1 (stop_m is held from IDX to the alternative)
  signal run_m         : unsigned(30 downto 0);        -- the m of a soft stop in RUN, L - sd + 1 (the move's)
  signal alt_ok_r      : std_logic;
  signal alt_d_r       : unsigned(32 downto 0);
  signal alt_acc       : unsigned(31 downto 0);
  signal alt_range     : std_logic;                    -- alt_code RANGE
  signal alt_zero      : std_logic;                    -- alt_code ZERO_TICKS (when not RANGE)

  -- Next-delay unit.
  signal nd_flush     : std_logic;
  signal req_r        : std_logic;
  signal req_seed_r   : std_logic;
  signal req_decel_r  : std_logic;
  signal req_index_r  : unsigned(30 downto 0);
  signal req_alt_r    : std_logic; -- the request is the soft-stop alternative: value D, remainder 0
  signal nd_req_value : std_logic_vector(47 downto 0);
  signal nd_req_num   : std_logic_vector(G_DIV_WIDTH - 1 downto 0);
  -- 2 * rec_val + rec_rem, the numerator of the next recurrence step, registered every clock (rec_val and rec_rem
  -- are set at least one clock before the request that reads it), so that the divider loads a flip-flop. The
  -- register in three parts, bits 24 .. 0 and 48 .. 25 as numbers and the bits above as a vector (a simulator's
  -- transaction per number, not one per bit).
  signal rec_num_c     : unsigned(G_DIV_WIDTH - 1 downto 0);
  signal rec_num_c_lo  : natural range 0 to 2 ** 25 - 1;
  signal rec_num_c_mid : natural range 0 to 2 ** 24 - 1;
  signal rec_num_lo    : natural range 0 to 2 ** 25 - 1;
  signal rec_num_mid   : natural range 0 to 2 ** 24 - 1;
  signal rec_num_top   : unsigned(G_DIV_WIDTH - 1 downto 49);
  -- cur_prod + stop_ratio, and its two parts.
  signal prod_sum    : unsigned(47 downto 0);
  signal prod_sum_lo : natural range 0 to 2 ** 24 - 1;
  signal prod_sum_hi : natural range 0 to 2 ** 23 - 1;
  signal nd_busy     : std_logic;
  signal nd_valid    : std_logic;
  signal nd_value    : std_logic_vector(47 downto 0);
  signal nd_rem      : std_logic_vector(32 downto 0);
  signal nd_ovf      : std_logic;

begin

  -- The numerator 2 * Q32.16 + remainder needs 50 bits; the divider stops at 64.
  assert G_DIV_WIDTH >= 50 and G_DIV_WIDTH <= 64
    report "stepramp_precompute: G_DIV_WIDTH must be in 50 .. 64"
    severity failure;

  assert G_RAMP <= 1
    report "stepramp_precompute: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  p_l          <= unsigned(l);
  p_sa         <= unsigned(sa);
  p_sd         <= unsigned(sd);
  p_c_last     <= unsigned(c_last);
  p_c_sa       <= unsigned(c_sa);
  p_c_sd       <= unsigned(c_sd);
  p_decel_seed <= unsigned(decel_seed);
  p_cruise     <= unsigned(cruise);
  p_stop_ratio <= unsigned(stop_ratio);

  lt_sa <= le_sa and not eq_sa;
  lt_sd <= le_sd and not eq_sd;

  stop_mm1 <= stop_m - 1;
  run_m    <= p_l - p_sd + 1;

  -- A seed load carries its seed (the accel seed is already the running value, from latch); a recurrence step
  -- carries the running value (and its remainder); the first value of a soft stop's ramp is a step from D_m := D
  -- with remainder 0.
  nd_req_value <= std_logic_vector(p_decel_seed(47 downto 0)) when req_seed_r = '1' and req_decel_r = '1' else
                  std_logic_vector(v_r(63 downto 16)) when req_alt_r = '1' else
                  std_logic_vector(rec_val);
  nd_req_num   <= std_logic_vector(resize(v_r(63 downto 16) & '0', G_DIV_WIDTH)) when req_alt_r = '1' else
                  std_logic_vector(rec_num_top & to_unsigned(rec_num_mid, 24) & to_unsigned(rec_num_lo, 25));

  avr446_gen : if G_RAMP = 0 generate

    next_delay_inst : entity work.stepramp_next_delay
      generic map (
        G_DIV_WIDTH => G_DIV_WIDTH
      )
      port map (
        clk       => clk,
        rst       => rst,
        flush     => nd_flush,
        req       => req_r,
        req_seed  => req_seed_r,
        req_decel => req_decel_r,
        req_index => std_logic_vector(req_index_r),
        req_value => nd_req_value,
        req_num   => nd_req_num,
        busy      => nd_busy,
        ans_valid => nd_valid,
        ans_value => nd_value,
        ans_rem   => nd_rem,
        ans_ovf   => nd_ovf
      );

  end generate avr446_gen;

  -- The exact ramp answers from the index and the ramp constants alone (the seeds' registers hold them): C_ACC for
  -- an accel request, C_DEC for every decelerating one (final decel, down head, soft stop).

  exact_gen : if G_RAMP = 1 generate

    next_delay_inst : entity work.stepramp_next_delay_exact
      port map (
        clk       => clk,
        rst       => rst,
        flush     => nd_flush,
        req       => req_r,
        req_seed  => req_seed_r,
        req_decel => req_decel_r,
        req_alt   => req_alt_r,
        req_index => std_logic_vector(req_index_r),
        c_head    => accel_seed,
        c_dec     => decel_seed,
        busy      => nd_busy,
        ans_valid => nd_valid,
        ans_value => nd_value,
        ans_rem   => nd_rem,
        ans_ovf   => nd_ovf
      );

  end generate exact_gen;

  -- The adders pc_proc registers at every clock, as concurrent statements of the registers they add (the same logic
  -- as variables in the process, but a simulator evaluates them when an operand changes, not every clock):
  -- 2 * rec_val + rec_rem (registered in rec_num_*) and the next running product (registered in prod_next_*).
  rec_num_c     <= resize(rec_val & '0', G_DIV_WIDTH) + rec_rem;
  rec_num_c_lo  <= to_integer(rec_num_c(24 downto 0));
  rec_num_c_mid <= to_integer(rec_num_c(48 downto 25));
  prod_sum      <= ('0' & cur_prod) + p_stop_ratio;
  prod_sum_lo   <= to_integer(prod_sum(23 downto 0));
  prod_sum_hi   <= to_integer(prod_sum(46 downto 24));

  pc_proc : process (clk) is

    -- The index step of a pulse edge (advance or take_alt): the interval after the one that starts is prepared.
    variable v_idx      : boolean;
    variable v_pcm      : unsigned(30 downto 0);       -- pc_m before the step
    variable v_j        : unsigned(30 downto 0);       -- pc_j after the step
    variable v_cur_prod : unsigned(46 downto 0);       -- cur_prod after this edge
    variable v_prod_big : std_logic;
    -- The slots after this edge's pulse (advance moves B into A), the accumulator fractions a value added now starts
    -- from (after the interval now counting, for slot A and the alternative; after slot A's, for slot B), and
    -- whether the precompute may start a service this edge (idle, or an alternative dropped by the pulse).
    variable v_a_ok    : std_logic;
    variable v_b_ok    : std_logic;
    variable v_acc_cur : unsigned(31 downto 0);
    variable v_acc_a   : unsigned(31 downto 0);
    variable v_idle    : boolean;
    variable v_alt_go  : std_logic;
    variable v_pcs     : std_logic_vector(2 downto 0); -- pc_state as this edge acts on it

    -- The next-delay unit's answer becomes the value to add (Q32.16), with its range flag.

    procedure take_answer is
    begin

      v_r <= unsigned(nd_value) & C_Q16_PAD;

      if (nd_ovf = '1') then
        v_range <= '1';
      end if;

    end procedure take_answer;

    -- The accumulator step of v_r gives an interval: its ticks, the fraction carried on, and its error flags.

    procedure keep_interval (
      base            : unsigned(31 downto 0);
      signal ticks    : out unsigned(32 downto 0);
      signal fraction : out unsigned(31 downto 0);
      signal range_f  : out std_logic;
      signal zero_f   : out std_logic;
      signal ok       : out std_logic
    ) is

      variable v_sum : unsigned(65 downto 0);

    begin

      v_sum    := acc_step(v_r, base);
      ticks    <= v_sum(64 downto 32);
      fraction <= v_sum(31 downto 0);
      range_f  <= v_range;
      zero_f   <= v_sum(65);
      ok       <= '1';

    end procedure keep_interval;

    -- A request to the next-delay unit: the seed or a recurrence step, of the decel ramp at index n or the accel ramp.

    procedure request (
      seed  : std_logic;
      decel : std_logic;
      n     : unsigned(30 downto 0)
    ) is
    begin

      req_r       <= '1';
      req_seed_r  <= seed;
      req_decel_r <= decel;
      req_index_r <= n;

    end procedure request;

    -- At a pulse edge: the interval after the one that starts is prepared next, unless that one is the last.

    procedure prepare_unless_last (
      last : std_logic
    ) is
    begin

      if (last = '0') then
        v_idx := true;
      else
        pc_state <= C_PC_IDLE;
      end if;

    end procedure prepare_unless_last;

    -- ADD: the interval pc_j goes into the first free slot (A, or B behind a full A), with its phase, last flag and
    -- soft-stop judgement.

    procedure keep_prepared is

      variable v_base : unsigned(31 downto 0);
      variable v_sum  : unsigned(65 downto 0);

      -- One slot's registers take the interval.

      procedure fill (
        signal ticks    : out unsigned(32 downto 0);
        signal fraction : out unsigned(31 downto 0);
        signal range_f  : out std_logic;
        signal zero_f   : out std_logic;
        signal ok       : out std_logic;
        signal phase    : out std_logic_vector(1 downto 0);
        signal last     : out std_logic;
        signal altk     : out std_logic_vector(1 downto 0)
      ) is
      begin

        ticks    <= v_sum(64 downto 32);
        fraction <= v_sum(31 downto 0);
        range_f  <= v_range;
        zero_f   <= v_sum(65);
        ok       <= '1';
        phase    <= pd_state;
        last     <= pd_last;
        altk     <= alt_kind_r;

      end procedure fill;

    begin

      -- (One accumulator step for both slots: the base is picked, not the sum.)
      v_base := v_acc_a;

      if (v_a_ok = '0') then
        v_base := v_acc_cur;
      end if;

      v_sum := acc_step(v_r, v_base);

      if (v_a_ok = '0') then
        fill(nxt_d_r, nxt_acc, nxt_range, nxt_zero, nxt_ok_r, nxt_state_r, nxt_last_r, nxt_altk);
      else
        fill(nx2_d, nx2_acc, nx2_range, nx2_zero, nx2_ok, nx2_state, nx2_last, nx2_altk);
      end if;

    end procedure keep_prepared;

    -- The soft-stop alternative of the armed request, for alt kind LOAD (slot A holds interval c + 1 = pc_j, the
    -- last one prepared, and its value D is still in v_r; the next-delay unit is free).

    procedure begin_alternative is
    begin

      alt_go  <= '1';
      v_range <= '0';

      if (G_RAMP = 1 and prev_state = C_ST_RUN) then
        -- Exact ramp, a stop in the cruise: the motion's own decel from sd - 1 moves to pulse c, so interval
        -- c + 1 is c_sd (also when m = 1), and the stop's ramp goes on from C_DEC.
        v_r      <= p_c_sd & C_Q16_PAD;
        pc_state <= C_PC_ALT_ADD;
      elsif (alt_one_r = '1') then
        v_r      <= p_c_last & C_Q16_PAD;
        pc_state <= C_PC_ALT_ADD;
      elsif (alt_cont = '1' and eq_sa = '0') then
        -- A down head goes on: its next value (in v_r) is the stop's too.
        pc_state <= C_PC_ALT_ADD;
      elsif (alt_cont = '1' and head_started = '0' and G_RAMP = 0) then
        -- ... where it gave way to c_sa at interval 2 (sa = 2), its own value there: the seed D_(K-2), which
        -- is also still the unit's last answer (the seed load) for take_alt.
        v_r      <= rec_val & C_Q16_PAD;
        pc_state <= C_PC_ALT_ADD;
      elsif (alt_cont = '1') then
        -- ... and where it gave way to c_sa, its own value D_(K-sa).
        request('0', '1', head_ctr);
        pc_state <= C_PC_ALT_WAIT;
      else
        -- D_(m-1) = D + (2 D) div (4 m - 1): the unit's decel step at index m - 1.
        request('0', '1', stop_mm1);
        req_alt_r <= '1';
        pc_state  <= C_PC_ALT_WAIT;
      end if;

    end procedure begin_alternative;

    -- The segment's first interval is prepared (at setup, or in a take-over): its ramp phase, the counters and flags
    -- as after the DECIDE of interval 1, and (AVR446) the accel seed A_0 loaded through the unit (at index 0), like
    -- the decel seed later. The exact ramp's unit takes its constants from the seeds' registers directly.

    procedure begin_segment is

      variable v_state : std_logic_vector(1 downto 0);
      variable v_last  : std_logic;

    begin

      if (p_sa(30 downto 1) /= 0 and head_down = '1') then
        v_state := C_ST_DECEL;
      elsif (p_sa(30 downto 1) /= 0) then
        v_state := C_ST_ACCEL;
      elsif (p_sd(30 downto 1) /= 0 or endless = '1') then
        v_state := C_ST_RUN;
      else
        v_state := C_ST_DECEL;
      end if;

      -- (Slot A's copy serves setup, where interval 1 is offered at once; a take-over's ADD copies them again.)
      v_last      := to_sl(p_l = 1) and not endless;
      pd_state    <= v_state;
      pd_last     <= v_last;
      nxt_state_r <= v_state;
      nxt_last_r  <= v_last;
      nxt_altk    <= C_ALT_IGNORE;
      pc_more     <= not v_last;
      nxt_head_r  <= to_sl(p_sa(30 downto 1) /= 0);
      -- Interval 1 is <= sa (sa >= 1: the parameter check has passed), so the IDX after it steps the product.
      prod_step <= '1';

      pc_j <= to_unsigned(1, 31);
      -- Interval 1 needs no DECIDE: the flags start as after it, (1 < sa) and (1 < sd).
      le_sa <= '0';
      le_sd <= '0';

      if (p_sa(30 downto 1) /= 0) then
        le_sa <= '1';
      end if;

      if (p_sd(30 downto 1) /= 0 or endless = '1') then
        le_sd <= '1';
      end if;

      -- An endless move never counts pc_m down (until a soft stop sets it).
      pc_m      <= p_l - 1;
      pc_m_zero <= '0';

      if (endless = '1') then
        pc_m <= (others => '1');
      end if;

      head_started <= '0';
      head_ctr     <= step_head(head_ctr, head_down);
      dec_started  <= '0';
      first_pend   <= '1';
      req_alt_r    <= '0';
      -- The exact ramp has no seed to load (its first value is a fresh request like any other), so interval 2 is
      -- asked for at once.
      if (G_RAMP = 0) then
        request('1', '0', (others => '0'));
        seed_wait <= '1';
      end if;

    end procedure begin_segment;

  begin

    if rising_edge(clk) then
      nd_flush      <= '0';
      rec_num_lo    <= rec_num_c_lo;
      rec_num_mid   <= rec_num_c_mid;
      rec_num_top   <= rec_num_c(G_DIV_WIDTH - 1 downto 49);
      v_idx         := false;
      v_pcm         := pc_m;
      v_cur_prod    := cur_prod;
      v_prod_big    := prod_big;
      prod_next_lo  <= prod_sum_lo;
      prod_next_hi  <= prod_sum_hi;
      prod_next_big <= prod_big or prod_sum(47);

      -- Request handshake: the unit takes req at the first edge where it is not busy (always the first one in
      -- practice: it is flushed at start and serves at most one request per interval).
      if (req_r = '1' and nd_busy = '0') then
        req_r <= '0';
      end if;

      -- The accel seed load issued at setup is answered before the first precompute needs it.
      if (seed_wait = '1' and req_r = '0' and nd_valid = '1') then
        rec_val   <= unsigned(nd_value);
        rec_rem   <= unsigned(nd_rem);
        seed_wait <= '0';
      end if;

      -- The pulse edge's strobe (one clock after the pulse edge): slot A has started counting, slot B moves into A
      -- (a value added at this edge goes into the first slot free after the move). An alternative still being
      -- prepared was not taken (no request was decided at that pulse) and is dropped.
      v_a_ok    := nxt_ok_r;
      v_b_ok    := nx2_ok;
      v_acc_cur := acc;
      v_acc_a   := nxt_acc;
      v_alt_go  := alt_go;
      v_pcs     := pc_state;
      if (advance = '1') then
        v_a_ok      := nx2_ok;
        v_b_ok      := '0';
        v_acc_cur   := nxt_acc;
        v_acc_a     := nx2_acc;
        v_alt_go    := '0';
        acc         <= nxt_acc;
        nxt_ok_r    <= nx2_ok;
        nxt_d_r     <= nx2_d;
        nxt_acc     <= nx2_acc;
        nxt_range   <= nx2_range;
        nxt_zero    <= nx2_zero;
        nxt_state_r <= nx2_state;
        nxt_last_r  <= nx2_last;
        nxt_altk    <= nx2_altk;
        nx2_ok      <= '0';
        alt_ok_r    <= '0';
        alt_go      <= '0';
        first_pend  <= '0';
        if (pc_state = C_PC_ALT_WAIT or pc_state = C_PC_ALT_ADD) then
          nd_flush <= '1';
          req_r    <= '0';
          pc_state <= C_PC_IDLE;
          v_pcs    := C_PC_IDLE;
        end if;
      end if;
      -- No service starts at an edge whose strobes restart the precompute.
      v_idle := v_pcs = C_PC_IDLE and take_alt = '0' and take = '0' and begin_move = '0' and finish = '0';

      -- Precompute of interval pc_j. Its last step (C_PC_ADD) is the only wide adder of the engine, and it is off
      -- the countdown path: the pulse edge only copies its results.
      case v_pcs is

        when C_PC_IDLE =>

          -- The next service: the armed request's alternative (slot A holds interval c + 1 and v_r its value D), or
          -- the next interval into a free slot. Slot B waits while a request is armed (its alternative needs slot A's
          -- D), and a segment's first IDX waits for its first pulse (the latency budget counts from there).
          if (v_idle) then
            if (stop_armed = '1' and v_a_ok = '1' and v_b_ok = '0' and v_alt_go = '0' and
                alt_kind_r = C_ALT_LOAD) then
              begin_alternative;
            elsif (pc_more = '1' and v_b_ok = '0' and (v_a_ok = '0' or stop_armed = '0') and
                   (first_pend = '0' or advance = '1')) then
              v_idx := true;
            end if;
          end if;

        when C_PC_TAKE =>

          -- Take-over, second clock: the segment's interval 1 is c_first (held in nxt_d and nxt_acc since latch)
          -- through the accumulator step, so that the fraction after interval P carries on.
          begin_segment;
          v_r      <= nxt_d_r(31 downto 0) & nxt_acc;
          v_range  <= '0';
          pc_state <= C_PC_ADD;

        when C_PC_DECIDE =>

          -- What a soft stop decided at pulse c = pc_j - 1 does: ignored in DECEL, after a stop, and when c + m >= L
          -- (pc_m = L - c - 1 here: IDX has moved it on); m = 0 ends the move with pulse c, m >= 1 loads the
          -- alternative. (Repeated unchanged while DECIDE waits.)
          alt_kind_r <= C_ALT_IGNORE;
          -- (In a down head, whose phase is DECEL, prev_head lets it act.)
          alt_cont <= head_down and prev_head;
          if (stop_mode_r = '0' and
              (prev_state = C_ST_ACCEL or prev_state = C_ST_RUN or (head_down and prev_head) = '1')) then
            if (stop_big = '1' or stop_m > pc_m) then
              alt_kind_r <= C_ALT_IGNORE;
            elsif (stop_m = 0) then
              alt_kind_r <= C_ALT_END;
            else
              alt_kind_r <= C_ALT_LOAD;
            end if;
          end if;
          alt_one_r <= to_sl(stop_m = 1);

          if (seed_wait = '0') then
            -- The flags move on to pc_j + 1; prod_step keeps pc_j <= sa for the pulse that loads interval pc_j.
            le_sa     <= lt_sa;
            le_sd     <= lt_sd;
            prod_step <= le_sa;

            -- Ramp phase of interval j: the head if j < sa (ACCEL, or DECEL in a down head), RUN if sa <= j < sd,
            -- DECEL if j >= sd (sa <= sd); all intervals of a soft stop are DECEL.
            nxt_head_r <= lt_sa and not stop_mode_r;
            if (stop_mode_r = '1') then
              pd_state <= C_ST_DECEL;
            elsif (lt_sa = '1' and head_down = '1') then
              pd_state <= C_ST_DECEL;
            elsif (lt_sa = '1') then
              pd_state <= C_ST_ACCEL;
            elsif (lt_sd = '1') then
              pd_state <= C_ST_RUN;
            else
              pd_state <= C_ST_DECEL;
            end if;

            pd_last <= pc_m_zero;
            pc_more <= not pc_m_zero;

            v_range   <= '0';
            req_alt_r <= '0';

            -- The spec's rule order (j >= 2 here, so rule 1 never applies). In a soft stop: c_last at L', before
            -- it the stop's decel ramp D_(L'-j) from D_(L'-j+1).
            if (pc_m_zero = '1') then
              v_r      <= p_c_last & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (stop_mode_r = '1') then
              request('0', '1', pc_m);
              pc_state <= C_PC_WAIT;
            elsif (eq_sa = '1') then
              v_r      <= p_c_sa & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (eq_sd = '1') then
              v_r      <= p_c_sd & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (lt_sa = '1' and head_down = '0') then
              -- A_(n0+j-1) from A_(n0+j-2) (IDX set the index).
              req_r       <= '1';
              req_seed_r  <= '0';
              req_decel_r <= '0';
              pc_state    <= C_PC_WAIT;
            elsif (lt_sa = '1' and head_started = '0' and G_RAMP = 0) then
              -- The down head's first value D_(K-2), interval 2: the seed itself (rec_val since setup, remainder 0).
              -- (The exact ramp asks the unit for it, as for every other head value.)
              v_r          <= rec_val & C_Q16_PAD;
              head_started <= '1';
              pc_state     <= C_PC_ADD;
            elsif (lt_sa = '1') then
              -- D_(K-j) from D_(K-j+1).
              request('0', '1', head_ctr);
              pc_state <= C_PC_WAIT;
            elsif (le_sd = '0') then
              -- D_{L-j}: the seed itself at j = sd + 1, else from D_{L-j+1}.
              request(not dec_started, '1', pc_m);
              dec_started <= '1';
              pc_state    <= C_PC_WAIT;
            else
              v_r      <= p_cruise;
              pc_state <= C_PC_ADD;
            end if;
          end if;

        when C_PC_WAIT =>

          if (req_r = '0' and nd_valid = '1') then
            rec_val  <= unsigned(nd_value);
            rec_rem  <= unsigned(nd_rem);
            take_answer;
            pc_state <= C_PC_ADD;
          end if;

        when C_PC_ADD =>

          -- The fractional-carry accumulator: s = acc + v, the interval lasts s >> 32 ticks.
          -- The error it would cause, as two flags (nxt_code below): out of range, or 0 ticks (two pulses on one
          -- tick cannot be emitted; only a recurrence value can get here). One LUT after the carry.
          keep_prepared;
          pc_state <= C_PC_IDLE;

          -- A request armed while this interval, c + 1, was still being prepared for slot A: its alternative follows
          -- at once (the next-delay unit is free now). Its D is the value just added: the plan's interval c + 1
          -- (A_c, c_sa or cruise), Q32.16.
          v_range <= '0';
          if (v_a_ok = '0' and stop_armed = '1' and v_alt_go = '0' and alt_kind_r = C_ALT_LOAD) then
            begin_alternative;
          end if;

        when C_PC_ALT_WAIT =>

          if (req_r = '0' and nd_valid = '1') then
            take_answer;
            pc_state <= C_PC_ALT_ADD;
          end if;

        when C_PC_ALT_ADD =>

          keep_interval(v_acc_cur, alt_d_r, alt_acc, alt_range, alt_zero, alt_ok_r);
          pc_state <= C_PC_IDLE;

        when others =>

          pc_state <= C_PC_IDLE;

      end case;

      -- The sequencer's decisions of this edge (after the case: they win over it).
      -- The move is latched (its first values are taken here; the others are inputs held by the sequencer): interval
      -- 1 is c_first, with acc = 0 its ticks and fraction are plain slices, and the running value is A_0.
      if (latch = '1') then
        nxt_d_r <= resize(unsigned(c_first(47 downto 16)), 33);
        nxt_acc <= unsigned(c_first(15 downto 0)) & C_Q16_PAD;
        rec_val <= unsigned(accel_seed(47 downto 0));
        rec_rem <= (others => '0');
        -- The head's index (setup moves it on to interval 2's), and an up head's running product n0 * stop_ratio.
        head_ctr <= unsigned(head_index);
        cur_prod <= unsigned(head_prod(46 downto 0));
        prod_big <= head_prod(47);
      end if;

      if (begin_move = '1') then
        nd_flush    <= '1';
        pc_state    <= C_PC_IDLE;
        req_r       <= '0';
        seed_wait   <= '0';
        nxt_ok_r    <= '0';
        nx2_ok      <= '0';
        pc_more     <= '0';
        stop_mode_r <= '0';
        alt_kind_r  <= C_ALT_IGNORE;
        alt_ok_r    <= '0';
        alt_go      <= '0';
      end if;

      if (setup = '1') then
        -- Interval 1 is c_first (in nxt_d and nxt_acc since latch). The exact ramp starts the accumulator at one
        -- half, so that every pulse of the motion lands on the tick nearest its exact time: c_first + 1/2.
        if (G_RAMP = 1) then
          nxt_acc(31) <= not nxt_acc(31);
          if (nxt_acc(31) = '1') then
            nxt_d_r <= nxt_d_r + 1;
          end if;
        end if;
        nxt_range <= '0';
        nxt_zero  <= '0';
        nxt_ok_r  <= '1';
        begin_segment;
      end if;

      -- Soft stop takes effect: interval p + 1 is the alternative, L' = p + m; what the slots hold is dropped, and the
      -- precompute continues the stop's ramp from D_(m-1) (pc_m = L' - (p + 1) = m - 1). (It was idle: the
      -- alternative was ready, and slot B waited.)
      if (take_alt = '1') then
        nxt_ok_r    <= '0';
        nx2_ok      <= '0';
        alt_ok_r    <= '0';
        alt_go      <= '0';
        alt_kind_r  <= C_ALT_IGNORE;
        pc_more     <= not alt_one_r;
        acc         <= alt_acc;
        stop_mode_r <= '1';
        -- D_(m-1) and its remainder, the stop's recurrence state: still the unit's last answer (ALT_WAIT took it,
        -- ALT_ADD set alt_ok, and nothing asks the unit between then and this edge).
        -- (A down head going on: the unit's last answer is the head's own value of interval p + 1, or its seed.)
        rec_val <= unsigned(nd_value);
        rec_rem <= unsigned(nd_rem);
        v_pcm   := stop_mm1;
        pc_m    <= stop_mm1;
        prepare_unless_last(alt_one_r);
      end if;

      -- The index step (IDX), when a slot is free (at the pulse edge's strobe itself, one clock after the pulse
      -- edge, where the precompute was idle; or after the ADD of slot A), and at take_alt: pc_j moves on.
      if (v_idx) then
        -- The index of an accel step for interval pc_j + 1 (A_(pc_j) from A_(pc_j - 1)); DECIDE replaces it for
        -- any other request. The unit is idle here, and latches the index it takes.
        -- (n0 + pc_j: head_ctr in an up head).
        req_index_r <= head_ctr;
        head_ctr    <= step_head(head_ctr, head_down);
        -- The running product follows interval pc_j while it is <= sa (prod_step, from its DECIDE or from
        -- begin_segment for interval 1); interval pc_j's phase and head flag become the previous interval's.
        if (prod_step = '1') then
          v_cur_prod := to_unsigned(prod_next_hi, 23) & to_unsigned(prod_next_lo, 24);
          v_prod_big := prod_next_big;
        end if;
        cur_prod   <= v_cur_prod;
        prod_big   <= v_prod_big;
        prev_state <= pd_state;
        prev_head  <= nxt_head_r;
        -- The equalities of the new pc_j, registered here so that DECIDE starts from flip-flops (sa only while pc_j
        -- is below it, and sd never in an endless move: pc_j may wrap there).
        eq_sa <= '0';
        eq_sd <= '0';
        v_j   := pc_j + 1;
        if (le_sa = '1' and v_j = p_sa) then
          eq_sa <= '1';
        end if;
        if (endless = '0' and v_j = p_sd) then
          eq_sd <= '1';
        end if;
        pc_j <= v_j;
        -- pc_m = 0 after this step (j = L: the last interval), as a flip-flop for DECIDE; an endless move counts
        -- only in a soft stop.
        if (endless = '0' or stop_mode_r = '1' or take_alt = '1') then
          pc_m      <= v_pcm - 1;
          pc_m_zero <= to_sl(v_pcm = 1);
        end if;
        pc_state <= C_PC_DECIDE;

        -- The m of a soft stop decided at pulse c = pc_j (before this step; pd_state is interval c's phase):
        -- floor(c * stop_ratio / 2^16) in ACCEL, L - sd + 1 in RUN. DECIDE compares it with L - c.
        -- In a down head (interval c is one: nxt_head_r still tells it here) m = K - c, head_ctr before its step;
        -- in the cruise of an endless move, run_stop.
        if (pd_state = C_ST_RUN and endless = '1') then
          stop_m   <= unsigned(run_stop);
          stop_big <= '0';
        elsif (pd_state = C_ST_RUN) then
          stop_m   <= run_m;
          stop_big <= '0';
        elsif (head_down = '1' and nxt_head_r = '1') then
          stop_m   <= head_ctr;
          stop_big <= '0';
        else
          stop_m   <= v_cur_prod(46 downto 16);
          stop_big <= v_prod_big;
        end if;
      end if;

      -- Take-over, first clock (two clocks after pulse P - 1's edge; latch is set too): whatever was prepared for
      -- interval P + 1 is dropped, and no soft-stop alternative is prepared for pulse P (a request then waits for
      -- pulse P + 1: stepramp_engine).
      if (take = '1') then
        nd_flush   <= '1';
        req_r      <= '0';
        seed_wait  <= '0';
        nxt_ok_r   <= '0';
        nx2_ok     <= '0';
        alt_kind_r <= C_ALT_IGNORE;
        alt_ok_r   <= '0';
        alt_go     <= '0';
        pc_state   <= C_PC_TAKE;
      end if;

      if (finish = '1') then
        pc_state    <= C_PC_IDLE;
        req_r       <= '0';
        seed_wait   <= '0';
        stop_mode_r <= '0';
        pc_more     <= '0';
      end if;

      if (rst = '1') then
        pc_state    <= C_PC_IDLE;
        nd_flush    <= '0';
        req_r       <= '0';
        seed_wait   <= '0';
        nxt_ok_r    <= '0';
        nx2_ok      <= '0';
        pc_more     <= '0';
        stop_mode_r <= '0';
        alt_ok_r    <= '0';
        alt_go      <= '0';
        alt_kind_r  <= C_ALT_IGNORE;
      end if;
    end if;

  end process pc_proc;

  nxt_ok    <= nxt_ok_r;
  nxt_d     <= std_logic_vector(nxt_d_r);
  nxt_state <= nxt_state_r;
  nxt_last  <= nxt_last_r;
  nxt_code  <= C_ERR_RANGE when nxt_range = '1' else
               C_ERR_ZERO_TICKS when nxt_zero = '1' else
               C_ERR_NONE;
  alt_ok    <= alt_ok_r;
  -- (What a soft stop decided at the next pulse does: slot A's judgement, once slot A is ready.)
  alt_kind  <= nxt_altk when nxt_ok_r = '1' else
               C_ALT_IGNORE;
  alt_d     <= std_logic_vector(alt_d_r);
  alt_one   <= alt_one_r;
  alt_code  <= C_ERR_RANGE when alt_range = '1' else
               C_ERR_ZERO_TICKS when alt_zero = '1' else
               C_ERR_NONE;
  stop_mode <= stop_mode_r;

end architecture rtl;
