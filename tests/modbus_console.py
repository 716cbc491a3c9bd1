"""A bridge console's Modbus I/O as a real pymodbus server on 127.0.0.1 (TCP) or on a serial
port (RTU), run in a thread with its own event loop; it can be stopped and started again
(its register values survive a restart, as a PLC's would)."""
from __future__ import annotations

import asyncio
import threading

from conftest import free_port
from pymodbus.server import ModbusSerialServer, ModbusTcpServer
from pymodbus.simulator import DataType, SimData, SimDevice

READ_HOLDING, WRITE_MULTIPLE = 3, 16  # Modbus function codes
REGISTERS = 100


class ModbusConsole:
    """Holding registers 0..99 of device 1; ``set(address, raw)`` changes what the node reads."""

    def __init__(self, transport: str = "tcp", serial_port: str | None = None) -> None:
        self.transport, self.serial_port = transport, serial_port
        self.port = free_port()
        self.values = [0] * REGISTERS
        self._loop = None
        self._server = None
        self._thread = None

    def _call(self, coro):
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(5.0)

    def set(self, address: int, raw: int) -> None:
        self.values[address] = raw & 0xFFFF
        if self._server is not None:
            self._call(self._server.async_setValues(1, WRITE_MULTIPLE, address, [raw & 0xFFFF]))

    def get(self, address: int) -> int:
        return self._call(self._server.async_getValues(1, READ_HOLDING, address, 1))[0]

    def start(self) -> None:
        ready = threading.Event()
        device = SimDevice(1, [SimData(0, count=REGISTERS, values=list(self.values), datatype=DataType.REGISTERS)])

        async def serve() -> None:
            if self.transport == "tcp":
                self._server = ModbusTcpServer(device, address=("127.0.0.1", self.port))
            else:
                self._server = ModbusSerialServer(device, port=self.serial_port, baudrate=38400)
            self._loop = asyncio.get_running_loop()
            self._loop.call_soon(ready.set)
            await self._server.serve_forever()

        self._thread = threading.Thread(target=asyncio.run, args=(serve(),), daemon=True)
        self._thread.start()
        ready.wait(5.0)

    def stop(self) -> None:
        if self._server is not None:
            self.values = [self.get(a) for a in range(REGISTERS)]
            self._call(self._server.shutdown())
            self._thread.join(5.0)
            self._loop = self._server = self._thread = None
