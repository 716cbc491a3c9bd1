"""The CAN link kind: python-can buses, the console's DBC frames and NMEA 2000."""
