// pmg VR teleoperation page: streams the headset and controller poses to pmg_vr_bridge over a
// secure WebSocket (protocol: include/pmg/teleop/vr_protocol.hpp, docs/teleop.md).
//
//  - WebXR: "Enter VR" (immersive-vr) or "Enter AR" (immersive-ar, passthrough) with the
//    local-floor reference space; every XR frame sends the viewer pose and the two controllers'
//    gripSpace poses + xr-standard gamepad state.
//  - Synthetic source (?synthetic=1, or the button): the deterministic pattern of
//    include/pmg/teleop/vr_synthetic.hpp at 72 Hz, for tests and demos without a headset.
//  - Link: automatic reconnect with exponential backoff (0.25 s … 5 s), a watchdog that treats
//    3 s without a status message from the bridge as a dead link, and a visible indicator.
'use strict';

const PAGE_VERSION = 'pmg-vr-page 1';
const SYNTHETIC_RATE_HZ = 72;
const STATUS_TIMEOUT_MS = 3000;     // no status from the bridge this long: the link is dead
const CONNECT_TIMEOUT_MS = 5000;    // a connection attempt that hangs this long is abandoned
const MAX_BUFFERED_BYTES = 16384;   // poses are dropped (not queued) while the socket is congested
const BACKOFF_MIN_MS = 250;
const BACKOFF_MAX_MS = 5000;

const params = new URLSearchParams(location.search);
const token = params.get('token') || '';

const $ = (id) => document.getElementById(id);

// ------------------------------------------------------------------------------------------------
// Link to the bridge

const link = {
  ws: null,
  state: 'disconnected',   // connecting | connected | reconnecting | disconnected
  attempt: 0,
  retryTimer: null,
  openedAt: 0,
  lastStatusAt: 0,
  lastError: '',
  retry: true,             // false after a refusal that retrying cannot fix (wrong token)
  server: null,            // last status message
  sentTimes: [],           // send times of the last second (rate)
  sent: 0,
  dropped: 0,
};

function wsUrl() {
  return `wss://${location.host}/ws` + (token ? `?token=${encodeURIComponent(token)}` : '');
}

function describeClose(ev) {
  const reason = ev.reason ? `: ${ev.reason}` : '';
  switch (ev.code) {
    case 1000: return `closed by the bridge${reason}`;
    case 1001: return `bridge stopping${reason}`;
    case 1006: return 'connection lost (no closing handshake: network drop, bridge not running, or certificate not accepted)';
    case 1009: return `message too large${reason}`;
    case 4001: return `replaced by a newer connection${reason}`;
    case 4002: return `bridge busy${reason}`;
    case 4003: return `refused${reason}`;
    default: return `closed (code ${ev.code})${reason}`;
  }
}

function setState(s) {
  link.state = s;
  render();
}

function connect() {
  clearTimeout(link.retryTimer);
  link.retryTimer = null;
  if (link.ws) {
    const old = link.ws;
    link.ws = null;
    try { old.close(); } catch (e) { /* already closed */ }
  }
  let ws;
  try {
    ws = new WebSocket(wsUrl());
  } catch (e) {
    link.lastError = `cannot open WebSocket: ${e.message}`;
    scheduleReconnect();
    return;
  }
  link.ws = ws;
  link.openedAt = performance.now();
  setState(link.attempt === 0 ? 'connecting' : 'reconnecting');
  ws.onopen = () => {
    if (link.ws !== ws) return;
    link.attempt = 0;
    link.lastStatusAt = performance.now();
    setState('connected');
  };
  ws.onmessage = (ev) => {
    if (link.ws !== ws || typeof ev.data !== 'string') return;
    let m;
    try { m = JSON.parse(ev.data); } catch (e) { return; }
    if (m && m.type === 'status') {
      link.server = m;
      link.lastStatusAt = performance.now();
      if (m.last_error) link.lastError = `bridge: ${m.last_error}`;
      render();
    }
  };
  ws.onclose = (ev) => {
    if (link.ws !== ws) return;
    link.ws = null;
    link.lastError = describeClose(ev);
    if (ev.code === 4003) {
      link.retry = false;
      link.lastError += ' — open the URL printed by pmg_vr_bridge (with ?token=…)';
      setState('disconnected');
      return;
    }
    scheduleReconnect();
  };
  ws.onerror = () => { /* onclose follows with the code */ };
}

