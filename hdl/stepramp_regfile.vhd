-- SPDX-License-Identifier: MIT
-- stepramp_regfile: the bus registers of the stepramp core, bus-agnostic (one-cycle rd/wr strobes, the answer one
-- clock later), with the staging copy of the move and a read-back RAM; masks and reset values come from the register
-- map (stepramp_regs_pkg, generated from rdl/stepramp.rdl). Ports and timing: docs/stepramp_plb.md.

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

library work;
  use work.stepramp_regs_pkg.all;

entity stepramp_regfile is
  generic (
    -- true: a write's address is waddr (the AXI4-Lite top: its held write address, so that the write decode does not
    -- wait for the read / write arbitration); false: addr serves reads and writes (waddr unused).
    G_WADDR : boolean := false;
    -- The core's ramp arithmetic (stepramp_core's G_RAMP), read in ID bit 15.
    G_RAMP : natural := 0;
    -- The core has the winding outputs (stepramp_core's G_WINDINGS): else ID bit 14 reads 1 and DRIVE.MODE reads 0
    -- and ignores writes.
    G_WINDINGS : boolean := true
  );
  port (
    clk : in    std_logic;
    rst : in    std_logic;
    -- Bus side.
    wr   : in    std_logic;
    rd   : in    std_logic;
    addr : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    -- The write's address: addr on a bus with one address (the PLB-like top), the AXI4-Lite write address channel's
    -- own register on the AXI4-Lite top (the write decode then does not wait for the read / write arbitration).
    waddr : in    std_logic_vector(C_ADDR_BITS - 1 downto 0);
    wdata : in    std_logic_vector(31 downto 0);
    be    : in    std_logic_vector(3 downto 0);
    rdata : out   std_logic_vector(31 downto 0);
    ack   : out   std_logic;
    err   : out   std_logic;
    irq   : out   std_logic;
    -- Engine commands and move registers.
    start     : out   std_logic;
    soft_stop : out   std_logic;
    hard_stop : out   std_logic;
    -- A take-over commit (CTRL.CHANGE, checked here against idle, pending and direction; the engine checks the rest)
    -- and its pulse (docs/algorithm.md, "The take-over, the queue and the script contract").
    change     : out   std_logic;
    change_at  : out   std_logic_vector(30 downto 0);
    steps      : out   std_logic_vector(30 downto 0);
    direction  : out   std_logic;
    prescale   : out   std_logic_vector(15 downto 0);
    c_first    : out   std_logic_vector(47 downto 0);
    c_last     : out   std_logic_vector(47 downto 0);
    sa         : out   std_logic_vector(30 downto 0);
    c_sa       : out   std_logic_vector(47 downto 0);
    sd         : out   std_logic_vector(30 downto 0);
    c_sd       : out   std_logic_vector(47 downto 0);
    accel_seed : out   std_logic_vector(63 downto 0);
    decel_seed : out   std_logic_vector(63 downto 0);
    cruise     : out   std_logic_vector(63 downto 0);
    stop_ratio : out   std_logic_vector(31 downto 0);
    head_down  : out   std_logic;
    endless    : out   std_logic;
    head_index : out   std_logic_vector(30 downto 0);
    run_stop   : out   std_logic_vector(30 downto 0);
    head_prod  : out   std_logic_vector(47 downto 0);
    pos_load   : out   std_logic;
    pos_value  : out   std_logic_vector(31 downto 0);
    -- Stepping logic configuration.
    enable     : out   std_logic;
    mode       : out   std_logic_vector(2 downto 0);
    ustep_log2 : out   std_logic_vector(2 downto 0);
    step_width : out   std_logic_vector(15 downto 0);
    dir_setup  : out   std_logic_vector(15 downto 0);
    dir_hold   : out   std_logic_vector(15 downto 0);
    pwm_period : out   std_logic_vector(15 downto 0);
    step_space : out   std_logic_vector(15 downto 0);
    -- Engine and stepping logic status (eng_busy: the engine, or a start held for DIR timing).
    eng_busy       : in    std_logic;
    eng_done       : in    std_logic;
    eng_error      : in    std_logic;
    eng_err_code   : in    std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
    eng_state      : in    std_logic_vector(1 downto 0);
    eng_dir        : in    std_logic;
    eng_position   : in    std_logic_vector(31 downto 0);
    eng_step_count : in    std_logic_vector(30 downto 0);
    eng_cur_delay  : in    std_logic_vector(31 downto 0);
    -- The engine holds an accepted change until its pulse (chg_pend), or refused one (chg_refused strobe).
    eng_chg_pend    : in    std_logic;
    eng_chg_refused : in    std_logic;
    dir_fault       : in    std_logic;
    -- A START from outside the bus (the multi-axis top's SYNC_START): taken as a START written at this edge.
    ext_start : in    std_logic;
    -- A SOFT_STOP from outside the bus (the multi-axis top's SYNC_SOFT_STOP): a CTRL.SOFT_STOP written at this edge.
    ext_soft_stop : in    std_logic;
    -- STATUS.DONE and STATUS.BUSY, for the multi-axis top's status word.
    done_sticky : out   std_logic;
    busy_status : out   std_logic;
    -- Machine inputs (stepramp_inputs): configuration out; filtered levels (bit 0 LIMIT_NEG, 1 LIMIT_POS, 2 HOME,
    -- 3 ESTOP), activation strobes, the latch and TIME in.
    in_filter     : out   std_logic_vector(19 downto 0);
    in_pol        : out   std_logic_vector(3 downto 0);
    latch_src     : out   std_logic_vector(1 downto 0);
    latch_active  : out   std_logic;
    latch_release : out   std_logic;
    latch_clr     : out   std_logic;
    in_level      : in    std_logic_vector(3 downto 0);
    in_rise       : in    std_logic_vector(3 downto 0);
    latched       : in    std_logic;
    latch_pos     : in    std_logic_vector(31 downto 0);
    latch_time    : in    std_logic_vector(63 downto 0);
    time_count    : in    std_logic_vector(63 downto 0);
    -- STATUS.ESTOP_FAULT: the core hard-stops and holds ENABLE low while it is set.
    estop_fault : out   std_logic
  );
end entity stepramp_regfile;

architecture rtl of stepramp_regfile is

  -- The plain read/write words: the motion registers STEPS .. STOP_RATIO and SEGMENT .. HEAD_PROD_HI, and the
  -- stepping configuration DRIVE .. STEP_SPACE (written only while stopped). One register per word, indexed by word
  -- offset, reached with constant
  -- indices only (loops below), so no memory is inferred; the words in between are never written (constant 0).
  -- ram is their read-back copy (header), indexed by the word address; only its storage words are ever read.
  constant C_FIRST_W      : natural := C_REG_STEPS / 4;
  constant C_LAST_MOVE_W  : natural := C_REG_STOP_RATIO / 4;
  constant C_FIRST_CFG_W  : natural := C_REG_DRIVE / 4;
  constant C_LAST_CFG_W   : natural := C_REG_STEP_SPACE / 4;
  constant C_FIRST_SEG_W  : natural := C_REG_SEGMENT / 4;
  constant C_LAST_W       : natural := C_REG_INPUT_CFG / 4;
  constant C_ERR_CODE_MSB : natural := C_STATUS_ERR_CODE_LSB + C_STATUS_ERR_CODE_W - 1;
  constant C_WORDS        : natural := 2 ** (C_ADDR_BITS - 2);

  type reg_array_t is array (C_FIRST_W to C_LAST_W) of std_logic_vector(31 downto 0);

  type ram_t is array (0 to C_WORDS - 1) of std_logic_vector(31 downto 0);

  signal mem : reg_array_t;

  -- The read-back RAM: its port (word address, lane write enables, write data) and registered read data; written
  -- tells, per storage word, whether it was written since reset; ram_sel_r picks ram_q over rdata_r for the read.
  signal ram      : ram_t;
  signal ram_addr : natural range 0 to C_WORDS - 1;
  -- The write's word (waddr with G_WADDR; the access's word ram_addr otherwise), as a concurrent statement like
  -- ram_addr: a simulator converts the addresses when they change, not every clock.
  signal bus_wword : natural range 0 to 2 ** (C_ADDR_BITS - 2) - 1;
  signal ram_we    : std_logic_vector(3 downto 0);
  signal ram_wdata : std_logic_vector(31 downto 0);
  signal ram_q     : std_logic_vector(31 downto 0);
  signal written   : std_logic_vector(C_FIRST_W to C_LAST_W);
  signal ram_sel_r : std_logic;

  signal irq_done_en  : std_logic;
  signal enable_r     : std_logic;
  signal irq_error_en : std_logic;
  -- The machine inputs' interrupt enables (LIMIT_NEG_EV, LIMIT_POS_EV, HOME_EV, ESTOP_FAULT, LATCHED) and their
  -- sticky flags (the first four; LATCHED lives in stepramp_inputs).
  signal irq_in_en : std_logic_vector(4 downto 0);
  signal in_ev     : std_logic_vector(3 downto 0);
  -- The direction of the running (or held) move, as STEPS gave it at its START; a limit acts against it.
  signal mv_dir : std_logic;
  -- A limit stopped the running move (once per move).
  signal lim_hit : std_logic;
  -- TIME bits 63:32 as the last read of TIME_LO saw them.
  signal time_hi_r   : std_logic_vector(31 downto 0);
  signal latch_clr_r : std_logic;
  signal done_flag   : std_logic;
  signal error_flag  : std_logic;
  signal err_code_r  : std_logic_vector(C_STATUS_ERR_CODE_W - 1 downto 0);
  signal rdata_r     : std_logic_vector(31 downto 0);
  signal ack_r       : std_logic;
  signal err_r       : std_logic;
  signal irq_r       : std_logic;
  signal start_r     : std_logic;
  signal soft_stop_r : std_logic;
  signal hard_stop_r : std_logic;
  signal pos_load_r  : std_logic;
  signal pos_value_r : std_logic_vector(31 downto 0);
  -- STEPS holds -2^31 (a START is then rejected), registered as STEPS is written, so that the START path reads a
  -- flip-flop instead of a 32-bit compare (the clock, issue 12).
  signal steps_bad : std_logic;
  -- A take-over commit on its way to the engine, and a queued move (started at the engine's next done).
  signal change_r : std_logic;
  signal q_pend   : std_logic;
  -- STATUS.BUSY: the engine or a held start (eng_busy), or a start on its way to them: the START strobe, and a queued
  -- move in the clock between the engine's done and its START strobe. POSITION and the configuration words are
  -- written only while it is low.
  signal moving : std_logic;
  -- STATUS.PENDING: the staging registers are locked until the change is taken or the queued move started.
  signal locked : std_logic;
  -- STEPS' sign: the direction of the staged move (1: position counts down).
  signal direction_i : std_logic;
  -- Combinational terms that bus_proc reads at every edge, as concurrent statements (a simulator evaluates them when
  -- an operand changes, not every clock; the logic and its registers are the same): a START's direction (STEPS)
  -- and the running move's (mv_dir) against an active limit, and the interrupt line before irq_r.
  signal toward_c : std_logic;
  signal lim_c    : std_logic;
  signal irq_c    : std_logic;

  -- Word index of a byte offset.
  function word (
    byte_offset : natural
  ) return natural is
  begin

    return byte_offset / 4;

  end function word;

  -- old with the bytes selected by be replaced by new.
  function merge (
    old_v : std_logic_vector(31 downto 0);
    new_v : std_logic_vector(31 downto 0);
    be_v  : std_logic_vector(3 downto 0)
  ) return std_logic_vector is

    variable res : std_logic_vector(31 downto 0);

  begin

    res := old_v;

    for b in 0 to 3 loop

      if (be_v(b) = '1') then
        res(8 * b + 7 downto 8 * b) := new_v(8 * b + 7 downto 8 * b);
      end if;

    end loop;

    return res;

  end function merge;

  -- Whether a word index is a plain read/write storage register.
  function is_storage (
    w : natural
  ) return boolean is
  begin

    return (w >= C_FIRST_W and w <= C_LAST_MOVE_W) or (w >= C_FIRST_CFG_W and w <= C_LAST_CFG_W) or
           (w >= C_FIRST_SEG_W and w <= C_LAST_W);

  end function is_storage;

  -- Whether a word index is a stepping configuration register (written only while stopped).
  function is_config (
    w : natural
  ) return boolean is
  begin

    return (w >= C_FIRST_CFG_W and w <= C_LAST_CFG_W) or w = C_REG_INPUT_FILTER / 4 or w = C_REG_INPUT_CFG / 4;

  end function is_config;

  -- DRIVE.MODE's bits, which a core without windings does not store.
  constant C_DRIVE_MODE_BITS : unsigned(31 downto 0) := shift_left(to_unsigned(2 ** C_DRIVE_MODE_W - 1, 32),
                                                                   C_DRIVE_MODE_LSB);

  -- Bits of a storage register that exist (the others read 0), from the register map (stepramp_regs_pkg); without
  -- windings not DRIVE.MODE.
  function storage_mask (
    w : natural
  ) return std_logic_vector is
  begin

    if (not G_WINDINGS and w = C_REG_DRIVE / 4) then
      return C_REG_RW_MASK(w) and not std_logic_vector(C_DRIVE_MODE_BITS);
    end if;

    return C_REG_RW_MASK(w);

  end function storage_mask;

  -- Reset value of a storage register, from the register map.
  function reset_value (
    w : natural
  ) return std_logic_vector is
  begin

    return C_REG_RESET(w);

  end function reset_value;

  -- The address decode as tables, one flag per word (a few LUTs on the address bits instead of range compares
  -- with carry chains on the bus's write path). Kind 0: storage, 1: configuration, 2: any mapped word.

  type t_word_flags is array (0 to C_WORDS - 1) of std_logic;

  function word_flags (
    kind : natural
  ) return t_word_flags is

    variable res : t_word_flags;
    variable hit : boolean;

  begin

    for w in 0 to C_WORDS - 1 loop

      if (kind = 0) then
        hit := is_storage(w);
      elsif (kind = 1) then
        hit := is_config(w);
      else
        hit := is_storage(w) or w = word(C_REG_ID) or w = word(C_REG_CTRL) or w = word(C_REG_STATUS) or
               w = word(C_REG_POSITION) or w = word(C_REG_CUR_DELAY) or w = word(C_REG_STEP_COUNT) or
               (w >= word(C_REG_LATCH_POS) and w <= word(C_REG_TIME_HI));
      end if;

      if (hit) then
        res(w) := '1';
      else
        res(w) := '0';
      end if;

    end loop;

    return res;

  end function word_flags;

  constant C_STORAGE_WORDS : t_word_flags := word_flags(0);
  constant C_CONFIG_WORDS  : t_word_flags := word_flags(1);
  constant C_MAPPED_WORDS  : t_word_flags := word_flags(2);
  -- ID bit 15: the ramp arithmetic the core was built with (G_RAMP), so that a driver can refuse a plan for the other;
  -- bit 14: 1 when the core was built without the winding outputs (G_WINDINGS false), so that a driver refuses
  -- their modes.
  constant C_ID_BUILD : natural                       := G_RAMP * 2 ** 15 + (1 - boolean'pos(G_WINDINGS)) * 2 ** 14;
  constant C_ID_RAMP  : std_logic_vector(31 downto 0) := std_logic_vector(to_unsigned(C_ID_BUILD, 32));

  -- v when c, else 0 (the terms of an AND-OR multiplexer).
  function gate (
    v : std_logic_vector(31 downto 0);
    c : boolean
  ) return std_logic_vector is
  begin

    if (c) then
      return v;
    else
      return x"00000000";
    end if;

  end function gate;

  -- '1' when the limits are enabled (INPUT_CFG.LIMIT_EN) and the one a motion in direction dir runs into is active
  -- (dir 1: position counting down, towards LIMIT_NEG, level bit 0; dir 0: towards LIMIT_POS, level bit 1).
  function against_limit (
    cfg   : std_logic_vector(31 downto 0);
    level : std_logic_vector(3 downto 0);
    dir   : std_logic
  ) return std_logic is
  begin

    return cfg(C_INPUT_CFG_LIMIT_EN_LSB) and ((level(0) and dir) or (level(1) and not dir));

  end function against_limit;

begin

  assert G_RAMP <= 1
    report "stepramp_regfile: G_RAMP must be 0 (AVR446) or 1 (exact)"
    severity failure;

  bus_proc : process (clk) is

    variable w        : natural range 0 to 2 ** (C_ADDR_BITS - 2) - 1;
    variable ww       : natural range 0 to 2 ** (C_ADDR_BITS - 2) - 1; -- the write's word (waddr)
    variable rd_v     : std_logic_vector(31 downto 0);
    variable ctrl_v   : std_logic_vector(31 downto 0);
    variable stat_v   : std_logic_vector(31 downto 0);
    variable mapped   : boolean;
    variable mapped_w : boolean;
    variable new_ctrl : std_logic_vector(31 downto 0);
    variable clr      : std_logic_vector(31 downto 0);
    variable start_v  : std_logic;

  begin

    if rising_edge(clk) then
      w           := ram_addr;
      ww          := bus_wword;
      ack_r       <= '0';
      err_r       <= '0';
      start_r     <= '0';
      soft_stop_r <= '0';
      hard_stop_r <= '0';
      change_r    <= '0';
      pos_load_r  <= '0';
      latch_clr_r <= '0';
      start_v     := '0';

      -- Sticky flags: engine events (set) have priority over a W1C write in the same cycle (below).
      clr := x"00000000";

      if (wr = '1') then
        ack_r    <= '1';
        mapped_w := C_MAPPED_WORDS(ww) = '1';

        if (not mapped_w) then
          err_r <= '1';
        elsif (C_CONFIG_WORDS(ww) = '1' and moving = '1') then
          error_flag <= '1';
          err_code_r <= C_ERR_CFG_BUSY;
        elsif (C_STORAGE_WORDS(ww) = '1' and C_CONFIG_WORDS(ww) = '0' and locked = '1') then
          -- (the configuration words keep their own rule above: written only while stopped)
          error_flag <= '1';
          err_code_r <= C_ERR_STAGED;
        elsif (C_STORAGE_WORDS(ww) = '1') then

          for i in mem'range loop

            if (i = ww) then
              mem(i)     <= merge(mem(i), wdata, be) and storage_mask(i);
              written(i) <= '1';
              if (i = word(C_REG_STEPS)) then
                steps_bad <= '0';
                if ((merge(mem(i), wdata, be) and storage_mask(i)) = x"80000000") then
                  steps_bad <= '1';
                end if;
              end if;
            end if;

          end loop;

        elsif (ww = word(C_REG_CTRL)) then
          new_ctrl := merge(x"00000000", wdata, be);

          if (be(1) = '1') then
            irq_done_en  <= wdata(C_CTRL_IRQ_DONE_EN_LSB);
            irq_error_en <= wdata(C_CTRL_IRQ_ERROR_EN_LSB);
            irq_in_en    <= wdata(C_CTRL_IRQ_LATCH_EN_LSB downto C_CTRL_IRQ_LIMIT_NEG_EN_LSB);
          end if;

          if (be(2) = '1') then
            enable_r <= wdata(C_CTRL_ENABLE_LSB);
          end if;

          start_v     := new_ctrl(C_CTRL_START_LSB);
          soft_stop_r <= new_ctrl(C_CTRL_SOFT_STOP_LSB);
          hard_stop_r <= new_ctrl(C_CTRL_HARD_STOP_LSB);

          -- A stop drops a queued move, unless it comes with the QUEUE that stages the move after it.
          if ((new_ctrl(C_CTRL_SOFT_STOP_LSB) = '1' or new_ctrl(C_CTRL_HARD_STOP_LSB) = '1') and
              new_ctrl(C_CTRL_QUEUE_LSB) = '0') then
            q_pend <= '0';
          end if;

          -- CHANGE and QUEUE need a running motion, nothing pending, and one of them; CHANGE keeps the direction; a
          -- QUEUE needs no ESTOP fault.
          if (new_ctrl(C_CTRL_CHANGE_LSB) = '1' or new_ctrl(C_CTRL_QUEUE_LSB) = '1') then
            if (moving = '0' or locked = '1' or (new_ctrl(C_CTRL_CHANGE_LSB) and new_ctrl(C_CTRL_QUEUE_LSB)) = '1' or
                (new_ctrl(C_CTRL_CHANGE_LSB) = '1' and mem(word(C_REG_STEPS))(31) /= eng_dir) or
                (new_ctrl(C_CTRL_QUEUE_LSB) = '1' and steps_bad = '1')) then
              error_flag <= '1';
              err_code_r <= C_ERR_CHANGE;
            elsif (new_ctrl(C_CTRL_QUEUE_LSB) = '1' and (in_ev(3) = '1' or in_level(3) = '1')) then
              -- A move queued during an ESTOP fault could never start: refused as a START would be.
              error_flag <= '1';
              err_code_r <= C_ERR_ESTOP;
            elsif (new_ctrl(C_CTRL_CHANGE_LSB) = '1') then
              change_r <= '1';
            else
              q_pend <= '1';
            end if;
          end if;
        elsif (ww = word(C_REG_STATUS)) then
          clr := merge(x"00000000", wdata, be);
        elsif (ww = word(C_REG_POSITION)) then
          if (moving = '1') then
            error_flag <= '1';
            err_code_r <= C_ERR_POS_BUSY;
          else
            pos_load_r  <= '1';
            pos_value_r <= merge(eng_position, wdata, be);
          end if;
        end if;
      end if;

      if (rd = '1') then
        ack_r     <= '1';
        ram_sel_r <= '0';
        mapped    := C_MAPPED_WORDS(w) = '1';

        if (not mapped) then
          err_r <= '1';
        end if;

        -- A storage word comes from the RAM once written since reset, before that as its reset value from rdata_r.
        for i in written'range loop

          if (i = w) then
            ram_sel_r <= written(i);
          end if;

        end loop;

        -- The live words, or a storage word's reset value: at most one term is selected (none for an unmapped
        -- offset), so an AND-OR multiplexer, smaller than an if chain.
        ctrl_v := (others => '0');
        stat_v := (others => '0');

        ctrl_v(C_CTRL_IRQ_DONE_EN_LSB)  := irq_done_en;
        ctrl_v(C_CTRL_IRQ_ERROR_EN_LSB) := irq_error_en;
        ctrl_v(C_CTRL_ENABLE_LSB)       := enable_r;

        ctrl_v(C_CTRL_IRQ_LATCH_EN_LSB downto C_CTRL_IRQ_LIMIT_NEG_EN_LSB) := irq_in_en;

        stat_v(C_STATUS_STATE_LSB + 1 downto C_STATUS_STATE_LSB)          := eng_state;
        stat_v(C_STATUS_BUSY_LSB)                                         := moving;
        stat_v(C_STATUS_DIR_LSB)                                          := eng_dir;
        stat_v(C_STATUS_DONE_LSB)                                         := done_flag;
        stat_v(C_STATUS_ERROR_LSB)                                        := error_flag;
        stat_v(C_STATUS_DIR_FAULT_LSB)                                    := dir_fault;
        stat_v(C_STATUS_PENDING_LSB)                                      := locked;
        stat_v(C_ERR_CODE_MSB downto C_STATUS_ERR_CODE_LSB)               := err_code_r;
        stat_v(C_STATUS_ESTOP_LSB downto C_STATUS_LIMIT_NEG_LSB)          := in_level;
        stat_v(C_STATUS_ESTOP_FAULT_LSB downto C_STATUS_LIMIT_NEG_EV_LSB) := in_ev;
        stat_v(C_STATUS_LATCHED_LSB)                                      := latched;

        if (w = word(C_REG_TIME_LO)) then
          time_hi_r <= time_count(63 downto 32);
        end if;

        rd_v := gate(reset_value(w), C_STORAGE_WORDS(w) = '1') or gate(C_ID_VALUE or C_ID_RAMP, w = word(C_REG_ID)) or
                gate(ctrl_v, w = word(C_REG_CTRL)) or gate(stat_v, w = word(C_REG_STATUS)) or
                gate(eng_position, w = word(C_REG_POSITION)) or gate(eng_cur_delay, w = word(C_REG_CUR_DELAY)) or
                gate('0' & eng_step_count, w = word(C_REG_STEP_COUNT)) or
                gate(latch_pos, w = word(C_REG_LATCH_POS)) or
                gate(latch_time(31 downto 0), w = word(C_REG_LATCH_TIME_LO)) or
                gate(latch_time(63 downto 32), w = word(C_REG_LATCH_TIME_HI)) or
                gate(time_count(31 downto 0), w = word(C_REG_TIME_LO)) or gate(time_hi_r, w = word(C_REG_TIME_HI));

        rdata_r <= rd_v;
      end if;

      if (clr(C_STATUS_DONE_LSB) = '1') then
        done_flag <= '0';
      end if;

      if (clr(C_STATUS_ERROR_LSB) = '1') then
        error_flag <= '0';
      end if;

      for i in 0 to 2 loop

        if (clr(C_STATUS_LIMIT_NEG_EV_LSB + i) = '1') then
          in_ev(i) <= '0';
        end if;

      end loop;

      -- The fault clears only once ESTOP has gone inactive.
      if (clr(C_STATUS_ESTOP_FAULT_LSB) = '1' and in_level(3) = '0') then
        in_ev(3) <= '0';
      end if;

      latch_clr_r <= clr(C_STATUS_LATCHED_LSB);

      -- The multi-axis top's SYNC_SOFT_STOP: as a CTRL.SOFT_STOP (without QUEUE) written at this edge.
      if (ext_soft_stop = '1') then
        soft_stop_r <= '1';
        q_pend      <= '0';
      end if;

      -- A START (written, or the multi-axis top's) while idle: refused with STEPS = -2^31 (no 31-bit magnitude),
      -- during an ESTOP fault, or towards an active limit; it then ends at once (DONE and ERROR), nothing moves.
      if (ext_start = '1') then
        start_v := '1';
      end if;

      if (start_v = '1') then
        start_r <= '1';
        if (eng_busy = '0') then
          mv_dir <= direction_i;
          if (steps_bad = '1' or in_ev(3) = '1' or in_level(3) = '1' or toward_c = '1') then
            start_r    <= '0';
            done_flag  <= '1';
            error_flag <= '1';
            if (steps_bad = '1') then
              err_code_r <= C_ERR_STEPS;
            elsif (toward_c = '1') then
              err_code_r <= C_ERR_LIMIT;
            else
              err_code_r <= C_ERR_ESTOP;
            end if;
          end if;
        end if;
      end if;

      if (eng_done = '1') then
        done_flag <= '1';
      end if;

      -- The queued move starts at the engine's done, as a START written at this edge; an error drops it, and an
      -- active limit against its direction refuses it.
      if (eng_done = '1' and q_pend = '1') then
        q_pend  <= '0';
        start_r <= not eng_error and not toward_c;
        mv_dir  <= direction_i;
        if (eng_error = '0' and toward_c = '1') then
          error_flag <= '1';
          err_code_r <= C_ERR_LIMIT;
        end if;
      end if;

      if (eng_error = '1') then
        error_flag <= '1';
        err_code_r <= eng_err_code;
      end if;

      if (eng_chg_refused = '1') then
        error_flag <= '1';
        err_code_r <= C_ERR_CHANGE;
      end if;

      -- A limit against the running move stops it, once (soft or hard, INPUT_CFG.LIMIT_HARD), and drops a queued
      -- move; the move's own direction counts, mv_dir (1: position counting down, towards LIMIT_NEG).
      if (eng_busy = '0') then
        lim_hit <= '0';
      elsif (lim_hit = '0' and lim_c = '1') then
        lim_hit    <= '1';
        q_pend     <= '0';
        error_flag <= '1';
        err_code_r <= C_ERR_LIMIT;
        if (mem(word(C_REG_INPUT_CFG))(C_INPUT_CFG_LIMIT_HARD_LSB) = '1') then
          hard_stop_r <= '1';
        else
          soft_stop_r <= '1';
        end if;
      end if;

      -- Input events; ESTOP latches the fault, clears CTRL.ENABLE and drops a queued move (the core hard-stops
      -- from the filtered level itself).
      for i in 0 to 3 loop

        if (in_rise(i) = '1') then
          in_ev(i) <= '1';
        end if;

      end loop;

      if (in_rise(3) = '1' or in_level(3) = '1') then
        in_ev(3) <= '1';
        enable_r <= '0';
        q_pend   <= '0';
      end if;

      if (in_rise(3) = '1') then
        error_flag <= '1';
        err_code_r <= C_ERR_ESTOP;
      end if;

      irq_r <= irq_c;

      if (rst = '1') then
        ack_r        <= '0';
        err_r        <= '0';
        start_r      <= '0';
        soft_stop_r  <= '0';
        hard_stop_r  <= '0';
        change_r     <= '0';
        q_pend       <= '0';
        pos_load_r   <= '0';
        irq_r        <= '0';
        irq_done_en  <= '0';
        irq_error_en <= '0';
        irq_in_en    <= (others => '0');
        in_ev        <= (others => '0');
        mv_dir       <= '0';
        lim_hit      <= '0';
        time_hi_r    <= (others => '0');
        latch_clr_r  <= '0';
        enable_r     <= '0';
        done_flag    <= '0';
        error_flag   <= '0';
        err_code_r   <= C_ERR_NONE;
        rdata_r      <= (others => '0');
        ram_sel_r    <= '0';
        written      <= (others => '0');
        steps_bad    <= '0';
        if (C_REG_RESET(word(C_REG_STEPS)) = x"80000000") then
          steps_bad <= '1';
        end if;

        for i in mem'range loop

          mem(i) <= C_REG_RESET(i);

        end loop;

      end if;
    end if;

  end process bus_proc;

  -- (Concurrent: see toward_c.)
  toward_c <= against_limit(mem(word(C_REG_INPUT_CFG)), in_level, direction_i);
  lim_c    <= against_limit(mem(word(C_REG_INPUT_CFG)), in_level, mv_dir);
  irq_c    <= (done_flag and irq_done_en) or (error_flag and irq_error_en) or
              (in_ev(0) and irq_in_en(0)) or (in_ev(1) and irq_in_en(1)) or (in_ev(2) and irq_in_en(2)) or
              (in_ev(3) and irq_in_en(3)) or (latched and irq_in_en(4));

  -- The RAM's write port: the storage writes that bus_proc accepts into mem, with the same byte merge and mask. A
  -- word's first write since reset enables every lane, the disabled ones taking the reset value (what mem holds).
  ram_addr <= to_integer(unsigned(addr(C_ADDR_BITS - 1 downto 2)));

  bus_wword <= to_integer(unsigned(waddr(C_ADDR_BITS - 1 downto 2))) when G_WADDR else
               ram_addr;

  ram_wr_proc : process (wr, ram_addr, wdata, be, moving, written, locked) is

    variable fresh : std_logic;

  begin

    fresh := '0';

    for i in written'range loop

      if (i = ram_addr) then
        fresh := not written(i);
      end if;

    end loop;

    ram_wdata <= merge(reset_value(ram_addr), wdata, be) and storage_mask(ram_addr);
    ram_we    <= (others => '0');

    if (wr = '1' and C_STORAGE_WORDS(ram_addr) = '1' and not (C_CONFIG_WORDS(ram_addr) = '1' and moving = '1') and
        (locked = '0' or C_CONFIG_WORDS(ram_addr) = '1')) then

      for b in 0 to 3 loop

        ram_we(b) <= be(b) or fresh;

      end loop;

    end if;

  end process ram_wr_proc;

  -- The RAM: a write port with one enable per byte lane, and a read port registered and enabled by rd, so ram_q
  -- holds the last read until the next, like rdata_r; a read in the cycle of a write reads the old word. No reset.
  ram_proc : process (clk) is
  begin

    if rising_edge(clk) then

      for b in 0 to 3 loop

        if (ram_we(b) = '1') then
          ram(ram_addr)(8 * b + 7 downto 8 * b) <= ram_wdata(8 * b + 7 downto 8 * b);
        end if;

      end loop;

      if (rd = '1') then
        ram_q <= ram(ram_addr);
      end if;
    end if;

  end process ram_proc;

  rdata <= ram_q when ram_sel_r = '1' else
           rdata_r;
  ack   <= ack_r;
  err   <= err_r;
  irq   <= irq_r;

  start     <= start_r;
  soft_stop <= soft_stop_r;
  hard_stop <= hard_stop_r;
  pos_load  <= pos_load_r;
  change    <= change_r;
  locked    <= change_r or eng_chg_pend or q_pend;
  moving    <= eng_busy or start_r or q_pend;

  done_sticky   <= done_flag;
  busy_status   <= moving;
  estop_fault   <= in_ev(3);
  latch_clr     <= latch_clr_r;
  in_filter     <= mem(word(C_REG_INPUT_FILTER))(19 downto 0);
  in_pol        <= mem(word(C_REG_INPUT_CFG))(C_INPUT_CFG_POL_ESTOP_LSB downto C_INPUT_CFG_POL_LIMIT_NEG_LSB);
  latch_src     <= mem(word(C_REG_INPUT_CFG))(C_INPUT_CFG_LATCH_SRC_LSB + 1 downto C_INPUT_CFG_LATCH_SRC_LSB);
  latch_active  <= mem(word(C_REG_INPUT_CFG))(C_INPUT_CFG_LATCH_ON_ACTIVE_LSB);
  latch_release <= mem(word(C_REG_INPUT_CFG))(C_INPUT_CFG_LATCH_ON_RELEASE_LSB);
  pos_value     <= pos_value_r;

  -- The signed step count as magnitude and direction (-2^31 is rejected at START above).
  direction <= direction_i;

  steps_proc : process (mem) is

    variable s : signed(31 downto 0);

  begin

    s           := signed(mem(word(C_REG_STEPS)));
    direction_i <= s(31);

    if (s(31) = '1') then
      s := -s;
    end if;

    steps <= std_logic_vector(s(30 downto 0));

  end process steps_proc;

  prescale   <= mem(word(C_REG_PRESCALE))(15 downto 0);
  c_first    <= mem(word(C_REG_C_FIRST_HI))(15 downto 0) & mem(word(C_REG_C_FIRST_LO));
  c_last     <= mem(word(C_REG_C_LAST_HI))(15 downto 0) & mem(word(C_REG_C_LAST_LO));
  sa         <= mem(word(C_REG_SA))(30 downto 0);
  c_sa       <= mem(word(C_REG_C_SA_HI))(15 downto 0) & mem(word(C_REG_C_SA_LO));
  sd         <= mem(word(C_REG_SD))(30 downto 0);
  c_sd       <= mem(word(C_REG_C_SD_HI))(15 downto 0) & mem(word(C_REG_C_SD_LO));
  accel_seed <= mem(word(C_REG_ACCEL_SEED_HI)) & mem(word(C_REG_ACCEL_SEED_LO));
  decel_seed <= mem(word(C_REG_DECEL_SEED_HI)) & mem(word(C_REG_DECEL_SEED_LO));
  cruise     <= mem(word(C_REG_CRUISE_HI)) & mem(word(C_REG_CRUISE_LO));
  stop_ratio <= mem(word(C_REG_STOP_RATIO));
  head_down  <= mem(word(C_REG_SEGMENT))(C_SEGMENT_HEAD_DOWN_LSB);
  endless    <= mem(word(C_REG_SEGMENT))(C_SEGMENT_ENDLESS_LSB);
  head_index <= mem(word(C_REG_HEAD_INDEX))(30 downto 0);
  run_stop   <= mem(word(C_REG_RUN_STOP))(30 downto 0);
  head_prod  <= mem(word(C_REG_HEAD_PROD_HI))(15 downto 0) & mem(word(C_REG_HEAD_PROD_LO));
  change_at  <= mem(word(C_REG_CHANGE_AT))(30 downto 0);
  enable     <= enable_r and not in_ev(3);
  mode       <= mem(word(C_REG_DRIVE))(C_DRIVE_MODE_LSB + 2 downto C_DRIVE_MODE_LSB);
  ustep_log2 <= mem(word(C_REG_DRIVE))(C_DRIVE_USTEP_LOG2_LSB + 2 downto C_DRIVE_USTEP_LOG2_LSB);
  step_width <= mem(word(C_REG_STEP_WIDTH))(15 downto 0);
  dir_setup  <= mem(word(C_REG_DIR_TIMING))(C_DIR_TIMING_SETUP_LSB + 15 downto C_DIR_TIMING_SETUP_LSB);
  dir_hold   <= mem(word(C_REG_DIR_TIMING))(C_DIR_TIMING_HOLD_LSB + 15 downto C_DIR_TIMING_HOLD_LSB);
  pwm_period <= mem(word(C_REG_PWM_PERIOD))(15 downto 0);
  step_space <= mem(word(C_REG_STEP_SPACE))(15 downto 0);

end architecture rtl;
