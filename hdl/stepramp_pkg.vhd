-- SPDX-License-Identifier: MIT
-- stepramp_pkg: helpers shared by the stepramp entities (log2_ceil, clog2, to_sl, any, csel_sub, csel_sub_int);
-- compiled first (docs/integration.md, "Compile order").

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

package stepramp_pkg is

  -- The smallest b >= 0 with 2 ** b >= n (the exact log2 of a power of two).
  function log2_ceil (
    n : positive
  ) return natural;

  -- Number of bits needed to hold the values 0 .. n - 1 (at least 1).
  function clog2 (
    n : positive
  ) return positive;

  -- '1' for true, '0' for false.
  function to_sl (
    b : boolean
  ) return std_logic;

  -- '1' when a bit of bits is '1' (their OR).
  function any (
    bits : std_logic_vector
  ) return std_logic;

  -- trial - sub (both of one width w >= 2, modulo 2^w) as a carry-select subtractor: the low (w + 1) / 2 bits are one
  -- borrow chain, the bits above are computed for both borrows and picked by the low chain's borrow, so no borrow
  -- ripples through the whole width (the divider's radix-4 step and the square root's trial, each in one clock).
  function csel_sub (
    trial : unsigned;
    sub   : unsigned
  ) return unsigned;

  -- csel_sub on integer parts, for widths up to 60 bits (the divider's step, the square root's trial): the operands
  -- split into a low part of lo_w bits and a high part of hi_w bits, given as integers (t_lo, t_hi the trial's;
  -- s_lo, s_hi the subtrahend's, s_not its high part inverted as bits: trial - sub - 1 is trial + not sub less
  -- 2 ** hi_w). diff gets the lo_w + hi_w bits of trial - sub (its top bit is the sign when the operands have a spare
  -- top bit), fits whether sub <= trial (the borrow out of the high part). A simulator evaluates an integer in a few
  -- instructions, a vector bit by bit, and computes only the high part the low part's borrow picks; the conversions
  -- from and to the bits are wiring in hardware.

  procedure csel_sub_int (
    t_lo  : in    natural;
    t_hi  : in    natural;
    s_lo  : in    natural;
    s_hi  : in    natural;
    s_not : in    natural;
    lo_w  : in    positive;
    hi_w  : in    positive;
    diff  : out   unsigned;
    fits  : out   boolean
  );

end package stepramp_pkg;

package body stepramp_pkg is

  function log2_ceil (
    n : positive
  ) return natural is

    variable bits : natural;

  begin

    bits := 0;

    while 2 ** bits < n loop

      bits := bits + 1;

    end loop;

    return bits;

  end function log2_ceil;

  function clog2 (
    n : positive
  ) return positive is
  begin

    if (n <= 2) then
      return 1;
    end if;

    return log2_ceil(n);

  end function clog2;

  function to_sl (
    b : boolean
  ) return std_logic is
  begin

    if (b) then
      return '1';
    end if;

    return '0';

  end function to_sl;

  function any (
    bits : std_logic_vector
  ) return std_logic is

    constant C_NONE : std_logic_vector(bits'range) := (others => '0');

  begin

    return to_sl(bits /= C_NONE);

  end function any;

  function csel_sub (
    trial : unsigned;
    sub   : unsigned
  ) return unsigned is

    constant C_W  : positive := trial'length;
    constant C_LO : positive := (C_W + 1) / 2;

    alias    a  : unsigned(C_W - 1 downto 0) is trial;
    alias    b  : unsigned(C_W - 1 downto 0) is sub;
    variable lo : unsigned(C_LO downto 0); -- the low bits' difference and its borrow

  begin

    lo := ('0' & a(C_LO - 1 downto 0)) - ('0' & b(C_LO - 1 downto 0));

    -- The bits above with a borrow from below (a - b - 1 = a + not b) and without one: two subtractors and a
    -- multiplexer in hardware, as if both were computed first; a simulator evaluates only the one it returns.
    if (lo(C_LO) = '1') then
      return (a(C_W - 1 downto C_LO) + not b(C_W - 1 downto C_LO)) & lo(C_LO - 1 downto 0);
    end if;

    return (a(C_W - 1 downto C_LO) - b(C_W - 1 downto C_LO)) & lo(C_LO - 1 downto 0);

  end function csel_sub;

  procedure csel_sub_int (
    t_lo  : in    natural;
    t_hi  : in    natural;
    s_lo  : in    natural;
    s_hi  : in    natural;
    s_not : in    natural;
    lo_w  : in    positive;
    hi_w  : in    positive;
    diff  : out   unsigned;
    fits  : out   boolean
  ) is

    variable lo : signed(lo_w downto 0);   -- the low part's difference, its borrow on top
    variable hb : unsigned(hi_w downto 0); -- the high part with the borrow: trial + not sub, carry on top
    variable hn : signed(hi_w downto 0);   -- the high part without it, borrow on top

  begin

    lo := to_signed(t_lo - s_lo, lo_w + 1);

    if (lo(lo_w) = '1') then
      hb                                                      := to_unsigned(t_hi + s_not, hi_w + 1);
      fits                                                    := hb(hi_w) = '1';
      diff(diff'low + lo_w + hi_w - 1 downto diff'low + lo_w) := hb(hi_w - 1 downto 0);
    else
      hn                                                      := to_signed(t_hi - s_hi, hi_w + 1);
      fits                                                    := hn(hi_w) = '0';
      diff(diff'low + lo_w + hi_w - 1 downto diff'low + lo_w) := unsigned(hn(hi_w - 1 downto 0));
    end if;

    diff(diff'low + lo_w - 1 downto diff'low) := unsigned(lo(lo_w - 1 downto 0));

  end procedure csel_sub_int;

end package body stepramp_pkg;
