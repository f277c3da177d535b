// pcisim-remote page: one WebSocket (/ws?token=...) carries frames (binary) and JSON messages.
// No libraries, no network but this gateway. Protocol: docs/remote.md.
"use strict";

const $ = (id) => document.getElementById(id);
const view = {
  connected: false, role: null, id: null, frames: 0, lastSeq: -1, lastFrame: null,
  modality: null, ultrasoundFrames: 0, state: null, status: null, errors: [], acks: 0,
};
window.pcisim = view;  // for tests and the curious: what the page has seen

function tokenFromUrl() {
  const hash = new URLSearchParams(location.hash.replace(/^#/, ""));
  const query = new URLSearchParams(location.search);
  return hash.get("token") || query.get("token") || sessionStorage.getItem("pcisim-token") || "";
}

let token = tokenFromUrl();
let ws = null, everOpened = false, retryMs = 1000, nextId = 1, failures = 0;

function log(text, isError) {
  const line = document.createElement("div");
  if (isError) line.className = "err";
  line.textContent = new Date().toLocaleTimeString() + "  " + text;
  const box = $("log");
  box.prepend(line);
  while (box.childNodes.length > 6) box.removeChild(box.lastChild);
}

function showTokenRequired(message) {
  $("token-required").hidden = false;
  $("token-error").textContent = message || "";
  setConn(false, "no token");
}

function setConn(on, text) {
  view.connected = on;
  const c = $("conn");
  c.textContent = text;
  c.className = "badge " + (on ? "on" : "off");
}

function connect() {
  if (!token) return showTokenRequired("");
  sessionStorage.setItem("pcisim-token", token);
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  ws = new WebSocket(scheme + location.host + "/ws?token=" + encodeURIComponent(token));
  ws.binaryType = "arraybuffer";
  let opened = false;
  ws.onopen = () => {
    opened = everOpened = true;
    retryMs = 1000;
    failures = 0;
    $("token-required").hidden = true;
    setConn(true, "live");
  };
  ws.onmessage = (ev) => (typeof ev.data === "string" ? onText(JSON.parse(ev.data)) : onFrame(ev.data));
  ws.onclose = () => {
    ws = null;
    setControls(false);
    if (!opened && !everOpened) {
      // the upgrade was refused (401/403) or nothing answers: the browser cannot tell which
      return showTokenRequired("The gateway refused this token (or is not running).");
    }
    setConn(false, "reconnecting…");
    // a restarted gateway has new tokens: after a few refusals, ask for one (and keep trying)
    failures = opened ? 0 : failures + 1;
    if (failures >= 3) showTokenRequired("Lost the gateway: it is down, or it restarted with new tokens. Retrying…");
    setTimeout(connect, retryMs);
    retryMs = Math.min(retryMs * 2, 10000);
  };
}

function send(msg) {
  if (!ws || ws.readyState !== WebSocket.OPEN) return null;
  msg.id = nextId++;
  ws.send(JSON.stringify(msg));
  return msg.id;
}

function command(name, extra) {
  send(Object.assign({ type: "command", command: name }, extra || {}));
}

// ---- frames: draw only the newest; a frame arriving while one decodes replaces the waiting one
const canvas = $("fluoro"), ctx = canvas.getContext("2d");
let decoding = false, waiting = null, fpsCount = 0, fpsT0 = performance.now();

function onFrame(buf) {
  if (decoding) { waiting = buf; return; }
  decoding = true;
  const n = new DataView(buf).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, n)));
  const blob = new Blob([new Uint8Array(buf, 4 + n)], { type: header.mime });
  createImageBitmap(blob).then((img) => {
    if (canvas.width !== img.width || canvas.height !== img.height) { canvas.width = img.width; canvas.height = img.height; }
    ctx.drawImage(img, 0, 0);
    img.close();
    view.frames++;
    view.lastSeq = header.seq;
    view.lastFrame = header;
    fpsCount++;
    if (header.kind === "ultrasound") showUltrasound(header); else showXray(header);
  }).catch((e) => log("cannot decode a frame: " + e, true)).finally(() => {
    decoding = false;
    if (waiting) { const next = waiting; waiting = null; onFrame(next); }
  });
}

// the screen shows whichever modality the scene sends: X-ray fills it; an ultrasound image keeps
// its size in mm (its pixels need not be square), row 0 (the probe's face) at the top
function fitCanvas(aspect) {
  const side = 512;
  const w = aspect >= 1 ? side : Math.round(side * aspect), h = aspect >= 1 ? Math.round(side / aspect) : side;
  canvas.style.width = w + "px";
  canvas.style.height = h + "px";
}

function showXray(h) {
  if (view.modality !== "xray") { view.modality = "xray"; fitCanvas(1); }
  $("angles").textContent = angleText(h.primary_deg, h.secondary_deg);
  $("frame-info").textContent = "frame " + h.seq + "  t=" + h.sim_time_s.toFixed(2) + " s" + (h.cine ? "  CINE run " + h.cine_run : "");
}

