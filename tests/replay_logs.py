"""Synthetic voyages and the logs a real system would write of them, for the replay tests:
NMEA 0183 captures, AIS logs (pyais encodes), CSV tracks, GPX."""
from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass

import numpy as np
from pyais import encode_dict

from bridge_node.links.nmea0183.sentences import checksum
from sim_core.frames.geodesy import local_to_geodetic

KNOT = 1852.0 / 3600.0
T0 = 1_700_000_000.0  # unix s: 2023-11-14 22:13:20 UTC
REFERENCE = (math.radians(74.0), math.radians(20.0))  # the voyage's local frame origin


@dataclass(frozen=True)
class Fix:
    """One logged point of a voyage: unix time s, lat/lon deg, heading and course deg, speed kn."""

    t: float
    lat: float
    lon: float
    heading: float
    course: float
    speed: float


def voyage(duration: float = 120.0, every: float = 2.0, speed_kn: float = 6.0, turn_after: float = 50.0,
           rate_deg_s: float = 0.25, start: tuple[float, float] = (0.0, 0.0), heading0: float = 0.0,
           t0: float = T0) -> list[Fix]:
    """A ship steaming at constant speed, straight, then turning to starboard at a constant
    rate; fixes every ``every`` s. ``start``: north, east m from the reference point."""
    h, fine = 0.01, []
    north, east = start
    psi = math.radians(heading0)
    v = speed_kn * KNOT
    for k in range(int(round(duration / h)) + 1):
        t = k * h
        fine.append((t, north, east, psi))
        r = math.radians(rate_deg_s) if t >= turn_after else 0.0
        mid = psi + 0.5 * r * h
        north, east, psi = north + v * h * math.cos(mid), east + v * h * math.sin(mid), psi + r * h
    step = int(round(every / h))
    out = []
    for t, n, e, p in fine[::step]:
        lat, lon = local_to_geodetic(n, e, *REFERENCE)
        deg = math.degrees(p) % 360.0
        out.append(Fix(t0 + t, math.degrees(lat), math.degrees(lon), deg, deg, speed_kn))
    return out


def sentence(body: str, start: str = "$") -> str:
    return f"{start}{body}*{checksum(body):02X}"


def _latlon(lat: float, lon: float) -> str:
    a, b = abs(lat), abs(lon)
    return (f"{int(a):02d}{(a - int(a)) * 60:08.5f},{'N' if lat >= 0 else 'S'},"
            f"{int(b):03d}{(b - int(b)) * 60:08.5f},{'E' if lon >= 0 else 'W'}")


def utc(t: float) -> dt.datetime:
    return dt.datetime.fromtimestamp(t, dt.timezone.utc)


def nmea_lines(fixes: list[Fix], prefix: str = "") -> list[str]:
    """RMC, GGA and HDT of every fix. prefix: "" (a plain capture: time from RMC), "unix"
    (the node's nmea.log form) or "vdr" (OpenCPN VDR's CSV, with its header)."""
    out = ["timestamp,type,id,message"] if prefix == "vdr" else []
    for f in fixes:
        u = utc(f.t)
        hms = u.strftime("%H%M%S.") + f"{u.microsecond // 10000:02d}"
        for s in (sentence(f"GPRMC,{hms},A,{_latlon(f.lat, f.lon)},{f.speed:.1f},{f.course:.1f},"
                           f"{u.strftime('%d%m%y')},,,A"),
                  sentence(f"GPGGA,{hms},{_latlon(f.lat, f.lon)},1,10,0.9,10.0,M,20.0,M,,"),
                  sentence(f"HEHDT,{f.heading:.1f},T")):
            if prefix == "unix":
                out.append(f"{f.t:.3f} gps rx {s}")
            elif prefix == "vdr":
                out.append(f"{u.strftime('%Y-%m-%dT%H:%M:%S.')}{u.microsecond // 1000:03d}Z,NMEA0183,,\"{s}\"")
            else:
                out.append(s)
    return out


def ais_position(mmsi: int, f: Fix) -> str:
    """A class A position report (type 1) of a fix, with an NMEA 4 tag block giving its time."""
    [s] = encode_dict({"type": 1, "mmsi": mmsi, "status": 0, "speed": f.speed, "accuracy": 1,
                       "lon": round(f.lon * 600_000) / 600_000, "lat": round(f.lat * 600_000) / 600_000,
                       "course": round(f.course, 1) % 360.0, "heading": round(f.heading) % 360,
                       "second": int(f.t) % 60}, talker_id="AI", sentence_type="VDM")
    return tag_block(f.t) + s


def tag_block(t: float) -> str:
    body = f"s:test,c:{int(t)}"
    return f"\\{body}*{checksum(body):02X}\\"


