"""Units used at the edges (config files, displays, NMEA): SI inside, these only outside."""

KNOT = 1852.0 / 3600.0  # m/s
