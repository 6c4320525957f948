-- SPDX-License-Identifier: MIT
-- stepramp_core: the stepramp core behind a bus-agnostic register port (one-cycle read/write strobes, answer one
-- clock later). It only wires the blocks: register file, ramp engine. The bus tops (stepramp_plb for the
-- PLB-like IPIF, stepramp_axil for AXI4-Lite) turn their bus into the strobes.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_regs_pkg.all;

entity stepramp_core is
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Register port: wr or rd for one cycle; ack (with err, and rdata for a read) one clock later.
    wr    : in    std_logic;
    rd    : in    std_logic;
    addr  : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    wdata : in    std_logic_vector(31 downto 0);
    be    : in    std_logic_vector(3 downto 0);
    rdata : out   std_logic_vector(31 downto 0);
    ack   : out   std_logic;
    err   : out   std_logic;
    -- Interrupt and motor outputs.
    irq  : out   std_logic;
    step : out   std_logic;
    dir  : out   std_logic
  );
end entity stepramp_core;

architecture rtl of stepramp_core is

  signal start      : std_logic;
  signal soft_stop  : std_logic;
  signal hard_stop  : std_logic;
  signal steps      : std_logic_vector(30 downto 0);
  signal direction  : std_logic;
  signal prescale   : std_logic_vector(15 downto 0);
  signal c_first    : std_logic_vector(47 downto 0);
  signal c_last     : std_logic_vector(47 downto 0);
  signal sa         : std_logic_vector(30 downto 0);
  signal c_sa       : std_logic_vector(47 downto 0);
  signal sd         : std_logic_vector(30 downto 0);
  signal c_sd       : std_logic_vector(47 downto 0);
  signal accel_seed : std_logic_vector(47 downto 0);
  signal decel_seed : std_logic_vector(47 downto 0);
  signal cruise     : std_logic_vector(63 downto 0);
  signal stop_ratio : std_logic_vector(31 downto 0);
  signal pos_load   : std_logic;
  signal pos_value  : std_logic_vector(31 downto 0);
  signal busy       : std_logic;
  signal done       : std_logic;
  signal error      : std_logic;
  signal err_code   : std_logic_vector(3 downto 0);
  signal state      : std_logic_vector(1 downto 0);
  signal dir_i      : std_logic;
  signal position   : std_logic_vector(31 downto 0);
  signal step_count : std_logic_vector(30 downto 0);
  signal cur_delay  : std_logic_vector(31 downto 0);

begin

  regfile_inst : entity work.stepramp_regfile
    port map (
      clk            => clk,
      rst            => rst,
      wr             => wr,
      rd             => rd,
      addr           => addr,
      wdata          => wdata,
      be             => be,
      rdata          => rdata,
      ack            => ack,
      err            => err,
      irq            => irq,
      start          => start,
      soft_stop      => soft_stop,
      hard_stop      => hard_stop,
      steps          => steps,
      direction      => direction,
      prescale       => prescale,
      c_first        => c_first,
      c_last         => c_last,
      sa             => sa,
      c_sa           => c_sa,
      sd             => sd,
      c_sd           => c_sd,
      accel_seed     => accel_seed,
      decel_seed     => decel_seed,
      cruise         => cruise,
      stop_ratio     => stop_ratio,
      pos_load       => pos_load,
      pos_value      => pos_value,
      eng_busy       => busy,
      eng_done       => done,
      eng_error      => error,
      eng_err_code   => err_code,
      eng_state      => state,
      eng_dir        => dir_i,
      eng_position   => position,
      eng_step_count => step_count,
      eng_cur_delay  => cur_delay
    );

  engine_inst : entity work.stepramp_engine
    port map (
      clk        => clk,
      rst        => rst,
      start      => start,
      soft_stop  => soft_stop,
      hard_stop  => hard_stop,
      steps      => steps,
      direction  => direction,
      prescale   => prescale,
      c_first    => c_first,
      c_last     => c_last,
      sa         => sa,
      c_sa       => c_sa,
      sd         => sd,
      c_sd       => c_sd,
      accel_seed => accel_seed,
      decel_seed => decel_seed,
      cruise     => cruise,
      stop_ratio => stop_ratio,
      pos_load   => pos_load,
      pos_value  => pos_value,
      step       => step,
      dir        => dir_i,
      busy       => busy,
      done       => done,
      error      => error,
      err_code   => err_code,
      state      => state,
      position   => position,
      step_count => step_count,
      cur_delay  => cur_delay
    );

  dir <= dir_i;

end architecture rtl;
