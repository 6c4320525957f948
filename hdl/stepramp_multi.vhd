-- SPDX-License-Identifier: MIT
-- stepramp_multi: G_AXES stepramp_core axes behind one bus-agnostic register port with a 12-bit address: a global
-- window (ID / AXES, SYNC_START, AXES_STATUS, IRQ_MASK, SYNC_SOFT_STOP) at 0x000 and axis i's register window at
-- 0x100 * (i + 1). SYNC_START starts the selected axes with their pulse 0 on one clock edge (the common start);
-- SYNC_SOFT_STOP soft-stops them on one clock; irq is the OR of the axes' (masked) interrupts. The bus tops
-- stepramp_multi_plb and stepramp_multi_axil turn their bus into the strobes. docs/stepramp_multi.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_pkg.all;
  use work.stepramp_regs_pkg.all;
  use work.stepramp_multi_pkg.all;

entity stepramp_multi is
  generic (
    G_AXES       : positive := 2;  -- axes, 1 .. 8
    G_MICROSTEPS : positive := 16; -- sine table steps per full step of every axis (stepramp_stepper)
    -- stepramp_regfile's G_WADDR: the AXI4-Lite top decodes a write from waddr (the window too).
    G_WADDR : boolean := false;
    -- The winding outputs A1 A2 B1 B2 of every axis (stepramp_core): off by default here (driver chips take STEP /
    -- DIR); without them A1 .. B2 stay '0', each axis's ID bit 14 reads 1 and its DRIVE.MODE 0.
    G_WINDINGS : boolean := false
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Register port: wr or rd for one cycle; ack (with err, and rdata for a read) one clock later.
    wr   : in    std_logic;
    rd   : in    std_logic;
    addr : in    std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
    -- A write's address (addr on a one-address bus; stepramp_core, "waddr").
    waddr : in    std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
    wdata : in    std_logic_vector(31 downto 0);
    be    : in    std_logic_vector(3 downto 0);
    rdata : out   std_logic_vector(31 downto 0);
    ack   : out   std_logic;
    err   : out   std_logic;
    -- One interrupt: the OR of the axes' irq outputs whose IRQ_MASK bit is set.
    irq : out   std_logic;
    -- Motor outputs, bit i for axis i (see stepramp_core).
    step   : out   std_logic_vector(G_AXES - 1 downto 0);
    dir    : out   std_logic_vector(G_AXES - 1 downto 0);
    enable : out   std_logic_vector(G_AXES - 1 downto 0);
    a1     : out   std_logic_vector(G_AXES - 1 downto 0);
    a2     : out   std_logic_vector(G_AXES - 1 downto 0);
    b1     : out   std_logic_vector(G_AXES - 1 downto 0);
    b2     : out   std_logic_vector(G_AXES - 1 downto 0);
    -- Machine inputs, asynchronous, bit i for axis i; one ESTOP for every axis (each filters it with its own
    -- INPUT_CFG). Tie to '0' when unused.
    limit_neg : in    std_logic_vector(G_AXES - 1 downto 0);
    limit_pos : in    std_logic_vector(G_AXES - 1 downto 0);
    home      : in    std_logic_vector(G_AXES - 1 downto 0);
    estop     : in    std_logic
  );
end entity stepramp_multi;

