-- SPDX-License-Identifier: MIT
-- stepramp_pkg: helpers shared by the stepramp entities (log2_ceil, clog2, to_sl); compiled first
-- (docs/integration.md, "Compile order").

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

end package body stepramp_pkg;
