-- SPDX-License-Identifier: MIT
-- stepramp_stepper: the stepping logic between the register file / ramp engine and the motor pins: STEP / DIR /
-- ENABLE timing, the start gate that keeps DIR setup and hold, and the winding outputs of two H-bridges (wave, full
-- step two-phase-on, half step, sine/cosine PWM microstepping). Ports, timing and tables: docs/stepramp_stepper.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;
  use ieee.math_real.all;

library work;
  use work.stepramp_pkg.all;

entity stepramp_stepper is
  generic (
    G_MICROSTEPS : positive := 16;
    G_DUTY_BITS  : positive := 12;
    -- The winding outputs A1 A2 B1 B2 (full, half, wave, PWM): without them (false) they stay '0' and their logic is
    -- left out in synthesis (docs/stepramp_stepper.md, "Generics").
    G_WINDINGS : boolean := true
  );
  port (
    clk        : in    std_logic;
    rst        : in    std_logic;
    mode       : in    std_logic_vector(2 downto 0);
    ustep_log2 : in    std_logic_vector(2 downto 0);
    step_width : in    std_logic_vector(15 downto 0);
    dir_setup  : in    std_logic_vector(15 downto 0);
    dir_hold   : in    std_logic_vector(15 downto 0);
    pwm_period : in    std_logic_vector(15 downto 0);
    step_space : in    std_logic_vector(15 downto 0);
    -- CTRL.ENABLE (the pin is enable).
    ctrl_enable : in    std_logic;
    -- Start gate: the register file's start and stop strobes and the direction of the move being started; a start
    -- being held and the direction check, for STATUS.
    start_req : in    std_logic;
    new_dir   : in    std_logic;
    hard_stop : in    std_logic;
    soft_stop : in    std_logic;
    gate_busy : out   std_logic;
    dir_fault : out   std_logic;
    -- The multi-axis top's common start (docs/stepramp_stepper.md, "Start gate"): gate_wait is '1' while the gate
    -- holds a start that its own DIR hold / setup or STEP spacing does not yet let go; while start_hold is '1' a
    -- start that could go waits (in SETUP), so that every axis of one SYNC_START fires on one edge. Tie to '0' alone.
    start_hold : in    std_logic;
    gate_wait  : out   std_logic;
    -- From the ramp engine (eng_X is the engine's port X).
    eng_step     : in    std_logic;
    eng_busy     : in    std_logic;
    eng_dir      : in    std_logic;
    eng_elec_pos : in    std_logic_vector(8 downto 0);
    -- To the ramp engine (eng_hard_stop is ORed with the register file's hard_stop).
    eng_start     : out   std_logic;
    eng_hard_stop : out   std_logic;
    eng_direction : out   std_logic;
    eng_min_gap   : out   std_logic_vector(16 downto 0);
    -- Pins: STEP / DIR / ENABLE for a driver chip, A1 A2 B1 B2 for two H-bridges.
    step   : out   std_logic;
    dir    : out   std_logic;
    enable : out   std_logic;
    a1     : out   std_logic;
    a2     : out   std_logic;
    b1     : out   std_logic;
    b2     : out   std_logic
  );
end entity stepramp_stepper;

architecture rtl of stepramp_stepper is

  -- Microsteps per full step as a power of two (log2_ceil is exact for the powers of two the generic check below
  -- admits), and the width of the electrical index at full resolution
  -- (4 * G_MICROSTEPS positions per electrical cycle).
  constant C_LG : natural  := log2_ceil(G_MICROSTEPS);
  constant C_EW : positive := C_LG + 2;

  -- (Integers: a table read is one signal for a simulator, not one per bit; the same ROM in hardware.)

  type t_mag_table is array (natural range <>) of natural range 0 to 2 ** G_DUTY_BITS;

  -- Quarter-wave magnitude table: C_COS(k) = floor(2^G_DUTY_BITS * cos(pi * k / (2 * G_MICROSTEPS)) + 0.5),
  -- k = 0 .. G_MICROSTEPS (C_COS(0) = 2^G_DUTY_BITS, C_COS(G_MICROSTEPS) = 0), computed at elaboration.
  function make_cos_table return t_mag_table is

    variable v_tab : t_mag_table(0 to G_MICROSTEPS);
    variable v_x   : real;

  begin

    for k in 0 to G_MICROSTEPS loop

      v_x      := cos(MATH_PI * real(k) / real(2 * G_MICROSTEPS));
      v_tab(k) := integer(floor(real(2 ** G_DUTY_BITS) * v_x + 0.5));

    end loop;

    -- cos(pi / 2) is not exactly 0 in floating point; the table must end at 0 (winding off).
    v_tab(G_MICROSTEPS) := 0;
    return v_tab;

  end function make_cos_table;

  constant C_COS : t_mag_table(0 to G_MICROSTEPS) := make_cos_table;

  -- The multiplier's bit places BITS and BITS - 1 (constants: a simulator computes a generic's power at every use).
  constant C_Q_TOP : positive := 2 ** G_DUTY_BITS;
  constant C_Q_RND : positive := 2 ** (G_DUTY_BITS - 1);

  -- Modes.
  constant C_MODE_WAVE : std_logic_vector(2 downto 0) := "001";
  constant C_MODE_FULL : std_logic_vector(2 downto 0) := "010";
  constant C_MODE_HALF : std_logic_vector(2 downto 0) := "011";
  constant C_MODE_PWM  : std_logic_vector(2 downto 0) := "100";

  -- Start gate states (constants, not an enum, so that GHDL's VPI shows a plain vector).
  constant C_GS_IDLE  : std_logic_vector(1 downto 0) := "00";
  constant C_GS_HOLD  : std_logic_vector(1 downto 0) := "01";
  constant C_GS_SETUP : std_logic_vector(1 downto 0) := "10";
  constant C_GS_FIRED : std_logic_vector(1 downto 0) := "11";

  -- Clocks from the edge that registers eng_start to the edge at which step rises for the engine's pulse 0:
  -- 1 (engine samples start) + 2 (engine first-pulse latency) + 1 (STEP register).
  constant C_START_TO_STEP : natural := 4;
  -- Shortest DIR change -> first STEP rising edge: the gate registers eng_start one edge after the DIR change.
  constant C_SETUP_MIN : natural := C_START_TO_STEP + 1;

  -- since_step saturates above the largest min_gap - C_START_TO_STEP - 1 (min_gap <= 2 * 65535).
  constant C_SINCE_MAX : natural := 2 ** 17 - 1;

  -- STEP pulse. The reset keeps a pulse in progress, so it reads step_r: both start at 0 at configuration (the
  -- flip-flops' power-up value), which lets the first reset decide in every simulator (a netlist's X would stay).
  -- vsg_off signal_007
  signal step_r    : std_logic                      := '0';
  signal width_cnt : natural range 0 to 2 ** 16 - 1 := 0;
  -- vsg_on signal_007
  signal width_m1 : natural range 0 to 2 ** 16 - 1;
  -- The counters and comparisons that change every clock are integers (17-bit registers in hardware, as vectors
  -- would be): a simulator adds and compares them natively instead of bit by bit.
  signal since_step : natural range 0 to C_SINCE_MAX; -- edges since eng_step was last sampled '1' (saturating)
  signal min_gap_c  : natural range 0 to 2 ** 17 - 1;
  signal min_gap_r  : natural range 0 to 2 ** 17 - 1;
  signal space_ok   : std_logic;                      -- an eng_start registered at this edge keeps min_gap

  -- Start gate.
  signal gstate      : std_logic_vector(1 downto 0);
  signal dir_r       : std_logic;
  signal pend_dir    : std_logic;
  signal start_r     : std_logic;
  signal stop_r      : std_logic;
  signal gate_busy_r : std_logic;
  signal fault_r     : std_logic;
  signal setup_cnt   : unsigned(15 downto 0);
  signal setup_wait  : unsigned(15 downto 0);
  signal hold_m1     : natural range 0 to 2 ** 16 - 1;
  signal hold_ok     : std_logic;

  -- Winding levels of the on/off modes, from the half-step index h (0 .. 7).
  signal half_idx : unsigned(2 downto 0);
  signal lvl_a1   : std_logic;
  signal lvl_a2   : std_logic;
  signal lvl_b1   : std_logic;
  signal lvl_b2   : std_logic;
  -- The mode decoded (wires; a simulator compares the vector when it changes, not at every clock).
  signal mode_onoff : std_logic;
  signal mode_pwm   : std_logic;

  -- PWM: electrical index at full resolution, table stage, duty stage, carrier.
  signal u_shift  : natural range 0 to C_LG;
  signal e_idx    : unsigned(C_EW - 1 downto 0);
  signal quad     : std_logic_vector(1 downto 0);
  signal frac_idx : natural range 0 to G_MICROSTEPS - 1;
  signal cos_f    : natural range 0 to 2 ** G_DUTY_BITS;
  signal cos_g    : natural range 0 to 2 ** G_DUTY_BITS;
  signal swap1    : std_logic;
  signal neg_a1   : std_logic;
  signal neg_b1   : std_logic;
  signal mag_a    : natural range 0 to 2 ** G_DUTY_BITS;
  signal mag_b    : natural range 0 to 2 ** G_DUTY_BITS;
  signal mul_cnt  : natural range 0 to G_DUTY_BITS + 2;
  -- The multipliers' accumulators and period, the duties, the carrier and its last value are integers: one signal
  -- each for a simulator (a vector is one per bit, and these are assigned at every clock), the same registers in
  -- hardware. So are the multipliers' shift registers q (their shift q / 2 plus the new top bit: the same flip-flops,
  -- no LUT more in yosys).
  signal mul_p     : natural range 0 to 2 ** 16 - 1;
  signal acc_a     : natural range 0 to 2 ** 16 - 1;
  signal acc_b     : natural range 0 to 2 ** 16 - 1;
  signal q_a       : natural range 0 to 2 ** (G_DUTY_BITS + 1) - 1;
  signal q_b       : natural range 0 to 2 ** (G_DUTY_BITS + 1) - 1;
  signal neg_a2    : std_logic;
  signal neg_b2    : std_logic;
  signal duty_a    : natural range 0 to 2 ** 16 - 1;
  signal duty_b    : natural range 0 to 2 ** 16 - 1;
  signal neg_a     : std_logic;
  signal neg_b     : std_logic;
  signal carrier   : natural range 0 to 2 ** 16 - 1;
  signal period_i  : natural range 0 to 2 ** 16 - 1;
  signal period_m1 : natural range 0 to 2 ** 16 - 1;
  signal pwm_run   : std_logic;

  -- Output registers.
  signal enable_r : std_logic;
  signal a1_r     : std_logic;
  signal a2_r     : std_logic;
  signal b1_r     : std_logic;
  signal b2_r     : std_logic;

begin

  assert G_MICROSTEPS >= 1 and G_MICROSTEPS <= 128 and 2 ** C_LG = G_MICROSTEPS
    report "stepramp_stepper: G_MICROSTEPS must be a power of two in 1 .. 128"
    severity failure;

  assert G_DUTY_BITS >= 4 and G_DUTY_BITS <= 16
    report "stepramp_stepper: G_DUTY_BITS must be in 4 .. 16"
    severity failure;

  ---------------------------------------------------------------------------------------------------------------------
  -- STEP pulse: exactly max(step_width, 1) clocks high per eng_step; an eng_step during a pulse restarts the width.
  ---------------------------------------------------------------------------------------------------------------------
  width_m1 <= 0 when to_integer(unsigned(step_width)) = 0 else
              to_integer(unsigned(step_width)) - 1;

  -- The shortest distance between two STEP rising edges (step_space: the STEP low time, 0 acts as 1), registered
  -- (min_gap_r, in clk_proc).
  min_gap_c <= width_m1 + 2 when unsigned(step_space) = 0 else
               width_m1 + 1 + to_integer(unsigned(step_space));

  eng_min_gap <= std_logic_vector(to_unsigned(min_gap_r, 17));

  -- An eng_start registered at edge S gives a STEP rising edge at S + C_START_TO_STEP; the previous one was at the
  -- last edge R that sampled eng_step = '1' (R = S when eng_step is '1' now, else since_step = S - 1 - R).
  space_ok <= '1' when eng_step = '1' and min_gap_r <= C_START_TO_STEP else
              '1' when eng_step = '0' and since_step + C_START_TO_STEP + 1 >= min_gap_r else
              '0';

  ---------------------------------------------------------------------------------------------------------------------
  -- Start gate: DIR changes only between moves, dir_hold after the last STEP rising edge at the earliest, and
  -- eng_start follows so that the engine's first STEP rising edge comes max(dir_setup, 5) clocks after it.
  ---------------------------------------------------------------------------------------------------------------------
  -- DIR may change at edge D when D - R >= max(dir_hold, 1), i.e. since_step (value after edge D - 1) >= hold - 1.
  hold_m1 <= 0 when to_integer(unsigned(dir_hold)) = 0 else
             to_integer(unsigned(dir_hold)) - 1;

  hold_ok <= '1' when since_step >= hold_m1 else
             '0';

  setup_wait <= unsigned(dir_setup) - C_SETUP_MIN when unsigned(dir_setup) > C_SETUP_MIN else
                (others => '0');

  -- A held start that the gate's own rules do not yet let go (the common start waits for it); a stop lets it go.
  gate_wait_proc : process (gstate, start_req, eng_busy, hard_stop, soft_stop, new_dir, dir_r, space_ok,
                            setup_cnt) is
  begin

    gate_wait <= '0';

    if (gstate = C_GS_IDLE) then
      if (start_req = '1' and eng_busy = '0' and hard_stop = '0' and
          (new_dir /= dir_r or space_ok = '0')) then
        gate_wait <= '1';
      end if;
    elsif (gstate = C_GS_HOLD) then
      if (hard_stop = '0' and soft_stop = '0') then
        gate_wait <= '1';
      end if;
    elsif (gstate = C_GS_SETUP) then
      if (hard_stop = '0' and soft_stop = '0' and (setup_cnt /= 0 or space_ok = '0')) then
        gate_wait <= '1';
      end if;
    end if;

  end process gate_wait_proc;

  ---------------------------------------------------------------------------------------------------------------------
  -- On/off modes: half-step index h, then AVR446 Table 2-1 (h = 0: A+, 1: A+B+, 2: B+, 3: A-B+, 4: A-, 5: A-B-,
  -- 6: B-, 7: A+B-). Wave drive uses the even h, full step two-phase-on the odd h.
  ---------------------------------------------------------------------------------------------------------------------
  half_idx <= unsigned(eng_elec_pos(1 downto 0)) & '0' when mode = C_MODE_WAVE else
              unsigned(eng_elec_pos(1 downto 0)) & '1' when mode = C_MODE_FULL else
              unsigned(eng_elec_pos(2 downto 0));

  mode_onoff <= '1' when mode = C_MODE_WAVE or mode = C_MODE_FULL or mode = C_MODE_HALF else
                '0';
  mode_pwm   <= '1' when mode = C_MODE_PWM else
                '0';

  lvl_a1 <= '1' when half_idx = 7 or half_idx = 0 or half_idx = 1 else
            '0';
  lvl_a2 <= '1' when half_idx = 3 or half_idx = 4 or half_idx = 5 else
            '0';
  lvl_b1 <= '1' when half_idx = 1 or half_idx = 2 or half_idx = 3 else
            '0';
  lvl_b2 <= '1' when half_idx = 5 or half_idx = 6 or half_idx = 7 else
            '0';

  ---------------------------------------------------------------------------------------------------------------------
  -- PWM microstepping. e = position mod (4 * 2^u), scaled to the table's resolution: e_idx = e * G / 2^u.
  -- Quadrant q = e_idx / G, f = e_idx mod G:
  --   |A| = C_COS(f) for q = 0, 2 and C_COS(G - f) for q = 1, 3; A < 0 for q = 1, 2 (cos)
  --   |B| = C_COS(G - f) for q = 0, 2 and C_COS(f) for q = 1, 3; B < 0 for q = 2, 3 (sin)
  ---------------------------------------------------------------------------------------------------------------------
  u_shift <= C_LG - to_integer(unsigned(ustep_log2)) when to_integer(unsigned(ustep_log2)) < C_LG else
             0;

  e_idx    <= shift_left(unsigned(eng_elec_pos(C_EW - 1 downto 0)), u_shift);
  quad     <= std_logic_vector(e_idx(C_EW - 1 downto C_EW - 2));
  frac_idx <= to_integer(e_idx and to_unsigned(G_MICROSTEPS - 1, C_EW));

  -- (pwm_period - 1 wraps to 2^16 - 1 for 0, when pwm_run holds the carrier at 0; an undefined period reads 0)
  period_i  <= to_integer(unsigned(pwm_period));
  period_m1 <= to_integer(unsigned(pwm_period) - 1);
  pwm_run   <= '1' when unsigned(pwm_period) >= 2 else
               '0';

  mag_a <= cos_f when swap1 = '0' else
           cos_g;
  mag_b <= cos_g when swap1 = '0' else
           cos_f;

  -- The PWM datapath (in clk_proc below): the table reads (stage 1), the multipliers and the carrier; mag_a and mag_b
  -- above pick from the table stage.
  -- Duty = floor((|value| * pwm_period + 2^(G_DUTY_BITS - 1)) / 2^G_DUTY_BITS), at most pwm_period, for both
  -- windings by one serial shift-add multiplier each (no wide multiplier: iCE40 has no DSP). A round takes
  -- C_ROUND = G_DUTY_BITS + 3 clocks and rounds follow each other without pause:
  --   mul_cnt = 0:                 load |A|, |B|, signs and pwm_period; clear the accumulators;
  --   mul_cnt = 1 .. BITS + 1:     A + (pwm_period if the multiplier's LSB is '1'), shift {acc, q} right;
  --   mul_cnt = BITS + 2:          product = acc * 2^(BITS + 1) + q; duty = product / 2^BITS rounded (bit BITS - 1)

  -- Outputs: one register per pin. Bridge encoding: current + : IN1 = 1 (or PWM), IN2 = 0; current - : IN1 = 0,
  -- IN2 = 1 (or PWM); off: both 0. IN1 and IN2 are never both '1'.

  ---------------------------------------------------------------------------------------------------------------------
  -- The registers of all the blocks above (STEP pulse, start gate, PWM datapath, outputs) in one clocked process: a
  -- simulator wakes one process per clock edge, not four; the same registers and logic in hardware.
  ---------------------------------------------------------------------------------------------------------------------
  clk_proc : process (clk) is

    variable v_next : std_logic_vector(1 downto 0);

    variable v_sum_a : natural range 0 to 2 ** 17 - 1;
    variable v_sum_b : natural range 0 to 2 ** 17 - 1;

    -- The rounded duty of a finished product acc * 2^(BITS + 1) + q: its bits BITS + 15 .. BITS (acc's low 15 bits and
    -- q's top bit), plus q's bit BITS - 1 (once per round).

    function rounded (
      acc : natural;
      q   : natural
    ) return natural is

      variable v_dut : natural range 0 to 2 ** 16 - 1;

    begin

      -- (Integers: acc mod 2^15 is its low bits, times 2 a shift; the product's bit BITS fills the LSB it leaves 0.)
      v_dut := (acc mod 2 ** 15) * 2;

      if (q / C_Q_TOP = 1) then
        v_dut := v_dut + 1;
      end if;

      if ((q / C_Q_RND) mod 2 = 1) then
        return v_dut + 1;
      end if;

      return v_dut;

    end function rounded;

    variable v_on_a : std_logic;
    variable v_on_b : std_logic;

  begin

    if rising_edge(clk) then
      -- STEP pulse and the registered shortest gap.
      min_gap_r <= min_gap_c;

      if (rst = '1') then
        -- A pulse in progress keeps its width; otherwise STEP is low from the first reset edge on.
        if (step_r = '1' and width_cnt /= 0) then
          width_cnt <= width_cnt - 1;
        else
          step_r    <= '0';
          width_cnt <= 0;
        end if;
        since_step <= C_SINCE_MAX;
      elsif (eng_step = '1') then
        step_r     <= '1';
        width_cnt  <= width_m1;
        since_step <= 0;
      else
        if (step_r = '1') then
          if (width_cnt = 0) then
            step_r <= '0';
          else
            width_cnt <= width_cnt - 1;
          end if;
        end if;
        if (since_step /= C_SINCE_MAX) then
          since_step <= since_step + 1;
        end if;
      end if;

      -- Start gate.
      if (rst = '1') then
        gstate      <= C_GS_IDLE;
        dir_r       <= '0';
        pend_dir    <= '0';
        start_r     <= '0';
        stop_r      <= '0';
        gate_busy_r <= '0';
        fault_r     <= '0';
        setup_cnt   <= (others => '0');
      else
        start_r <= '0';
        stop_r  <= '0';
        v_next  := gstate;

        case gstate is

          when C_GS_HOLD =>

            if (hard_stop = '1' or soft_stop = '1') then
              start_r <= '1';
              stop_r  <= '1';
              v_next  := C_GS_FIRED;
            elsif (hold_ok = '1' and eng_step = '0') then
              dir_r     <= pend_dir;
              setup_cnt <= setup_wait;
              v_next    := C_GS_SETUP;
            end if;

          when C_GS_SETUP =>

            if (hard_stop = '1' or soft_stop = '1') then
              start_r <= '1';
              stop_r  <= '1';
              v_next  := C_GS_FIRED;
            elsif (setup_cnt = 0) then
              -- Setup kept; the STEP spacing across moves, or the common start, may hold the start a little longer.
              if (space_ok = '1' and start_hold = '0') then
                start_r <= '1';
                v_next  := C_GS_FIRED;
              end if;
            else
              setup_cnt <= setup_cnt - 1;
            end if;

          when C_GS_FIRED =>

            -- The engine samples eng_start at this edge and shows busy from the next cycle on: a start_req seen
            -- now would pass the engine's idle check, so it is dropped here.
            v_next := C_GS_IDLE;

          when others =>

            if (start_req = '1' and eng_busy = '0') then
              if (hard_stop = '1') then
                start_r <= '1';
                stop_r  <= '1';
                v_next  := C_GS_FIRED;
              elsif (new_dir = dir_r and space_ok = '1' and start_hold = '0') then
                start_r <= '1';
                v_next  := C_GS_FIRED;
              elsif (new_dir = dir_r) then
                -- Same direction, but too close to the last STEP pulse or held for the common start: wait in SETUP
                -- (nothing to set up).
                setup_cnt <= (others => '0');
                v_next    := C_GS_SETUP;
              else
                pend_dir <= new_dir;
                v_next   := C_GS_HOLD;
              end if;
            end if;

        end case;

        gstate <= v_next;
        if (v_next = C_GS_IDLE) then
          gate_busy_r <= '0';
        else
          gate_busy_r <= '1';
        end if;

        -- A pulse while the engine's direction differs from DIR: the engine was started around the gate (or
        -- its direction input is not wired to eng_direction). Sticky until the next accepted start_req.
        if (eng_step = '1' and eng_dir /= dir_r) then
          fault_r <= '1';
        elsif (start_req = '1' and eng_busy = '0' and gstate = C_GS_IDLE) then
          fault_r <= '0';
        end if;
      end if;

      -- PWM datapath.
      -- Stage 1: the two table reads (registered: a ROM).
      cos_f  <= C_COS(frac_idx);
      cos_g  <= C_COS(G_MICROSTEPS - frac_idx);
      swap1  <= quad(0);
      neg_a1 <= quad(1) xor quad(0);
      neg_b1 <= quad(1);

      -- The multipliers.
      if (rst = '1') then
        mul_cnt <= 0;
        duty_a  <= 0;
        duty_b  <= 0;
        neg_a   <= '0';
        neg_b   <= '0';
      elsif (mul_cnt = 0) then
        q_a     <= mag_a;
        q_b     <= mag_b;
        neg_a2  <= neg_a1;
        neg_b2  <= neg_b1;
        mul_p   <= period_i;
        acc_a   <= 0;
        acc_b   <= 0;
        mul_cnt <= 1;
      elsif (mul_cnt <= G_DUTY_BITS + 1) then
        -- {acc, q} shifted right by one, acc + pwm_period (17 bits) taking q's LSB's place
        v_sum_a := acc_a;
        if (q_a mod 2 = 1) then
          v_sum_a := v_sum_a + mul_p;
        end if;
        v_sum_b := acc_b;
        if (q_b mod 2 = 1) then
          v_sum_b := v_sum_b + mul_p;
        end if;
        acc_a   <= v_sum_a / 2;
        q_a     <= q_a / 2 + (v_sum_a mod 2) * C_Q_TOP;
        acc_b   <= v_sum_b / 2;
        q_b     <= q_b / 2 + (v_sum_b mod 2) * C_Q_TOP;
        mul_cnt <= mul_cnt + 1;
      else
        -- product < 2^(BITS + 16), so acc(15) = '0' and the duty fits 16 bits
        duty_a  <= rounded(acc_a, q_a);
        duty_b  <= rounded(acc_b, q_b);
        neg_a   <= neg_a2;
        neg_b   <= neg_b2;
        mul_cnt <= 0;
      end if;

      -- Carrier 0 .. pwm_period - 1, free running (a shorter new period wraps at once).
      if (rst = '1' or pwm_run = '0' or carrier >= period_m1) then
        carrier <= 0;
      else
        carrier <= carrier + 1;
      end if;

      -- Outputs.
      if (rst = '1') then
        enable_r <= '0';
        a1_r     <= '0';
        a2_r     <= '0';
        b1_r     <= '0';
        b2_r     <= '0';
      else
        enable_r <= ctrl_enable;
        a1_r     <= '0';
        a2_r     <= '0';
        b1_r     <= '0';
        b2_r     <= '0';

        v_on_a := '0';
        v_on_b := '0';
        if (pwm_run = '1' and carrier < duty_a) then
          v_on_a := '1';
        end if;
        if (pwm_run = '1' and carrier < duty_b) then
          v_on_b := '1';
        end if;

        if (ctrl_enable = '1') then
          if (mode_onoff = '1') then
            a1_r <= lvl_a1;
            a2_r <= lvl_a2;
            b1_r <= lvl_b1;
            b2_r <= lvl_b2;
          elsif (mode_pwm = '1') then
            a1_r <= v_on_a and not neg_a;
            a2_r <= v_on_a and neg_a;
            b1_r <= v_on_b and not neg_b;
            b2_r <= v_on_b and neg_b;
          end if;
        end if;
      end if;
    end if;

  end process clk_proc;

  step          <= step_r;
  dir           <= dir_r;
  eng_start     <= start_r;
  eng_hard_stop <= stop_r;
  eng_direction <= dir_r;
  gate_busy     <= gate_busy_r;
  dir_fault     <= fault_r;
  enable        <= enable_r;
  a1            <= a1_r and to_sl(G_WINDINGS);
  a2            <= a2_r and to_sl(G_WINDINGS);
  b1            <= b1_r and to_sl(G_WINDINGS);
  b2            <= b2_r and to_sl(G_WINDINGS);

end architecture rtl;
