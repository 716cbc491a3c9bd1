// The instructor station's page: the WebSocket to the station (geometry once, then binary
// frames about ten times a second), the ship and environment panels, alarms, the event log,
// and every instructor command as a control, with the node's reply shown.
"use strict";

const $ = (id) => document.getElementById(id);
const map = new MapView($("map"));
let socket = null, nextId = 1, retry = 500, lastFrame = null;
const pending = new Map();  // command id -> name

// binary message: uint32 JSON length, JSON (padded), then 4-byte typed arrays
function unpack(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const arrays = {}, types = { f4: Float32Array, i4: Int32Array, u4: Uint32Array };
  let offset = 4 + length;
  for (const [name, kind, count] of header.arrays) {
    arrays[name] = new types[kind](buffer, offset, count);
    offset += 4 * count;
  }
  return [header, arrays];
}

function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  socket = ws;
  ws.onopen = () => { retry = 500; badge("link-page", true, "station"); };
  ws.onclose = (e) => {
    badge("link-page", false, e.code === 1008 ? "station: refused" : "station: offline");
    showWaiting(e.code === 1008 ? "the station refused this page (access token?)" : "the station is not reachable; retrying…");
    if (e.code === 1008) return;
    setTimeout(connect, retry); retry = Math.min(retry * 2, 5000);
  };
  ws.onmessage = (e) => {
    if (typeof e.data === "string") return onText(JSON.parse(e.data));
    const [header, arrays] = unpack(e.data);
    if (header.type === "geometry") {
      map.setGeometry(header, arrays); iceNames(header.ice_names); failureShips(header.fleet || []);
      if (!lastFrame) map.zoom(1);
    }
    else if (header.type === "frame") onFrame(header, arrays);
    else if (header.type === "debrief") startDebrief(header, arrays);
  };
}

function onText(msg) {
  if (msg.type === "hello") {
    $("ship-name").textContent = msg.mode === "debrief" ? `${msg.ship} · debrief` : msg.ship;
    document.title = `IceBridge instructor: ${msg.ship}${msg.mode === "debrief" ? " (debrief)" : ""}`;
    if (msg.mode === "debrief") ["link-stream", "link-control"].forEach((id) => { $(id).hidden = true; });
  }
  else if (msg.type === "waiting") showWaiting(msg.text);
  else if (msg.type === "reply") onReply(msg);
}

function showWaiting(text) { $("waiting").hidden = false; $("waiting").textContent = text; }

function badge(id, ok, text) {
  const b = $(id), cls = `badge ${ok ? "ok" : "bad"}`;
  setText(b, text);
  if (b.className !== cls) b.className = cls;
}

// the page's values change a few digits a frame: only what changed is written, as writing a
// whole table ten times a second kept the browser's layout busy
function setText(element, text) { if (element.textContent !== text) element.textContent = text; }
function setHtml(element, html) { if (element.cachedHtml !== html) { element.innerHTML = html; element.cachedHtml = html; } }

function onFrame(h, arrays) {
  const first = !lastFrame;
  $("waiting").hidden = true;
  map.applyFrame(h, arrays);
  lastFrame = h;
  const s = h.ship, e = h.environment;
  setText($("utc"), s.utc.slice(11, 19));
  setText($("sim-time"), `${h.time.toFixed(1)} s`);
  $("frozen-badge").hidden = !e.frozen;
  badge("link-stream", h.stream.age_s < 2, h.stream.age_s < 2 ? "stream" : `stream silent ${h.stream.age_s.toFixed(0)} s`);
  badge("link-control", !h.control.error, h.control.error ? `control: ${h.control.error}` : "control");
  shipPanel(h);
  envPanel(e, h.ice_offset || [0, 0]);
  alarms(h.alarms);
  failuresNow(h.failures);
  linksPanel(h.links);
  for (const ev of h.events) logRow(ev);
  if (first) fillForms(h);
  setText($("map-stats"), `${h.counts.free} live floes · ${h.counts.frozen_floes} frozen · ${h.counts.tiles_live}/${h.counts.tiles_frozen} tiles live/frozen · ${map.stats.fps.toFixed(0)} fps`);
}

function rows(table, pairs) {
  if (table.rows.length !== pairs.length) table.innerHTML = "<tr><td></td><td></td></tr>".repeat(pairs.length);
  pairs.forEach((pair, i) => pair.forEach((html, j) => setHtml(table.rows[i].cells[j], html)));
}

const fix = (v, n) => (Number.isFinite(v) ? (Math.abs(v) < 0.5 * 10 ** -n ? 0 : v).toFixed(n) : "–");
const deg = (v) => { const d = fix(((v % 360) + 360) % 360, 1); return `${d === "360.0" ? "0.0" : d}°`; };

