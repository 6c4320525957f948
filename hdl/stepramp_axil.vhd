-- SPDX-License-Identifier: MIT
-- stepramp_axil: the stepramp core with an AXI4-Lite slave (ports s_axil_*, stepramp_axil_slave; for Vivado /
-- MicroBlaze on AXI). Ports and channel behaviour: docs/stepramp_plb.md; registers: docs/registers.md.

library ieee;
  use ieee.std_logic_1164.all;

library work;
  use work.stepramp_regs_pkg.all;

entity stepramp_axil is
  generic (
    G_MICROSTEPS : positive := 16; -- sine table steps per full step (stepramp_stepper)
    -- The ramp arithmetic: 0 the AVR446 recurrence, 1 the exact ramp (docs/algorithm.md, "Exact step times").
    G_RAMP : natural := 0
  );
  port (
    aclk    : in    std_logic;
    aresetn : in    std_logic;
    -- AXI4-Lite slave.
    s_axil_awaddr  : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
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
    s_axil_araddr  : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    s_axil_arprot  : in    std_logic_vector(2 downto 0);
    s_axil_arvalid : in    std_logic;
    s_axil_arready : out   std_logic;
    s_axil_rdata   : out   std_logic_vector(31 downto 0);
    s_axil_rresp   : out   std_logic_vector(1 downto 0);
    s_axil_rvalid  : out   std_logic;
    s_axil_rready  : in    std_logic;
    -- Interrupt and motor outputs (see stepramp_core).
    irq    : out   std_logic;
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
end entity stepramp_axil;

architecture rtl of stepramp_axil is

  signal rst   : std_logic;
  signal wr    : std_logic;
  signal rd    : std_logic;
  signal addr  : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal waddr : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal wdata : std_logic_vector(31 downto 0);
  signal be    : std_logic_vector(3 downto 0);
  signal rdata : std_logic_vector(31 downto 0);
  signal ack   : std_logic;
  signal err   : std_logic;

begin

  assert G_RAMP <= 1
    report "stepramp_axil: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  rst <= not aresetn;

  -- s_axil_awprot and s_axil_arprot are not used: every access is served alike.
  slave_inst : entity work.stepramp_axil_slave
    generic map (
      G_ADDR_BITS => C_ADDR_BITS
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

  -- The write register is decoded from the held write address (G_WADDR), not from the arbitrated addr.
  core_inst : entity work.stepramp_core
    generic map (
      G_MICROSTEPS => G_MICROSTEPS,
      G_WADDR      => true,
      G_RAMP       => G_RAMP
    )
    port map (
      clk            => aclk,
      rst            => rst,
      wr             => wr,
      rd             => rd,
      addr           => addr,
      waddr          => waddr,
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
