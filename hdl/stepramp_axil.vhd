-- SPDX-License-Identifier: MIT
-- stepramp_axil: the stepramp core with an AXI4-Lite slave (ports s_axil_*, for Vivado / MicroBlaze on AXI).
-- Ports and channel behaviour: docs/stepramp_plb.md; registers: docs/registers.md.

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

  constant C_OKAY   : std_logic_vector(1 downto 0) := "00";
  constant C_SLVERR : std_logic_vector(1 downto 0) := "10";

  -- The response of an access the core answered: SLVERR when it flagged an error (an unmapped offset).
  function response (
    flagged : std_logic
  ) return std_logic_vector is
  begin

    if (flagged = '1') then
      return C_SLVERR;
    end if;

    return C_OKAY;

  end function response;

  signal rst : std_logic;

  -- Held requests.
  signal aw_full : std_logic;
  signal w_full  : std_logic;
  signal ar_full : std_logic;
  signal awaddr  : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal araddr  : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal wdata   : std_logic_vector(31 downto 0);
  signal wstrb   : std_logic_vector(3 downto 0);

  -- Accesses in flight: issued this clock, answered by the core next clock.
  signal wr          : std_logic;
  signal rd          : std_logic;
  signal wr_pending  : std_logic; -- a write was issued last clock
  signal rd_pending  : std_logic; -- a read was issued last clock
  signal last_was_rd : std_logic;

  -- Responses.
  signal bvalid : std_logic;
  signal bresp  : std_logic_vector(1 downto 0);
  signal rvalid : std_logic;
  signal rresp  : std_logic_vector(1 downto 0);
  signal rdata  : std_logic_vector(31 downto 0);

  -- Core register port.
  signal addr     : std_logic_vector(C_ADDR_BITS - 1 downto 0);
  signal core_rd  : std_logic_vector(31 downto 0);
  signal core_ack : std_logic;
  signal core_err : std_logic;
  signal wr_ready : std_logic;
  signal rd_ready : std_logic;

begin

  assert G_RAMP <= 1
    report "stepramp_axil: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  rst <= not aresetn;

  -- A write may go when its address and data are held and its response channel is free; a read likewise.
  wr_ready <= aw_full and w_full and not bvalid and not wr_pending;
  rd_ready <= ar_full and not rvalid and not rd_pending;

  -- One access per clock; on a tie the kind that did not go last goes first.
  wr <= wr_ready and not (rd_ready and not last_was_rd);
  rd <= rd_ready and not wr;

  addr <= awaddr when wr = '1' else
          araddr;

  axil_proc : process (aclk) is
  begin

    if rising_edge(aclk) then
      -- Accept address and data (ready is high while the holding register is empty).
      if (aw_full = '0' and s_axil_awvalid = '1') then
        aw_full <= '1';
        awaddr  <= s_axil_awaddr;
      end if;

      if (w_full = '0' and s_axil_wvalid = '1') then
        w_full <= '1';
        wdata  <= s_axil_wdata;
        wstrb  <= s_axil_wstrb;
      end if;

      if (ar_full = '0' and s_axil_arvalid = '1') then
        ar_full <= '1';
        araddr  <= s_axil_araddr;
      end if;

      wr_pending <= wr;
      rd_pending <= rd;

      if (wr = '1') then
        aw_full     <= '0';
        w_full      <= '0';
        last_was_rd <= '0';
      end if;

      if (rd = '1') then
        ar_full     <= '0';
        last_was_rd <= '1';
      end if;

      -- The core answers the access of the previous clock.
      if (wr_pending = '1' and core_ack = '1') then
        bvalid <= '1';
        bresp  <= response(core_err);
      elsif (s_axil_bready = '1') then
        bvalid <= '0';
      end if;

      if (rd_pending = '1' and core_ack = '1') then
        rvalid <= '1';
        rdata  <= core_rd;
        rresp  <= response(core_err);
      elsif (s_axil_rready = '1') then
        rvalid <= '0';
      end if;

      if (rst = '1') then
        aw_full     <= '0';
        w_full      <= '0';
        ar_full     <= '0';
        wr_pending  <= '0';
        rd_pending  <= '0';
        last_was_rd <= '0';
        bvalid      <= '0';
        rvalid      <= '0';
      end if;
    end if;

  end process axil_proc;

  s_axil_awready <= not aw_full;
  s_axil_wready  <= not w_full;
  s_axil_arready <= not ar_full;
  s_axil_bvalid  <= bvalid;
  s_axil_bresp   <= bresp;
  s_axil_rvalid  <= rvalid;
  s_axil_rresp   <= rresp;
  s_axil_rdata   <= rdata;

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
      waddr          => awaddr,
      wdata          => wdata,
      be             => wstrb,
      rdata          => core_rd,
      ack            => core_ack,
      err            => core_err,
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
