-- SPDX-License-Identifier: MIT
-- stepramp_plb_slave: a native PLB-like slave (Xilinx IPIF signal names) turned into the bus-agnostic register port
-- of stepramp_core and stepramp_multi: one wr or rd strobe per access, the answer (ack, err, rdata) one clock later
-- becomes the one-cycle IP2Bus_RdAck / WrAck. The bus side of stepramp_plb and stepramp_multi_plb; bus timing:
-- docs/stepramp_plb.md.

library ieee;
  use ieee.std_logic_1164.all;

entity stepramp_plb_slave is
  generic (
    G_ADDR_BITS : positive := 8 -- address bits passed on (the rest of bus2ip_addr is ignored)
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
    -- Register port (master side).
    wr    : out   std_logic;
    rd    : out   std_logic;
    addr  : out   std_logic_vector(G_ADDR_BITS - 1 downto 0);
    wdata : out   std_logic_vector(31 downto 0);
    be    : out   std_logic_vector(3 downto 0);
    rdata : in    std_logic_vector(31 downto 0);
    ack   : in    std_logic;
    err   : in    std_logic
  );
end entity stepramp_plb_slave;

architecture rtl of stepramp_plb_slave is

  signal access_r : std_logic; -- the access now on the bus has been passed on
  signal rd_r     : std_logic; -- the register port answers a read (else a write) in this cycle
  signal wr_s     : std_logic;
  signal rd_s     : std_logic;

begin

  assert G_ADDR_BITS >= 2 and G_ADDR_BITS <= 32
    report "stepramp_plb_slave: G_ADDR_BITS must be in 2 .. 32"
    severity failure;

  -- One strobe per access: CS is still high in the cycle of the ack, so the strobe cycle blocks the next one.
  wr_s <= bus2ip_cs and not bus2ip_rnw and not access_r;
  rd_s <= bus2ip_cs and bus2ip_rnw and not access_r;

  handshake_proc : process (clk) is
  begin

    if rising_edge(clk) then
      access_r <= wr_s or rd_s;
      rd_r     <= rd_s;

      if (rst = '1') then
        access_r <= '0';
        rd_r     <= '0';
      end if;
    end if;

  end process handshake_proc;

  wr    <= wr_s;
  rd    <= rd_s;
  addr  <= bus2ip_addr(G_ADDR_BITS - 1 downto 0);
  wdata <= bus2ip_data;
  be    <= bus2ip_be;

  ip2bus_rdack <= ack and rd_r;
  ip2bus_wrack <= ack and not rd_r;
  ip2bus_error <= err;
  ip2bus_data  <= rdata when rd_r = '1' else
                  (others => '0');

end architecture rtl;
