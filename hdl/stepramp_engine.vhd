-- SPDX-License-Identifier: MIT
-- stepramp_engine: the ramp engine, the sequencer of one move: it emits the move's step pulses with the exact timing
-- of docs/algorithm.md, keeps the position and step counters, and takes soft and hard stops; stepramp_precompute
-- prepares the intervals. Ports, timing, stops, error codes and latency budget: docs/stepramp_engine.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;
  -- C_ERR_* (the err_code values): one source with STATUS.ERR_CODE, the C header and the docs.
  use work.stepramp_regs_pkg.all;

entity stepramp_engine is
  generic (
    G_DIV_WIDTH      : positive := 50;
    G_PRESCALE_WIDTH : positive := 16;
    -- The ramp arithmetic: 0 the AVR446 recurrence, 1 the exact ramp (docs/algorithm.md, "Exact step times").
    G_RAMP : natural := 0
  );
  port (
    clk       : in    std_logic;
    rst       : in    std_logic;
    load      : in    std_logic;
    start     : in    std_logic;
    soft_stop : in    std_logic;
    hard_stop : in    std_logic;
    -- A take-over: the staged segment (the move inputs) takes over at pulse change_at (docs/algorithm.md, "The
    -- take-over, the queue and the script contract"). chg_pend: accepted and waiting; chg_refused: a strobe.
    change      : in    std_logic;
    change_at   : in    std_logic_vector(30 downto 0);
    chg_pend    : out   std_logic;
    chg_refused : out   std_logic;
    steps       : in    std_logic_vector(30 downto 0);
    direction   : in    std_logic;
    prescale    : in    std_logic_vector(G_PRESCALE_WIDTH - 1 downto 0);
    c_first     : in    std_logic_vector(47 downto 0);
    c_last      : in    std_logic_vector(47 downto 0);
    sa          : in    std_logic_vector(30 downto 0);
    c_sa        : in    std_logic_vector(47 downto 0);
    sd          : in    std_logic_vector(30 downto 0);
    c_sd        : in    std_logic_vector(47 downto 0);
    accel_seed  : in    std_logic_vector(63 downto 0);
    decel_seed  : in    std_logic_vector(63 downto 0);
    cruise      : in    std_logic_vector(63 downto 0);
    stop_ratio  : in    std_logic_vector(31 downto 0);
    -- The segment (docs/algorithm.md, "Changes while moving"): all 0 for a move from rest to rest.
    head_down  : in    std_logic;
    endless    : in    std_logic;
    head_index : in    std_logic_vector(30 downto 0);
    run_stop   : in    std_logic_vector(30 downto 0);
    head_prod  : in    std_logic_vector(47 downto 0);
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
    -- Electrical position: the pulses counted up/down modulo 512, moved by pulses only (pos_load leaves it).
    elec_pos   : out   std_logic_vector(8 downto 0);
    step_count : out   std_logic_vector(30 downto 0);
    cur_delay  : out   std_logic_vector(31 downto 0)
  );
end entity stepramp_engine;

architecture rtl of stepramp_engine is

  -- FSM state on the state port (the ramp phase of the interval now counting down).
  constant C_ST_STOP  : std_logic_vector(1 downto 0) := "00";
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

  -- L = N - 1 of a move of N = 0 (modulo 2^31).
  constant C_L_OF_N0 : unsigned(30 downto 0) := (others => '1');
  -- An interval of one tick, and cnt_hi = 0 (compared as plain vectors: numeric_std's "=" is slow in a simulator).
  constant C_D_ONE    : std_logic_vector(32 downto 0) := (0 => '1', others => '0');
  constant C_CNT_HI_0 : std_logic_vector(16 downto 0) := (others => '0');

  -- Latched move parameters (data: no reset): the active copy (the register file holds the staging copy).
  signal p_l           : unsigned(30 downto 0); -- L = N - 1, the number of intervals
  signal p_sd_sa       : unsigned(31 downto 0); -- sd - sa, bit 31 the borrow (sa > sd); latched with the move
  signal p_l_sd        : unsigned(31 downto 0); -- L - sd, bit 31 the borrow (sd > L); latched with the move
  signal p_prescale    : unsigned(G_PRESCALE_WIDTH - 1 downto 0);
  signal p_c_first0    : std_logic;             -- integer part of c_first = 0 (c_first itself is latched by the precompute)
  signal p_c_last      : unsigned(47 downto 0);
  signal p_sa          : unsigned(30 downto 0);
  signal p_c_sa        : unsigned(47 downto 0);
  signal p_sd          : unsigned(30 downto 0);
  signal p_c_sd        : unsigned(47 downto 0);
  signal p_accel_seed0 : std_logic;             -- seed_zero(accel_seed) (the seed is latched by the precompute)
  signal p_decel_seed  : unsigned(63 downto 0);
  signal p_decel_seed0 : std_logic;             -- seed_zero(decel_seed)
  signal p_cruise      : unsigned(63 downto 0);
  signal p_stop_ratio  : unsigned(31 downto 0); -- accel / decel, Q16.16
  signal p_head_down   : std_logic;
  signal p_endless     : std_logic;
  signal p_run_stop    : unsigned(30 downto 0);
  -- The running segment's last pulse, counted in the motion's pulses (STEP_COUNT): L = N - 1 from a start, P + L of
  -- the segment from a take-over at pulse P (32 bits: the sum does not wrap). A CHANGE_AT past it is refused.
  signal p_last_pulse : unsigned(31 downto 0);
  -- For the parameter check, latched with the move: K - sa (bit 31 the borrow: a down head ends after its rest) and
  -- n0 + sa - 1 (bit 31: an up head's last index passes 2^31 - 1).
  signal p_k_sa  : unsigned(31 downto 0);
  signal p_n0_sa : unsigned(31 downto 0);

  -- Move sequencer and outputs.
  signal phase      : std_logic_vector(1 downto 0);
  signal idle_r     : std_logic; -- phase = C_PH_IDLE
  signal busy_r     : std_logic;
  signal done_r     : std_logic;
  signal error_r    : std_logic;
  signal err_code_r : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal step_r     : std_logic;
  signal dir_r      : std_logic;
  signal state_r    : std_logic_vector(1 downto 0);
  -- The pulse counters POSITION (32 bits), ELEC_POS (9) and STEP_COUNT (31): plain counters in hardware, held as
  -- integers so that a simulator counts natively (docs/conventions.md): POSITION and STEP_COUNT as their low 16 bits
  -- (pos_lo, stc_lo) and their high bits (pos_hi, stc_hi), which step on the low part's carry (or borrow), the carry
  -- chain split in two; position_r and step_count_r are the whole values (concurrent statements).
  signal pos_lo       : natural range 0 to 2 ** 16 - 1;
  signal pos_hi       : unsigned(15 downto 0);
  signal elec_pos_r   : natural range 0 to 2 ** 9 - 1;
  signal stc_lo       : natural range 0 to 2 ** 16 - 1;
  signal stc_hi       : unsigned(14 downto 0);
  signal position_r   : unsigned(31 downto 0);
  signal step_count_r : unsigned(30 downto 0);
  signal cur_delay_r  : unsigned(31 downto 0);
  signal chk_code     : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal n_zero       : std_logic;
  signal n_one        : std_logic;
  -- The check before its register (check_proc).
  signal chk_c    : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal n_zero_c : std_logic;
  signal n_one_c  : std_logic;
  -- Clocks until a pulse keeps min_gap from the previous pulse of the move (0: it may come).
  signal gap_left : natural range 0 to 2 ** 17 - 1;
  -- min_gap as an integer, min_gap /= 0 and min_gap > 1: concurrent, evaluated when min_gap changes (not each pulse).
  signal min_gap_i  : natural range 0 to 2 ** 17 - 1;
  signal min_gap_nz : std_logic;
  signal min_gap_gt : std_logic;
  -- A soft stop request: sreq_w waits for q, the first pulse edge after the edge that sampled it; q arms it (sreq),
  -- and the pulse after q decides it (docs/algorithm.md, "Soft stop": decided at p = q + 1).
  signal sreq_w : std_logic;
  signal sreq   : std_logic;
  -- Take-over: chg_pend_r an accepted change waits for its pulse P; chg_hit STEP_COUNT = P (registered: pulse P - 1
  -- has been emitted); tk the take-over itself (two clocks after pulse P - 1's edge); tk_d1 and tk_d2 delay tk until
  -- the parameter check of the new segment is ready; cur_err the code the motion ends with at its last pulse (NONE
  -- but after a take-over of a segment that failed the check).
  signal chg_pend_r    : std_logic;
  signal chg_hit       : std_logic;
  signal tk            : std_logic;
  signal pc_latch      : std_logic; -- the precompute latches c_first and the seeds (start or take-over)
  signal tk_d1         : std_logic;
  signal tk_d2         : std_logic;
  signal chg_refused_r : std_logic;
  signal cur_err       : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);

  -- Base timer.
  signal tmr_restart : std_logic;
  signal tick        : std_logic;

  -- Interval now counting down. cnt is 33 bits: an interval lasts up to 2^32 ticks (integer part 2^32 - 1 plus a
  -- carry from the fraction). Its low 16 bits are an integer and the high 17 bits step when they wrap: a 33-bit
  -- down counter in hardware, but a simulator counts the low part natively instead of bit by bit (gap_left too).
  signal cnt_lo : natural range 0 to 2 ** 16 - 1;
  signal cnt_hi : unsigned(16 downto 0);
  -- step_count_r = change_at (registered as chg_hit)
  signal chg_eq : std_logic;
  -- cnt = 1 and gap_left /= 0 as registered flags, set together with the counters, so that the decision of a
  -- pulse edge starts from flip-flops.
  signal cnt_one  : std_logic;
  signal gap_nz   : std_logic;
  signal cur_last : std_logic;

  -- This edge's decisions (decide_proc).
  signal d_begin : std_logic; -- an accepted start: edge 0
  signal d_setup : std_logic; -- edge 1
  -- The move inputs are latched (here and, c_first and accel_seed, in the precompute): load while idle, or a start
  -- while idle without a load since the previous start (the values a move consumes are not kept for a rerun).
  signal d_latch  : std_logic;
  signal loaded   : std_logic; -- a latch since the last accepted start
  signal d_pulse  : std_logic; -- a pulse
  signal d_load   : std_logic; -- the next interval (nxt_*) starts
  signal d_alt    : std_logic; -- a soft stop takes effect: the alternative (alt_*) starts
  signal d_finish : std_logic; -- the move ends (done), with error code d_err if not C_ERR_NONE
  signal d_err    : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  -- d_load and d_alt, registered: the precompute acts on a pulse edge's outcome one clock later, so that the pulse
  -- decision (a few LUTs on flip-flops) fans out only to the sequencer's own registers. In that clock the precompute
  -- still shows what the pulse consumed (nxt_ok, the alternative, stop_mode not yet set): the decision masks it.
  signal adv_r   : std_logic;
  signal alt_r   : std_logic;
  signal taken_r : std_logic; -- adv_r or alt_r

  -- From the precompute.
  signal nxt_ok    : std_logic;
  signal nxt_d     : std_logic_vector(32 downto 0);
  signal nxt_state : std_logic_vector(1 downto 0);
  signal nxt_last  : std_logic;
  signal nxt_code  : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal alt_ok    : std_logic;
  signal alt_kind  : std_logic_vector(1 downto 0);
  signal alt_d     : std_logic_vector(32 downto 0);
  signal alt_one   : std_logic;
  signal alt_code  : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal stop_mode : std_logic;
  -- The precompute's answers as the decision may read them (masked in the clock after a pulse edge).
  signal nxt_ok_m    : std_logic;
  signal alt_kind_m  : std_logic_vector(1 downto 0);
  signal stop_mode_m : std_logic;

  -- 33-bit ticks shown in 32 bits (cur_delay), saturated.
  function saturate (
    d : std_logic_vector(32 downto 0)
  ) return unsigned is
  begin

    if (d(32) = '1') then
      return to_unsigned(0, 32) - 1;
    end if;

    return unsigned(d(31 downto 0));

  end function saturate;

  -- '1' when the integer part of a Q32.16 value is 0.

  function int_zero (
    v : std_logic_vector(47 downto 0)
  ) return std_logic is
  begin

    if (unsigned(v(47 downto 16)) = 0) then
      return '1';
    end if;

    return '0';

  end function int_zero;

  -- A seed that cannot give a ramp value: its integer part is 0 (AVR446: a Q32.16 value in bits 47:0 below one
  -- tick; bits 63:48 are not used), or (the exact ramp, a seed word) its mantissa (bits 59:0) is 0 or its scale
  -- (bits 63:60) above 6 (a ramp constant c0^2 * 2^8 is below 2^16 for any c0 under 16 ticks).
  function seed_zero (
    v : std_logic_vector(63 downto 0)
  ) return std_logic is
  begin

    if (G_RAMP = 1) then
      if (unsigned(v(59 downto 0)) = 0 or unsigned(v(63 downto 60)) > 6) then
        return '1';
      end if;
      return '0';
    end if;

    return int_zero(v(47 downto 0));

  end function seed_zero;

begin

  state_name <= t_state_name'val(to_integer(unsigned(state_r)));

  -- The numerator 2 * Q32.16 + remainder needs 50 bits; the divider stops at 64.
  assert G_DIV_WIDTH >= 50 and G_DIV_WIDTH <= 64
    report "stepramp_engine: G_DIV_WIDTH must be in 50 .. 64"
    severity failure;

  assert G_RAMP <= 1
    report "stepramp_engine: G_RAMP must be 0 (AVR446) or 1 (exact)"
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

  precompute_inst : entity work.stepramp_precompute
    generic map (
      G_DIV_WIDTH => G_DIV_WIDTH,
      G_RAMP      => G_RAMP
    )
    port map (
      clk        => clk,
      rst        => rst,
      begin_move => d_begin,
      setup      => d_setup,
      take       => tk,
      advance    => adv_r,
      take_alt   => alt_r,
      finish     => d_finish,
      stop_armed => sreq,
      l          => std_logic_vector(p_l),
      sa         => std_logic_vector(p_sa),
      sd         => std_logic_vector(p_sd),
      latch      => pc_latch,
      c_first    => c_first,
      c_last     => std_logic_vector(p_c_last),
      c_sa       => std_logic_vector(p_c_sa),
      c_sd       => std_logic_vector(p_c_sd),
      accel_seed => accel_seed,
      decel_seed => std_logic_vector(p_decel_seed),
      cruise     => std_logic_vector(p_cruise),
      stop_ratio => std_logic_vector(p_stop_ratio),
      head_index => head_index,
      head_prod  => head_prod,
      head_down  => p_head_down,
      endless    => p_endless,
      run_stop   => std_logic_vector(p_run_stop),
      nxt_ok     => nxt_ok,
      nxt_d      => nxt_d,
      nxt_state  => nxt_state,
      nxt_last   => nxt_last,
      nxt_code   => nxt_code,
      alt_ok     => alt_ok,
      alt_kind   => alt_kind,
      alt_d      => alt_d,
      alt_one    => alt_one,
      alt_code   => alt_code,
      stop_mode  => stop_mode
    );

  nxt_ok_m    <= nxt_ok and not taken_r;
  alt_kind_m  <= alt_kind when taken_r = '0' else
                 "00";
  stop_mode_m <= stop_mode or alt_r;

  -- Parameter check of the latched move: only values the move will really use (rule order of the spec) must be
  -- >= 1.0. Combinational from the latched parameters and registered every clock (seq_proc); the sequencer reads it
  -- at edge 2 (the parameters are latched at edge 0). A process on the parameters, not on the clock: a simulator
  -- evaluates it once a move, not every clock (the register is the same).
  check_proc : process (p_prescale, p_l, p_endless, p_sa, p_sd, p_sd_sa, p_l_sd, p_c_first0, p_c_last, p_c_sa,
                        p_c_sd, p_cruise, p_accel_seed0, p_decel_seed0, p_head_down, p_k_sa, p_n0_sa) is

    variable v_chk   : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    variable v_n_one : boolean;
    variable v_n_two : boolean;
    variable v_fin   : boolean;

  begin

    -- (Before the first latch the parameters are undefined; the result is read only after one.)
    -- Two subtractions (p_sd_sa, p_l_sd, registered with the move) give every relation of sa, sd and L the rules
    -- need. Once sa <= sd <= L holds (BOUNDS), sa <= L follows, sa = L is sa = sd = L, and sa, sd >= 1 make
    -- "/= 1" a test of the upper bits.
    -- p_l = N - 1 modulo 2^31: all ones for N = 0, 0 for N = 1.
    v_n_one := p_l = 0 and p_endless = '0';
    v_n_two := (p_l /= 0 and p_l /= C_L_OF_N0) or p_endless = '1';
    -- An endless move has no last interval and no final decel: sd and L are not read (v_fin: they are).
    v_fin := p_endless = '0';

    v_chk := C_ERR_NONE;

    if (p_prescale = 0) then
      v_chk := C_ERR_PRESCALE;
    elsif (v_n_two) then
      -- N >= 2
      if (p_sa = 0 or (v_fin and (p_sd = 0 or p_sd_sa(31) = '1' or p_l_sd(31) = '1'))) then
        v_chk := C_ERR_BOUNDS;
      elsif (p_c_first0 = '1') then
        v_chk := C_ERR_C_FIRST;
      elsif ((p_l(30 downto 1) /= 0 or not v_fin) and p_c_last(47 downto 16) = 0) then
        v_chk := C_ERR_C_LAST;
      elsif (p_sa(30 downto 1) /= 0 and (p_sd_sa /= 0 or p_l_sd /= 0 or not v_fin) and p_c_sa(47 downto 16) = 0) then
        v_chk := C_ERR_C_SA;
      elsif (v_fin and p_sd(30 downto 1) /= 0 and p_l_sd /= 0 and p_sd_sa /= 0 and p_c_sd(47 downto 16) = 0) then
        v_chk := C_ERR_C_SD;
      elsif ((p_sd_sa(30 downto 1) /= 0 or not v_fin) and p_cruise(63 downto 32) = 0) then
        v_chk := C_ERR_CRUISE;
      elsif ((p_sa(30 downto 2) /= 0 or p_sa(1 downto 0) = "11") and p_accel_seed0 = '1') then
        v_chk := C_ERR_ACCEL_SEED;
      elsif (v_fin and p_l_sd(30 downto 1) /= 0 and p_decel_seed0 = '1') then
        v_chk := C_ERR_DECEL_SEED;
      elsif ((p_head_down = '1' and p_k_sa(31) = '1') or (p_head_down = '0' and p_n0_sa(31) = '1')) then
        v_chk := C_ERR_SEGMENT;
      end if;
    end if;

    chk_c <= v_chk;

    if (not v_n_one and not v_n_two) then
      n_zero_c <= '1';
    else
      n_zero_c <= '0';
    end if;

    if (v_n_one) then
      n_one_c <= '1';
    else
      n_one_c <= '0';
    end if;

  end process check_proc;

  -- What this edge does, from registered state and the strobes only (no arithmetic): read by seq_proc and by the
  -- precompute, so that both act at the same edge.
  decide_proc : process (phase, chk_code, n_zero, n_one, sreq, tick, cnt_one, gap_nz, alt_kind_m, alt_ok, alt_code,
                         cur_last, cur_err, nxt_ok_m, nxt_code, hard_stop, busy_r, idle_r, start) is

    variable v_pulse  : std_logic;
    variable v_load   : std_logic;
    variable v_finish : std_logic;
    variable v_err    : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    variable v_alt    : std_logic;

    -- A pulse that starts a prepared interval (the next one, or the soft stop's alternative): taken when it is
    -- ready (ok) and its check passed, else the move ends with LATE or with the interval's error code.

    procedure start_if_ready (
      ok            : std_logic;
      code          : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
      variable take : out std_logic
    ) is
    begin

      take := '0';

      if (ok = '0') then
        v_finish := '1';
        v_err    := C_ERR_LATE;
      elsif (code /= C_ERR_NONE) then
        v_finish := '1';
        v_err    := code;
      else
        take := '1';
      end if;

    end procedure start_if_ready;

  begin

    v_pulse  := '0';
    v_load   := '0';
    v_finish := '0';
    v_alt    := '0';
    v_err    := C_ERR_NONE;

    case phase is

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
          else
            v_load := '1';
          end if;
        end if;

      when C_PH_RUN =>

        -- The hot path: one compare per tick.
        if (tick = '1' and cnt_one = '1') then
          if (gap_nz = '1') then
            -- Too close to the previous pulse: it would merge with it on the STEP pin.
            v_finish := '1';
            v_err    := C_ERR_STEP_SPACE;
          else
            v_pulse := '1';
            -- alt_kind is one-hot: bit 0 END, bit 1 LOAD; it is slot A's judgement, so an armed request needs
            -- slot A ready (unless this pulse is the last).
            if (sreq = '1' and nxt_ok_m = '0' and cur_last = '0') then
              v_finish := '1';
              v_err    := C_ERR_LATE;
            elsif (sreq = '1' and alt_kind_m(0) = '1') then
              -- Soft stop with m = 0: this pulse is the last.
              v_finish := '1';
            elsif (sreq = '1' and alt_kind_m(1) = '1') then
              -- Soft stop: the next interval is the alternative.
              start_if_ready(alt_ok, alt_code, v_alt);
            elsif (cur_last = '1') then
              v_finish := '1';
              v_err    := cur_err;
            else
              start_if_ready(nxt_ok_m, nxt_code, v_load);
            end if;
          end if;
        end if;

      when others =>

        null;

    end case;

    -- Hard stop: sampled while busy (or with the start it would accept), it ends the move at this edge; a pulse
    -- due at this edge is not emitted. done without error.
    -- (idle_r is phase = C_PH_IDLE as a flip-flop: the hard stop's condition is one LUT deep.)
    if (hard_stop = '1' and (busy_r = '1' or (idle_r = '1' and start = '1'))) then
      v_pulse  := '0';
      v_load   := '0';
      v_alt    := '0';
      v_finish := '1';
      v_err    := C_ERR_NONE;
    end if;

    d_pulse  <= v_pulse;
    d_load   <= v_load;
    d_alt    <= v_alt;
    d_finish <= v_finish;
    d_err    <= v_err;

  end process decide_proc;

  d_begin  <= idle_r and start;
  d_latch  <= idle_r and (load or (start and not loaded));
  d_setup  <= '1' when phase = C_PH_SETUP else
              '0';
  tk       <= chg_hit and chg_pend_r;
  pc_latch <= d_latch or tk;

  -- (Concurrent: evaluated when min_gap changes, read at each pulse by seq_proc.)
  min_gap_i  <= to_integer(unsigned(min_gap));
  min_gap_nz <= '1' when unsigned(min_gap) /= 0 else
                '0';
  min_gap_gt <= '1' when unsigned(min_gap(16 downto 1)) /= 0 else
                '0';

  seq_proc : process (clk) is

    variable v_dir_all : unsigned(15 downto 0);
    -- A low part plus one (or minus one: plus all ones), its carry in bit 16; the addend of POSITION, of ELEC_POS.
    variable v_sum    : natural range 0 to 2 ** 17 - 1;
    variable v_step   : natural range 1 to 2 ** 16 - 1;
    variable v_step_e : natural range 1 to 2 ** 9 - 1;

    -- The move inputs (the staging registers) become the active copy: at a start, and at a take-over.

    procedure latch_move is
    begin

      p_l <= unsigned(steps) - 1;
      -- For the parameter check, off its path: sd - sa, and L - sd = N + not sd (= N - sd - 1).
      p_sd_sa       <= ('0' & unsigned(sd)) - ('0' & unsigned(sa));
      p_l_sd        <= ('0' & unsigned(steps)) + ('1' & not unsigned(sd));
      p_prescale    <= unsigned(prescale);
      p_c_first0    <= int_zero(c_first);
      p_c_last      <= unsigned(c_last);
      p_sa          <= unsigned(sa);
      p_c_sa        <= unsigned(c_sa);
      p_sd          <= unsigned(sd);
      p_c_sd        <= unsigned(c_sd);
      p_accel_seed0 <= seed_zero(accel_seed);
      p_decel_seed  <= unsigned(decel_seed);
      p_decel_seed0 <= seed_zero(decel_seed);
      p_cruise      <= unsigned(cruise);
      p_stop_ratio  <= unsigned(stop_ratio);
      -- The segment (head_index and head_prod go to the precompute only), and its check's two sums.
      p_k_sa      <= ('0' & unsigned(head_index)) - ('0' & unsigned(sa));
      p_n0_sa     <= ('0' & unsigned(head_index)) + ('0' & unsigned(sa)) - 1;
      p_head_down <= head_down;
      p_endless   <= endless;
      p_run_stop  <= unsigned(run_stop);
      -- At a take-over CHANGE_AT still holds P (the staging is locked until now); at a start it may hold anything.
      if (tk = '1') then
        p_last_pulse <= ('0' & unsigned(change_at)) + ('0' & unsigned(steps)) - 1;
      else
        p_last_pulse <= ('0' & unsigned(steps)) - 1;
      end if;

    end procedure latch_move;

    -- A pulse edge starts interval p + 1: its length in ticks, whether it is the last and its state.

    procedure start_interval (
      d          : std_logic_vector(32 downto 0);
      last       : std_logic;
      ramp_state : std_logic_vector(1 downto 0)
    ) is
    begin

      cnt_lo  <= to_integer(unsigned(d(15 downto 0)));
      cnt_hi  <= unsigned(d(32 downto 16));
      cnt_one <= '0';

      if (d = C_D_ONE) then
        cnt_one <= '1';
      end if;

      cur_last    <= last;
      state_r     <= ramp_state;
      cur_delay_r <= saturate(d);

    end procedure start_interval;

  begin

    if rising_edge(clk) then
      -- Strobes are low unless set below.
      step_r      <= '0';
      done_r      <= '0';
      error_r     <= '0';
      tmr_restart <= '0';
      adv_r       <= d_load;
      alt_r       <= d_alt;
      -- (d_load or d_alt, as a test: a simulator then calls no std_logic "or".)
      if (d_load = '1' or d_alt = '1') then
        taken_r <= '1';
      else
        taken_r <= '0';
      end if;
      chk_code <= chk_c;
      n_zero   <= n_zero_c;
      n_one    <= n_one_c;

      -- (An if chain, not a case, with the hot path first: a simulator compares phase once a clock while running
      -- instead of three times; a metavalue (before the reset) goes idle as a case's others would. Compares with
      -- the constants only, so that synthesis still recodes phase as a state machine.)
      if (phase = C_PH_RUN) then
        if (tick = '1' and cnt_one = '0') then
          if (cnt_lo = 0) then
            cnt_lo <= 2 ** 16 - 1;
            cnt_hi <= cnt_hi - 1;
          else
            cnt_lo <= cnt_lo - 1;
          end if;
          if (cnt_lo = 2 and std_logic_vector(cnt_hi) = C_CNT_HI_0) then
            cnt_one <= '1';
          end if;
        end if;
      elsif (phase = C_PH_IDLE) then
        if (d_latch = '1') then
          loaded <= '1';
          latch_move;
        end if;

        if (start = '1') then
          dir_r       <= direction;
          busy_r      <= '1';
          err_code_r  <= C_ERR_NONE;
          cur_err     <= C_ERR_NONE;
          stc_lo      <= 0;
          stc_hi      <= (others => '0');
          tmr_restart <= '1';
          sreq        <= '0';
          sreq_w      <= '0';
          phase       <= C_PH_SETUP;
          idle_r      <= '0';
          loaded      <= '0';
        end if;
      elsif (phase = C_PH_SETUP) then
        -- The parameter check (check_proc) sees the latched parameters from this edge on: chk_code,
        -- n_zero and n_one are read at edge 2. The precompute prepares interval 1 (c_first) at this edge.
        phase <= C_PH_FIRST;
      elsif (phase = C_PH_FIRST) then
        if (d_load = '1') then
          phase <= C_PH_RUN;
        end if;
      else
        phase  <= C_PH_IDLE;
        idle_r <= '1';
      end if;

      -- Step spacing: gap_left is 0 once min_gap clocks have passed since the last pulse (none before pulse 0).
      if (d_pulse = '1' and min_gap_nz = '1') then
        gap_left <= min_gap_i - 1;
        gap_nz   <= min_gap_gt;
      elsif (gap_nz = '1') then
        gap_left <= gap_left - 1;
        if (gap_left = 1) then
          gap_nz <= '0';
        end if;
      end if;

      if (d_pulse = '1') then
        step_r <= '1';
        -- STEP_COUNT + 1: the low part's carry (bit 16 of its sum) steps the high part.
        v_sum  := stc_lo + 1;
        stc_lo <= v_sum mod 2 ** 16;
        if (v_sum / 2 ** 16 = 1) then
          stc_hi <= stc_hi + 1;
        end if;
        -- POSITION and ELEC_POS + 1 or - 1 (+ all ones) through one adder each. POSITION's high part adds all ones
        -- and the low part's carry when counting down (it steps down without a carry), 0 and the carry when counting
        -- up (it steps up with one).
        v_step   := 1;
        v_step_e := 1;
        if (dir_r = '1') then
          v_step   := 2 ** 16 - 1;
          v_step_e := 2 ** 9 - 1;
        end if;
        v_sum  := pos_lo + v_step;
        pos_lo <= v_sum mod 2 ** 16;
        if ((v_sum / 2 ** 16 = 1) /= (dir_r = '1')) then
          v_dir_all := (others => dir_r);
          pos_hi    <= pos_hi + (v_dir_all(15 downto 1) & '1');
        end if;
        elec_pos_r <= (elec_pos_r + v_step_e) mod 2 ** 9;
      end if;

      -- Pulse edge: the next interval starts; only register copies here.
      if (d_load = '1') then
        start_interval(nxt_d, nxt_last, nxt_state);
      end if;

      -- Soft stop takes effect: interval p + 1 is the alternative (L' = p + m).
      if (d_alt = '1') then
        start_interval(alt_d, alt_one, C_ST_DECEL);
      end if;

      -- Soft stop request: taken while busy, no stop in effect and no earlier request undecided. A pulse decides the
      -- armed request (sreq) and arms the waiting one (sreq_w): a request is decided at the pulse after the first
      -- pulse after it (one sampled at a pulse edge waits for the next pulse). After a take-over at pulse P no
      -- request is armed at P: one sampled before the take-over dropped the change.
      if (d_pulse = '1') then
        sreq   <= sreq_w;
        sreq_w <= '0';
      end if;
      if (soft_stop = '1' and busy_r = '1' and stop_mode_m = '0' and d_alt = '0' and sreq_w = '0' and
          (sreq = '0' or d_pulse = '1')) then
        sreq_w <= '1';
      end if;

      -- Take-over (docs/algorithm.md, "The take-over, the queue and the script contract"). A commit is accepted while
      -- busy, with nothing pending, no soft stop requested or in effect (nor one in this write), pulse P - 1 not
      -- yet emitted (STEP_COUNT < P) and P not past the running segment's last pulse (an endless one has none);
      -- else refused (the motion goes on).
      chg_hit       <= chg_eq;
      chg_refused_r <= '0';
      tk_d1         <= tk;
      tk_d2         <= tk_d1;
      if (change = '1') then
        if (busy_r = '1' and chg_pend_r = '0' and sreq = '0' and sreq_w = '0' and stop_mode_m = '0' and
            soft_stop = '0' and
            step_count_r < unsigned(change_at) and d_finish = '0' and
            (p_endless = '1' or ('0' & unsigned(change_at)) <= p_last_pulse)) then
          chg_pend_r <= '1';
        else
          chg_refused_r <= '1';
        end if;
      end if;
      -- A soft stop sampled before the take-over drops the change (it is decided as in the running segment).
      if (soft_stop = '1' and chg_pend_r = '1' and tk = '0') then
        chg_pend_r <= '0';
      end if;
      if (tk = '1') then
        chg_pend_r <= '0';
        latch_move;
        -- Interval P was started as the running segment's last, or not: the new segment decides (tk_d2).
        cur_last <= '0';
        cur_err  <= C_ERR_NONE;
      end if;
      -- The new segment's parameter check is ready: a bad segment, or one of no interval, ends the motion at pulse P.
      if (tk_d2 = '1' and (chk_code /= C_ERR_NONE or n_one = '1' or n_zero = '1')) then
        cur_last <= '1';
        cur_err  <= chk_code;
      end if;

      if (d_finish = '1') then
        -- A change still pending when the motion ends normally was never taken (its pulse was past the end).
        chg_refused_r <= chg_pend_r and not hard_stop and to_sl(d_err = C_ERR_NONE);
        chg_pend_r    <= '0';
        done_r        <= '1';
        busy_r        <= '0';
        state_r       <= C_ST_STOP;
        cur_delay_r   <= (others => '0');
        phase         <= C_PH_IDLE;
        idle_r        <= '1';
        sreq          <= '0';
        sreq_w        <= '0';
        if (d_err /= C_ERR_NONE) then
          error_r    <= '1';
          err_code_r <= d_err;
        end if;
      end if;

      -- Position preset while stopped (a start at the same edge still sees the new position). The electrical
      -- position stays: a preset (homing) must not move the motor's field.
      if (pos_load = '1' and idle_r = '1') then
        pos_lo <= to_integer(unsigned(pos_value(15 downto 0)));
        pos_hi <= unsigned(pos_value(31 downto 16));
      end if;

      if (rst = '1') then
        phase         <= C_PH_IDLE;
        idle_r        <= '1';
        loaded        <= '0';
        busy_r        <= '0';
        done_r        <= '0';
        error_r       <= '0';
        gap_left      <= 0;
        gap_nz        <= '0';
        err_code_r    <= C_ERR_NONE;
        step_r        <= '0';
        dir_r         <= '0';
        state_r       <= C_ST_STOP;
        pos_lo        <= 0;
        pos_hi        <= (others => '0');
        elec_pos_r    <= 0;
        stc_lo        <= 0;
        stc_hi        <= (others => '0');
        cur_delay_r   <= (others => '0');
        tmr_restart   <= '0';
        adv_r         <= '0';
        alt_r         <= '0';
        taken_r       <= '0';
        sreq          <= '0';
        sreq_w        <= '0';
        chg_pend_r    <= '0';
        chg_hit       <= '0';
        chg_refused_r <= '0';
        tk_d1         <= '0';
        tk_d2         <= '0';
        cur_err       <= C_ERR_NONE;
        -- Not state, but it feeds the timer, which then runs defined (as P = 1) from reset on.
        p_prescale <= (others => '0');
      end if;
    end if;

  end process seq_proc;

  -- The pulse counters as vectors (concurrent: evaluated at a pulse, not every clock).
  position_r   <= pos_hi & to_unsigned(pos_lo, 16);
  step_count_r <= stc_hi & to_unsigned(stc_lo, 16);

  -- (A concurrent compare: evaluated when STEP_COUNT or CHANGE_AT changes, registered every clock in seq_proc.)
  chg_eq <= '1' when step_count_r = unsigned(change_at) else
            '0';

  chg_pend    <= chg_pend_r;
  chg_refused <= chg_refused_r;
  step        <= step_r;
  dir         <= dir_r;
  busy        <= busy_r;
  done        <= done_r;
  error       <= error_r;
  err_code    <= err_code_r;
  state       <= state_r;
  -- (From the parts directly, not through position_r and step_count_r: the ports change in the delta after the
  -- registers, as a register's port does, which the benches' samplers at a value change rely on.)
  position   <= std_logic_vector(pos_hi & to_unsigned(pos_lo, 16));
  elec_pos   <= std_logic_vector(to_unsigned(elec_pos_r, 9));
  step_count <= std_logic_vector(stc_hi & to_unsigned(stc_lo, 16));
  cur_delay  <= std_logic_vector(cur_delay_r);

end architecture rtl;
