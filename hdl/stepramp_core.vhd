-- SPDX-License-Identifier: MIT
-- stepramp_core: the stepramp core behind a bus-agnostic register port (one-cycle read / write strobes, the answer
-- one clock later). It only wires the register file, the stepping logic and the ramp engine; the bus tops
-- stepramp_plb and stepramp_axil turn their bus into the strobes. docs/stepramp_plb.md.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_regs_pkg.all;

entity stepramp_core is
  generic (
    G_MICROSTEPS : positive := 16;
    -- stepramp_regfile's G_WADDR: the AXI4-Lite top decodes a write from waddr.
    G_WADDR : boolean := false;
    -- The ramp arithmetic: 0 the AVR446 recurrence, 1 the exact ramp (docs/algorithm.md, "Exact step times"); ID
    -- bit 15 reads it.
    G_RAMP : natural := 0;
    -- The winding outputs A1 A2 B1 B2 (stepramp_stepper); without them ID bit 14 reads 1 and DRIVE.MODE 0.
    G_WINDINGS : boolean := true
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Register port: wr or rd for one cycle; ack (with err, and rdata for a read) one clock later.
    wr   : in    std_logic;
    rd   : in    std_logic;
    addr : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    -- A write's address (addr on a one-address bus; stepramp_regfile, "waddr").
    waddr : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    wdata : in    std_logic_vector(31 downto 0);
    be    : in    std_logic_vector(3 downto 0);
    rdata : out   std_logic_vector(31 downto 0);
    ack   : out   std_logic;
    err   : out   std_logic;
    -- Interrupt and motor outputs: STEP/DIR/ENABLE for a driver chip, A1 A2 B1 B2 for two H-bridges.
    irq    : out   std_logic;
    step   : out   std_logic;
    dir    : out   std_logic;
    enable : out   std_logic;
    a1     : out   std_logic;
    a2     : out   std_logic;
    b1     : out   std_logic;
    b2     : out   std_logic;
    -- Machine inputs, asynchronous (synchronised, filtered and given their polarity inside; INPUT_CFG).
    limit_neg : in    std_logic;
    limit_pos : in    std_logic;
    home      : in    std_logic;
    estop     : in    std_logic;
    -- The multi-axis top: a START or a SOFT_STOP on this clock (as if written), STATUS.BUSY / STATUS.DONE, and the
    -- common start (stepramp_stepper's start_hold and gate_wait; tie to '0', open alone).
    sync_start     : in    std_logic;
    sync_soft_stop : in    std_logic;
    st_busy        : out   std_logic;
    st_done        : out   std_logic;
    sync_hold      : in    std_logic;
    gate_wait      : out   std_logic
  );
end entity stepramp_core;

architecture rtl of stepramp_core is

  signal start_req     : std_logic;
  signal load          : std_logic;
  signal step_space    : std_logic_vector(15 downto 0);
  signal min_gap       : std_logic_vector(16 downto 0);
  signal eng_start     : std_logic;
  signal eng_direction : std_logic;
  signal gate_busy     : std_logic;
  signal busy_any      : std_logic;
  signal dir_fault     : std_logic;
  signal eng_step      : std_logic;
  signal ctrl_enable   : std_logic;
  signal mode          : std_logic_vector(2 downto 0);
  signal ustep_log2    : std_logic_vector(2 downto 0);
  signal step_width    : std_logic_vector(15 downto 0);
  signal dir_setup     : std_logic_vector(15 downto 0);
  signal dir_hold      : std_logic_vector(15 downto 0);
  signal pwm_period    : std_logic_vector(15 downto 0);
  signal soft_stop     : std_logic;
  signal hard_stop     : std_logic;
  signal gate_stop     : std_logic;
  signal eng_hard_stop : std_logic;
  signal change        : std_logic;
  signal change_at     : std_logic_vector(30 downto 0);
  signal chg_pend      : std_logic;
  signal chg_refused   : std_logic;
  signal steps         : std_logic_vector(30 downto 0);
  signal direction     : std_logic;
  signal prescale      : std_logic_vector(15 downto 0);
  signal c_first       : std_logic_vector(47 downto 0);
  signal c_last        : std_logic_vector(47 downto 0);
  signal sa            : std_logic_vector(30 downto 0);
  signal c_sa          : std_logic_vector(47 downto 0);
  signal sd            : std_logic_vector(30 downto 0);
  signal c_sd          : std_logic_vector(47 downto 0);
  signal accel_seed    : std_logic_vector(63 downto 0);
  signal decel_seed    : std_logic_vector(63 downto 0);
  signal cruise        : std_logic_vector(63 downto 0);
  signal stop_ratio    : std_logic_vector(31 downto 0);
  signal head_down     : std_logic;
  signal endless       : std_logic;
  signal head_index    : std_logic_vector(30 downto 0);
  signal run_stop      : std_logic_vector(30 downto 0);
  signal head_prod     : std_logic_vector(47 downto 0);
  signal pos_load      : std_logic;
  signal pos_value     : std_logic_vector(31 downto 0);
  signal busy          : std_logic;
  signal done          : std_logic;
  signal error         : std_logic;
  signal err_code      : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal state         : std_logic_vector(1 downto 0);
  signal eng_dir       : std_logic;
  signal position      : std_logic_vector(31 downto 0);
  signal elec_pos      : std_logic_vector(8 downto 0);
  signal step_count    : std_logic_vector(30 downto 0);
  signal cur_delay     : std_logic_vector(31 downto 0);
  signal pins          : std_logic_vector(3 downto 0);
  signal in_filter     : std_logic_vector(19 downto 0);
  signal in_pol        : std_logic_vector(3 downto 0);
  signal latch_src     : std_logic_vector(1 downto 0);
  signal latch_active  : std_logic;
  signal latch_release : std_logic;
  signal latch_clr     : std_logic;
  signal in_level      : std_logic_vector(3 downto 0);
  signal in_rise       : std_logic_vector(3 downto 0);
  signal in_fall       : std_logic_vector(3 downto 0);
  signal latched       : std_logic;
  signal latch_pos     : std_logic_vector(31 downto 0);
  signal latch_time    : std_logic_vector(63 downto 0);
  signal time_count    : std_logic_vector(63 downto 0);
  signal estop_fault   : std_logic;
  -- ESTOP's filtered level or its latched fault: a hard stop held on the engine and the stepping logic.
  signal estop_stop : std_logic;
  signal step_hard  : std_logic;

begin

  assert G_RAMP <= 1
    report "stepramp_core: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  regfile_inst : entity work.stepramp_regfile
    generic map (
      G_WADDR    => G_WADDR,
      G_RAMP     => G_RAMP,
      G_WINDINGS => G_WINDINGS
    )
    port map (
      clk             => clk,
      rst             => rst,
      wr              => wr,
      rd              => rd,
      addr            => addr,
      waddr           => waddr,
      wdata           => wdata,
      be              => be,
      rdata           => rdata,
      ack             => ack,
      err             => err,
      irq             => irq,
      start           => start_req,
      soft_stop       => soft_stop,
      hard_stop       => hard_stop,
      change          => change,
      change_at       => change_at,
      steps           => steps,
      direction       => direction,
      prescale        => prescale,
      c_first         => c_first,
      c_last          => c_last,
      sa              => sa,
      c_sa            => c_sa,
      sd              => sd,
      c_sd            => c_sd,
      accel_seed      => accel_seed,
      decel_seed      => decel_seed,
      cruise          => cruise,
      stop_ratio      => stop_ratio,
      head_down       => head_down,
      endless         => endless,
      head_index      => head_index,
      run_stop        => run_stop,
      head_prod       => head_prod,
      pos_load        => pos_load,
      pos_value       => pos_value,
      enable          => ctrl_enable,
      mode            => mode,
      ustep_log2      => ustep_log2,
      step_width      => step_width,
      dir_setup       => dir_setup,
      dir_hold        => dir_hold,
      pwm_period      => pwm_period,
      step_space      => step_space,
      eng_busy        => busy_any,
      eng_done        => done,
      eng_error       => error,
      eng_err_code    => err_code,
      eng_state       => state,
      eng_dir         => eng_dir,
      eng_position    => position,
      eng_step_count  => step_count,
      eng_cur_delay   => cur_delay,
      eng_chg_pend    => chg_pend,
      eng_chg_refused => chg_refused,
      dir_fault       => dir_fault,
      ext_start       => sync_start,
      ext_soft_stop   => sync_soft_stop,
      done_sticky     => st_done,
      busy_status     => st_busy,
      in_filter       => in_filter,
      in_pol          => in_pol,
      latch_src       => latch_src,
      latch_active    => latch_active,
      latch_release   => latch_release,
      latch_clr       => latch_clr,
      in_level        => in_level,
      in_rise         => in_rise,
      latched         => latched,
      latch_pos       => latch_pos,
      latch_time      => latch_time,
      time_count      => time_count,
      estop_fault     => estop_fault
    );

  pins <= estop & home & limit_pos & limit_neg;

  inputs_inst : entity work.stepramp_inputs
    port map (
      clk           => clk,
      rst           => rst,
      pins          => pins,
      filter        => in_filter,
      pol           => in_pol,
      level         => in_level,
      rise          => in_rise,
      fall          => in_fall,
      latch_src     => latch_src,
      latch_active  => latch_active,
      latch_release => latch_release,
      latch_clr     => latch_clr,
      position      => position,
      latched       => latched,
      latch_pos     => latch_pos,
      latch_time    => latch_time,
      time_count    => time_count
    );

  -- ESTOP stops from its filtered level on: the engine's hard stop is sampled at the next edge, so no pulse is
  -- decided after it (docs/stepramp_inputs.md, "ESTOP timing").
  estop_stop <= in_level(3) or estop_fault;
  step_hard  <= hard_stop or estop_stop;

  -- STATUS.BUSY covers a start held back by the stepping logic for DIR setup/hold or STEP spacing.
  busy_any <= busy or gate_busy;

  -- The engine takes the move at the edge that accepts START (START while idle: the stepping logic accepts it
  -- exactly then and drops it otherwise), not when the held start reaches it: writes during the hold go to the
  -- staging copy for the next move.
  load <= start_req and not busy_any;

  -- A hard stop that cancels a start held by the stepping logic reaches the engine with that start (done, no pulse).
  eng_hard_stop <= hard_stop or gate_stop or estop_stop;

  stepper_inst : entity work.stepramp_stepper
    generic map (
      G_MICROSTEPS => G_MICROSTEPS,
      G_WINDINGS   => G_WINDINGS
    )
    port map (
      clk           => clk,
      rst           => rst,
      mode          => mode,
      ustep_log2    => ustep_log2,
      step_width    => step_width,
      dir_setup     => dir_setup,
      dir_hold      => dir_hold,
      pwm_period    => pwm_period,
      step_space    => step_space,
      ctrl_enable   => ctrl_enable,
      start_req     => start_req,
      new_dir       => direction,
      hard_stop     => step_hard,
      soft_stop     => soft_stop,
      gate_busy     => gate_busy,
      dir_fault     => dir_fault,
      start_hold    => sync_hold,
      gate_wait     => gate_wait,
      eng_step      => eng_step,
      eng_busy      => busy,
      eng_dir       => eng_dir,
      eng_elec_pos  => elec_pos,
      eng_start     => eng_start,
      eng_hard_stop => gate_stop,
      eng_direction => eng_direction,
      eng_min_gap   => min_gap,
      step          => step,
      dir           => dir,
      enable        => enable,
      a1            => a1,
      a2            => a2,
      b1            => b1,
      b2            => b2
    );

  engine_inst : entity work.stepramp_engine
    generic map (
      G_RAMP => G_RAMP
    )
    port map (
      clk         => clk,
      rst         => rst,
      load        => load,
      start       => eng_start,
      soft_stop   => soft_stop,
      hard_stop   => eng_hard_stop,
      change      => change,
      change_at   => change_at,
      chg_pend    => chg_pend,
      chg_refused => chg_refused,
      steps       => steps,
      direction   => eng_direction,
      prescale    => prescale,
      c_first     => c_first,
      c_last      => c_last,
      sa          => sa,
      c_sa        => c_sa,
      sd          => sd,
      c_sd        => c_sd,
      accel_seed  => accel_seed,
      decel_seed  => decel_seed,
      cruise      => cruise,
      stop_ratio  => stop_ratio,
      head_down   => head_down,
      endless     => endless,
      head_index  => head_index,
      run_stop    => run_stop,
      head_prod   => head_prod,
      min_gap     => min_gap,
      pos_load    => pos_load,
      pos_value   => pos_value,
      step        => eng_step,
      dir         => eng_dir,
      busy        => busy,
      done        => done,
      error       => error,
      err_code    => err_code,
      state       => state,
      position    => position,
      elec_pos    => elec_pos,
      step_count  => step_count,
      cur_delay   => cur_delay
    );

end architecture rtl;
