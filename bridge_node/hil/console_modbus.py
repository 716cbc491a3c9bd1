"""The software console's Modbus end: a register server on 127.0.0.1 (pymodbus) holding the
console's orders for the node to read, and the indicators the node writes read back; its
framing fault is a malformed MBAP header in its replies."""
from __future__ import annotations

import asyncio
import math
import random
import threading
from collections.abc import Callable

from pymodbus.server import ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

from bridge_node.hil.console_links import ETL_CODES, ConsoleLink, Order, Reading
from bridge_node.hil.scenario import Fault
from bridge_node.hil.settings import ModbusConsoleSettings
from bridge_node.links.modbus.link import raw_register, register_value
from sim_core.ship.orders import OrderKind


REGISTERS = 100
READ_HOLDING, WRITE_MULTIPLE = 3, 16  # Modbus function codes
UNWRITTEN = 0x8000  # an indicator register the node has not written yet holds this
# indicator -> (quantity, SI per engineering unit); "speed" has no quantity here
INDICATORS = {"rudder_angle": ("rudder_angle", math.radians(1.0)), "shaft_rpm": ("shaft_speed", 1.0 / 60.0),
              "heading": ("heading", math.radians(1.0))}


MBAP_FAULTS = ("length", "protocol", "transaction", "truncated")  # what a malformed reply gets wrong


def mangle_mbap(frame: bytes, rng: random.Random) -> bytes:
    """A Modbus TCP frame with its MBAP header made wrong, one way drawn from ``rng``: a
    length field that does not match what follows, a protocol id other than 0, another
    request's transaction id, or the frame cut short."""
    how = rng.choice(MBAP_FAULTS)
    b = bytearray(frame)
    if how == "length":
        b[4:6] = max(0, int.from_bytes(b[4:6], "big") + rng.choice((-2, -1, 1, 3))).to_bytes(2, "big")
    elif how == "protocol":
        b[2:4] = rng.randrange(1, 0x10000).to_bytes(2, "big")
    elif how == "transaction":
        b[0:2] = ((int.from_bytes(b[0:2], "big") + rng.randrange(1, 0x10000)) & 0xFFFF).to_bytes(2, "big")
    else:
        del b[rng.randrange(1, len(b)):]
    return bytes(b)


class _RegisterServer:
    """A pymodbus TCP server (device registers 0..99) in a thread with its own event loop;
    ``trace_packet(sending, frame) -> frame`` sees (and may change) every frame."""

    def __init__(self, host: str, port: int, device_id: int, values: list[int],
                 trace_packet: Callable[[bool, bytes], bytes]) -> None:
        self.device_id = device_id
        self._server = None
        self._loop = None
        ready = threading.Event()
        device = SimDevice(device_id, [SimData(0, count=REGISTERS, values=values, datatype=DataType.REGISTERS)])

        async def serve() -> None:
            self._server = ModbusTcpServer(device, address=(host, port), trace_packet=trace_packet)
            self._loop = asyncio.get_running_loop()
            self._loop.call_soon(ready.set)
            await self._server.serve_forever()

        self._thread = threading.Thread(target=asyncio.run, args=(serve(),), daemon=True, name="console-modbus")
        self._thread.start()
        if not ready.wait(5.0):
            raise OSError(f"the Modbus server on {host}:{port} did not start")

    def _call(self, coro):
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(5.0)

    def set(self, address: int, raw: int) -> None:
        self._call(self._server.async_setValues(self.device_id, WRITE_MULTIPLE, address, [raw & 0xFFFF]))

    def values(self) -> list[int]:
        return list(self._call(self._server.async_getValues(self.device_id, READ_HOLDING, 0, REGISTERS)))

    def stop(self) -> None:
        self._call(self._server.shutdown())
        self._thread.join(5.0)


class ModbusConsole(ConsoleLink):
    """The console's register server: the node polls its order registers and writes its
    indicators; register values survive a disconnect, as a PLC's do. Its framing fault
    (corrupt = "format") is on the replies the node reads: malformed MBAP headers."""

    kind = "modbus"
    corruptions = ("format", "range")

    def __init__(self, settings: ModbusConsoleSettings) -> None:
        super().__init__(settings)
        self._values = [0] * REGISTERS
        for w in settings.writes:
            self._values[w.address] = UNWRITTEN
        self._bad_replies: tuple[Fault, random.Random] | None = None  # corrupt = "format", while on

    def inject(self, fault: Fault, rng: random.Random) -> None:
        if fault.kind == "corrupt" and fault.corrupt == "format":
            self._bad_replies = (fault, rng)
        else:
            super().inject(fault, rng)

    def clear(self, fault: Fault) -> None:
        if self._bad_replies is not None and self._bad_replies[0] is fault:
            self._bad_replies = None
        super().clear(fault)

    def _trace(self, sending: bool, frame: bytes) -> bytes:
        """Every frame of the server (on its thread): a reply, while corrupt = "format" is
        on, made malformed with the fault's probability."""
        bad = self._bad_replies
        if not sending or bad is None or bad[1].random() >= bad[0].probability:
            return frame
        self.sent["bad_replies"] += 1
        return mangle_mbap(frame, bad[1])

    def supports(self, kind: str) -> bool:
        return any(r.order.split("_")[0] == kind for r in self.settings.registers)  # searchlight_on: searchlight

    def _open(self) -> _RegisterServer:
        s = self.settings
        return _RegisterServer(s.host, s.port, s.device_id, list(self._values), self._trace)

    def _close(self, server: _RegisterServer) -> None:
        self._values = server.values()
        server.stop()

    def _encode(self, order: Order, corrupt: str | None) -> list[tuple[int, int]]:
        value = order.wire_value(corrupt)
        out = []
        if order.kind == OrderKind.SEARCHLIGHT:
            fields = {"searchlight_on": float(value.on), "searchlight_bearing": math.degrees(value.bearing),
                      "searchlight_elevation": math.degrees(value.elevation)}
            return [(r.address, raw_register(fields[r.order] / r.scale, r.type)) for r in self.settings.registers
                    if r.order in fields and r.light == value.index]
        for r in self.settings.registers:
            if r.order != order.kind:
                continue
            eng = math.degrees(value) if order.kind == OrderKind.RUDDER else (
                int(value if corrupt == "range" else ETL_CODES[value]) if order.kind == OrderKind.TELEGRAPH else value)
            out.append((r.address, raw_register(eng / r.scale, r.type)))
        return out

    def _write(self, item: tuple[int, int]) -> None:
        self.device.set(*item)

    def _read(self, now: float) -> list[Reading]:
        values = self.device.values()
        out = []
        for w in self.settings.writes:
            raw = values[w.address]
            if raw != UNWRITTEN and w.value in INDICATORS:
                quantity, factor = INDICATORS[w.value]
                out.append(Reading(now, self.role, quantity, register_value(raw, w.type) * w.scale * factor))
        return out