function showUltrasound(h) {
  view.ultrasoundFrames++;
  if (view.modality !== "ultrasound") {
    view.modality = "ultrasound";
    const beam = $("beam");
    beam.textContent = "US";
    beam.className = "beam us";
  }
  fitCanvas(h.image_mm[0] / h.image_mm[1]);
  const f = h.probe_force_n, force = Math.hypot(f[0], f[1], f[2]);
  $("angles").textContent = (h.geometry === "linear" ? "linear " + h.width_mm.toFixed(0) + " mm"
    : "curvilinear " + h.fan_angle_deg.toFixed(0) + "°, Rc " + h.radius_of_curvature_mm.toFixed(0) + " mm") + ", depth " + h.depth_mm.toFixed(0) + " mm";
  $("frame-info").textContent = "US frame " + h.seq + "  t=" + h.sim_time_s.toFixed(2) + " s  " + h.frequency_mhz.toFixed(1) + " MHz  gain " +
    h.gain_db.toFixed(0) + " dB  force " + force.toFixed(2) + " N";
}

setInterval(() => {
  const now = performance.now();
  $("fps").textContent = (fpsCount * 1000 / (now - fpsT0)).toFixed(1) + " fps";
  fpsCount = 0; fpsT0 = now;
}, 1000);

function angleText(p, s) {
  if (p === null || p === undefined) return "—";
  const a = (p >= 0 ? "LAO " : "RAO ") + Math.abs(p).toFixed(0);
  const b = (s >= 0 ? "CRA " : "CAU ") + Math.abs(s).toFixed(0);
  return a + "  " + b;
}

// ---- messages
function onText(m) {
  if (m.type === "hello") {
    view.role = m.role; view.id = m.id;
    $("role").textContent = m.role;
    setControls(m.role === "controller");
    log("connected as " + m.role);
  } else if (m.type === "state") {
    view.state = m; showState(m);
  } else if (m.type === "status") {
    view.status = m; showStatus(m);
  } else if (m.type === "ack") {
    view.acks++;
  } else if (m.type === "error") {
    view.errors.push(m);
    log(m.code + ": " + m.message, true);
    if (m.code === "instrument_busy") $("kbd-enable").checked = false;
  }
}

function mmss(s) {
  const m = Math.floor(s / 60), r = Math.floor(s % 60);
  return m + ":" + String(r).padStart(2, "0");
}

function classify(el, good, warn) {
  el.className = "v " + (good ? "good" : warn ? "warn" : "bad");
}

function showState(m) {
  const f = m.fluoro;
  $("fluoro-time").textContent = mmss(f.time_s) + " (" + f.time_s.toFixed(1) + " s)";
  $("contrast-used").textContent = m.contrast.used_ml.toFixed(1) + " ml";
  $("injections").textContent = m.contrast.injections;
  const beam = $("beam");
  if (view.modality !== "ultrasound") {  // the ultrasound scene has no X-ray beam to show
    beam.textContent = f.cine ? "CINE" : f.on ? "FLUORO" : "LIH";
    beam.className = "beam" + (f.cine ? " cine" : f.on ? " on" : "");
  }
  $("pedal").classList.toggle("active", f.pedal_console);
  $("cine").classList.toggle("active", f.cine_console);
  if (m.carm.primary_deg !== null && !view.lastFrame) $("angles").textContent = angleText(m.carm.primary_deg, m.carm.secondary_deg);
  const w = m.wire;
  if (w) {
    $("tip-branch").textContent = w.tip_branch || "—";
    $("insertion").textContent = w.insertion_mm.toFixed(1) + " mm";
    $("rotation").textContent = (w.rotation_rad * 180 / Math.PI).toFixed(0) + "°";
    $("heart").textContent = w.heart_phase.toFixed(2);
    $("contacts").textContent = w.contacts + " / " + w.nodes;
    $("simtime").textContent = w.sim_time_s.toFixed(1) + " s";
  }
  const server = $("server");
  server.textContent = m.server_alive ? (m.paused ? "server paused" : "server running") : "server silent";
  server.className = "badge " + (m.server_alive && !m.paused ? "on" : "off");
  const k = m.keyboard;
  const mine = k && k.owner !== 0 && k.owner === view.id;
  if (k && !mine && $("kbd-enable").checked && k.stopped_because) {
    $("kbd-enable").checked = false;
    log("keyboard instrument stopped: " + k.stopped_because, true);
  }
  $("kbd-state").textContent = !k ? "unavailable" : m.other_instrument ? "hardware active (device " + m.other_instrument.device_id + ")"
    : mine ? "driving: " + k.insertion_mm.toFixed(1) + " mm, " + (k.rotation_rad * 180 / Math.PI).toFixed(0) + "°"
    : k.owner ? "driven by another page" : "off";
}

