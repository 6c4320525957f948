# SPDX-License-Identifier: MIT
"""A cocotb-bus master for the PLB-like IPIF slave of stepramp_plb (Xilinx IPIF signal names).

Protocol as a Xilinx IPIF drives it: Bus2IP_CS with RNW, address, data and byte enables held until the slave's
one-cycle IP2Bus_RdAck/IP2Bus_WrAck (with IP2Bus_Error for a failed access) is sampled, then CS drops. Optional
idle cycles between accesses (an itertools.cycle of 0/1, 1 = insert an idle cycle) exercise other timings.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from cocotb.triggers import FallingEdge, Lock, ReadOnly, RisingEdge
from cocotb.utils import get_sim_time
from cocotb_bus.drivers import BusDriver


class IpifError(Exception):
    """The slave answered with IP2Bus_Error, or broke the protocol (both acknowledges at once)."""


class IpifMaster(BusDriver):
    _signals = (
        "bus2ip_addr",
        "bus2ip_data",
        "bus2ip_be",
        "bus2ip_cs",
        "bus2ip_rnw",
        "ip2bus_data",
        "ip2bus_rdack",
        "ip2bus_wrack",
        "ip2bus_error",
    )

    def __init__(
        self, entity: Any, clock: Any, period_ns: int, idle: Iterator[int] | None = None, timeout: int = 100
    ) -> None:
        super().__init__(entity, None, clock)
        self.period_ns = period_ns
        self.idle = idle
        self.timeout = timeout
        self.accesses = 0
        self.lock = Lock()  # one access at a time when several coroutines share the master
        self.last_ack_edge = 0  # clock edge (in periods) at which the slave registered the last ack
        self.bus.bus2ip_cs.value = 0
        self.bus.bus2ip_rnw.value = 1
        self.bus.bus2ip_addr.value = 0
        self.bus.bus2ip_data.value = 0
        self.bus.bus2ip_be.value = 0

    async def _access(self, addr: int, rnw: int, data: int, be: int) -> tuple[int, bool]:
        async with self.lock:
            await FallingEdge(self.clock)
            if self.idle is not None:
                while next(self.idle):
                    await FallingEdge(self.clock)
            self.bus.bus2ip_addr.value = addr
            self.bus.bus2ip_rnw.value = rnw
            self.bus.bus2ip_data.value = data
            self.bus.bus2ip_be.value = be
            self.bus.bus2ip_cs.value = 1
            for _ in range(self.timeout):
                await RisingEdge(self.clock)
                await ReadOnly()
                ack = self.bus.ip2bus_rdack.value if rnw else self.bus.ip2bus_wrack.value
                if int(ack):
                    other = self.bus.ip2bus_wrack.value if rnw else self.bus.ip2bus_rdack.value
                    if int(other):  # (IPIF: the acknowledge of the access's own kind only)
                        kind = "read" if rnw else "write"
                        raise IpifError(f"{kind} {addr:#x}: IP2Bus_RdAck and IP2Bus_WrAck both high at its ack")
                    self.last_ack_edge = round(get_sim_time("ns") / self.period_ns)
                    value = int(self.bus.ip2bus_data.value) if rnw else 0
                    error = bool(int(self.bus.ip2bus_error.value))
                    break
            else:
                raise TimeoutError(f"no ack within {self.timeout} cycles for {'read' if rnw else 'write'} {addr:#x}")
            # The master samples the ack at the next edge and drops CS after it.
            await RisingEdge(self.clock)
            self.bus.bus2ip_cs.value = 0
            self.accesses += 1
            return value, error

    async def read(self, addr: int, data_lines: int = 0) -> int:
        """A read; data_lines: what Bus2IP_Data shows during it (IPIF does not define it; a bus may leave a write's
        data there)."""
        value, error = await self._access(addr, 1, data_lines, 0xF)
        if error:
            raise IpifError(f"read {addr:#x}: IP2Bus_Error")
        return value

    async def write(self, addr: int, value: int, strobe: int = 0xF) -> None:
        _, error = await self._access(addr, 0, value & 0xFFFF_FFFF, strobe)
        if error:
            raise IpifError(f"write {addr:#x}: IP2Bus_Error")
