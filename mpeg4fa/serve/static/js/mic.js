// The microphone button of the live page: the browser's microphone (getUserMedia) -> 16 kHz s16le in 20 ms
// chunks (mic-worklet.js) -> the server (binary MIC1 messages on a WebSocket of its own, see
// mpeg4fa/serve/microphone.py), which listens (mpeg4fa.speech.live) and answers with the face as FBA1
// messages. Those go to the player's own handler (window.player.onBinary): decoded by fba.js and played on
// the player's clock like a sentence's stream. Their media times are the session's; they are moved onto the
// player's clock at the first one: a frame shows the server's latency plus MARGIN (a little room for the
// network's jitter) after its audio was sent, however late the first answer came. A session has no end the
// page knows of, so the player keeps only the frames shown in the last KEEP s (window.player.trim) and what
// is still to come; the status line says how far the face is behind the voice: how long ago, on the page's
// clock, the audio of the frame on screen was sent (a microphone the browser feeds slower than real time,
// as a busy machine's does, must not make the face seem to catch up). A frame coming after its time
// is no fault here (unlike a sentence's, whose whole stream is ahead of the clock): it shows when it comes. What
// the viewer sees go wrong is a frame that never shows (one after it was due before the next picture) and the
// face standing still while no frame comes (the longest wait between the server's messages); the status line
// says those, not the player's underruns.
const MIC = "MIC1", FBA = "FBA1";
const RATE = 16000;
const MARGIN = 0.08;  // s of room for the network on top of the server's latency
const KEEP = 2;  // s of frames kept behind the one showing
const SENT_KEPT = 1500;  // chunks (30 s) whose sending times are kept for the status line

const state = {  // read by the browser test (window.mic)
  on: false, starting: false, sent: 0, chunks: 0, faces: 0, faceBytes: 0, started: null, ended: null,
  errors: [], offset: null, levels: [], contextRate: null, frames: 0, dropped: 0, mostHeld: 0,
  shownAtStart: 0, lastFaceAt: null, longestWait: 0, sentAt: [], skipped: 0, skips: [],
};
window.mic = state;

const button = document.createElement("button");
button.id = "mic";
button.type = "button";
button.dataset.testid = "mic";
button.title = "Animate the head from your microphone while you speak";
button.textContent = "Microphone";
document.querySelector("header").appendChild(button);

let ws = null, context = null, stream = null, node = null;

function header(kind, t, bytes) {
  const out = new ArrayBuffer(12 + bytes);
  const view = new DataView(out);
  for (let i = 0; i < 4; i++) view.setUint8(i, kind.charCodeAt(i));
  view.setFloat64(4, t, true);
  return out;
}

function onMessage(e) {
  if (typeof e.data === "string") {
    const m = JSON.parse(e.data);
    if (m.type === "mic" && m.state === "started") state.started = m;
    else if (m.type === "mic" && m.state === "skipping") state.skips.push([m.at, null]);  // the server fell behind
    else if (m.type === "mic" && m.state === "resumed") {
      state.skipped = m.skipped;
      if (state.skips.length) state.skips[state.skips.length - 1][1] = m.at;
    }
    else if (m.type === "mic" && m.state === "ended") { state.ended = m; state.skipped = m.skipped; if (!state.on && ws) { ws.close(); ws = null; } }
    else if (m.type === "error") state.errors.push(m);
    return;
  }
  const buffer = e.data;
  if (buffer.byteLength < 12) return;
  const view = new DataView(buffer);
  const kind = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
  if (kind !== FBA) return;
  const player = window.player;
  const t = view.getFloat64(4, true);
  const at = performance.now();
  if (state.lastFaceAt !== null) state.longestWait = Math.max(state.longestWait, (at - state.lastFaceAt) / 1000);
  state.lastFaceAt = at;
  if (state.offset === null) {
    // the server says "started" (with its latency: mpeg4fa.speech.live.LATENCY) before the first face
    if (!state.started) { state.errors.push({ error: "face data before the microphone started", where: "mic" }); return; }
    // the audio sent so far ends about now: a frame of session time t shows at now + (t - sent) + latency +
    // MARGIN, whenever the first answer came (a server slow to start must not leave the face behind the voice
    // for the whole session: the frames it is late with are simply past when they come)
    player.startClock();
    state.offset = player.mediaNow() - state.sent / RATE + state.started.latency + MARGIN;
    player.done = null;  // a finished sentence's "back to rest" must not hold the face still
  }
  view.setFloat64(4, t + state.offset, true);
  state.faces++;
  state.faceBytes += buffer.byteLength - 12;
  const held = player.frames.length;
  player.onBinary(buffer);
  state.frames += player.frames.length - held;
  state.dropped += player.trim(KEEP);
  state.mostHeld = Math.max(state.mostHeld, player.frames.length);
}

/** Frames of this session whose time passed without their being shown: received, less those shown, less
 * those still to come (after the one showing). */
function neverShown() {
  const player = window.player;
  const toCome = player.frames.length - 1 - player.shown;
  return Math.max(0, state.frames - (player.shownFrames - state.shownAtStart) - toCome);
}
state.neverShown = neverShown;