function shipPanel(h) {
  const s = h.ship, o = map.geo ? map.geo.origin : null;
  const side = (v) => (v >= 0 ? "stbd" : "port");
  rows($("ship-values"), [
    ["Position", o ? formatLatLon(map.geo, s.east, s.north) : "–"],
    ["North / East", `${fix(s.north, 0)} m / ${fix(s.east, 0)} m`],
    ["Heading", deg(s.heading_deg)],
    ["Course / speed over ground", `${deg(s.cog_deg)} / ${fix(s.sog_kn, 1)} kn`],
    ["Speed through water", `${fix(s.stw_kn, 1)} kn`],
    ["Rate of turn", `${fix(s.rot_deg_min, 1)} °/min`],
    ["Rudder angle", `${fix(Math.abs(s.rudder_deg), 1)}° ${side(s.rudder_deg)}`],
    ["Rudder order", Number.isFinite(h.control?.rudder_order_deg)  // (a debrief has no control)
      ? `${fix(Math.abs(h.control.rudder_order_deg), 1)}° ${side(h.control.rudder_order_deg)}`
      : `<span class="muted" title="from the node's status, every few seconds">n/a</span>`],
    ["Shaft", `${fix(s.rpm, 0)} rpm`],
    ["Ice resistance", `${fix(s.ice_resistance_kn, 0)} kN`],
    ["Ice load X / Y / N", `${fix(s.ice_load_kn[0], 0)} / ${fix(s.ice_load_kn[1], 0)} kN / ${fix(s.ice_load_kn[2], 0)} kNm`],
    ["Refused orders", `${refusedCount}`],
    ["Floes live / frozen", h.counts ? `${h.counts.free} / ${h.counts.frozen_floes}` : "–"],
  ]);
}

function envPanel(e, drift) {
  const drifted = Math.hypot(drift[0], drift[1]);
  rows($("env-values"), [
    ["Visibility", e.visibility_m >= 1000 ? `${fix(e.visibility_m / 1000, 1)} km` : `${fix(e.visibility_m, 0)} m`],
    ["Wind", `${fix(e.wind_kn, 1)} kn from ${deg(e.wind_from_deg)}`],
    ["Current", `${fix(e.current_kn, 1)} kn to ${deg(e.current_to_deg)}`],
    ["Ice field", drifted >= 0.5 ? `drifted ${fix(drifted, 0)} m to ${deg(Math.atan2(drift[0], drift[1]) * 180 / Math.PI)}`
                                 : "as laid"],
    ["Physics", e.frozen ? "frozen" : "running"],
  ]);
}

function alarms(list) {
  setHtml($("alarms"), list.length ? list.map((a) => `<li>${escapeHtml(a)}</li>`).join("") : `<li class="muted">none</li>`);
}

function escapeHtml(t) { return String(t).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c])); }

let refusedCount = 0;
function logRow(ev) {
  if (ev.kind === "order") refusedCount++;
  const body = $("log").tBodies[0], tr = body.insertRow(0);
  const clock = ev.utc || new Date((ev.wall || Date.now() / 1000) * 1000).toISOString().slice(11, 19);
  tr.innerHTML = `<td>${clock}</td><td>${ev.time == null ? "" : ev.time.toFixed(1) + " s"}</td>` +
    `<td><span class="kind ${ev.kind}">${ev.kind}</span></td><td>${escapeHtml(ev.text)}</td>`;
  while (body.rows.length > 300) body.deleteRow(body.rows.length - 1);
}

// -- commands --------------------------------------------------------------------------------
function send(command) {
  const id = nextId++;
  if (!socket || socket.readyState !== WebSocket.OPEN) return showReply(command.command, false, "not connected to the station");
  pending.set(id, command.command);
  socket.send(JSON.stringify({ type: "command", id, command }));
  showReply(command.command, null, "sent…");
}

function onReply(msg) {
  const name = pending.get(msg.id) || msg.command || "command";
  pending.delete(msg.id);
  const path = msg.ok && msg.reply && msg.reply.path;  // a save point's file, written at the node's next step
  showReply(name, msg.ok, msg.ok ? (path ? `queued by the node; it writes ${path}` : "queued by the node") : msg.error);
  if (!msg.ok) logRow({ kind: "refused", text: `${name}: ${msg.error}`, time: null, utc: null, wall: Date.now() / 1000 });
  if (path) logRow({ kind: "command", text: `save point ${path}`, time: null, utc: null, wall: Date.now() / 1000 });
}

function showReply(name, ok, text) {
  const box = [...document.querySelectorAll(".reply")].find((b) => b.dataset.for.split(" ").includes(name));
  if (box) { box.textContent = `${name.replace("_", " ")}: ${text}`; box.className = `reply ${ok === null ? "" : ok ? "ok" : "err"}`; }
  if (ok === false) toast(`${name}: ${text}`, false);
}

