"""The software console's end for each link kind, by the node link's ``type`` it is the
peer of."""
from __future__ import annotations

from bridge_node.hil.console_can import CanConsole
from bridge_node.hil.console_links import ConsoleLink
from bridge_node.hil.console_modbus import ModbusConsole
from bridge_node.hil.console_nmea import NmeaConsole

CONSOLE_LINKS = {"can": CanConsole, "nmea0183": NmeaConsole, "modbus": ModbusConsole}


def make_console_link(settings) -> ConsoleLink:
    """The console end for one ``[[links]]`` table of a console config."""
    return CONSOLE_LINKS[settings.type](settings)
