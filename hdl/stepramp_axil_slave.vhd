-- SPDX-License-Identifier: MIT
-- stepramp_axil_slave: an AXI4-Lite slave (ports s_axil_*) turned into the bus-agnostic register port of
-- stepramp_core and stepramp_multi (the bus side of stepramp_axil and stepramp_multi_axil): address and data held
-- until both are there, one access per clock (on a tie the kind that did not go last goes first), responses held
-- under backpressure, SLVERR when the port answers err. waddr is the held write address. Channel behaviour:
-- docs/stepramp_plb.md.

library ieee;
  use ieee.std_logic_1164.all;

entity stepramp_axil_slave is
  generic (
    G_ADDR_BITS : positive := 8 -- address bits of the AXI4-Lite address channels and of the register port
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- AXI4-Lite slave.
    s_axil_awaddr  : in    std_logic_vector(G_ADDR_BITS - 1 downto 0);
    s_axil_awvalid : in    std_logic;
    s_axil_awready : out   std_logic;
    s_axil_wdata   : in    std_logic_vector(31 downto 0);
    s_axil_wstrb   : in    std_logic_vector(3 downto 0);
    s_axil_wvalid  : in    std_logic;
    s_axil_wready  : out   std_logic;
    s_axil_bresp   : out   std_logic_vector(1 downto 0);
    s_axil_bvalid  : out   std_logic;
    s_axil_bready  : in    std_logic;
    s_axil_araddr  : in    std_logic_vector(G_ADDR_BITS - 1 downto 0);
    s_axil_arvalid : in    std_logic;
    s_axil_arready : out   std_logic;
    s_axil_rdata   : out   std_logic_vector(31 downto 0);
    s_axil_rresp   : out   std_logic_vector(1 downto 0);
    s_axil_rvalid  : out   std_logic;
    s_axil_rready  : in    std_logic;
    -- Register port (master side): addr is the write address for a write, the read address for a read.
    wr    : out   std_logic;
    rd    : out   std_logic;
    addr  : out   std_logic_vector(G_ADDR_BITS - 1 downto 0);
    waddr : out   std_logic_vector(G_ADDR_BITS - 1 downto 0);
    wdata : out   std_logic_vector(31 downto 0);
    be    : out   std_logic_vector(3 downto 0);
    rdata : in    std_logic_vector(31 downto 0);
    ack   : in    std_logic;
    err   : in    std_logic
  );
end entity stepramp_axil_slave;

architecture rtl of stepramp_axil_slave is

  constant C_OKAY   : std_logic_vector(1 downto 0) := "00";
  constant C_SLVERR : std_logic_vector(1 downto 0) := "10";

  -- The response of an access the port answered: SLVERR when it flagged an error (an unmapped offset).
  function response (
    flagged : std_logic
  ) return std_logic_vector is
  begin

    if (flagged = '1') then
      return C_SLVERR;
    end if;

    return C_OKAY;

  end function response;

  -- Held requests.
  signal aw_full  : std_logic;
  signal w_full   : std_logic;
  signal ar_full  : std_logic;
  signal awaddr_r : std_logic_vector(G_ADDR_BITS - 1 downto 0);
  signal araddr_r : std_logic_vector(G_ADDR_BITS - 1 downto 0);
  signal wdata_r  : std_logic_vector(31 downto 0);
  signal wstrb_r  : std_logic_vector(3 downto 0);

  -- Accesses in flight: issued this clock, answered next clock.
  signal wr_s        : std_logic;
  signal rd_s        : std_logic;
  signal wr_pending  : std_logic; -- a write was issued last clock
  signal rd_pending  : std_logic; -- a read was issued last clock
  signal last_was_rd : std_logic;
  signal wr_ready    : std_logic;
  signal rd_ready    : std_logic;

  -- Responses.
  signal bvalid  : std_logic;
  signal bresp   : std_logic_vector(1 downto 0);
  signal rvalid  : std_logic;
  signal rresp   : std_logic_vector(1 downto 0);
  signal rdata_r : std_logic_vector(31 downto 0);

begin

  assert G_ADDR_BITS >= 2 and G_ADDR_BITS <= 32
    report "stepramp_axil_slave: G_ADDR_BITS must be in 2 .. 32"
    severity failure;

  -- A write may go when its address and data are held and its response channel is free; a read likewise.
  wr_ready <= aw_full and w_full and not bvalid and not wr_pending;
  rd_ready <= ar_full and not rvalid and not rd_pending;

  -- One access per clock; on a tie the kind that did not go last goes first.
  wr_s <= wr_ready and not (rd_ready and not last_was_rd);
  rd_s <= rd_ready and not wr_s;

  axil_proc : process (clk) is
  begin

    if rising_edge(clk) then
      -- Accept address and data (ready is high while the holding register is empty).
      if (aw_full = '0' and s_axil_awvalid = '1') then
        aw_full  <= '1';
        awaddr_r <= s_axil_awaddr;
      end if;

      if (w_full = '0' and s_axil_wvalid = '1') then
        w_full  <= '1';
        wdata_r <= s_axil_wdata;
        wstrb_r <= s_axil_wstrb;
      end if;

      if (ar_full = '0' and s_axil_arvalid = '1') then
        ar_full  <= '1';
        araddr_r <= s_axil_araddr;
      end if;

      wr_pending <= wr_s;
      rd_pending <= rd_s;

      if (wr_s = '1') then
        aw_full     <= '0';
        w_full      <= '0';
        last_was_rd <= '0';
      end if;

      if (rd_s = '1') then
        ar_full     <= '0';
        last_was_rd <= '1';
      end if;

      -- The port answers the access of the previous clock.
      if (wr_pending = '1' and ack = '1') then
        bvalid <= '1';
        bresp  <= response(err);
      elsif (s_axil_bready = '1') then
        bvalid <= '0';
      end if;

      if (rd_pending = '1' and ack = '1') then
        rvalid  <= '1';
        rdata_r <= rdata;
        rresp   <= response(err);
      elsif (s_axil_rready = '1') then
        rvalid <= '0';
      end if;

      if (rst = '1') then
        -- (The addresses too: the register file converts them every time they change, and an undefined one would
        -- be converted to a warning at every access of the other kind.)
        awaddr_r    <= (others => '0');
        araddr_r    <= (others => '0');
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

  wr    <= wr_s;
  rd    <= rd_s;
  addr  <= awaddr_r when wr_s = '1' else
           araddr_r;
  waddr <= awaddr_r;
  wdata <= wdata_r;
  be    <= wstrb_r;

  s_axil_awready <= not aw_full;
  s_axil_wready  <= not w_full;
  s_axil_arready <= not ar_full;
  s_axil_bvalid  <= bvalid;
  s_axil_bresp   <= bresp;
  s_axil_rvalid  <= rvalid;
  s_axil_rresp   <= rresp;
  s_axil_rdata   <= rdata_r;

end architecture rtl;