function scheduleReconnect() {
  if (!link.retry) return;
  const base = Math.min(BACKOFF_MAX_MS, BACKOFF_MIN_MS * Math.pow(2, link.attempt));
  const delay = base * (0.8 + 0.4 * Math.random());
  link.attempt += 1;
  setState(link.attempt > 6 ? 'disconnected' : 'reconnecting');  // after ~10 s of failures: red, still retrying
  clearTimeout(link.retryTimer);
  link.retryTimer = setTimeout(connect, delay);
}

function abandon(why) {
  const ws = link.ws;
  link.ws = null;
  link.lastError = why;
  try { ws.close(); } catch (e) { /* ignore */ }
  scheduleReconnect();
}

// Watchdog: a half-open connection (Wi-Fi gone, headset asleep) looks open to the browser for a
// long time; the bridge sends a status every 0.5 s, so silence means the link is dead.
setInterval(() => {
  const now = performance.now();
  if (link.ws && link.state === 'connected' && now - link.lastStatusAt > STATUS_TIMEOUT_MS) {
    abandon(`no status from the bridge for ${(STATUS_TIMEOUT_MS / 1000).toFixed(0)} s`);
  } else if (link.ws && link.ws.readyState === WebSocket.CONNECTING && now - link.openedAt > CONNECT_TIMEOUT_MS) {
    abandon('connection attempt timed out');
  }
  render();
}, 500);

window.addEventListener('online', () => { if (!link.ws && link.retry) connect(); });
document.addEventListener('visibilitychange', () => {
  if (document.visibilityState === 'visible' && !link.ws && link.retry) connect();
});

let frameCounter = 0;  // strictly increasing over the page's life (the bridge checks it per connection)

function send(msg) {
  const ws = link.ws;
  if (!ws || ws.readyState !== WebSocket.OPEN || ws.bufferedAmount > MAX_BUFFERED_BYTES) {
    link.dropped += 1;
    return false;
  }
  ws.send(JSON.stringify(msg));
  const now = performance.now();
  link.sent += 1;
  link.sentTimes.push(now);
  while (link.sentTimes.length && now - link.sentTimes[0] > 1000) link.sentTimes.shift();
  return true;
}

// ------------------------------------------------------------------------------------------------
// Display

let lastPoseText = '';
let lastRender = 0;

function render() {
  const now = performance.now();
  while (link.sentTimes.length && now - link.sentTimes[0] > 1000) link.sentTimes.shift();
  $('link').className = `panel state-${link.state}`;
  $('link-state').textContent = link.state;
  $('link-rate').textContent = `${link.sentTimes.length} msg/s sent · ${link.sent} total · ${link.dropped} dropped`;
  const s = link.server;
  $('link-server').textContent = s && link.state === 'connected'
    ? `bridge: received ${s.received}, rejected ${s.rejected}, published ${s.published}, LCM ${s.lcm}` +
      `${s.active ? '' : ' · STANDBY (another client is streaming)'} · ${s.clients} client(s)`
    : '';
  $('link-error').textContent = link.lastError;
  if (now - lastRender > 200) {
    $('pose').textContent = lastPoseText;
    lastRender = now;
  }
}

function fmt(v) { return v.map((x) => x.toFixed(3)).join(' '); }

// ------------------------------------------------------------------------------------------------
// Synthetic pose source: the pattern of include/pmg/teleop/vr_synthetic.hpp (keep them equal; the
// browser test checks every pose against the C++ version).

