-- SPDX-License-Identifier: MIT
-- stepramp_plb: the stepramp core with a native PLB-like slave interface (Xilinx IPIF signal names, the handshake of
-- stepramp_plb_slave) that answers every access in two clocks. Ports, bus timing and registers: docs/stepramp_plb.md,
-- docs/registers.md.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_regs_pkg.all;

entity stepramp_plb is
  generic (
    G_MICROSTEPS : positive := 16; -- sine table steps per full step (stepramp_stepper)
    -- The ramp arithmetic: 0 the AVR446 recurrence, 1 the exact ramp (docs/algorithm.md, "Exact step times").
    G_RAMP : natural := 0
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- IPIF slave.
    bus2ip_addr  : in    std_logic_vector(31 downto 0);
    bus2ip_data  : in    std_logic_vector(31 downto 0);
    bus2ip_be    : in    std_logic_vector(3 downto 0);
    bus2ip_cs    : in    std_logic;
    bus2ip_rnw   : in    std_logic;
    ip2bus_data  : out   std_logic_vector(31 downto 0);
    ip2bus_rdack : out   std_logic;
    ip2bus_wrack : out   std_logic;
    ip2bus_error : out   std_logic;
    -- Interrupt (level, active high): STATUS.DONE or STATUS.ERROR when enabled in CTRL.
    irq : out   std_logic;
    -- Motor outputs.
    step   : out   std_logic;
    dir    : out   std_logic;
    enable : out   std_logic;
    a1     : out   std_logic;
    a2     : out   std_logic;
    b1     : out   std_logic;
    b2     : out   std_logic;
    -- Machine inputs, asynchronous (stepramp_core; docs/stepramp_inputs.md): tie to '0' when unused.
    limit_neg : in    std_logic;
    limit_pos : in    std_logic;
    home      : in    std_logic;
    estop     : in    std_logic
  );
end entity stepramp_plb;

architecture rtl of stepramp_plb is

  signal wr    : std_logic;
  signal rd    : std_logic;
  signal addr  : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal wdata : std_logic_vector(31 downto 0);
  signal be    : std_logic_vector(3 downto 0);
  signal rdata : std_logic_vector(31 downto 0);
  signal ack   : std_logic;
  signal err   : std_logic;

begin

  assert G_RAMP <= 1
    report "stepramp_plb: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  slave_inst : entity work.stepramp_plb_slave
    generic map (
      G_ADDR_BITS => C_ADDR_BITS
    )
    port map (
      clk          => clk,
      rst          => rst,
      bus2ip_addr  => bus2ip_addr,
      bus2ip_data  => bus2ip_data,
      bus2ip_be    => bus2ip_be,
      bus2ip_cs    => bus2ip_cs,
      bus2ip_rnw   => bus2ip_rnw,
      ip2bus_data  => ip2bus_data,
      ip2bus_rdack => ip2bus_rdack,
      ip2bus_wrack => ip2bus_wrack,
      ip2bus_error => ip2bus_error,
      wr           => wr,
      rd           => rd,
      addr         => addr,
      wdata        => wdata,
      be           => be,
      rdata        => rdata,
      ack          => ack,
      err          => err
    );

  core_inst : entity work.stepramp_core
    generic map (
      G_MICROSTEPS => G_MICROSTEPS,
      G_RAMP       => G_RAMP
    )
    port map (
      clk            => clk,
      rst            => rst,
      wr             => wr,
      rd             => rd,
      addr           => addr,
      waddr          => addr,
      wdata          => wdata,
      be             => be,
      rdata          => rdata,
      ack            => ack,
      err            => err,
      irq            => irq,
      step           => step,
      dir            => dir,
      enable         => enable,
      a1             => a1,
      a2             => a2,
      b1             => b1,
      b2             => b2,
      limit_neg      => limit_neg,
      limit_pos      => limit_pos,
      home           => home,
      estop          => estop,
      sync_start     => '0',
      sync_soft_stop => '0',
      st_busy        => open,
      st_done        => open,
      sync_hold      => '0',
      gate_wait      => open
    );

end architecture rtl;
