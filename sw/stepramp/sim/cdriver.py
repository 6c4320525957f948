# SPDX-License-Identifier: MIT
"""The C driver (sw/c/src/stepramp.c) running against a simulated core: its register access goes through the callback
bus of build/libstepramp_cb.so (sw/c/host/stepramp_cbbus.c) into cocotb bus transactions.

Each C call runs in a thread started by cocotb's ``bridge``; every register access the C code makes calls back into
Python, where ``resume`` runs the bus transaction (and the driver's idle hook, between two STATUS polls) as a
coroutine in the simulation and blocks the C code until it is done. So the driver's own code, byte lanes and
polling loop included, talks to the RTL as a MicroBlaze program would.

    cdrv = CDriver(lib_path, bus, idle=lambda: ClockCycles(clk, 500))
    rc = await cdrv.call("stepramp_init", cdrv.dev_ref, cdrv.base, 1e6, 200.0, 1)
"""

from __future__ import annotations

import ctypes
import re
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from cocotb.task import bridge, resume

#: Where the C code believes the core is; the bus sees offsets from it.
BASE = 0x44A0_0000

#: ctypes of the C types the driver's structs use (sw/tests/c_abi.py reads the structs of the plan with them too).
C_TYPES: dict[str, Any] = {
    "uint16_t": ctypes.c_uint16,
    "uint32_t": ctypes.c_uint32,
    "uint64_t": ctypes.c_uint64,
    "int32_t": ctypes.c_int32,
    "int64_t": ctypes.c_int64,
    "int": ctypes.c_int,
    "double": ctypes.c_double,
    "uintptr_t": ctypes.c_size_t,
}


def c_struct(header: Path, name: str, types: dict[str, Any] | None = None) -> type[ctypes.Structure]:
    """The typedef struct `name` of a C header as a ctypes structure, its fields read from the header (so a field
    added in C cannot silently shift the Python view); `types` names further C types (a struct the struct holds)."""
    match = re.search(r"typedef struct \{([^{}]*)\} " + re.escape(name) + ";", header.read_text())
    if match is None:
        raise ValueError(f"no typedef struct {name} in {header}")
    body = re.sub(r"/\*.*?\*/", "", match.group(1), flags=re.S)
    known = C_TYPES | (types or {})
    fields = [(field, known[ctype]) for ctype, field in re.findall(r"(\w+)\s+(\w+)\s*;", body)]
    return type(name, (ctypes.Structure,), {"_fields_": fields})


_READ32 = ctypes.CFUNCTYPE(ctypes.c_uint32, ctypes.c_size_t)
_WRITE32 = ctypes.CFUNCTYPE(None, ctypes.c_size_t, ctypes.c_uint32)
_WRITE8 = ctypes.CFUNCTYPE(None, ctypes.c_size_t, ctypes.c_uint8)
_IDLE = ctypes.CFUNCTYPE(None)


