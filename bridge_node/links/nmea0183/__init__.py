"""The NMEA 0183 link kind: serial sentences in and out, a UDP copy, AIS."""