function syntheticPose(frame) {
  const t = frame / SYNTHETIC_RATE_HZ;
  const u = t % 40.0;
  const walked = 0.3 * (u <= 20.0 ? u : 40.0 - u);
  const yaw = 0.15 * Math.sin(2.0 * Math.PI * 0.25 * t);
  const w = 2.0 * Math.PI * 0.5 * t;
  const pitch = -0.3;
  const hand = (side) => ({
    valid: true,
    p: [side * 0.25 - side * 0.08 * Math.cos(w), 1.2 + 0.08 * Math.sin(w), -0.35 - walked],
    q: [Math.sin(pitch / 2.0), 0, 0, Math.cos(pitch / 2.0)],
    grip: 1,
    trigger: 0.5 + 0.5 * Math.sin(w),
    buttons: 0,
    stick: [0, 0],
  });
  const left = hand(-1.0);
  const right = hand(1.0);
  right.buttons = Math.floor(t) % 2 === 1 ? 1 : 0;
  left.stick = [0.2 * Math.sin(w), 0];
  right.stick = [0, -0.5];
  return {
    type: 'pose',
    frame,
    t: t * 1000.0,
    head: { p: [0, 1.6, -walked], q: [0, Math.sin(yaw / 2.0), 0, Math.cos(yaw / 2.0)] },
    hands: [left, right],
  };
}

let syntheticRunning = false;

function startSynthetic() {
  if (syntheticRunning || xrSession) return;
  syntheticRunning = true;
  $('synthetic').disabled = true;
  $('enter-vr').disabled = true;
  $('enter-ar').disabled = true;
  $('xr-state').textContent = `synthetic poses at ${SYNTHETIC_RATE_HZ} Hz (walk forward 0.3 m/s, hands circling)`;
  // Frame k is due at start + k / rate; a late tick sends only the newest due frame, so that the
  // frame number always equals the pattern time and a throttled tab never bursts.
  const start = performance.now();
  const period = 1000.0 / SYNTHETIC_RATE_HZ;
  frameCounter = 0;
  const tick = () => {
    const due = Math.floor((performance.now() - start) / period);
    if (due >= frameCounter) {
      const msg = syntheticPose(due);
      send(msg);
      frameCounter = due + 1;
      lastPoseText = `frame ${due}\nhead  p ${fmt(msg.head.p)}  q ${fmt(msg.head.q)}\n` +
        `left  p ${fmt(msg.hands[0].p)}\nright p ${fmt(msg.hands[1].p)}`;
    }
    setTimeout(tick, Math.max(1, start + (frameCounter) * period - performance.now()));
  };
  tick();
}

// ------------------------------------------------------------------------------------------------
// WebXR

let xrSession = null;

const clamp = (x, lo, hi) => (Number.isFinite(x) ? Math.min(hi, Math.max(lo, x)) : 0);
const vec3 = (p) => [p.x, p.y, p.z];
const quat = (q) => [q.x, q.y, q.z, q.w];

function handMessage(pose, gamepad) {
  const h = { valid: false, p: [0, 0, 0], q: [0, 0, 0, 1], grip: 0, trigger: 0, buttons: 0, stick: [0, 0] };
  if (pose && !pose.emulatedPosition) {
    h.valid = true;
    h.p = vec3(pose.transform.position);
    h.q = quat(pose.transform.orientation);
  } else if (pose) {  // emulated (e.g. 3-DoF): the position is a guess; send it, marked not tracked
    h.p = vec3(pose.transform.position);
    h.q = quat(pose.transform.orientation);
  }
  if (gamepad) {  // xr-standard mapping
    const b = gamepad.buttons;
    const a = gamepad.axes;
    h.trigger = clamp(b[0] ? b[0].value : 0, 0, 1);
    h.grip = clamp(b[1] ? b[1].value : 0, 0, 1);
    h.buttons = (b[4] && b[4].pressed ? 1 : 0) | (b[5] && b[5].pressed ? 2 : 0) | (b[3] && b[3].pressed ? 4 : 0);
    h.stick = [clamp(a.length > 2 ? a[2] : 0, -1, 1), clamp(a.length > 3 ? a[3] : 0, -1, 1)];
  }
  return h;
}

