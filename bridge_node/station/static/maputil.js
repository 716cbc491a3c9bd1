// The map's helpers: the convoy's lines and distances, the scale bar, the lat/lon grid's
// angles, paths of the geometry's polylines. Loaded before map.js.
"use strict";

// the own ship's lines to the convoy's ships in the picture (geometry's ``convoy``: their
// MMSIs and the alarm's distance), each with its distance; red while under the limit
function drawConvoy(ctx, s, convoy, frame) {
  const own = frame.ship;
  for (const [role, mmsi] of [["ahead", convoy.ahead_mmsi], ["astern", convoy.astern_mmsi]]) {
    const v = frame.traffic.find((t) => t.id === mmsi);
    if (!v) continue;
    const d = Math.hypot(v.x - own.east, v.y - own.north), close = d < convoy.min_distance_m;
    ctx.save();
    ctx.strokeStyle = close ? MAP_COLORS.ship : MAP_COLORS.convoy; ctx.lineWidth = 2 / s; ctx.setLineDash([8 / s, 6 / s]);
    ctx.beginPath(); ctx.moveTo(own.east, own.north); ctx.lineTo(v.x, v.y); ctx.stroke();
    ctx.translate((own.east + v.x) / 2, (own.north + v.y) / 2); ctx.scale(1 / s, -1 / s);
    ctx.fillStyle = close ? MAP_COLORS.ship : MAP_COLORS.convoy; ctx.font = "12px system-ui, sans-serif";
    ctx.fillText(`${role} ${d.toFixed(0)} m`, 8, 4);
    ctx.restore();
  }
}

// a debrief's areas of laid ice ({ice, area: [[east, north], ...]}, in the order laid), each
// filled in its kind's colour (the record has the command, not the tiles it changed)
function drawLaidAreas(ctx, areas, geo) {
  for (const a of areas) {
    const k = (geo.ice_names || []).indexOf(a.ice);
    ctx.fillStyle = MAP_COLORS[(geo.ice_kinds || [])[k]] || MAP_COLORS.ice;
    ctx.beginPath();
    a.area.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.closePath(); ctx.fill();
  }
}

// the scale bar (px per m: scale) at the bottom left, in metres and nautical miles
function drawScale(ctx, h, scale) {
  const target = 120 / scale, pow = Math.pow(10, Math.floor(Math.log10(target)));
  const metres = [1, 2, 5, 10].map((k) => k * pow).filter((m) => m <= target).pop();
  const px = metres * scale, x = 14, y = h - 18;
  ctx.fillStyle = "rgba(13, 24, 33, 0.7)"; ctx.fillRect(x - 6, y - 14, px + 110, 24);
  ctx.strokeStyle = "#fff"; ctx.lineWidth = 2; ctx.beginPath();
  ctx.moveTo(x, y - 5); ctx.lineTo(x, y); ctx.lineTo(x + px, y); ctx.lineTo(x + px, y - 5); ctx.stroke();
  ctx.fillStyle = "#fff"; ctx.font = "11px system-ui, sans-serif";
  ctx.fillText(`${metres >= 1000 ? `${metres / 1000} km` : `${metres} m`}  (${(metres / 1852).toPrecision(2)} NM)`, x + px + 6, y + 1);
}

function sameArrays(a, b) {
  if (a.length !== b.length) return false;
  for (let i = 0; i < a.length; i++) if (a[i] !== b[i]) return false;
  return true;
}

// a grid step in degrees: 0.01' to 30' (decimal minutes, as on a chart), or whole degrees
function niceAngle(span) {
  const steps = [0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 30].map((m) => m / 60).concat([1, 2, 5, 10]);
  return steps.find((st) => st >= span) || 10;
}

// degrees as 74°01.25'N
function formatAngle(deg, pos, neg, width) {
  const hemi = deg < 0 ? neg : pos, a = Math.abs(deg) + 1e-9, d = Math.floor(a), m = (a - d) * 60;
  return `${String(d).padStart(width, "0")}°${m.toFixed(2).padStart(5, "0")}'${hemi}`;
}

function formatLatLon(geo, x, y) {
  const o = geo.origin;
  return `${formatAngle(o.latitude_deg + y / o.m_per_deg_lat, "N", "S", 2)} ${formatAngle(o.longitude_deg + x / o.m_per_deg_lon, "E", "W", 3)}`;
}

// polylines (world m: points xy flattened, starts of each) as one path, rings if closed, or
// null when there are none (the regions' outline rings, the ridges' lines)
function pathOf(xy, start, closed) {
  if (!xy || !xy.length) return null;
  const path = new Path2D();
  for (let r = 0; r + 1 < start.length; r++) {
    for (let i = start[r]; i < start[r + 1]; i++) {
      if (i === start[r]) path.moveTo(xy[2 * i], xy[2 * i + 1]); else path.lineTo(xy[2 * i], xy[2 * i + 1]);
    }
    if (closed) path.closePath();
  }
  return path;
}
