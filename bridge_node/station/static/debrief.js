// The debrief of a session record on the same map: the ship played back from what the node
// sent the instruments (play, pause, seek, 1-1000x), the other own ships of a record of
// several beside it, the commands and alarms in the event log as the time passes them, and
// the record's time plots (exported as PNG).
"use strict";

const playback = { data: null, t: 0, playing: false, last: 0, shownEvents: -1 };

// the value of a series at time t (linear between samples; angles the short way round)
function sample(ts, vs, t, angle) {
  if (!ts || !ts.length) return NaN;
  if (t <= ts[0]) return vs[0];
  if (t >= ts[ts.length - 1]) return vs[vs.length - 1];
  let lo = 0, hi = ts.length - 1;
  while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
  const f = (t - ts[lo]) / (ts[hi] - ts[lo] || 1);
  let d = vs[hi] - vs[lo];
  if (angle) d = ((d + 540) % 360) - 180;
  return vs[lo] + f * d;
}

function startDebrief(header, arrays) {
  playback.data = { ...header, a: arrays };
  document.body.classList.add("debrief");
  $("debrief-card").hidden = false;
  $("waiting").hidden = true;
  $("debrief-name").textContent = `${header.record} · ${header.duration.toFixed(0)} s`;
  $("plots").src = "/plots.png";
  const a = arrays;
  map.plan = Array.from({ length: a.pos_t.length }, (_, i) => [a.pos_east[i], a.pos_north[i]]);
  $("play").onclick = () => {
    playback.playing = !playback.playing;
    if (playback.playing && playback.t >= header.duration) seekTo(0);
    $("play").textContent = playback.playing ? "Pause" : "Play";
    playback.last = performance.now();
  };
  $("seek").oninput = () => seekTo($("seek").value / 1000 * header.duration);
  seekTo(0);
  requestAnimationFrame(tick);
}

function tick(now) {
  const d = playback.data;
  if (playback.playing) {
    const t = playback.t + (now - playback.last) / 1000 * Number($("speed").value);
    seekTo(Math.min(t, d.duration), true);
    if (t >= d.duration) { playback.playing = false; $("play").textContent = "Play"; }
  }
  playback.last = now;
  requestAnimationFrame(tick);
}

// the record's other own ships at time t, as the map draws traffic (named and sized as the
// exercise's config gives them; a size of 0 is drawn at the map's default)
function otherShips(d, t) {
  const a = d.a;
  return (d.ships || []).map(({ k, name, length, beam }) => {
    const heading = sample(a[`ship${k}_heading_t`], a[`ship${k}_heading`], t, true);
    return {
      id: name, x: sample(a[`ship${k}_t`], a[`ship${k}_east`], t), y: sample(a[`ship${k}_t`], a[`ship${k}_north`], t),
      heading: Number.isFinite(heading) ? heading * Math.PI / 180 : 0, speed_kn: sample(a[`ship${k}_t`], a[`ship${k}_sog`], t),
      length, beam,
    };
  });
}

function seekTo(t, playing) {
  const d = playback.data, a = d.a;
  playback.t = t;
  if (!playing) $("seek").value = Math.round(t / (d.duration || 1) * 1000);
  else $("seek").value = Math.round(t / (d.duration || 1) * 1000);
  const east = sample(a.pos_t, a.pos_east, t), north = sample(a.pos_t, a.pos_north, t);
  const heading = sample(a.heading_t, a.heading, t, true);
  const o = map.geo.origin, utc = new Date((d.start_unix + t) * 1000).toISOString();
  const ship = {
    east, north, heading: heading * Math.PI / 180, heading_deg: heading, cog_deg: heading,
    sog_kn: sample(a.sog_t, a.sog, t), stw_kn: NaN, rot_deg_min: NaN, rudder_deg: sample(a.rudder_t, a.rudder, t),
    rpm: sample(a.rpm_t, a.rpm, t), ice_resistance_kn: sample(a.ice_t, a.ice, t), ice_load_kn: [NaN, NaN, NaN],
    latitude_deg: o.latitude_deg + north / o.m_per_deg_lat, longitude_deg: o.longitude_deg + east / o.m_per_deg_lon,
    searchlights: [], utc,
  };
  const travelled = [];
  for (let i = 0; i < a.pos_t.length && a.pos_t[i] <= t; i++) travelled.push([a.pos_east[i], a.pos_north[i]]);
  map.showDebrief(ship, travelled, otherShips(d, t));
  shipPanel({ ship });
  $("utc").textContent = utc.slice(11, 19);
  $("sim-time").textContent = `${t.toFixed(1)} s`;
  $("debrief-time").textContent = `${t.toFixed(1)} s of ${d.duration.toFixed(1)} s`;
  const shown = d.events.filter((e) => e.t <= t).length;
  map.laidAreas = d.events.slice(0, shown).filter((e) => e.area);
  if (shown !== playback.shownEvents) {
    playback.shownEvents = shown;
    $("log").tBodies[0].innerHTML = "";
    refusedCount = 0;
    for (const e of d.events.slice(0, shown)) logRow({ ...e, time: e.t, utc: new Date((d.start_unix + e.t) * 1000).toISOString().slice(11, 19) });
  }
}
