"""The Modbus link kind: the console's I/O registers polled over TCP or RTU (pymodbus)."""