class CDriver:
    """libstepramp_cb.so attached to a cocotb bus master (any object with async read(offset) and
    write(offset, value, strobe)). `idle`: the coroutine the driver's STEPRAMP_IDLE() runs between two polls.

    `dev` is the driver's stepramp_t and `status` a stepramp_status_t (both ctypes structures); `call` runs one C
    function in a bridged thread. A bus error inside a callback is kept and raised by `call` after the C function
    returns (the C code itself sees 0xFFFFFFFF for that read)."""

    def __init__(self, lib: Path, bus: Any, idle: Callable[[], Awaitable[Any]], base: int = BASE) -> None:
        self.so = ctypes.CDLL(str(lib))
        self.bus = bus
        self.idle = idle
        self.base = base
        c_dir = Path(__file__).resolve().parents[3] / "sw" / "c" / "src"
        self.dev_t = c_struct(c_dir / "stepramp.h", "stepramp_t")
        self.status_t = c_struct(c_dir / "stepramp.h", "stepramp_status_t")
        self.plan_t = c_struct(c_dir / "stepramp_plan.h", "stepramp_plan_t")
        self.dev = self.dev_t()
        self.status = self.status_t()
        self.errors: list[BaseException] = []
        self.reads = self.writes = self.idles = 0
        # The ctypes callbacks must outlive every C call: kept on the instance.
        self._callbacks = (
            _READ32(self._read32),
            _WRITE32(self._write32),
            _WRITE8(self._write8),
            _IDLE(self._idle),
        )
        self.so.stepramp_cbbus_attach.argtypes = [_READ32, _WRITE32, _WRITE8, _IDLE]
        self.so.stepramp_cbbus_attach(*self._callbacks)
        self._signatures()

    def _signatures(self) -> None:
        so, dev, st, plan = self.so, ctypes.POINTER(self.dev_t), ctypes.POINTER(self.status_t), self.plan_t
        sigs: dict[str, tuple[list[Any], Any]] = {
            "stepramp_init": ([dev, ctypes.c_size_t, ctypes.c_double, ctypes.c_double, ctypes.c_uint32], ctypes.c_int),
            "stepramp_init_ramp": (
                [dev, ctypes.c_size_t, ctypes.c_double, ctypes.c_double, ctypes.c_uint32, ctypes.c_uint32],
                ctypes.c_int,
            ),
            "stepramp_plan": ([dev, ctypes.POINTER(plan), ctypes.c_int64, *(ctypes.c_double,) * 3], ctypes.c_int),
            "stepramp_program": ([dev, ctypes.POINTER(plan)], ctypes.c_int),
            "stepramp_start": ([dev], None),
            "stepramp_move": ([dev, ctypes.c_int64, *(ctypes.c_double,) * 3], ctypes.c_int),
            "stepramp_change_to": (
                [dev, ctypes.c_uint32, ctypes.c_double, ctypes.c_int64, *(ctypes.c_double,) * 3],
                ctypes.c_int,
            ),
            "stepramp_queue": ([dev, ctypes.POINTER(plan)], ctypes.c_int),
            "stepramp_queue_move": ([dev, ctypes.c_int64, *(ctypes.c_double,) * 3], ctypes.c_int),
            "stepramp_soft_stop": ([dev], None),
            "stepramp_hard_stop": ([dev], None),
            "stepramp_enable_irq": ([dev, ctypes.c_int, ctypes.c_int], None),
            "stepramp_set_enable": ([dev, ctypes.c_int], None),
            "stepramp_status": ([dev, st], ctypes.c_uint32),
            "stepramp_clear_flags": ([dev], None),
            "stepramp_position": ([dev], ctypes.c_int32),
            "stepramp_set_position": ([dev, ctypes.c_int32], None),
            "stepramp_wait_done": ([dev, ctypes.c_uint32], ctypes.c_int),
            "stepramp_isr": ([dev, st], ctypes.c_int),
            "stepramp_corename": ([ctypes.c_uint32], ctypes.c_char_p),
            "stepramp_strresult": ([ctypes.c_int], ctypes.c_char_p),
        }
        for name, (args, res) in sigs.items():
            fn = getattr(so, name)
            fn.argtypes, fn.restype = args, res

    # -- callbacks: run in the bridged thread, each one a coroutine in the simulation ---------------------------
    def _offset(self, addr: int) -> int:
        return addr - self.base

    def _read32(self, addr: int) -> int:
        self.reads += 1
        try:
            return int(resume(self.bus.read)(self._offset(addr)))
        except Exception as exc:  # kept, raised by call() (ctypes would only print it)
            self.errors.append(exc)
            return 0xFFFF_FFFF

    def _write32(self, addr: int, value: int) -> None:
        self.writes += 1
        try:
            resume(self.bus.write)(self._offset(addr), value, 0xF)
        except Exception as exc:
            self.errors.append(exc)

    def _write8(self, addr: int, value: int) -> None:
        self.writes += 1
        lane = addr & 3
        try:
            resume(self.bus.write)(self._offset(addr) - lane, value << (8 * lane), 1 << lane)
        except Exception as exc:
            self.errors.append(exc)

    def _idle(self) -> None:
        self.idles += 1

        async def wait() -> None:
            await self.idle()

        try:
            resume(wait)()
        except Exception as exc:
            self.errors.append(exc)

    # -- calls ----------------------------------------------------------------------------------------------------
    async def call(self, name: str, *args: Any) -> Any:
        """Run C function `name` with args in a bridged thread; its result (bytes results decoded)."""
        fn = getattr(self.so, name)
        result = await bridge(lambda: fn(*args))()
        if self.errors:
            errors, self.errors = self.errors, []
            raise RuntimeError(f"{name}: bus error in the C driver's access: {errors[0]!r}") from errors[0]
        return result.decode() if isinstance(result, bytes) else result

    async def dev_call(self, name: str, *args: Any) -> Any:
        """`call` with the device structure as the first argument."""
        return await self.call(name, ctypes.byref(self.dev), *args)
