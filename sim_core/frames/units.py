"""Units used at the edges (config files, displays, NMEA): SI inside, these only outside."""

NAUTICAL_MILE = 1852.0  # m
KNOT = NAUTICAL_MILE / 3600.0  # m/s