def ais_static(mmsi: int, name: str, t: float, seq_id: int) -> list[str]:
    """A type 5 (two sentences) naming the vessel: 150 m x 24 m."""
    parts = encode_dict({"type": 5, "mmsi": mmsi, "shipname": name, "to_bow": 75, "to_stern": 75, "to_port": 12,
                         "to_starboard": 12}, talker_id="AI", sentence_type="VDM", seq_id=seq_id)
    return [tag_block(t) + parts[0], parts[1]]


def ais_lines(vessels: dict[int, tuple[str, list[Fix]]]) -> list[str]:
    """Position reports of several vessels interleaved in time, each named by a type 5."""
    timed = []
    for k, (mmsi, (name, fixes)) in enumerate(vessels.items()):
        timed.append((fixes[0].t - 1.0, ais_static(mmsi, name, fixes[0].t - 1.0, k + 1)))
        timed += [(f.t, [ais_position(mmsi, f)]) for f in fixes]
    return [line for _, lines in sorted(timed, key=lambda x: x[0]) for line in lines]


def csv_text(fixes: list[Fix]) -> str:
    rows = ["Time (UTC),Latitude,Longitude,Heading,SOG (kn)"]
    rows += [f"{utc(f.t).isoformat()},{f.lat:.8f},{f.lon:.8f},{f.heading:.2f},{f.speed:.2f}" for f in fixes]
    return "\n".join(rows) + "\n"


def gpx_text(fixes: list[Fix]) -> str:
    points = "".join(f'<trkpt lat="{f.lat:.8f}" lon="{f.lon:.8f}"><time>{utc(f.t).strftime("%Y-%m-%dT%H:%M:%SZ")}'
                     f"</time></trkpt>" for f in fixes)
    return ('<?xml version="1.0"?><gpx version="1.1" creator="test" xmlns="http://www.topografix.com/GPX/1/1">'
            f"<trk><trkseg>{points}</trkseg></trk></gpx>")


def replayed_errors(track_csv: str, fixes: list[Fix]) -> np.ndarray:
    """Distance (m) from each logged fix to the replayed ship at that logged time, read
    from a replay's track CSV (rows at the end of each step)."""
    import csv

    rows = list(csv.DictReader(track_csv.splitlines()))
    t = np.array([float(r["time"]) for r in rows])
    lat = np.radians([float(r["latitude_deg"]) for r in rows])
    lon = np.radians([float(r["longitude_deg"]) for r in rows])
    out = []
    for f in fixes:
        if not t[0] - 1e-6 <= f.t <= t[-1] + 1e-6:
            continue
        i = int(np.argmin(np.abs(t - f.t)))
        dn = (lat[i] - math.radians(f.lat)) * 6_378_137.0
        de = (lon[i] - math.radians(f.lon)) * 6_378_137.0 * math.cos(lat[i])
        out.append(math.hypot(dn, de))
    return np.array(out)


def at_anchor(t0: float, duration: float, every: float = 180.0, where: tuple[float, float] = (0.0, 0.0),
              swing_m: float = 15.0, heading0: float = 200.0) -> list[Fix]:
    """A ship at anchor reporting every ``every`` s (class A: 3 min): speed 0, swinging on
    its cable, the position on a circle of ``swing_m`` about ``where`` (north, east m from
    the reference point) and the heading following, a quarter turn an hour."""
    out = []
    for k in range(int(duration // every) + 1):
        t = k * every
        psi = math.radians(heading0) + 0.5 * math.pi * t / 3600.0
        lat, lon = local_to_geodetic(where[0] - swing_m * math.cos(psi), where[1] - swing_m * math.sin(psi),
                                     *REFERENCE)
        deg = math.degrees(psi) % 360.0
        out.append(Fix(t0 + t, math.degrees(lat), math.degrees(lon), deg, deg, 0.0))
    return out


def shifted(fixes: list[Fix], after: float, north_m: float) -> list[Fix]:
    """The fixes, those after logged time ``after`` (unix s) moved ``north_m`` m north: a
    log whose positions jump (a receiver swapped, a datum changed) while speed and course
    say the ship ran on as before."""
    from sim_core.frames.geodesy import radii

    def north(f: Fix) -> float:
        return f.lat + math.degrees(north_m / radii(math.radians(f.lat))[0])

    return [Fix(f.t, north(f), f.lon, f.heading, f.course, f.speed) if f.t > after else f for f in fixes]


def truncated_ais(line: str, chars: int) -> str:
    """An AIS sentence (with or without a tag block) with its payload cut to ``chars``
    six-bit characters and a fresh checksum: a message missing its later fields."""
    tag, _, rest = line.rpartition("!")
    parts = rest[:rest.rindex("*")].split(",")
    parts[5], parts[6] = parts[5][:chars], "0"
    return tag + sentence(",".join(parts), "!")


def tick_log(period: str, ticks: list[str]) -> str:
    """A session record's ``ticks.log``: the header with ``period`` as written, then the
    tick lines (``seq monotonic unix nmea can modbus``)."""
    return f"# icebridge ticks 1 period_s={period}\n" + "".join(f"{t}\n" for t in ticks)
