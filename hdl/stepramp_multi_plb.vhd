-- SPDX-License-Identifier: MIT
-- stepramp_multi_plb: the multi-axis top stepramp_multi with a native PLB-like slave interface (Xilinx IPIF signal
-- names, stepramp_plb_slave) that answers every access in two clocks. docs/stepramp_multi.md.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_multi_pkg.all;

entity stepramp_multi_plb is
  generic (
    G_AXES       : positive := 2;  -- axes, 1 .. 8
    G_MICROSTEPS : positive := 16; -- sine table steps per full step (stepramp_stepper)
    -- The winding outputs A1 A2 B1 B2 (stepramp_multi): off by default (A1 .. B2 stay '0').
    G_WINDINGS : boolean := false
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
    -- Interrupt (level, active high): an axis's irq with its IRQ_MASK bit set.
    irq : out   std_logic;
    -- Motor outputs, bit i for axis i.
    step   : out   std_logic_vector(G_AXES - 1 downto 0);
    dir    : out   std_logic_vector(G_AXES - 1 downto 0);
    enable : out   std_logic_vector(G_AXES - 1 downto 0);
    a1     : out   std_logic_vector(G_AXES - 1 downto 0);
    a2     : out   std_logic_vector(G_AXES - 1 downto 0);
    b1     : out   std_logic_vector(G_AXES - 1 downto 0);
    b2     : out   std_logic_vector(G_AXES - 1 downto 0);
    -- Machine inputs, asynchronous: tie to '0' when unused.
    limit_neg : in    std_logic_vector(G_AXES - 1 downto 0);
    limit_pos : in    std_logic_vector(G_AXES - 1 downto 0);
    home      : in    std_logic_vector(G_AXES - 1 downto 0);
    estop     : in    std_logic
  );
end entity stepramp_multi_plb;

architecture rtl of stepramp_multi_plb is

  signal wr    : std_logic;
  signal rd    : std_logic;
  signal addr  : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
  signal wdata : std_logic_vector(31 downto 0);
  signal be    : std_logic_vector(3 downto 0);
  signal rdata : std_logic_vector(31 downto 0);
  signal ack   : std_logic;
  signal err   : std_logic;

begin

  slave_inst : entity work.stepramp_plb_slave
    generic map (
      G_ADDR_BITS => C_MULTI_ADDR_BITS
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

  multi_inst : entity work.stepramp_multi
    generic map (
      G_AXES       => G_AXES,
      G_MICROSTEPS => G_MICROSTEPS,
      G_WINDINGS   => G_WINDINGS
    )
    port map (
      clk       => clk,
      rst       => rst,
      wr        => wr,
      rd        => rd,
      addr      => addr,
      waddr     => addr,
      wdata     => wdata,
      be        => be,
      rdata     => rdata,
      ack       => ack,
      err       => err,
      irq       => irq,
      step      => step,
      dir       => dir,
      enable    => enable,
      a1        => a1,
      a2        => a2,
      b1        => b1,
      b2        => b2,
      limit_neg => limit_neg,
      limit_pos => limit_pos,
      home      => home,
      estop     => estop
    );

end architecture rtl;
