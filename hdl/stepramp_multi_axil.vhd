-- SPDX-License-Identifier: MIT
-- stepramp_multi_axil: the multi-axis top stepramp_multi with an AXI4-Lite slave (ports s_axil_*,
-- stepramp_axil_slave), for Vivado / MicroBlaze on AXI. docs/stepramp_multi.md.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_multi_pkg.all;

entity stepramp_multi_axil is
  generic (
    G_AXES       : positive := 2;  -- axes, 1 .. 8
    G_MICROSTEPS : positive := 16; -- sine table steps per full step (stepramp_stepper)
    -- The winding outputs A1 A2 B1 B2 (stepramp_multi): off by default (A1 .. B2 stay '0').
    G_WINDINGS : boolean := false
  );
  port (
    aclk    : in    std_logic;
    aresetn : in    std_logic;
    -- AXI4-Lite slave.
    s_axil_awaddr  : in    std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
    s_axil_awprot  : in    std_logic_vector(2 downto 0);
    s_axil_awvalid : in    std_logic;
    s_axil_awready : out   std_logic;
    s_axil_wdata   : in    std_logic_vector(31 downto 0);
    s_axil_wstrb   : in    std_logic_vector(3 downto 0);
    s_axil_wvalid  : in    std_logic;
    s_axil_wready  : out   std_logic;
    s_axil_bresp   : out   std_logic_vector(1 downto 0);
    s_axil_bvalid  : out   std_logic;
    s_axil_bready  : in    std_logic;
    s_axil_araddr  : in    std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
    s_axil_arprot  : in    std_logic_vector(2 downto 0);
    s_axil_arvalid : in    std_logic;
    s_axil_arready : out   std_logic;
    s_axil_rdata   : out   std_logic_vector(31 downto 0);
    s_axil_rresp   : out   std_logic_vector(1 downto 0);
    s_axil_rvalid  : out   std_logic;
    s_axil_rready  : in    std_logic;
    -- Interrupt and motor outputs (see stepramp_multi_plb).
    irq    : out   std_logic;
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
end entity stepramp_multi_axil;

architecture rtl of stepramp_multi_axil is

  signal rst   : std_logic;
  signal wr    : std_logic;
  signal rd    : std_logic;
  signal addr  : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
  signal waddr : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
  signal wdata : std_logic_vector(31 downto 0);
  signal be    : std_logic_vector(3 downto 0);
  signal rdata : std_logic_vector(31 downto 0);
  signal ack   : std_logic;
  signal err   : std_logic;

begin

  rst <= not aresetn;

  slave_inst : entity work.stepramp_axil_slave
    generic map (
      G_ADDR_BITS => C_MULTI_ADDR_BITS
    )
    port map (
      clk            => aclk,
      rst            => rst,
      s_axil_awaddr  => s_axil_awaddr,
      s_axil_awvalid => s_axil_awvalid,
      s_axil_awready => s_axil_awready,
      s_axil_wdata   => s_axil_wdata,
      s_axil_wstrb   => s_axil_wstrb,
      s_axil_wvalid  => s_axil_wvalid,
      s_axil_wready  => s_axil_wready,
      s_axil_bresp   => s_axil_bresp,
      s_axil_bvalid  => s_axil_bvalid,
      s_axil_bready  => s_axil_bready,
      s_axil_araddr  => s_axil_araddr,
      s_axil_arvalid => s_axil_arvalid,
      s_axil_arready => s_axil_arready,
      s_axil_rdata   => s_axil_rdata,
      s_axil_rresp   => s_axil_rresp,
      s_axil_rvalid  => s_axil_rvalid,
      s_axil_rready  => s_axil_rready,
      wr             => wr,
      rd             => rd,
      addr           => addr,
      waddr          => waddr,
      wdata          => wdata,
      be             => be,
      rdata          => rdata,
      ack            => ack,
      err            => err
    );

  -- The write window and register are decoded from the held write address (G_WADDR), as in stepramp_axil.
  multi_inst : entity work.stepramp_multi
    generic map (
      G_AXES       => G_AXES,
      G_MICROSTEPS => G_MICROSTEPS,
      G_WADDR      => true,
      G_WINDINGS   => G_WINDINGS
    )
    port map (
      clk       => aclk,
      rst       => rst,
      wr        => wr,
      rd        => rd,
      addr      => addr,
      waddr     => waddr,
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