function showStatus(s) {
  const h = s.haptic, p = s.physics;
  const rate = $("haptic-rate");
  rate.textContent = h.rate_hz.toFixed(1) + " Hz";
  classify(rate, h.rate_hz >= 990, h.rate_hz >= 950);
  const jit = $("haptic-jitter");
  jit.textContent = h.jitter_us_p99.toFixed(0) + " µs";
  classify(jit, h.jitter_us_p99 <= 100, h.jitter_us_p99 <= 500);
  $("haptic-overruns").textContent = h.overruns;
  $("physics-rate").textContent = p.rate_hz.toFixed(1) + " Hz";
  $("physics-step").textContent = p.step_ms_p99.toFixed(1) + " ms";
  $("xray-fps").textContent = s.xray.fps.toFixed(1);
  showDebrief(s.debrief);
}

// the server's debrief figures so far (session_metrics_t; docs/debrief.md); "—" where the session
// cannot give one (no target branch, a wire that computes no wall force)
function showDebrief(d) {
  if (!d) return;
  const fixed = (v, n, unit) => (v === null || v === undefined ? "—" : v.toFixed(n) + unit);
  $("db-procedure").textContent = fixed(d.procedure_time_s, 0, " s");
  $("db-beam").textContent = fixed(d.fluoro_time_s, 1, " s");
  $("db-cine").textContent = d.cine_runs;
  $("db-kerma").textContent = fixed(d.air_kerma_mgy, 2, " mGy");
  $("db-dap").textContent = fixed(d.dap_gycm2, 3, " Gy·cm²");
  $("db-path").textContent = fixed(d.tip_path_in_vessels_mm, 0, " mm");
  $("db-wrong").textContent = d.wrong_branch_s === null ? "—" : d.wrong_branch_s.toFixed(1) + " s of " + d.target_branch;
  $("db-force").textContent = fixed(d.peak_tip_force_n, 3, " N");
}

// ---- controls
const controls = ["pedal", "cine", "contrast", "carm-apply", "pause", "resume", "reset", "kbd-enable", "debrief-write"];
function setControls(on) {
  for (const id of controls) $(id).disabled = !on;
  for (const b of document.querySelectorAll(".preset")) b.disabled = !on;
}
setControls(false);

$("pedal").onclick = () => command("fluoro", { down: !(view.state && view.state.fluoro.pedal_console) });
$("cine").onclick = () => command("cine", { down: !(view.state && view.state.fluoro.cine_console) });
$("contrast").onclick = () => command("contrast");
$("pause").onclick = () => command("pause");
// the server writes its debrief page at the end of the session, or now when asked; the gateway
// serves it (to a page holding a token) where it was told the server writes it
$("debrief-write").onclick = () => command("debrief");
$("debrief-link").onclick = (e) => {
  e.preventDefault();
  window.open("/debrief.html?token=" + encodeURIComponent(token) + "&t=" + Date.now(), "_blank", "noopener");
};
$("resume").onclick = () => command("resume");
$("reset").onclick = () => { if (confirm("Reset the session's wire and world?")) command("reset"); };
for (const id of ["primary", "secondary"]) {
  $(id).oninput = () => { $(id + "-out").textContent = $(id).value + "°"; };
}
function moveCarm(p, s) {
  $("primary").value = p; $("secondary").value = s;
  $("primary-out").textContent = p + "°"; $("secondary-out").textContent = s + "°";
  command("carm", { primary_deg: Number(p), secondary_deg: Number(s) });
}
$("carm-apply").onclick = () => moveCarm($("primary").value, $("secondary").value);
for (const b of document.querySelectorAll(".preset")) b.onclick = () => moveCarm(b.dataset.p, b.dataset.s);

// ---- keyboard instrument: held keys become speeds; resent while held so the gateway's
// dead-man timeout only fires when the page is gone
const held = new Set();
$("kbd-enable").onchange = () => {
  held.clear();
  send({ type: "keyboard", enable: $("kbd-enable").checked });
};
function keySpeeds() {
  const f = held.has("Shift") ? 0.25 : 1;
  return {
    insert: ((held.has("ArrowUp") ? 1 : 0) - (held.has("ArrowDown") ? 1 : 0)) * f,
    rotate: ((held.has("ArrowRight") ? 1 : 0) - (held.has("ArrowLeft") ? 1 : 0)) * f,
  };
}
function sendKeys() {
  if ($("kbd-enable").checked) send(Object.assign({ type: "keys" }, keySpeeds()));
}
const arrows = ["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight", "Shift"];
document.addEventListener("keydown", (e) => {
  if (!$("kbd-enable").checked || !arrows.includes(e.key) || e.target.tagName === "INPUT" && e.target.type !== "checkbox") return;
  e.preventDefault();
  if (!held.has(e.key)) { held.add(e.key); sendKeys(); }
});
document.addEventListener("keyup", (e) => {
  if (held.delete(e.key)) sendKeys();
});
window.addEventListener("blur", () => { held.clear(); sendKeys(); });
setInterval(() => { if (held.size) sendKeys(); }, 150);

$("token-form").onsubmit = (e) => {
  e.preventDefault();
  token = $("token-input").value.trim();
  everOpened = false;
  connect();
};

connect();