architecture rtl of stepramp_multi is

  type word_array_t is array (0 to G_AXES - 1) of std_logic_vector(31 downto 0);

  -- The window an address selects: 0 global, i + 1 axis i.
  function window (
    a : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0)
  ) return natural is
  begin

    return to_integer(unsigned(a(C_MULTI_ADDR_BITS - 1 downto C_ADDR_BITS)));

  end function window;

  -- The word of a global-window offset.
  function word (
    a : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0)
  ) return natural is
  begin

    return to_integer(unsigned(a(C_ADDR_BITS - 1 downto 2)));

  end function word;

  -- The word of a global-window offset written with byte lane 0 (SYNC_START, SYNC_SOFT_STOP, IRQ_MASK take bits of
  -- lane 0 only), else a word past every register.
  function lane0_word (
    a  : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);
    be : std_logic_vector(3 downto 0)
  ) return natural is
  begin

    if (window(a) = 0 and be(0) = '1') then
      return word(a);
    end if;

    return 2 ** (C_ADDR_BITS - 2);

  end function lane0_word;

  -- '1' for the offset of a global register (window 0, ID .. SYNC_SOFT_STOP); the global logic answers the rest
  -- with err.
  function global_mapped (
    a : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0)
  ) return std_logic is
  begin

    if (window(a) = 0 and word(a) <= C_MREG_SYNC_SOFT_STOP / 4) then
      return '1';
    end if;

    return '0';

  end function global_mapped;

  -- A bit per axis, in an 8-bit field.
  function field (
    bits : std_logic_vector(G_AXES - 1 downto 0)
  ) return std_logic_vector is

    variable result : std_logic_vector(C_MULTI_MAX_AXES - 1 downto 0);

  begin

    result                      := (others => '0');
    result(G_AXES - 1 downto 0) := bits;
    return result;

  end function field;

  constant C_ID : std_logic_vector(31 downto 0) := C_MULTI_ID_MAGIC & C_MULTI_ID_VERSION &
                                                   std_logic_vector(to_unsigned(G_AXES, 8));

  -- The address a write is decoded from.
  signal wsel : std_logic_vector(C_MULTI_ADDR_BITS - 1 downto 0);

  -- Strobes of the axes and of the global logic.
  signal axis_wr    : std_logic_vector(G_AXES - 1 downto 0);
  signal axis_rd    : std_logic_vector(G_AXES - 1 downto 0);
  signal glob_wr    : std_logic;
  signal glob_rd    : std_logic;
  signal sync_start : std_logic_vector(G_AXES - 1 downto 0);
  signal sync_soft  : std_logic_vector(G_AXES - 1 downto 0);

  -- The common start: the axes of the last SYNC_START that accepted it (idle), kept while one of them waits in its
  -- start gate; every axis's gate holds a start that could go while sync_hold is '1'.
  signal sync_group : std_logic_vector(G_AXES - 1 downto 0);
  signal gate_wait  : std_logic_vector(G_AXES - 1 downto 0);
  signal sync_hold  : std_logic;

  -- The axes' answers and status.
  signal axis_rdata : word_array_t;
  signal axis_ack   : std_logic_vector(G_AXES - 1 downto 0);
  signal axis_err   : std_logic_vector(G_AXES - 1 downto 0);
  signal axis_irq   : std_logic_vector(G_AXES - 1 downto 0);
  signal axis_busy  : std_logic_vector(G_AXES - 1 downto 0);
  signal axis_done  : std_logic_vector(G_AXES - 1 downto 0);

  -- The global logic's answer, the axis whose rdata the last read returns (none: the global one), IRQ_MASK.
  signal glob_ack   : std_logic;
  signal glob_err   : std_logic;
  signal glob_rdata : std_logic_vector(31 downto 0);
  signal rd_axis    : std_logic_vector(G_AXES - 1 downto 0);
  signal irq_mask   : std_logic_vector(G_AXES - 1 downto 0);

