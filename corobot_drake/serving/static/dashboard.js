// The dashboard: drive pad (drag or keys), stop/enable, IR gauges, pose, encoders, contact
// telemetry (wheel loads, slip, tip margin), every sensor's reading, camera.
// State arrives by Server-Sent Events from /robots/<name>/subscribe; commands are POSTs to
// the drive contract; every request carries the server's token (token.js). No framework, no
// build step.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { robot: null, services: [], events: null, enabled: true, pad: [0, 0],
                keys: new Set(), lastSent: "", sendTimer: null, cameraTimer: null,
                frames: 0 };
window.dashboard = state;  // for tests and the curious

async function api(path, body) {
  const init = body === undefined ? {} : {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) };
  const response = await fetch(path, authorized(init));
  const data = await response.json().catch(() => ({}));
  if (!response.ok) throw new Error(data.detail || response.statusText);
  return data;
}

function fmt(x, digits = 3) { return x === null || x === undefined ? "-" : Number(x).toFixed(digits); }

// --- commands -----------------------------------------------------------------------------
function base() { return `/robots/${encodeURIComponent(state.robot)}`; }

async function send(command, body) {
  try {
    const result = await api(`${base()}/drive/${command}`, body || {});
    $("sent").textContent = `${command} ${body ? JSON.stringify(body) : ""}`;
    return result;
  } catch (e) {
    $("sent").textContent = `${command} failed: ${e.message}`;
  }
}

function powers() {
  // Pad (or keys): forward in [-1, 1], turn in [-1, 1] (positive = right); arcade mix.
  let [turn, forward] = state.pad;
  if (state.keys.size) {
    forward = (state.keys.has("up") ? 1 : 0) - (state.keys.has("down") ? 1 : 0);
    turn = (state.keys.has("right") ? 1 : 0) - (state.keys.has("left") ? 1 : 0);
    if (forward === 0) turn *= 0.6;
  }
  const max = Number($("max-power").value);
  const clamp = (v) => Math.max(-1, Math.min(1, v));
  return [clamp(forward + turn * 0.5) * max, clamp(forward - turn * 0.5) * max];
}

function drive() {
  const [left, right] = powers().map((p) => Math.round(p * 100) / 100);
  const key = `${left},${right}`;
  if (key === state.lastSent) return;
  state.lastSent = key;
  if (left === 0 && right === 0) send("all_stop");
  else send("set_power", { left, right });
}

function startDriving() {
  if (!state.sendTimer) state.sendTimer = setInterval(drive, 100);
  drive();
}

function stopDriving() {
  clearInterval(state.sendTimer);
  state.sendTimer = null;
  state.pad = [0, 0];
  state.lastSent = "";
  placeKnob(0, 0);
  send("all_stop");
}

// --- the pad --------------------------------------------------------------------------------
const pad = $("pad");
function placeKnob(x, y) {
  const knob = pad.querySelector(".knob");
  knob.style.left = `${92 + x * 92}px`;
  knob.style.top = `${92 - y * 92}px`;
}

function padPoint(event) {
  const r = pad.getBoundingClientRect();
  let x = (event.clientX - r.left - r.width / 2) / (r.width / 2);
  let y = -(event.clientY - r.top - r.height / 2) / (r.height / 2);
  const n = Math.hypot(x, y);
  if (n > 1) { x /= n; y /= n; }
  return [x, y];
}

pad.addEventListener("pointerdown", (e) => {
  pad.setPointerCapture(e.pointerId);
  state.pad = padPoint(e);
  placeKnob(...state.pad);
  startDriving();
});
pad.addEventListener("pointermove", (e) => {
  if (!state.sendTimer || !pad.hasPointerCapture(e.pointerId)) return;
  state.pad = padPoint(e);
  placeKnob(...state.pad);
});
const release = () => { if (state.sendTimer && !state.keys.size) stopDriving(); };
pad.addEventListener("pointerup", release);
pad.addEventListener("pointercancel", release);

