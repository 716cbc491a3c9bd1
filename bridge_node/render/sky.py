"""The sun and the sky of the exercise: the sun's direction from the date, time and place
(NOAA's solar position equations, after Meeus: better than 0.1 deg for 1900-2100), and the
light it gives: sky colours at the zenith and the horizon, the direct light's colour and
the sky's ambient light, from polar day through twilight to polar night, and the daylight's
illuminance, against which the eye judges a searchlight."""
from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np

J2000 = datetime.fromisoformat("2000-01-01T12:00:00+00:00")


def sun_position(utc: datetime, lat: float, lon: float) -> tuple[float, float]:
    """Azimuth (clockwise from north) and elevation of the sun's centre, rad, seen from
    latitude and longitude (rad, east positive) at a timezone-aware time."""
    days = (utc - J2000) / timedelta(days=1)
    c = days / 36525.0  # Julian centuries
    l0 = math.radians((280.46646 + c * (36000.76983 + 0.0003032 * c)) % 360.0)
    m = math.radians(357.52911 + c * (35999.05029 - 0.0001537 * c))
    e = 0.016708634 - c * (0.000042037 + 0.0000001267 * c)
    centre = math.radians(math.sin(m) * (1.914602 - c * (0.004817 + 0.000014 * c))
                          + math.sin(2 * m) * (0.019993 - 0.000101 * c) + math.sin(3 * m) * 0.000289)
    omega = math.radians(125.04 - 1934.136 * c)
    longitude = l0 + centre - math.radians(0.00569 + 0.00478 * math.sin(omega))
    obliquity = math.radians(23.0 + (26.0 + (21.448 - c * (46.815 + c * (0.00059 - c * 0.001813))) / 60.0) / 60.0
                             + 0.00256 * math.cos(omega))
    declination = math.asin(math.sin(obliquity) * math.sin(longitude))
    y = math.tan(obliquity / 2) ** 2
    equation_of_time = (y * math.sin(2 * l0) - 2 * e * math.sin(m) + 4 * e * y * math.sin(m) * math.cos(2 * l0)
                        - 0.5 * y * y * math.sin(4 * l0) - 1.25 * e * e * math.sin(2 * m))  # rad
    day_fraction = (utc.timestamp() % 86400.0) / 86400.0
    hour_angle = 2 * math.pi * day_fraction - math.pi + equation_of_time + lon
    elevation = math.asin(math.sin(lat) * math.sin(declination)
                          + math.cos(lat) * math.cos(declination) * math.cos(hour_angle))
    azimuth = math.atan2(math.sin(hour_angle),
                         math.cos(hour_angle) * math.sin(lat) - math.tan(declination) * math.cos(lat)) + math.pi
    return azimuth % (2 * math.pi), elevation


# Sky by the sun's elevation (deg): zenith, horizon, direct light, ambient (sky) light;
# linear in display values, interpolated between rows. Night is starlight and airglow;
# civil twilight (-6..0 deg) has the pink-orange horizon and blue zenith of the Arctic.
_ELEVATIONS = np.array([-18.0, -12.0, -6.0, -2.0, 2.0, 8.0, 20.0, 45.0])
_ZENITH = np.array([[0.01, 0.012, 0.025], [0.02, 0.03, 0.07], [0.11, 0.16, 0.32], [0.18, 0.27, 0.48],
                    [0.24, 0.36, 0.62], [0.30, 0.46, 0.74], [0.36, 0.53, 0.78], [0.32, 0.50, 0.80]])
_HORIZON = np.array([[0.02, 0.025, 0.04], [0.05, 0.06, 0.10], [0.30, 0.24, 0.30], [0.72, 0.52, 0.42],
                     [0.85, 0.72, 0.60], [0.82, 0.84, 0.86], [0.78, 0.84, 0.90], [0.76, 0.83, 0.92]])
_DIRECT = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, 0], [0.55, 0.40, 0.25],
                    [0.80, 0.68, 0.52], [0.90, 0.87, 0.82], [0.95, 0.93, 0.90]])
_ILLUMINANCE = np.array([0.002, 0.01, 3.0, 100.0, 1000.0, 1.0e4, 4.0e4, 8.0e4])  # lux, on the ground
_AMBIENT = np.array([[0.02, 0.025, 0.04], [0.04, 0.05, 0.09], [0.17, 0.18, 0.28], [0.36, 0.34, 0.40],
                     [0.40, 0.40, 0.46], [0.36, 0.38, 0.44], [0.36, 0.39, 0.45], [0.38, 0.41, 0.48]])


@dataclass(frozen=True)
class Sky:
    """The light of one moment: sun direction (world x east, y north, z up, unit), colours
    of the zenith and horizon, the sun's direct light and the sky's ambient light (display
    values), and the daylight's illuminance."""

    sun: tuple[float, float, float]
    zenith: tuple[float, float, float]
    horizon: tuple[float, float, float]
    direct: tuple[float, float, float]
    ambient: tuple[float, float, float]
    illuminance: float  # lux: the daylight on the ground


def sky_for(utc: datetime, lat: float, lon: float) -> Sky:
    """The sky at a time (timezone-aware) and place (rad)."""
    azimuth, elevation = sun_position(utc, lat, lon)
    deg = math.degrees(elevation)

    def at(table: np.ndarray) -> tuple[float, float, float]:
        return tuple(float(np.interp(deg, _ELEVATIONS, table[:, k])) for k in range(3))

    # the light comes from the sun's visible disc: never from below the horizon
    lit = max(elevation, 0.02)
    sun = (math.sin(azimuth) * math.cos(lit), math.cos(azimuth) * math.cos(lit), math.sin(lit))
    illuminance = float(np.exp(np.interp(deg, _ELEVATIONS, np.log(_ILLUMINANCE))))
    return Sky(sun, at(_ZENITH), at(_HORIZON), at(_DIRECT), at(_AMBIENT), illuminance)