/** How long ago (s, the page's clock) the audio at session time t was sent: the first chunk that reached
 * past t. Audio not sent yet (a face ahead of its voice cannot be) counts as now. */
function behindTheVoice(t) {
  const upTo = t * RATE, sentAt = state.sentAt;
  let lo = 0, hi = sentAt.length;
  while (lo < hi) { const mid = (lo + hi) >> 1; if (sentAt[mid][0] < upTo) lo = mid + 1; else hi = mid; }
  return lo < sentAt.length ? Math.max(0, (performance.now() - sentAt[lo][1]) / 1000) : 0;
}

/** The status line while the microphone runs: how far the face shown is behind the audio sent, the frames
 * received and held, those never shown and the longest the face waited for a message (null when it does not
 * run: the player's own lines). */
function statusLines() {
  if (!state.on && !state.starting) return null;
  const player = window.player;
  const t = state.offset === null || player.shown < 0 ? -1 : player.frames[player.shown].t - state.offset;
  if (t < 0) return [`microphone: listening, ${(state.sent / RATE).toFixed(1)} s sent, no face yet`];  // or an earlier one's
  const behind = behindTheVoice(t);
  const skipping = state.skips.length && state.skips[state.skips.length - 1][1] === null;
  const lines = [`microphone: listening, the face ${(behind * 1000).toFixed(0)} ms behind the voice`,
                 `${state.frames} frames in ${state.faces} messages, ${player.frames.length} held, ${neverShown()} ` +
                 `never shown, longest wait ${(state.longestWait * 1000).toFixed(0)} ms`];
  if (skipping) lines.push("the server fell behind: skipping to catch up");  // a line of its own: the box does not wrap
  else if (state.skipped) lines.push(`the server fell behind and skipped ${state.skipped.toFixed(1)} s to catch up`);
  return lines;
}

async function start() {
  state.starting = true;
  Object.assign(state, { sent: 0, chunks: 0, faces: 0, faceBytes: 0, started: null, ended: null, offset: null,
                         levels: [], frames: 0, dropped: 0, mostHeld: 0, shownAtStart: window.player.shownFrames,
                         lastFaceAt: null, longestWait: 0, sentAt: [], skipped: 0, skips: [] });
  window.player.statusLines = statusLines;
  button.disabled = true;
  try {
    ws = new WebSocket(`ws://${location.host}/ws`);
    ws.binaryType = "arraybuffer";
    ws.onmessage = onMessage;
    const open = new Promise((resolve, reject) => { ws.onopen = resolve; ws.onerror = () => reject(new Error("no connection")); });
    stream = await navigator.mediaDevices.getUserMedia({
      audio: { echoCancellation: false, noiseSuppression: false, autoGainControl: false, channelCount: 1 } });
    await open;
    context = new AudioContext();
    if (context.state !== "running") { try { await context.resume(); } catch (e) { /* runs when it can */ } }
    state.contextRate = context.sampleRate;
    await context.audioWorklet.addModule("/static/js/mic-worklet.js");
    node = new AudioWorkletNode(context, "mic-pcm16k");
    node.port.onmessage = (e) => send(e.data);
    const silent = context.createGain();
    silent.gain.value = 0;  // the worklet runs only when pulled: to the output, at no volume
    context.createMediaStreamSource(stream).connect(node).connect(silent).connect(context.destination);
    state.on = true;
    button.textContent = "Stop microphone";
    button.classList.add("on");
  } catch (e) {
    state.errors.push({ error: String(e && e.message || e), where: "microphone" });
    stop();
  } finally {
    state.starting = false;
    button.disabled = false;
  }
}

function send(pcm) {
  if (!ws || ws.readyState !== WebSocket.OPEN || !state.on) return;
  const out = header(MIC, state.sent / RATE, pcm.byteLength);
  new Int16Array(out, 12).set(pcm);
  ws.send(out);
  let sum = 0;
  for (let i = 0; i < pcm.length; i++) sum += pcm[i] * pcm[i];
  state.levels.push(10 * Math.log10(sum / pcm.length / (32768 * 32768) + 1e-12));  // dBFS of each chunk
  state.sent += pcm.length;
  state.chunks++;
  state.sentAt.push([state.sent, performance.now()]);  // where each chunk's audio ends, and when it went
  if (state.sentAt.length > 2 * SENT_KEPT) state.sentAt.splice(0, state.sentAt.length - SENT_KEPT);
}

function stop() {
  const wasOn = state.on;
  state.on = false;
  button.textContent = "Microphone";
  button.classList.remove("on");
  if (node) { node.port.onmessage = null; node.disconnect(); node = null; }
  if (stream) { for (const track of stream.getTracks()) track.stop(); stream = null; }
  if (context) { context.close(); context = null; }
  if (ws && ws.readyState === WebSocket.OPEN && wasOn) ws.send(header(MIC, state.sent / RATE, 0));  // the end
  else if (ws) { ws.close(); ws = null; }
}

button.addEventListener("click", () => { if (state.starting) return; if (state.on) stop(); else start(); });