const KEYS = { ArrowUp: "up", KeyW: "up", ArrowDown: "down", KeyS: "down", ArrowLeft: "left",
               KeyA: "left", ArrowRight: "right", KeyD: "right" };
document.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT" && e.target.type === "number") return;
  if (KEYS[e.code]) {
    e.preventDefault();
    if (!state.keys.has(KEYS[e.code])) { state.keys.add(KEYS[e.code]); startDriving(); }
  } else if (e.code === "Space") {
    e.preventDefault();
    state.keys.clear();
    stopDriving();
  } else if (e.code === "KeyE" && !e.repeat) {
    toggleEnable();
  }
});
document.addEventListener("keyup", (e) => {
  if (!KEYS[e.code]) return;
  state.keys.delete(KEYS[e.code]);
  if (!state.keys.size) stopDriving();
});
// A key held while the page loses focus never sends its keyup here: stop instead.
window.addEventListener("blur", () => {
  if (!state.keys.size) return;
  state.keys.clear();
  stopDriving();
});

$("stop").addEventListener("click", () => { state.keys.clear(); stopDriving(); });
function toggleEnable() { send("enable", { enabled: !state.enabled }); }
$("enable").addEventListener("click", toggleEnable);
$("max-power").addEventListener("input", () => {
  $("max-power-value").textContent = $("max-power").value;
});
$("drive-distance").addEventListener("click", () =>
  send("drive_distance", { distance: Number($("dd-distance").value), power: 0.3, wait: false }));
$("rotate-degrees").addEventListener("click", () =>
  send("rotate_degrees", { degrees: Number($("rd-degrees").value), power: 0.3, wait: false }));

// --- state ----------------------------------------------------------------------------------
function showDrive(d) {
  $("sim-time").textContent = fmt(d.time_stamp, 2);
  $("pos-x").textContent = fmt(d.position.x);
  $("pos-y").textContent = fmt(d.position.y);
  $("heading").textContent = fmt(d.heading_deg, 1);
  $("speed").textContent = fmt(d.velocity.forward, 3);
  const left = sideWheel(d, "left"), right = sideWheel(d, "right");
  $("enc-fl").textContent = left.encoder_ticks;
  $("enc-fr").textContent = right.encoder_ticks;
  $("axle-l").textContent = fmt(left.axle_speed, 2);
  $("axle-r").textContent = fmt(right.axle_speed, 2);
  $("power-l").textContent = fmt(left.commanded_power, 2);
  $("power-r").textContent = fmt(right.commanded_power, 2);
  state.enabled = d.is_enabled;
  const en = $("enabled");
  en.textContent = d.is_enabled ? "enabled" : "disabled";
  en.className = `enabled-${d.is_enabled}`;
  $("enable").textContent = d.is_enabled ? "Disable (E)" : "Enable (E)";
  // SVG rotation is clockwise; heading is counter-clockwise from +x (drawn pointing up).
  $("compass-needle").setAttribute("transform", `rotate(${-d.heading_deg})`);
  const c = d.command;
  $("command").textContent = c ? `#${c.seq} ${c.command} ${c.status}${c.reason ? ` (${c.reason})` : ""}` : "-";
  showContact(d);
}

// A side's wheel with an encoder (the first of the side: the Corobot's front wheel).
function sideWheel(d, side) {
  const wheels = Object.values(d.wheels).filter((w) => w.side === side);
  return wheels.find((w) => w.encoder_ticks !== null && w.encoder_ticks !== undefined) || wheels[0];
}

// The wheels' short names, as the run log's columns have them (signals.wheel_short): each
// name's words' initials (fl, fr, rl, rr), or the names when two are alike.
function wheelShort(names) {
  const short = names.map((n) => n.split("_").map((w) => w[0]).join(""));
  return new Set(short).size === short.length ? short : names;
}

