-- SPDX-License-Identifier: MIT
-- stepramp_engine: the ramp engine. Emits the step pulses of one move with the exact timing of docs/algorithm.md.
--
-- Structure (docs/stepramp_engine.md has the timing diagrams and the latency budget):
--   * base timer (stepramp_timer), restarted by every accepted start, so that every pulse lies on a tick;
--   * countdown: the only logic that runs every clock is "tick and cnt = 1 ?"; at the pulse edge the registers of
--     the next interval (ticks, accumulator fraction, state, last flag) are merely copied;
--   * precompute: while an interval counts down, the value of the following interval is chosen (rule order of the
--     spec), computed by the next-delay unit when it is a recurrence value, and added to the fractional
--     accumulator. The result waits in nxt_* until the pulse edge. The countdown never waits for it: if it is not
--     there in time the move stops with error C_ERR_LATE.
--
-- Parameters: latched at any edge that samples load = '1' while idle (the core drives load at the edge that accepts
-- START, so a start held back by the stepping logic keeps them); a bench may give load with start.
-- Timing (edge 0 samples start = '1' while busy = '0'):
--   edge 0: busy <= '1', dir <= direction, timer restart and next-delay flush requested;
--   edge 1: parameters checked, interval 1 prepared (no arithmetic needed: the accumulator is 0), accel seed load
--           requested from the next-delay unit;
--   edge 2: pulse 0 (step '1' in the following cycle), or done + error when a parameter is bad, or done for N = 0;
--   edge 2 + prescale * T_k: pulse k. done comes with the last pulse; a late value stops the move with done + error
--   at the edge of the pulse that had no successor ready (that pulse is emitted and counted).
--   A pulse k >= 1 less than min_gap clocks after pulse k - 1 is not emitted: the move ends at its edge with done +
--   error C_ERR_STEP_SPACE (docs/algorithm.md, "Step spacing").
-- Every output is registered.
--
-- Stops (docs/stepramp_engine.md "Stops", docs/algorithm.md "Soft stop"), strobes sampled at edge e while busy:
--   hard_stop: no pulse after edge e (a pulse due at e is not emitted); done (no error) after edge e. Also taken
--              together with an accepted start (the move ends at edge 0 without a pulse).
--   soft_stop: decided at pulse p, the first pulse whose edge is strictly after e. In ACCEL / RUN the move then
--              decelerates over m more steps, m = floor(p * stop_ratio / 2^16) in ACCEL, m = L - sd + 1 in RUN
--              (ignored in DECEL or when p + m >= L; m = 0 ends the move with pulse p), from D = the plan's value
--              of interval p + 1. To meet "strictly after e" with no latency, the value of interval p + 1 for
--              such a stop (the alternative) is prepared in every ACCEL / RUN interval, after the normal next value
--              (which is D), and only chosen at the pulse edge.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  -- C_ERR_* (the err_code values): one source with STATUS.ERR_CODE, the C header and the docs.
  use work.stepramp_regs_pkg.all;

entity stepramp_engine is
  generic (
    G_DIV_WIDTH      : positive := 50;
    G_PRESCALE_WIDTH : positive := 16
  );
  port (
    clk        : in    std_logic;
    rst        : in    std_logic;
    load       : in    std_logic;
    start      : in    std_logic;
    soft_stop  : in    std_logic;
    hard_stop  : in    std_logic;
    steps      : in    std_logic_vector(30 downto 0);
    direction  : in    std_logic;
    prescale   : in    std_logic_vector(G_PRESCALE_WIDTH - 1 downto 0);
    c_first    : in    std_logic_vector(47 downto 0);
    c_last     : in    std_logic_vector(47 downto 0);
    sa         : in    std_logic_vector(30 downto 0);
    c_sa       : in    std_logic_vector(47 downto 0);
    sd         : in    std_logic_vector(30 downto 0);
    c_sd       : in    std_logic_vector(47 downto 0);
    accel_seed : in    std_logic_vector(47 downto 0);
    decel_seed : in    std_logic_vector(47 downto 0);
    cruise     : in    std_logic_vector(63 downto 0);
    stop_ratio : in    std_logic_vector(31 downto 0);
    min_gap    : in    std_logic_vector(16 downto 0);
    pos_load   : in    std_logic;
    pos_value  : in    std_logic_vector(31 downto 0);
    step       : out   std_logic;
    dir        : out   std_logic;
    busy       : out   std_logic;
    done       : out   std_logic;
    error      : out   std_logic;
    err_code   : out   std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    state      : out   std_logic_vector(1 downto 0);
    position   : out   std_logic_vector(31 downto 0);
    step_count : out   std_logic_vector(30 downto 0);
    cur_delay  : out   std_logic_vector(31 downto 0)
  );