begin

  assert G_AXES >= 1 and G_AXES <= C_MULTI_MAX_AXES
    report "stepramp_multi: G_AXES must be in 1 .. 8"
    severity failure;

  wsel <= waddr when G_WADDR else
          addr;

  -- Window decode: axis i takes the strobes of window i + 1; the global logic answers window 0 and every window
  -- past the last axis (with err). SYNC_START: bit i of a write (byte lane 0) is a START of axis i at the edge that
  -- samples the write, exactly as a CTRL.START written to every selected axis at that edge; SYNC_SOFT_STOP likewise
  -- a CTRL.SOFT_STOP.
  decode_proc : process (wr, rd, addr, wsel, wdata, be) is

    -- A write the global logic takes.
    variable glob_w : boolean;

  begin

    glob_w  := wr = '1' and (window(wsel) = 0 or window(wsel) > G_AXES);
    glob_wr <= to_sl(glob_w);
    glob_rd <= to_sl(rd = '1' and (window(addr) = 0 or window(addr) > G_AXES));

    for i in 0 to G_AXES - 1 loop

      axis_wr(i)    <= to_sl(wr = '1' and window(wsel) = i + 1);
      axis_rd(i)    <= to_sl(rd = '1' and window(addr) = i + 1);
      sync_start(i) <= to_sl(glob_w and lane0_word(wsel, be) = C_MREG_SYNC_START / 4 and wdata(i) = '1');
      sync_soft(i)  <= to_sl(glob_w and lane0_word(wsel, be) = C_MREG_SYNC_SOFT_STOP / 4 and wdata(i) = '1');

    end loop;

  end process decode_proc;

  -- The common start: while an axis of the group still waits for its own DIR hold / setup or STEP spacing, the
  -- others hold their starts; all fire at the edge at which none waits, the latest of their own start edges.
  sync_hold <= any(sync_group and gate_wait);

  global_proc : process (clk) is
  begin

    if rising_edge(clk) then
      glob_ack <= glob_wr or glob_rd;
      glob_err <= (glob_wr and not global_mapped(wsel)) or (glob_rd and not global_mapped(addr));

      if (rd = '1') then
        rd_axis    <= axis_rd;
        glob_rdata <= (others => '0');

        if (glob_rd = '1' and global_mapped(addr) = '1') then
          if (word(addr) = C_MREG_ID / 4) then
            glob_rdata <= C_ID;
          elsif (word(addr) = C_MREG_AXES_STATUS / 4) then
            glob_rdata <= x"00" & field(axis_irq) & field(axis_done) & field(axis_busy);
          elsif (word(addr) = C_MREG_IRQ_MASK / 4) then
            glob_rdata <= x"000000" & field(irq_mask);
          end if;
        end if;
      end if;

      if (glob_wr = '1' and lane0_word(wsel, be) = C_MREG_IRQ_MASK / 4) then
        irq_mask <= wdata(G_AXES - 1 downto 0);
      end if;

      -- The group of a SYNC_START: the selected axes that are idle (a busy axis ignores the START); it ends at the
      -- edge at which none of them waits in its start gate (all fire there).
      if (any(sync_start) = '1') then
        sync_group <= sync_start and not axis_busy;
      elsif (sync_hold = '0') then
        sync_group <= (others => '0');
      end if;

      if (rst = '1') then
        glob_ack   <= '0';
        glob_err   <= '0';
        rd_axis    <= (others => '0');
        irq_mask   <= (others => '1');
        sync_group <= (others => '0');
      end if;
    end if;

  end process global_proc;

  -- The answer: at most one source acknowledges (one access per clock); rdata is the source of the last read, held
  -- until the next read (each axis holds its own).
  ack <= glob_ack or any(axis_ack);
  err <= glob_err or any(axis_err);

  rdata_proc : process (glob_rdata, axis_rdata, rd_axis) is

    variable v : std_logic_vector(31 downto 0);

  begin

    v := glob_rdata;

    for i in 0 to G_AXES - 1 loop

      if (rd_axis(i) = '1') then
        v := v or axis_rdata(i);
      end if;

    end loop;

    rdata <= v;

  end process rdata_proc;

  irq <= any(axis_irq and irq_mask);

  axes_gen : for i in 0 to G_AXES - 1 generate

    core_inst : entity work.stepramp_core
      generic map (
        G_MICROSTEPS => G_MICROSTEPS,
        G_WADDR      => G_WADDR,
        G_WINDINGS   => G_WINDINGS
      )
      port map (
        clk            => clk,
        rst            => rst,
        wr             => axis_wr(i),
        rd             => axis_rd(i),
        addr           => addr(C_ADDR_BITS - 1 downto 0),
        waddr          => waddr(C_ADDR_BITS - 1 downto 0),
        wdata          => wdata,
        be             => be,
        rdata          => axis_rdata(i),
        ack            => axis_ack(i),
        err            => axis_err(i),
        irq            => axis_irq(i),
        step           => step(i),
        dir            => dir(i),
        enable         => enable(i),
        a1             => a1(i),
        a2             => a2(i),
        b1             => b1(i),
        b2             => b2(i),
        limit_neg      => limit_neg(i),
        limit_pos      => limit_pos(i),
        home           => home(i),
        estop          => estop,
        sync_start     => sync_start(i),
        sync_soft_stop => sync_soft(i),
        st_busy        => axis_busy(i),
        st_done        => axis_done(i),
        sync_hold      => sync_hold,
        gate_wait      => gate_wait(i)
      );

  end generate axes_gen;

end architecture rtl;
