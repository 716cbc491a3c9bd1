// The instructor station's links and failures: the Links card (each link's state, counts,
// errors by kind, fault and last error, from the node's status replies), the failures now,
// and the controls for steering, engine and sensor failures (to the own ship chosen), link
// faults and save points.
"use strict";

const PROBABLE_FAULTS = ["drop", "corrupt", "duplicate", "delay"];  // the link faults with a probability
const SENSOR_SHOWN = { gyro: "gyro", gnss: "GNSS", log: "speed log" };
const PUMPS_SHOWN = ["both pumps working", "one pump failed", "both pumps failed"];

function linkRows(l) {
  const state = l.connected ? "up" : l.opening ? "opening" : "down";
  const errors = Object.entries(l.errors || {}).map(([kind, n]) => `${kind} ${n}`).join(", ");
  const detail = [l.fault && l.fault !== "none" ? `fault: ${l.fault}` : "", errors ? `errors: ${errors}` : "",
    l.last_error ? `last error: ${l.last_error}` : ""].filter(Boolean).join(" · ");
  const count = (v) => (Number.isFinite(v) ? v : "–");
  return `<tr data-link="${escapeHtml(l.name)}"><td>${escapeHtml(l.name)}</td><td><span class="state ${state}">${state}</span></td>` +
    `<td>${count(l.inputs)}</td><td>${count(l.outputs)}</td><td>${count(l.reconnects)}</td></tr>` +
    (detail ? `<tr class="detail"><td colspan="5">${escapeHtml(detail)}</td></tr>` : "");
}

// links: the node's links' health (null: no status reply yet)
function linksPanel(links) {
  const html = links && links.length ? links.map(linkRows).join("")
    : `<tr><td colspan="5" class="muted">${links ? "the node reports no links" : "no status from the node yet"}</td></tr>`;
  setHtml($("links").tBodies[0], html);
  const select = $("lf-link"), names = (links || []).map((l) => l.name);
  if (names.join("\n") !== [...select.options].map((o) => o.value).join("\n")) {
    const chosen = select.value;
    select.replaceChildren(...names.map((n) => new Option(n, n, false, n === chosen)));
  }
}

// the own ships the failures go to (the geometry's fleet, the first ship first): a choice
// only where the exercise has several
function failureShips(names) {
  const select = $("failure-ship"), chosen = select.value;
  select.replaceChildren(...names.map((n, k) => new Option(k ? `${n} (ship ${k})` : n, String(k), false, String(k) === chosen)));
  $("failure-ship-row").hidden = names.length < 2;
}

const forShip = (command) => ({ ...command, ship: Number($("failure-ship").value || 0) });

// failures: each own ship's, the first ship's first; the chosen ship's are shown
function failuresNow(failures) {
  const f = failures[Number($("failure-ship").value || 0)] || failures[0];
  const sensors = Object.entries(f.sensors || {}).map(([k, mode]) => `${SENSOR_SHOWN[k] || k} ${mode}`).join(", ");
  const text = `now: steering ${PUMPS_SHOWN[f.pumps_failed]}, engine ${f.power_percent} % power` + (sensors ? `; ${sensors}` : "");
  setText($("failures-now"), text);
}

function sensorCommand(form) {
  const mode = form.querySelector("select").value, command = { command: "sensor_failure", sensor: form.dataset.sensor, mode };
  for (const input of form.querySelectorAll("input[data-for-mode]")) {
    if (input.dataset.forMode === mode) command[input.dataset.key] = Number(input.value);
  }
  return forShip(command);
}

function linkFaultCommand() {
  const fault = $("lf-fault").value, command = { command: "link_fault", link: $("lf-link").value, fault };
  if (PROBABLE_FAULTS.includes(fault)) command.probability = num("lf-probability");
  if (fault === "delay") command.delay_s = num("lf-delay");
  return command;
}

// the inputs a select's choice does not use are disabled (not sent, not checked by the browser)
function enableFor(select, inputs, uses) {
  const update = () => inputs.forEach((input) => { input.disabled = !uses(select.value, input); });
  select.addEventListener("change", update);
  update();
}

function wireFailureControls() {
  onSubmit("steering-form", () => forShip({ command: "steering_failure", pumps_failed: Number($("steering").value) }));
  onSubmit("engine-form", () => forShip({ command: "engine_failure", power_percent: num("engine-power") }));
  document.querySelectorAll("[data-power]").forEach((b) => {
    b.onclick = () => { $("engine-power").value = b.dataset.power; send(forShip({ command: "engine_failure", power_percent: Number(b.dataset.power) })); };
  });
  for (const form of document.querySelectorAll("form[data-sensor]")) {
    enableFor(form.querySelector("select"), [...form.querySelectorAll("input[data-for-mode]")],
      (mode, input) => input.dataset.forMode === mode);
    onSubmit(form.id, () => sensorCommand(form));
  }
  enableFor($("lf-fault"), [$("lf-probability"), $("lf-delay")],
    (fault, input) => (input.id === "lf-delay" ? fault === "delay" : PROBABLE_FAULTS.includes(fault)));
  onSubmit("link-fault-form", linkFaultCommand);
  onSubmit("save-form", () => ({ command: "save", name: $("save-name").value }));
}

wireFailureControls();