// Per wheel, the robot's own (a row each): load (N), slip ratio (+ traction), slip angle
// (deg, + left); the tip margin.
function showContact(d) {
  const table = $("contact");
  const names = Object.keys(d.wheels), short = wheelShort(names);
  if (table.dataset.wheels !== names.join(",")) {
    while (table.rows.length > 1) table.deleteRow(1);
    names.forEach((name, k) => {
      const row = table.insertRow();
      row.title = name;
      row.insertCell().outerHTML = `<th>${short[k].toUpperCase()}</th>`;
      for (const field of ["load", "slip", "angle"]) row.insertCell().id = `${field}-${short[k]}`;
    });
    table.dataset.wheels = names.join(",");
  }
  names.forEach((name, k) => {
    const w = d.wheels[name];
    $(`load-${short[k]}`).textContent = fmt(w.load, 2);
    $(`slip-${short[k]}`).textContent = fmt(w.slip_ratio, 3);
    $(`angle-${short[k]}`).textContent = fmt(w.slip_angle_deg, 1);
  });
  $("tip-margin").textContent = fmt(d.tip_margin_deg, 1);
}

// The IR panel as the page starts: no gauges; each robot shown adds its own.
function clearIr() {
  const none = document.createElement("span");
  Object.assign(none, { id: "ir-none", className: "muted", textContent: "no IR sensors" });
  $("ir-gauges").replaceChildren(none);
}

function showIr(name, s) {
  let gauge = $(`ir-${name}`);
  if (!gauge) {
    const box = $("ir-gauges");
    const placeholder = $("ir-none");
    if (placeholder) placeholder.remove();
    box.insertAdjacentHTML("beforeend",
      `<div>${name}: <b id="ir-${name}-raw">-</b> m <span class="muted">(<span id="ir-${name}-norm">-</span>)</span>` +
      `<div class="gauge" id="ir-${name}"><div></div></div></div>`);
    gauge = $(`ir-${name}`);
  }
  $(`ir-${name}-raw`).textContent = fmt(s.raw);
  $(`ir-${name}-norm`).textContent = fmt(s.normalized, 2);
  gauge.firstElementChild.style.width = `${Math.max(0, Math.min(1, s.normalized)) * 100}%`;
}

// Every sensor's latest reading, by kind and name (/robots/<robot>/sensors), whatever its
// kind: numbers rounded, a long list summarized.
function showValue(v) {
  if (v === null || v === undefined) return "-";
  if (typeof v === "number") return Number.isInteger(v) ? String(v) : fmt(v, 3);
  if (Array.isArray(v)) {
    if (v.length > 4) {
      const xs = v.filter((x) => typeof x === "number");
      const range = xs.length ? ` ${fmt(Math.min(...xs))}..${fmt(Math.max(...xs))}` : "";
      return `[${v.length} values${range}]`;
    }
    return `[${v.map(showValue).join(", ")}]`;
  }
  if (typeof v === "object") return `{${Object.entries(v).map(([k, x]) => `${k}: ${showValue(x)}`).join(", ")}}`;
  return String(v);
}

function showSensors(sensors) {
  const table = $("sensors");
  while (table.rows.length > 1) table.deleteRow(1);
  for (const [kind, named] of Object.entries(sensors)) {
    for (const [name, reading] of Object.entries(named)) {
      const row = table.insertRow();
      row.dataset.sensor = `${kind}/${name}`;
      row.insertCell().textContent = kind;
      row.insertCell().textContent = name;
      row.insertCell().textContent = Object.entries(reading)
        .map(([k, x]) => `${k} ${showValue(x)}`).join(", ");
    }
  }
  $("sensors-none").hidden = table.rows.length > 1;
}

async function refreshSensors() {
  if (!state.robot) return;
  try { showSensors(await api(`${base()}/sensors`)); } catch (e) { /* try again */ }
}