async function startXr(mode) {
  if (xrSession || syntheticRunning) return;
  let session;
  try {
    session = await navigator.xr.requestSession(mode, { requiredFeatures: ['local-floor'] });
  } catch (e) {
    $('xr-state').textContent = `cannot start ${mode}: ${e.message}`;
    return;
  }
  xrSession = session;
  const canvas = document.createElement('canvas');
  const gl = canvas.getContext('webgl2', { xrCompatible: true }) || canvas.getContext('webgl', { xrCompatible: true });
  try {
    if (gl.makeXRCompatible) await gl.makeXRCompatible();
    session.updateRenderState({ baseLayer: new XRWebGLLayer(session, gl) });
  } catch (e) {
    $('xr-state').textContent = `WebGL for XR failed: ${e.message}`;
    session.end();
    return;
  }
  const space = await session.requestReferenceSpace('local-floor');
  const transparent = mode === 'immersive-ar';
  session.addEventListener('end', () => {
    xrSession = null;
    $('xr-state').textContent = 'XR session ended (press Enter VR/AR to resume)';
    setupXrButtons();
  });
  $('xr-state').textContent = `${mode} running`;
  $('synthetic').disabled = true;
  const onFrame = (time, frame) => {
    session.requestAnimationFrame(onFrame);
    const layer = session.renderState.baseLayer;
    gl.bindFramebuffer(gl.FRAMEBUFFER, layer.framebuffer);
    const ok = link.state === 'connected';
    // The link state inside the headset: a red tint while the link is down (premultiplied alpha).
    if (transparent) gl.clearColor(ok ? 0 : 0.3, 0, 0, ok ? 0 : 0.3);  // passthrough
    else gl.clearColor(ok ? 0.05 : 0.35, ok ? 0.12 : 0.08, 0.08, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    const viewer = frame.getViewerPose(space);
    if (!viewer) return;  // tracking lost: send nothing (the robot side sees a stale stream)
    const hands = [handMessage(null, null), handMessage(null, null)];
    for (const src of session.inputSources) {
      const i = src.handedness === 'left' ? 0 : src.handedness === 'right' ? 1 : -1;
      if (i < 0) continue;
      const pose = src.gripSpace ? frame.getPose(src.gripSpace, space) : null;
      hands[i] = handMessage(pose, src.gamepad);
    }
    const msg = {
      type: 'pose',
      frame: frameCounter++,
      t: Math.max(0, time),
      head: { p: vec3(viewer.transform.position), q: quat(viewer.transform.orientation) },
      hands,
    };
    send(msg);
    lastPoseText = `frame ${msg.frame}\nhead  p ${fmt(msg.head.p)}\nleft  ${hands[0].valid ? fmt(hands[0].p) : '-'}` +
      `\nright ${hands[1].valid ? fmt(hands[1].p) : '-'}`;
  };
  session.requestAnimationFrame(onFrame);
}

async function setupXrButtons() {
  const vr = $('enter-vr');
  const ar = $('enter-ar');
  if (!window.isSecureContext) {
    $('xr-state').textContent = 'not a secure context: open the page over https://';
    return;
  }
  if (!navigator.xr) {
    $('xr-state').textContent = 'WebXR not available in this browser: use "Synthetic poses" to test the link';
    return;
  }
  const supported = async (m) => { try { return await navigator.xr.isSessionSupported(m); } catch (e) { return false; } };
  const [hasVr, hasAr] = await Promise.all([supported('immersive-vr'), supported('immersive-ar')]);
  vr.disabled = !hasVr || syntheticRunning;
  ar.disabled = !hasAr || syntheticRunning;
  if (!syntheticRunning) {
    $('xr-state').textContent = hasVr || hasAr ? 'ready: press Enter VR (or AR for passthrough)'
      : 'no immersive XR device found: use "Synthetic poses" to test the link';
  }
}

// ------------------------------------------------------------------------------------------------

window.addEventListener('DOMContentLoaded', () => {
  $('version').textContent = PAGE_VERSION;
  $('enter-vr').addEventListener('click', () => startXr('immersive-vr'));
  $('enter-ar').addEventListener('click', () => startXr('immersive-ar'));
  $('synthetic').addEventListener('click', startSynthetic);
  $('reconnect').addEventListener('click', () => { link.retry = true; link.attempt = 0; connect(); });
  connect();
  setupXrButtons();
  if (params.get('synthetic') === '1') startSynthetic();
});