let toastTimer = null;
function toast(text, ok) {
  const t = $("toast"); t.textContent = text; t.className = ok ? "ok" : ""; t.hidden = false;
  clearTimeout(toastTimer); toastTimer = setTimeout(() => { t.hidden = true; }, 6000);
}

const num = (id) => Number($(id).value);
function onSubmit(id, make) { $(id).addEventListener("submit", (e) => { e.preventDefault(); send(make()); }); }

function wireControls() {
  $("freeze").onclick = () => send({ command: "freeze" });
  $("resume").onclick = () => send({ command: "resume" });
  onSubmit("clock-form", () => ({ command: "clock", time_of_day: $("clock-time").value }));
  onSubmit("reposition-form", () => {
    map.ghost = null;
    return { command: "reposition", north_m: num("rp-north"), east_m: num("rp-east"), heading_deg: num("rp-heading"), speed_kn: num("rp-speed") };
  });
  onSubmit("visibility-form", () => ({ command: "visibility", visibility_m: num("visibility") }));
  onSubmit("wind-form", () => ({ command: "wind", speed_kn: num("wind-speed"), from_deg: num("wind-from") }));
  onSubmit("current-form", () => ({ command: "current", speed_kn: num("current-speed"), to_deg: num("current-to") }));
  document.querySelectorAll("[data-visibility]").forEach((b) => { b.onclick = () => { $("visibility").value = b.dataset.visibility; send({ command: "visibility", visibility_m: Number(b.dataset.visibility) }); }; });
  $("pick").onclick = () => {
    $("pick-hint").hidden = false; $("map").classList.add("picking");
    map.pick = (x, y) => {
      $("pick-hint").hidden = true;
      $("rp-east").value = x.toFixed(1); $("rp-north").value = y.toFixed(1);
      updateGhost();
    };
  };
  ["rp-north", "rp-east", "rp-heading"].forEach((id) => $(id).addEventListener("input", updateGhost));
  wireIceForm();
  window.addEventListener("keydown", (e) => { if (e.key === "Escape" && map.pick) { map.pick = null; $("pick-hint").hidden = true; $("map").classList.remove("picking"); } });
  $("zoom-in").onclick = () => map.zoom(1.5);
  $("zoom-out").onclick = () => map.zoom(1 / 1.5);
  $("fit").onclick = () => map.fitField();
  $("follow").onclick = () => map.setFollow(!map.follow);
}

// lay ice: a rectangle of the field, picked as two corners on the map or typed
function wireIceForm() {
  onSubmit("ice-form", () => {
    const e0 = num("ice-e0"), e1 = num("ice-e1"), n0 = num("ice-n0"), n1 = num("ice-n1");
    return { command: "set_ice", ice: $("ice-name").value, polygon_m: [[e0, n0], [e1, n0], [e1, n1], [e0, n1]] };
  });
  const corner = (e, n, then) => {
    $("pick-hint").hidden = false; $("map").classList.add("picking");
    map.pick = (x, y) => { $("pick-hint").hidden = true; $(e).value = x.toFixed(0); $(n).value = y.toFixed(0); if (then) then(); };
  };
  $("ice-pick").onclick = () => corner("ice-e0", "ice-n0", () => corner("ice-e1", "ice-n1"));
}

function iceNames(names) {
  const select = $("ice-name");
  if (select.options.length) return;
  for (const name of names || []) select.add(new Option(name, name));
}

function updateGhost() {
  const x = num("rp-east"), y = num("rp-north");
  map.ghost = Number.isFinite(x) && Number.isFinite(y) && $("rp-east").value !== "" ? { x, y, heading: num("rp-heading") || 0 } : null;
  if (map.ghost && map.geo) $("rp-latlon").textContent = formatLatLon(map.geo, x, y);
  map.dirty = true;
}

// the forms start from the exercise as it is
function fillForms(h) {
  const s = h.ship, e = h.environment;
  $("rp-north").value = s.north.toFixed(0); $("rp-east").value = s.east.toFixed(0);
  $("rp-heading").value = s.heading_deg.toFixed(0) % 360; $("rp-speed").value = Math.max(0, s.stw_kn).toFixed(1);
  $("visibility").value = e.visibility_m.toFixed(0);
  $("wind-speed").value = e.wind_kn.toFixed(1); $("wind-from").value = e.wind_from_deg.toFixed(0) % 360;
  $("current-speed").value = e.current_kn.toFixed(1); $("current-to").value = e.current_to_deg.toFixed(0) % 360;
  $("clock-time").value = s.utc.slice(11, 19);
  if (map.geo) $("rp-latlon").textContent = formatLatLon(map.geo, s.east, s.north);
}

wireControls();
connect();
