// The instructor station's links and failures: the Links card (each link's state, counts,
// errors by kind, fault and last error, from the node's status replies), the failures now,
// and the controls for sensor failures, link faults and save points.
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

function failuresNow(f) {
  const sensors = Object.entries(f.sensors || {}).map(([k, mode]) => `${SENSOR_SHOWN[k] || k} ${mode}`).join(", ");
  const text = `now: steering ${PUMPS_SHOWN[f.pumps_failed]}, engine ${f.power_percent} % power` + (sensors ? `; ${sensors}` : "");
  setText($("failures-now"), text);
}

function sensorCommand(form) {
  const mode = form.querySelector("select").value, command = { command: "sensor_failure", sensor: form.dataset.sensor, mode };
  for (const input of form.querySelectorAll("input[data-for-mode]")) {
    if (input.dataset.forMode === mode) command[input.dataset.key] = Number(input.value);
  }
  return command;
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