end entity stepramp_engine;

architecture rtl of stepramp_engine is

  -- FSM state on the state port (the ramp phase of the interval now counting down).
  constant C_ST_STOP  : std_logic_vector(1 downto 0) := "00";
  constant C_ST_ACCEL : std_logic_vector(1 downto 0) := "01";
  constant C_ST_RUN   : std_logic_vector(1 downto 0) := "10";
  constant C_ST_DECEL : std_logic_vector(1 downto 0) := "11";

  -- The same state by name, for waveform viewers only: a GHW waveform shows the literal (GHDL's VPI would show
  -- its position, hence the vector port). Nothing reads it, so synthesis removes it.

  type t_state_name is (stop, accel, run, decel);

  signal state_name : t_state_name;

  -- Error codes on err_code: C_ERR_* of stepramp_regs_pkg (the lowest code wins when several parameters are bad).

  -- Move sequencer (constants, not an enum, so that GHDL's VPI shows a plain vector).
  constant C_PH_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_PH_SETUP : std_logic_vector(1 downto 0) := "01";
  constant C_PH_FIRST : std_logic_vector(1 downto 0) := "10";
  constant C_PH_RUN   : std_logic_vector(1 downto 0) := "11";

  -- Precompute of the next interval.
  constant C_PC_IDLE   : std_logic_vector(2 downto 0) := "000";
  constant C_PC_IDX    : std_logic_vector(2 downto 0) := "001";
  constant C_PC_DECIDE : std_logic_vector(2 downto 0) := "010";
  constant C_PC_WAIT   : std_logic_vector(2 downto 0) := "011";
  constant C_PC_ADD    : std_logic_vector(2 downto 0) := "100";
  -- The soft-stop alternative of the next interval (see "Soft stop" below).
  constant C_PC_ALT_WAIT : std_logic_vector(2 downto 0) := "101";
  constant C_PC_ALT_ADD  : std_logic_vector(2 downto 0) := "110";

  -- What a soft stop decided at the pulse ending the current interval does.
  constant C_ALT_IGNORE : std_logic_vector(1 downto 0) := "00"; -- nothing: DECEL, last pulse, or p + m >= L
  constant C_ALT_END    : std_logic_vector(1 downto 0) := "01"; -- m = 0: the move ends with this pulse
  constant C_ALT_LOAD   : std_logic_vector(1 downto 0) := "10"; -- m >= 1: the next interval is the alternative

  constant C_Q16_PAD : unsigned(15 downto 0) := (others => '0');

  -- Latched move parameters (data: no reset).
  signal p_steps      : unsigned(30 downto 0);
  signal p_l          : unsigned(30 downto 0); -- L = N - 1, the number of intervals
  signal p_prescale   : unsigned(G_PRESCALE_WIDTH - 1 downto 0);
  signal p_c_first    : unsigned(47 downto 0);
  signal p_c_last     : unsigned(47 downto 0);
  signal p_sa         : unsigned(30 downto 0);
  signal p_c_sa       : unsigned(47 downto 0);
  signal p_sd         : unsigned(30 downto 0);
  signal p_c_sd       : unsigned(47 downto 0);
  signal p_accel_seed : unsigned(47 downto 0);
  signal p_decel_seed : unsigned(47 downto 0);
  signal p_cruise     : unsigned(63 downto 0);
  signal p_stop_ratio : unsigned(31 downto 0); -- accel / decel, Q16.16
  signal p_run_m      : unsigned(30 downto 0); -- L - sd + 1: m of a soft stop in RUN (set at edge 1)

  -- Move sequencer and outputs.
  signal phase        : std_logic_vector(1 downto 0);
  signal busy_r       : std_logic;
  signal done_r       : std_logic;
  signal error_r      : std_logic;
  signal err_code_r   : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal step_r       : std_logic;
  signal dir_r        : std_logic;
  signal state_r      : std_logic_vector(1 downto 0);
  signal position_r   : unsigned(31 downto 0);
  signal step_count_r : unsigned(30 downto 0);
  signal cur_delay_r  : unsigned(31 downto 0);
  signal chk_code     : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  -- Clocks until a pulse keeps min_gap from the previous pulse of the move (0: it may come).
  signal gap_left : unsigned(16 downto 0);
  signal n_zero   : std_logic;
  signal n_one    : std_logic;

  -- Base timer.
  signal tmr_restart : std_logic;
  signal tick        : std_logic;

  -- Interval now counting down. cnt is 33 bits: an interval lasts up to 2^32 ticks (integer part 2^32 - 1 plus a
  -- carry from the fraction).
  signal cnt      : unsigned(32 downto 0);
  signal acc      : unsigned(31 downto 0); -- accumulator fraction after this interval
  signal cur_last : std_logic;

  -- Next interval, ready to be copied at the pulse edge.
  signal nxt_ok    : std_logic;
  signal nxt_d     : unsigned(32 downto 0);
  signal nxt_acc   : unsigned(31 downto 0);
  signal nxt_code  : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal nxt_state : std_logic_vector(1 downto 0);
  signal nxt_last  : std_logic;

  -- Precompute: pc_j is the index of the interval being prepared, pc_jm1 = pc_j - 1, pc_m = L - pc_j.
  signal pc_state    : std_logic_vector(2 downto 0);
  signal seed_wait   : std_logic; -- the accel seed load of this move is not answered yet
  signal pc_j        : unsigned(30 downto 0);
  signal pc_jm1      : unsigned(30 downto 0);
  signal pc_m        : unsigned(30 downto 0);
  signal dec_started : std_logic;
  -- Recurrence state: A_{j-2} while accelerating, D_{L-j+1} while decelerating (never both in one move).
  signal rec_val : unsigned(47 downto 0);
  signal rec_rem : unsigned(32 downto 0);
  signal v_r     : unsigned(63 downto 0); -- Q32.32 value of interval pc_j (then of the alternative)
  signal v_code  : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  -- The integer part of v_r is 0 (in parallel with the accumulator's carry chain).
  signal v_int_zero : std_logic;

  -- Soft stop. sreq: a request waits for its pulse p (the first pulse edge after the edge that sampled it).
  -- stop_mode: a soft stop is in effect; the precompute then follows the stop's decel ramp, pc_m = L' - pc_j.
  -- While interval c counts down (ACCEL or RUN), the alternative "soft stop decided at pulse c" is prepared
  -- after the normal next interval: alt_kind (what it does), and for m >= 1 the value of interval c + 1 in the
  -- stop (c_last when m = 1, else D_(m-1) from D_m := D), through the same accumulator step as a normal value.
  -- D is the normal value of interval c + 1 just prepared (A_c or c_sa in ACCEL, cruise in RUN), truncated to Q32.16.
  signal sreq        : std_logic;
  signal stop_mode   : std_logic;
  signal cur_prod    : unsigned(62 downto 0); -- c * stop_ratio, Q47.16, for the ACCEL interval c now counting
  signal prod_step   : std_logic;             -- pc_j <= sa: the next pulse adds stop_ratio to cur_prod
  signal alt_kind    : std_logic_vector(1 downto 0);
  signal alt_one     : std_logic;             -- m = 1
  signal alt_mm1     : unsigned(30 downto 0); -- m - 1
  signal alt_dval    : unsigned(47 downto 0); -- D: the Q32.16 value of interval c + 1 in the plan
  signal alt_ok      : std_logic;
  signal alt_d       : unsigned(32 downto 0);
  signal alt_acc     : unsigned(31 downto 0);
  signal alt_code    : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal alt_rec_val : unsigned(47 downto 0); -- D_(m-1) and its remainder: the stop's recurrence state
  signal alt_rec_rem : unsigned(32 downto 0);

  -- Next-delay unit.
  signal nd_flush     : std_logic;
  signal req_r        : std_logic;
  signal req_seed_r   : std_logic;
  signal req_decel_r  : std_logic;
  signal req_index_r  : unsigned(30 downto 0);
  signal req_alt_r    : std_logic; -- the request is the soft-stop alternative: value D, remainder 0
  signal nd_req_value : std_logic_vector(47 downto 0);
  signal nd_req_rem   : std_logic_vector(32 downto 0);
  signal nd_busy      : std_logic;
  signal nd_valid     : std_logic;
  signal nd_value     : std_logic_vector(47 downto 0);
  signal nd_rem       : std_logic_vector(32 downto 0);
  signal nd_ovf       : std_logic;

begin

  state_name <= t_state_name'val(to_integer(unsigned(state_r)));

  v_int_zero <= '1' when v_r(63 downto 32) = 0 else
                '0';

  -- The numerator 2 * Q32.16 + remainder needs 50 bits; the divider stops at 64.
  assert G_DIV_WIDTH >= 50 and G_DIV_WIDTH <= 64
    report "stepramp_engine: G_DIV_WIDTH must be in 50 .. 64"
    severity failure;

  -- The timer supports 1 .. 32 bits; the driver's register is 16 bits wide.
  assert G_PRESCALE_WIDTH >= 1 and G_PRESCALE_WIDTH <= 32
    report "stepramp_engine: G_PRESCALE_WIDTH must be in 1 .. 32"
    severity failure;

  timer_inst : entity work.stepramp_timer
    generic map (
      G_WIDTH => G_PRESCALE_WIDTH
    )
    port map (
      clk      => clk,
      rst      => rst,
      restart  => tmr_restart,
      prescale => std_logic_vector(p_prescale),
      tick     => tick
    );

  -- A seed load carries its seed; a recurrence step carries the running value (and its remainder); the first value
  -- of a soft stop's ramp is a step from D_m := D with remainder 0.
  nd_req_value <= std_logic_vector(p_accel_seed) when req_seed_r = '1' and req_decel_r = '0' else
                  std_logic_vector(p_decel_seed) when req_seed_r = '1' else
                  std_logic_vector(alt_dval) when req_alt_r = '1' else
                  std_logic_vector(rec_val);
  nd_req_rem   <= (others => '0') when req_alt_r = '1' else
                  std_logic_vector(rec_rem);

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
      req_rem   => nd_req_rem,
      busy      => nd_busy,
      ans_valid => nd_valid,
      ans_value => nd_value,
      ans_rem   => nd_rem,
      ans_ovf   => nd_ovf
    );

  -- Parameter check of the latched move: only values the move will really use (rule order of the spec) must be
  -- >= 1.0. Registered every clock; the sequencer reads it at edge 2 (the parameters are latched at edge 0).
  check_proc : process (clk) is

    variable v_chk : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);

  begin

    -- Only while busy: the latched parameters are undefined before the first start, and an idle engine should not
    -- compare them every clock (simulation speed; the result is only read at edge 2 of a move).
    if (rising_edge(clk) and busy_r = '1') then
      v_chk := C_ERR_NONE;
      if (p_prescale = 0) then
        v_chk := C_ERR_PRESCALE;
      elsif (p_steps(30 downto 1) /= 0) then
        -- N >= 2
        if (p_sa = 0 or p_sd = 0 or p_sa > p_l or p_sd > p_l or p_sa > p_sd) then
          v_chk := C_ERR_BOUNDS;
        elsif (p_c_first(47 downto 16) = 0) then
          v_chk := C_ERR_C_FIRST;
        elsif (p_l(30 downto 1) /= 0 and p_c_last(47 downto 16) = 0) then
          v_chk := C_ERR_C_LAST;
        elsif (p_sa /= 1 and p_sa /= p_l and p_c_sa(47 downto 16) = 0) then
          v_chk := C_ERR_C_SA;
        elsif (p_sd /= 1 and p_sd /= p_l and p_sd /= p_sa and p_c_sd(47 downto 16) = 0) then
          v_chk := C_ERR_C_SD;
        elsif (p_sd - p_sa >= 2 and p_cruise(63 downto 32) = 0) then
          v_chk := C_ERR_CRUISE;
        elsif (p_sa >= 3 and p_accel_seed(47 downto 16) = 0) then
          v_chk := C_ERR_ACCEL_SEED;
        elsif (p_l - p_sd >= 2 and p_decel_seed(47 downto 16) = 0) then
          v_chk := C_ERR_DECEL_SEED;
        end if;
      end if;
      chk_code <= v_chk;

      if (p_steps = 0) then
        n_zero <= '1';
      else
        n_zero <= '0';
      end if;
      if (p_steps = 1) then
        n_one <= '1';
      else
        n_one <= '0';
      end if;
    end if;

  end process check_proc;

  main_proc : process (clk) is

    variable v_sum    : unsigned(64 downto 0);
    variable v_low    : unsigned(32 downto 0);
    variable v_zero   : std_logic;
    variable v_pulse  : std_logic;
    variable v_load   : std_logic;
    variable v_finish : std_logic;
    variable v_err    : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    variable v_alt    : std_logic;
    variable v_m      : unsigned(30 downto 0);
    variable v_big    : std_logic;

  begin

    if rising_edge(clk) then
      -- Strobes are low unless set below.
      step_r      <= '0';
      done_r      <= '0';
      error_r     <= '0';
      tmr_restart <= '0';
      nd_flush    <= '0';
      v_pulse     := '0';
      v_load      := '0';
      v_finish    := '0';
      v_alt       := '0';
      v_err       := C_ERR_NONE;
      v_m         := (others => '0');
      v_big       := '0';
      -- The fractional-carry accumulator step of the value in v_r (used by C_PC_ADD and C_PC_ALT_ADD: one adder),
      -- carry-select: the fraction's sum and the integer part + 1 are computed side by side and the fraction's carry
      -- picks the integer part, so no carry ripples through all 65 bits. "s >> 32 = 0" (no ticks) follows from the
      -- same carry and v_r's integer part.
      v_low := ('0' & v_r(31 downto 0)) + ('0' & acc);
      if (v_low(32) = '1') then
        v_sum := (('0' & v_r(63 downto 32)) + 1) & v_low(31 downto 0);
      else
        v_sum := ('0' & v_r(63 downto 32)) & v_low(31 downto 0);
      end if;
      v_zero := v_int_zero and not v_low(32);

      -- pc_j <= sa, registered off the pulse path (read at pulse edges after pulse 0 only).
      if (pc_j <= p_sa) then
        prod_step <= '1';
      else
        prod_step <= '0';
      end if;

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

      -- Precompute of interval pc_j. Its last step (C_PC_ADD) is the only wide adder of the engine, and it is off
      -- the countdown path: the pulse edge only copies its results.
      case pc_state is

        when C_PC_IDLE =>

          null;

        when C_PC_IDX =>

          pc_jm1   <= pc_j;
          pc_j     <= pc_j + 1;
          pc_m     <= pc_m - 1;
          pc_state <= C_PC_DECIDE;

          -- The soft stop decided at pulse c = pc_j (the end of the interval now counting, L - c = pc_m):
          -- m = floor(c * stop_ratio / 2^16) in ACCEL, L - sd + 1 in RUN; ignored in DECEL, after a stop, and
          -- when c + m >= L.
          if (state_r = C_ST_RUN) then
            v_m   := p_run_m;
            v_big := '0';
          else
            v_m := cur_prod(46 downto 16);
            if (cur_prod(62 downto 47) /= 0) then
              v_big := '1';
            else
              v_big := '0';
            end if;
          end if;
          alt_kind <= C_ALT_IGNORE;
          if (stop_mode = '0' and (state_r = C_ST_ACCEL or state_r = C_ST_RUN)) then
            if (v_big = '1' or v_m >= pc_m) then
              alt_kind <= C_ALT_IGNORE;
            elsif (v_m = 0) then
              alt_kind <= C_ALT_END;
            else
              alt_kind <= C_ALT_LOAD;
            end if;
          end if;
          alt_mm1 <= v_m - 1;
          if (v_m = 1) then
            alt_one <= '1';
          else
            alt_one <= '0';
          end if;

        when C_PC_DECIDE =>

          if (seed_wait = '0') then
            -- Ramp phase of interval j: ACCEL if j < sa, RUN if sa <= j < sd, DECEL if j >= sd (sa <= sd); all
            -- intervals of a soft stop are DECEL.
            if (stop_mode = '1') then
              nxt_state <= C_ST_DECEL;
            elsif (pc_j < p_sa) then
              nxt_state <= C_ST_ACCEL;
            elsif (pc_j < p_sd) then
              nxt_state <= C_ST_RUN;
            else
              nxt_state <= C_ST_DECEL;
            end if;

            if (pc_m = 0) then
              nxt_last <= '1';
            else
              nxt_last <= '0';
            end if;

            v_code    <= C_ERR_NONE;
            req_alt_r <= '0';

            -- The spec's rule order (j >= 2 here, so rule 1 never applies). In a soft stop: c_last at L', before
            -- it the stop's decel ramp D_(L'-j) from D_(L'-j+1).
            if (pc_m = 0) then
              v_r      <= p_c_last & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (stop_mode = '1') then
              req_r       <= '1';
              req_seed_r  <= '0';
              req_decel_r <= '1';
              req_index_r <= pc_m;
              pc_state    <= C_PC_WAIT;
            elsif (pc_j = p_sa) then
              v_r      <= p_c_sa & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (pc_j = p_sd) then
              v_r      <= p_c_sd & C_Q16_PAD;
              pc_state <= C_PC_ADD;
            elsif (pc_j < p_sa) then
              -- A_{j-1} from A_{j-2}.
              req_r       <= '1';
              req_seed_r  <= '0';
              req_decel_r <= '0';
              req_index_r <= pc_jm1;
              pc_state    <= C_PC_WAIT;
            elsif (pc_j > p_sd) then
              -- D_{L-j}: the seed itself at j = sd + 1, else from D_{L-j+1}.
              req_r       <= '1';
              req_seed_r  <= not dec_started;
              req_decel_r <= '1';
              req_index_r <= pc_m;
              dec_started <= '1';
              pc_state    <= C_PC_WAIT;
            else
              v_r      <= p_cruise;
              pc_state <= C_PC_ADD;
            end if;
          end if;

        when C_PC_WAIT =>

          if (req_r = '0' and nd_valid = '1') then
            rec_val <= unsigned(nd_value);
            rec_rem <= unsigned(nd_rem);
            v_r     <= unsigned(nd_value) & C_Q16_PAD;
            if (nd_ovf = '1') then
              v_code <= C_ERR_RANGE;
            end if;
            pc_state <= C_PC_ADD;
          end if;

        when C_PC_ADD =>

          -- The fractional-carry accumulator: s = acc + v, the interval lasts s >> 32 ticks.
          nxt_d   <= v_sum(64 downto 32);
          nxt_acc <= v_sum(31 downto 0);
          if (v_code /= C_ERR_NONE) then
            nxt_code <= v_code;
          elsif (v_zero = '1') then
            -- Two pulses on one tick cannot be emitted (only a recurrence value can get here).
            nxt_code <= C_ERR_ZERO_TICKS;
          else
            nxt_code <= C_ERR_NONE;
          end if;
          nxt_ok   <= '1';
          pc_state <= C_PC_IDLE;

          -- Then the soft-stop alternative of the same interval (the next-delay unit is free now). Its D is the
          -- value just added: the plan's interval c + 1 (A_c, c_sa or cruise), Q32.16.
          v_code   <= C_ERR_NONE;
          alt_dval <= v_r(63 downto 16);
          if (alt_kind = C_ALT_LOAD) then
            if (alt_one = '1') then
              v_r      <= p_c_last & C_Q16_PAD;
              pc_state <= C_PC_ALT_ADD;
            else
              -- D_(m-1) = D + (2 D) div (4 m - 1): the unit's decel step at index m - 1.
              req_r       <= '1';
              req_seed_r  <= '0';
              req_decel_r <= '1';
              req_alt_r   <= '1';
              req_index_r <= alt_mm1;
              pc_state    <= C_PC_ALT_WAIT;
            end if;
          end if;

        when C_PC_ALT_WAIT =>

          if (req_r = '0' and nd_valid = '1') then
            alt_rec_val <= unsigned(nd_value);
            alt_rec_rem <= unsigned(nd_rem);
            v_r         <= unsigned(nd_value) & C_Q16_PAD;
            if (nd_ovf = '1') then
              v_code <= C_ERR_RANGE;
            end if;
            pc_state <= C_PC_ALT_ADD;
          end if;

        when C_PC_ALT_ADD =>

          alt_d   <= v_sum(64 downto 32);
          alt_acc <= v_sum(31 downto 0);
          if (v_code /= C_ERR_NONE) then
            alt_code <= v_code;
          elsif (v_zero = '1') then
            alt_code <= C_ERR_ZERO_TICKS;
          else
            alt_code <= C_ERR_NONE;
          end if;
          alt_ok   <= '1';
          pc_state <= C_PC_IDLE;

        when others =>

          pc_state <= C_PC_IDLE;

      end case;

      -- Move sequencer.
      case phase is

        when C_PH_IDLE =>

          if (load = '1') then
            p_steps      <= unsigned(steps);
            p_l          <= unsigned(steps) - 1;
            p_prescale   <= unsigned(prescale);
            p_c_first    <= unsigned(c_first);
            p_c_last     <= unsigned(c_last);
            p_sa         <= unsigned(sa);
            p_c_sa       <= unsigned(c_sa);
            p_sd         <= unsigned(sd);
            p_c_sd       <= unsigned(c_sd);
            p_accel_seed <= unsigned(accel_seed);
            p_decel_seed <= unsigned(decel_seed);
            p_cruise     <= unsigned(cruise);
            p_stop_ratio <= unsigned(stop_ratio);
          end if;

          if (start = '1') then
            dir_r        <= direction;
            busy_r       <= '1';
            err_code_r   <= C_ERR_NONE;
            step_count_r <= (others => '0');
            tmr_restart  <= '1';
            nd_flush     <= '1';
            pc_state     <= C_PC_IDLE;
            req_r        <= '0';
            seed_wait    <= '0';
            nxt_ok       <= '0';
            sreq         <= '0';
            stop_mode    <= '0';
            alt_kind     <= C_ALT_IGNORE;
            alt_ok       <= '0';
            phase        <= C_PH_SETUP;
          end if;

        when C_PH_SETUP =>

          -- The parameter check (check_proc) sees the latched parameters from this edge on: chk_code, n_zero and
          -- n_one are read at edge 2.

          -- Interval 1 is c_first; with acc = 0 its ticks and fraction are plain slices.
          nxt_d    <= resize(p_c_first(47 downto 16), 33);
          nxt_acc  <= p_c_first(15 downto 0) & C_Q16_PAD;
          nxt_code <= C_ERR_NONE;
          nxt_ok   <= '1';
          if (p_sa > 1) then
            nxt_state <= C_ST_ACCEL;
          elsif (p_sd > 1) then
            nxt_state <= C_ST_RUN;
          else
            nxt_state <= C_ST_DECEL;
          end if;
          if (p_l = 1) then
            nxt_last <= '1';
          else
            nxt_last <= '0';
          end if;

          pc_j        <= to_unsigned(1, 31);
          pc_m        <= p_l - 1;
          p_run_m     <= p_l - p_sd + 1;
          dec_started <= '0';
          cur_prod    <= (others => '0');
          -- Load the accel seed A_0 through the unit (at index 0), like the decel seed later: the unit sees the
          -- start of every value sequence, so a closed-form mode can take its constants from the seeds.
          req_r       <= '1';
          req_seed_r  <= '1';
          req_decel_r <= '0';
          req_index_r <= (others => '0');
          req_alt_r   <= '0';
          seed_wait   <= '1';
          phase       <= C_PH_FIRST;

        when C_PH_FIRST =>

          if (chk_code /= C_ERR_NONE) then
            v_finish := '1';
            v_err    := chk_code;
          elsif (n_zero = '1') then
            v_finish := '1';
          else
            v_pulse := '1';
            if (n_one = '1') then
              v_finish := '1';
            elsif (sreq = '1') then
              -- A soft stop requested before pulse 0 (p = 0: no speed, m = 0): the move ends with pulse 0.
              v_finish := '1';
            else
              v_load := '1';
              phase  <= C_PH_RUN;
            end if;
          end if;

        when C_PH_RUN =>

          -- The hot path: one compare per tick.
          if (tick = '1') then
            if (cnt = 1 and gap_left /= 0) then
              -- Too close to the previous pulse: it would merge with it on the STEP pin.
              v_finish := '1';
              v_err    := C_ERR_STEP_SPACE;
            elsif (cnt = 1) then
              v_pulse := '1';
              if (sreq = '1' and alt_kind = C_ALT_END) then
                -- Soft stop with m = 0: this pulse is the last.
                v_finish := '1';
              elsif (sreq = '1' and alt_kind = C_ALT_LOAD) then
                -- Soft stop: the next interval is the alternative.
                if (alt_ok = '0') then
                  v_finish := '1';
                  v_err    := C_ERR_LATE;
                elsif (alt_code /= C_ERR_NONE) then
                  v_finish := '1';
                  v_err    := alt_code;
                else
                  v_alt := '1';
                end if;
              elsif (cur_last = '1') then
                v_finish := '1';
              elsif (nxt_ok = '0') then
                v_finish := '1';
                v_err    := C_ERR_LATE;
              elsif (nxt_code /= C_ERR_NONE) then
                v_finish := '1';
                v_err    := nxt_code;
              else
                v_load := '1';
              end if;
            else
              cnt <= cnt - 1;
            end if;
          end if;

        when others =>

          phase <= C_PH_IDLE;

      end case;

      -- Hard stop: sampled while busy (or with the start it would accept), it ends the move at this edge; a pulse
      -- due at this edge is not emitted. done without error.
      if (hard_stop = '1' and (busy_r = '1' or (phase = C_PH_IDLE and start = '1'))) then
        v_pulse  := '0';
        v_load   := '0';
        v_alt    := '0';
        v_finish := '1';
        v_err    := C_ERR_NONE;
      end if;

      -- Step spacing: gap_left is 0 once min_gap clocks have passed since the last pulse (none before pulse 0).
      if (v_pulse = '1' and unsigned(min_gap) /= 0) then
        gap_left <= unsigned(min_gap) - 1;
      elsif (gap_left /= 0) then
        gap_left <= gap_left - 1;
      end if;

      if (v_pulse = '1') then
        step_r       <= '1';
        step_count_r <= step_count_r + 1;
        if (dir_r = '0') then
          position_r <= position_r + 1;
        else
          position_r <= position_r - 1;
        end if;
      end if;

      -- Pulse edge: the next interval starts; only register copies here (and the running product of the stop).
      if (v_load = '1' or v_alt = '1') then
        nxt_ok   <= '0';
        alt_ok   <= '0';
        alt_kind <= C_ALT_IGNORE;
        -- An alternative still being prepared is dropped (the unit is flushed before the next request).
        if (pc_state /= C_PC_IDLE) then
          nd_flush <= '1';
          req_r    <= '0';
        end if;
      end if;

      if (v_load = '1') then
        cnt      <= nxt_d;
        acc      <= nxt_acc;
        cur_last <= nxt_last;
        state_r  <= nxt_state;
        if (nxt_d(32) = '1') then
          cur_delay_r <= (others => '1');
        else
          cur_delay_r <= nxt_d(31 downto 0);
        end if;
        -- The interval loaded is pc_j (<= sa: the running product follows it). pc_j is 1 at pulse 0 (sa >= 1 there,
        -- the parameter check has passed), and stable for at least two clocks before any later pulse edge, so the
        -- registered compare (prod_step) is current.
        if (phase = C_PH_FIRST or prod_step = '1') then
          cur_prod <= cur_prod + p_stop_ratio;
        end if;
        if (nxt_last = '0') then
          pc_state <= C_PC_IDX;
        else
          pc_state <= C_PC_IDLE;
        end if;
      end if;

      -- Soft stop takes effect: interval p + 1 is the alternative, L' = p + m; the precompute continues the stop's
      -- ramp from D_(m-1) (pc_m = L' - (p + 1) = m - 1).
      if (v_alt = '1') then
        cnt       <= alt_d;
        acc       <= alt_acc;
        cur_last  <= alt_one;
        state_r   <= C_ST_DECEL;
        stop_mode <= '1';
        rec_val   <= alt_rec_val;
        rec_rem   <= alt_rec_rem;
        pc_m      <= alt_mm1;
        if (alt_d(32) = '1') then
          cur_delay_r <= (others => '1');
        else
          cur_delay_r <= alt_d(31 downto 0);
        end if;
        if (alt_one = '0') then
          pc_state <= C_PC_IDX;
        else
          pc_state <= C_PC_IDLE;
        end if;
      end if;

      -- Soft stop request: taken while busy and no stop is in effect; a pulse consumes the request it decided on
      -- (a request sampled at a pulse edge is for the next pulse).
      if (v_pulse = '1') then
        sreq <= '0';
      end if;
      if (soft_stop = '1' and busy_r = '1' and stop_mode = '0' and v_alt = '0') then
        sreq <= '1';
      end if;

      if (v_finish = '1') then
        done_r      <= '1';
        busy_r      <= '0';
        state_r     <= C_ST_STOP;
        cur_delay_r <= (others => '0');
        phase       <= C_PH_IDLE;
        pc_state    <= C_PC_IDLE;
        req_r       <= '0';
        seed_wait   <= '0';
        sreq        <= '0';
        stop_mode   <= '0';
        if (v_err /= C_ERR_NONE) then
          error_r    <= '1';
          err_code_r <= v_err;
        end if;
      end if;

      -- Position preset while stopped (a start at the same edge still sees the new position).
      if (pos_load = '1' and phase = C_PH_IDLE) then
        position_r <= unsigned(pos_value);
      end if;

      if (rst = '1') then
        phase        <= C_PH_IDLE;
        pc_state     <= C_PC_IDLE;
        busy_r       <= '0';
        done_r       <= '0';
        error_r      <= '0';
        gap_left     <= (others => '0');
        err_code_r   <= C_ERR_NONE;
        step_r       <= '0';
        dir_r        <= '0';
        state_r      <= C_ST_STOP;
        position_r   <= (others => '0');
        step_count_r <= (others => '0');
        cur_delay_r  <= (others => '0');
        tmr_restart  <= '0';
        nd_flush     <= '0';
        req_r        <= '0';
        seed_wait    <= '0';
        nxt_ok       <= '0';
        sreq         <= '0';
        stop_mode    <= '0';
        alt_ok       <= '0';
        alt_kind     <= C_ALT_IGNORE;
        -- Not state, but it feeds the timer, which then runs defined (as P = 1) from reset on.
        p_prescale <= (others => '0');
      end if;
    end if;

  end process main_proc;

  step       <= step_r;
  dir        <= dir_r;
  busy       <= busy_r;
  done       <= done_r;
  error      <= error_r;
  err_code   <= err_code_r;
  state      <= state_r;
  position   <= std_logic_vector(position_r);
  step_count <= std_logic_vector(step_count_r);
  cur_delay  <= std_logic_vector(cur_delay_r);

end architecture rtl;
