-- SPDX-License-Identifier: MIT
-- stepramp_pkg: helpers shared by the stepramp entities (clog2); compiled first (docs/integration.md, "Compile
-- order").

library ieee;
  use ieee.std_logic_1164.all;
  use ieee.numeric_std.all;

package stepramp_pkg is

  -- Number of bits needed to hold the values 0 .. n - 1 (at least 1).
  function clog2 (
    n : positive
  ) return positive;

end package stepramp_pkg;

package body stepramp_pkg is

  function clog2 (
    n : positive
  ) return positive is

    variable bits : positive;

  begin

    bits := 1;

    while 2 ** bits < n loop

      bits := bits + 1;

    end loop;

    return bits;

  end function clog2;

end package body stepramp_pkg;