// Server-Sent Events read with fetch (EventSource cannot send the token's header); like
// EventSource, it reconnects a second after the stream ends or fails.
async function subscribe() {
  if (state.events) state.events.abort();
  const names = state.services.filter((s) => s.subscribe_url).map((s) => s.name);
  const handlers = { drive: showDrive };
  for (const name of names.filter((n) => n.endsWith("_ir"))) handlers[name] = (d) => showIr(name, d);
  const events = new AbortController();
  state.events = events;
  // A robot at rest sends no changes; the heartbeat keeps the shown time moving.
  const url = `${base()}/subscribe?services=${names.join(",")}&heartbeat=1`;
  while (!events.signal.aborted) {
    try {
      const response = await fetch(url, authorized({ signal: events.signal }));
      const reader = response.body.pipeThrough(new TextDecoderStream()).getReader();
      let buffer = "";
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buffer += value;
        let end;
        while ((end = buffer.indexOf("\n\n")) >= 0) {
          let event = "message", data = "";
          for (const line of buffer.slice(0, end).split("\n")) {
            if (line.startsWith("event: ")) event = line.slice(7);
            else if (line.startsWith("data: ")) data += line.slice(6);
          }
          buffer = buffer.slice(end + 2);
          if (data && handlers[event]) handlers[event](JSON.parse(data));
        }
      }
    } catch (e) { if (events.signal.aborted) return; }
    await new Promise((resolve) => setTimeout(resolve, 1000));
  }
}

// --- camera: fetch each frame (so we see its time stamp), then wait, then the next ----------
async function nextFrame() {
  try {
    const response = await fetch(`${base()}/camera/frame.jpg?t=${Date.now()}`,
                                 authorized({ cache: "no-store" }));
    if (response.ok) {
      const url = URL.createObjectURL(await response.blob());
      const img = $("camera");
      const old = img.src;
      img.src = url;
      if (old.startsWith("blob:")) URL.revokeObjectURL(old);
      state.frames += 1;
      img.dataset.frames = state.frames;
      img.dataset.frameTime = response.headers.get("X-Frame-Time");
      $("camera-info").textContent = `frame at t = ${img.dataset.frameTime} s (${state.frames} shown)`;
    }
  } catch (e) { /* the server may be restarting; try again */ }
  state.cameraTimer = setTimeout(nextFrame, 200);
}

async function refreshStats() {
  try {
    const s = await api("/simulation");
    await showRobots(s.robots);
    $("rtf").textContent = s.recent_realtime_factor === null ? "-" : fmt(s.recent_realtime_factor, 2);
    if (s.meshcat_url) {
      $("meshcat-link").href = s.meshcat_url;
      $("meshcat-link").hidden = false;
      $("meshcat-none").hidden = true;
    }
  } catch (e) { /* ignore */ }
}

async function selectRobot(name) {
  state.robot = name;
  // The previous robot's stream stops first: an IR reading of it must not add its gauge back.
  if (state.events) state.events.abort();
  const info = await api(base());
  state.services = info.services;
  showDrive(info.state.drive);
  clearIr();
  for (const [n, s] of Object.entries(info.state.ir)) showIr(n, s);
  showSensors(info.state.sensors);
  $("completing").hidden = !(info.capabilities.drive_distance && info.capabilities.rotate_degrees);
  const hasCamera = state.services.some((s) => s.name === "camera");
  $("webcam-link").href = hasCamera ? withToken(`${base()}/camera/page`) : "#";
  $("webcam-link").hidden = !hasCamera;  // nothing offered for a part the robot lacks
  $("camera-panel").hidden = !hasCamera;
  clearTimeout(state.cameraTimer);
  if (hasCamera) nextFrame();
  subscribe();
}

// The robot list follows the server's (a robot spawned or deleted while it serves, over
// ROS 2, comes or goes at the next poll of /simulation); the robot shown stays while it is
// there, else the first is shown.
async function showRobots(robots) {
  const select = $("robot");
  if ([...select.options].map((o) => o.value).join("\n") === robots.join("\n")) return;
  select.replaceChildren(...robots.map((r) => new Option(r, r)));
  if (robots.includes(state.robot)) select.value = state.robot;
  else if (robots.length) await selectRobot(robots[0]);
}

async function main() {
  const { robots } = await api("/robots");
  $("robot").addEventListener("change", () => selectRobot($("robot").value));
  await showRobots(robots);
  refreshStats();
  setInterval(refreshStats, 2000);
  setInterval(refreshSensors, 500);
  document.body.dataset.ready = "1";
}

main();
