-- SPDX-License-Identifier: MIT
-- stepramp_plb_tb: a small self-checking plain-VHDL testbench of stepramp_plb (no cocotb), run by FuseSoC
-- (`fusesoc --cores-root=. run --target=sim stepramp:ip:stepramp`) and by tb/test_fusesoc.py.
--
-- Through the IPIF bus it reads ID, programs a 20-step move with the register values of the Python driver, enables
-- the done interrupt, writes START and waits for irq; it then checks STATUS (DONE, no ERROR), POSITION and
-- STEP_COUNT, the number of STEP pulses and every STEP rising edge, clock for clock, against the `edges` the model
-- prints for the same move, and that clearing DONE drops irq. Any mismatch stops the simulation with an assertion
-- of severity failure (non-zero exit status); on success it prints "stepramp_plb_tb: PASS" and stops the clock, so
-- the simulation ends by itself. Plain VHDL-93 (analyses with --std=93c and --std=08); FuseSoC runs it as 2008.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

entity stepramp_plb_tb is
end entity stepramp_plb_tb;

architecture sim of stepramp_plb_tb is

  constant C_PERIOD : time                  := 10 ns;
  constant C_BASE   : unsigned(31 downto 0) := x"40A0_0000"; -- the core decodes the low 8 address bits

  -- Register offsets (docs/registers.md).
  constant C_ID         : natural := 16#00#;
  constant C_CTRL       : natural := 16#04#;
  constant C_STATUS     : natural := 16#08#;
  constant C_STOP_RATIO : natural := 16#54#;
  constant C_POSITION   : natural := 16#58#;
  constant C_STEP_COUNT : natural := 16#60#;
  constant C_UNMAPPED   : natural := 16#AC#;

  constant C_ID_VALUE : std_logic_vector(31 downto 0) := x"5352_0008";

  type t_reg_write is record
    offset : natural;
    value  : std_logic_vector(31 downto 0);
  end record t_reg_write;

  type t_reg_writes is array (natural range <>) of t_reg_write;

  type t_naturals is array (natural range <>) of natural;

  type t_times is array (natural range <>) of time;

  -- The move, produced by
  --   .venv/bin/stepramp model --steps 20 --accel 1000 --decel 1000 --speed 50 --spr 200 --fclk 1e6
  -- ("registers", split into bus words as stepramp.board.driver.plan_writes does: 48-bit values into _LO = bits 31:0 and
  -- _HI = bits 47:32, CRUISE into bits 31:0 and 63:32; STOP_RATIO 0x10000 = accel / decel = 1.0).
  constant C_MOVE : t_reg_writes :=
  (
    (16#0C#, x"0000_0014"), -- STEPS = 20 (direction 0)
    (16#10#, x"0000_0001"), -- PRESCALE = 1
    (16#14#, x"1F2B_B8EF"), -- C_FIRST_LO  (c_first = 522959087)
    (16#18#, x"0000_0000"), -- C_FIRST_HI
    (16#1C#, x"1EF6_A794"), -- C_LAST_LO   (c_last = 519481236)
    (16#20#, x"0000_0000"), -- C_LAST_HI
    (16#24#, x"0000_000A"), -- SA = 10
    (16#28#, x"0517_40C5"), -- C_SA_LO     (c_sa = 85409989)
    (16#2C#, x"0000_0000"), -- C_SA_HI
    (16#30#, x"0000_000A"), -- SD = 10
    (16#34#, x"0517_40C5"), -- C_SD_LO     (c_sd = 85409989)
    (16#38#, x"0000_0000"), -- C_SD_HI
    (16#3C#, x"1500_4DA0"), -- ACCEL_SEED_LO (accel_seed = 352341408)
    (16#40#, x"0000_0000"), -- ACCEL_SEED_HI
    (16#44#, x"0553_B26A"), -- DECEL_SEED_LO (decel_seed = 89371242)
    (16#48#, x"0000_0000"), -- DECEL_SEED_HI
    (16#4C#, x"518B_3AA8"), -- CRUISE_LO   (cruise = 2698607540904)
    (16#50#, x"0000_0274"), -- CRUISE_HI
    (16#54#, x"0001_0000")  -- STOP_RATIO = 1.0 (Q16.16)
  );

  -- "edges" of the same command: the clock edge of each STEP rising edge, counted from the edge at which the engine
  -- samples start (one clock after the edge at which the slave samples the bus write of START).
  constant C_EDGES : t_naturals(0 to 19) :=
  (
    2, 7981, 11207, 13716, 15839, 17712, 19407, 20966, 22418, 23781,
    25085, 26448, 27900, 29459, 31154, 33027, 35150, 37659, 40885, 48812
  );

  constant C_STEPS        : natural := C_EDGES'length;
  constant C_MOVE_TIMEOUT : time    := 2 * (C_EDGES(C_STEPS - 1) + 1000) * C_PERIOD;
  constant C_WATCHDOG     : time    := 2 * C_MOVE_TIMEOUT;

  -- A 32-bit word in hex, for messages (VHDL-93 has no to_hstring).
  function hex (
    word : std_logic_vector(31 downto 0)
  ) return string is

    constant C_DIGITS : string(1 to 16) := "0123456789ABCDEF";
    variable result   : string(1 to 8);
    variable nibble   : std_logic_vector(3 downto 0);

  begin

    for i in 0 to 7 loop

      nibble := word(31 - 4 * i downto 28 - 4 * i);

      if (is_x(nibble)) then
        result(i + 1) := 'X';
      else
        result(i + 1) := C_DIGITS(to_integer(unsigned(nibble)) + 1);
      end if;

    end loop;

    return result;

  end function hex;

  signal running : boolean := true;

  signal clk          : std_logic                     := '0';
  signal rst          : std_logic                     := '1';
  signal bus2ip_addr  : std_logic_vector(31 downto 0) := (others => '0');
  signal bus2ip_data  : std_logic_vector(31 downto 0) := (others => '0');
  signal bus2ip_be    : std_logic_vector(3 downto 0)  := (others => '0');
  signal bus2ip_cs    : std_logic                     := '0';
  signal bus2ip_rnw   : std_logic                     := '1';
  signal ip2bus_data  : std_logic_vector(31 downto 0);
  signal ip2bus_rdack : std_logic;
  signal ip2bus_wrack : std_logic;
  signal ip2bus_error : std_logic;
  signal irq          : std_logic;
  signal step         : std_logic;
  signal dir          : std_logic;

  -- STEP monitor: number of rising edges and their times.
  signal n_steps    : natural                   := 0;
  signal step_times : t_times(0 to C_STEPS + 7) := (others => 0 ns);

begin

  clk_proc : process is
  begin

    while running loop

      clk <= '0';
      wait for C_PERIOD / 2;
      clk <= '1';
      wait for C_PERIOD / 2;

    end loop;

    wait;

  end process clk_proc;

  -- Watchdog: a hang anywhere fails the simulation instead of leaving it running.
  watchdog_proc : process is
  begin

    wait until not running for C_WATCHDOG;
    assert not running
      report "watchdog: the test did not finish within " & integer'image(C_WATCHDOG / 1 us) & " us"
      severity failure;
    wait;

  end process watchdog_proc;

  dut_inst : entity work.stepramp_plb
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
      irq          => irq,
      step         => step,
      dir          => dir,
      limit_neg    => '0',
      limit_pos    => '0',
      home         => '0',
      estop        => '0'
    );

  step_mon_proc : process is

    variable n : natural := 0;

  begin

    wait until rising_edge(step);

    if (n <= step_times'high) then
      step_times(n) <= now;
    end if;

    n       := n + 1;
    n_steps <= n;

  end process step_mon_proc;

  stim_proc : process is

    variable word    : std_logic_vector(31 downto 0);
    variable bus_err : std_logic;
    variable t_wr    : time;
    variable t_start : time; -- the engine's edge 0 plus the STEP pin's register (so edges compare with the model)
    variable edge    : integer;

    -- One IPIF access, called just after a rising edge of clk. Bus2IP_CS (with RNW, address, data, byte enables)
    -- is held until the master samples IP2Bus_RdAck / IP2Bus_WrAck at a rising edge; CS drops right after that
    -- edge and stays low for one cycle. t_strobe: the edge at which the slave samples the access (the first edge
    -- with CS high).

    procedure bus_access (
      offset   : in    natural;
      rnw      : in    std_logic;
      wdata    : in    std_logic_vector(31 downto 0);
      be       : in    std_logic_vector(3 downto 0);
      rdata    : out   std_logic_vector(31 downto 0);
      err      : out   std_logic;
      t_strobe : out   time
    ) is

      variable cycles : natural := 0;

    begin

      bus2ip_addr <= std_logic_vector(C_BASE + offset);
      bus2ip_rnw  <= rnw;
      bus2ip_data <= wdata;
      bus2ip_be   <= be;
      bus2ip_cs   <= '1';

      loop

        wait until rising_edge(clk);

        if (cycles = 0) then
          t_strobe := now;
        end if;

        -- Values sampled at this edge (signals the edge updates change one delta later).
        exit when (rnw = '1' and ip2bus_rdack = '1') or (rnw = '0' and ip2bus_wrack = '1');
        cycles := cycles + 1;
        assert cycles < 16
          report "no acknowledge for the access at offset " & integer'image(offset)
          severity failure;

      end loop;

      rdata     := ip2bus_data;
      err       := ip2bus_error;
      bus2ip_cs <= '0';
      wait until rising_edge(clk);

    end procedure bus_access;

    procedure bus_read (
      offset : in    natural;
      rdata  : out   std_logic_vector(31 downto 0);
      err    : out   std_logic
    ) is

      variable t : time;

    begin

      bus_access(offset, '1', x"0000_0000", "1111", rdata, err, t);

    end procedure bus_read;

    procedure bus_write (
      offset   : in    natural;
      wdata    : in    std_logic_vector(31 downto 0);
      be       : in    std_logic_vector(3 downto 0);
      t_strobe : out   time
    ) is

      variable rdata : std_logic_vector(31 downto 0);
      variable err   : std_logic;

    begin

      bus_access(offset, '0', wdata, be, rdata, err, t_strobe);
      assert err = '0'
        report "bus error on the write at offset " & integer'image(offset)
        severity failure;

    end procedure bus_write;

    -- Read a register and compare it with an expected value.

    procedure check_reg (
      offset   : in    natural;
      name     : in    string;
      expected : in    std_logic_vector(31 downto 0)
    ) is

      variable rdata : std_logic_vector(31 downto 0);
      variable err   : std_logic;

    begin

      bus_read(offset, rdata, err);
      assert err = '0'
        report "bus error on the read of " & name
        severity failure;
      assert rdata = expected
        report name & " reads 0x" & hex(rdata) & ", expected 0x" & hex(expected)
        severity failure;

    end procedure check_reg;

  begin

    -- Reset (synchronous, active high).
    rst <= '1';

    for i in 1 to 5 loop

      wait until rising_edge(clk);

    end loop;

    rst <= '0';
    wait until rising_edge(clk);

    -- ID, and a bus error for an unmapped offset.
    check_reg(C_ID, "ID", C_ID_VALUE);
    bus_read(C_UNMAPPED, word, bus_err);
    assert bus_err = '1'
      report "no bus error on the read of unmapped offset 0x78"
      severity failure;

    -- Program the move, enable the done interrupt (CTRL byte 1), START (CTRL byte 0 only, as the driver does).
    for i in C_MOVE'range loop

      bus_write(C_MOVE(i).offset, C_MOVE(i).value, "1111", t_wr);

    end loop;

    check_reg(C_STOP_RATIO, "STOP_RATIO", x"0001_0000");
    bus_write(C_CTRL, x"0000_0100", "0010", t_wr);
    assert irq = '0'
      report "irq is high before the move"
      severity failure;
    bus_write(C_CTRL, x"0000_0001", "0001", t_wr);
    -- The register file's start strobe reaches the stepping logic's start gate one edge after the write, the
    -- engine one edge later (DIR does not change here), and the STEP pin is one register after the engine's pulse.
    t_start := t_wr + 2 * C_PERIOD + C_PERIOD;

    -- Wait for the done interrupt.
    if (irq /= '1') then
      wait until irq = '1' for C_MOVE_TIMEOUT;
    end if;

    assert irq = '1'
      report "no done interrupt within " & integer'image(C_MOVE_TIMEOUT / 1 us) & " us"
      severity failure;
    wait until rising_edge(clk);

    -- STATUS: DONE (bit 4), not ERROR (bit 5), not BUSY (bit 2), STATE STOP, ERR_CODE NONE, DIR 0.
    bus_read(C_STATUS, word, bus_err);
    assert bus_err = '0' and word(4) = '1' and word(5) = '0' and word(2) = '0'
      report "STATUS reads 0x" & hex(word) & ", expected DONE and no ERROR, not BUSY"
      severity failure;
    check_reg(C_STATUS, "STATUS", x"0000_0010");
    check_reg(C_POSITION, "POSITION", std_logic_vector(to_signed(C_STEPS, 32)));
    check_reg(C_STEP_COUNT, "STEP_COUNT", std_logic_vector(to_unsigned(C_STEPS, 32)));

    -- STEP pulses: count, intervals, and the position of every edge against the model.
    assert n_steps = C_STEPS
      report integer'image(n_steps) & " STEP pulses, expected " & integer'image(C_STEPS)
      severity failure;

    for k in 1 to C_STEPS - 1 loop

      edge := (step_times(k) - step_times(k - 1)) / C_PERIOD;
      assert edge = C_EDGES(k) - C_EDGES(k - 1)
        report "interval " & integer'image(k) & " is " & integer'image(edge) & " clocks, the model's is "
               & integer'image(C_EDGES(k) - C_EDGES(k - 1))
        severity failure;

    end loop;

    for k in 0 to C_STEPS - 1 loop

      edge := (step_times(k) - t_start) / C_PERIOD;
      assert edge = C_EDGES(k)
        report "STEP edge " & integer'image(k) & " at engine edge " & integer'image(edge) & ", the model's is "
               & integer'image(C_EDGES(k))
        severity failure;

    end loop;

    -- Clearing DONE (write 1) drops irq; no pulse after the move.
    bus_write(C_STATUS, x"0000_0010", "0001", t_wr);
    assert irq = '0'
      report "irq still high after clearing STATUS.DONE"
      severity failure;

    for i in 1 to 100 loop

      wait until rising_edge(clk);

    end loop;

    assert n_steps = C_STEPS
      report "STEP pulses after the end of the move"
      severity failure;

    report "stepramp_plb_tb: PASS (" & integer'image(C_STEPS) & " steps, first interval "
           & integer'image(C_EDGES(1) - C_EDGES(0)) & " clocks, last interval "
           & integer'image(C_EDGES(C_STEPS - 1) - C_EDGES(C_STEPS - 2)) & " clocks)"
      severity note;
    running <= false;
    wait;

  end process stim_proc;

end architecture sim;
