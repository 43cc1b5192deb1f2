// The live player: the server speaks the text and sends each sentence's FBA bitstream and its audio
// (mpeg4fa/serve/protocol.py); the page decodes the stream itself (fba.js, shown.js) and poses the head
// with the face engine's rig (head.js), the speech through WebAudio. Frames and audio carry media times;
// both are placed on the AudioContext's clock (media time 0 plays at `base`), so mouth and voice stay
// together whatever the network does. Buffer reports go back every 100 ms: the server sends no more than
// its window ahead of our playhead. Any FBA message is taken alike (a sentence, or another source of face
// frames on the socket): decoded, shifted by its media time, played at that time.
import { decode as decodeFba, FbaError } from "./fba/fba.js";
import { Shown } from "./fba/shown.js";
import { createView, loadHead } from "./head.js";

const PREBUFFER = 0.3;   // s of media held before playing starts
const REPORT_MS = 100;
const AUDIO = "AUD1", FBA = "FBA1";

const view = document.getElementById("view");
const statusBox = document.getElementById("status");
const caption = document.getElementById("caption");
const message = document.getElementById("message");
const speakButton = document.getElementById("speak");

const state = {            // read by the browser tests (window.player)
  ready: false, hello: null, frames: [], audioChunks: 0, fbaBytes: 0, fbaMessages: 0, segments: [],
  shown: -1, shownFrames: 0, latencyMs: null, underruns: 0, done: null, errors: [], reports: 0,
  valuesNow: new Float64Array(68), mediaTime: 0, clock: "none", received: 0, maxAhead: 0, maxFaceAhead: 0, tick: null,
};
window.player = state;

const scene = createView(view);
let head = null;
loadHead(scene, { key: "/static/fap-head.json", glb: "/static/fap-head.glb" }).then((h) => {
  head = h;
  state.ready = true;
  speakButton.disabled = false;
  setStatus();
}, (err) => { state.errors.push({ error: String(err), where: "head" }); setStatus(); });

// ---- the clock: the AudioContext's when it runs, else the page's ----
let audio = null, base = null;
function now() {
  if (audio && audio.state === "running") return audio.currentTime - (audio.outputLatency || 0);
  return performance.now() / 1000;
}
function mediaTime() { return base === null ? -Infinity : now() - base; }
function startClock() {
  if (base === null) { base = now() + PREBUFFER; state.clock = audio && audio.state === "running" ? "audio" : "page"; }
}

// ---- the connection ----
let ws = null, sayAt = 0, rate = 22050;
let announced = null;  // the segment message whose stream comes next (other FBA messages are named by time)
function connect() {
  ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  ws.onmessage = (e) => (typeof e.data === "string" ? onText(JSON.parse(e.data)) : onBinary(e.data));
  ws.onclose = () => { ws = null; setStatus(); };
  return new Promise((resolve) => { ws.onopen = resolve; });
}

function onText(m) {
  if (m.type === "hello") state.hello = m;
  else if (m.type === "segment") { state.segments.push(m); announced = m; rate = m.rate; caption.textContent = m.text; }
  else if (m.type === "done") state.done = m;
  else if (m.type === "error") state.errors.push(m);
  setStatus();
}

function setMessage(text) {
  message.textContent = text;
  message.classList.toggle("shown", !!text);
}

/** One FBA message: decode it, keep its frames (media times) with the values they show. A fault keeps the
 * frames before it and says where, once, in the page's message line. */
function onFace(t, bytes) {
  state.fbaBytes += bytes.length;
  state.fbaMessages++;
  const name = announced ? `sentence ${announced.index + 1}` : `face data at ${t.toFixed(2)} s`;
  announced = null;
  let frames;
  try {
    frames = decodeFba(bytes).frames;
  } catch (e) {
    if (!(e instanceof FbaError)) throw e;
    frames = e.partial ? e.partial.frames : [];
    const kept = frames.length;
    const text = `${name}: ${e.toString()}` + (kept ? ` — playing the ${kept} frame${kept === 1 ? "" : "s"} before it` : "");
    state.errors.push({ error: text, where: "fba" });
    setMessage(text);
  }
  if (!frames.length) return;
  if (state.latencyMs === null) state.latencyMs = performance.now() - sayAt;
  startClock();
  const shown = new Shown();  // each message is a whole fba_object: nothing held from the one before
  const at = state.frames.length;
  for (const f of frames) state.frames.push({ t: t + f.timestamp, values: shown.push(f) });
  if (at && state.frames[at].t < state.frames[at - 1].t) state.frames.sort((a, b) => a.t - b.t);  // out of order
  if (state.frames[at].t < mediaTime()) state.underruns++;
  const fps = state.hello ? state.hello.fps : 25;
  received(state.frames[state.frames.length - 1].t + 1 / fps, true);
}

function onBinary(buffer) {
  const head12 = new DataView(buffer, 0, Math.min(12, buffer.byteLength));
  if (buffer.byteLength < 12) { state.errors.push({ error: `binary message of ${buffer.byteLength} bytes`, where: "message" }); return; }
  const kind = String.fromCharCode(head12.getUint8(0), head12.getUint8(1), head12.getUint8(2), head12.getUint8(3));
  const t = head12.getFloat64(4, true);
  if (kind === FBA) { onFace(t, new Uint8Array(buffer, 12)); setStatus(); return; }
  if (kind !== AUDIO) return;
  const pcm = new Int16Array(buffer.slice(12));
  startClock();
  received(t + pcm.length / rate);
  state.audioChunks++;
  if (!audio || audio.state !== "running") return;  // no sound device: the frames still play on the page clock
  const chunk = audio.createBuffer(1, pcm.length, rate);
  const data = chunk.getChannelData(0);
  for (let i = 0; i < pcm.length; i++) data[i] = pcm[i] / 32768;
  const source = audio.createBufferSource();
  source.buffer = chunk;
  source.connect(audio.destination);
  const when = base + t + (audio.outputLatency || 0);
  if (when < audio.currentTime) { state.underruns++; source.start(audio.currentTime, audio.currentTime - when); }
  else source.start(when);
}
state.onBinary = onBinary;  // the message handler itself, for tests that hand it a damaged stream

function received(end, face = false) {
  state.received = Math.max(state.received, end);
  const ahead = end - Math.max(0, mediaTime());  // a sentence's face comes whole; its audio as the window allows
  if (face) state.maxFaceAhead = Math.max(state.maxFaceAhead, ahead);
  else state.maxAhead = Math.max(state.maxAhead, ahead);
}

setInterval(() => {
  if (!ws || ws.readyState !== WebSocket.OPEN || base === null || state.done) return;
  const played = Math.max(0, mediaTime());
  ws.send(JSON.stringify({ type: "buffer", received: state.received, buffered: Math.max(0, state.received - played) }));
  state.reports++;
}, REPORT_MS);

async function speak() {
  if (!audio) audio = new AudioContext();
  if (audio.state !== "running") { try { await audio.resume(); } catch (e) { /* no device: page clock */ } }
  if (!ws) await connect();
  Object.assign(state, { frames: [], segments: [], audioChunks: 0, fbaBytes: 0, fbaMessages: 0, shown: -1,
                         shownFrames: 0, latencyMs: null, underruns: 0, done: null, received: 0, maxAhead: 0,
                         maxFaceAhead: 0, tick: null, held: false });
  setMessage("");
  base = null;
  sayAt = performance.now();
  ws.send(JSON.stringify({ type: "say", text: document.getElementById("text").value }));
}
speakButton.addEventListener("click", speak);
document.getElementById("stop").addEventListener("click", () => ws && ws.send(JSON.stringify({ type: "stop" })));
connect();

// ---- drawing: the latest frame whose time has come ----
const REST = new Float64Array(68);
function apply(values) {
  state.valuesNow = values;
  if (head) head.pose(values);
}

function frame() {
  requestAnimationFrame(frame);
  const m = mediaTime();
  state.mediaTime = m;
  if (state.held) { scene.render(); return; }  // a frame held for a look (window.player.pose)
  let k = state.shown;
  while (k + 1 < state.frames.length && state.frames[k + 1].t <= m) k++;
  if (k !== state.shown) { state.shown = k; state.shownFrames++; apply(state.frames[k].values); }
  if (state.done && k === state.frames.length - 1 && m > state.done.duration && state.valuesNow !== REST) {
    apply(REST);  // back to rest after the last frame's time
  }
  scene.render();
  state.tick = { t: m, k };  // what this picture shows, and at what media time
}
frame();

/** Hold frame ``k`` on the head (playing stops moving it until the next Speak): for tests and a look. */
state.pose = (k) => { state.held = true; apply(state.frames[k].values); scene.render(); };
/** Feature points of the drawn head (mm), read back from its vertices. */
state.featurePoints = () => head.featurePoints();
/** Drop the frames whose time passed more than ``seconds`` ago (the one showing then stays), so that an
 * endless source (the microphone) holds what it shows and what is coming, not all it ever sent; returns how
 * many went. By the clock, not by what was drawn: a page stalled for a while trims all the same. */
state.trim = (seconds) => {
  const before = mediaTime() - seconds;
  let n = 0;
  while (n + 1 < state.frames.length && state.frames[n + 1].t <= before) n++;
  if (n) { state.frames.splice(0, n); state.shown = Math.max(-1, state.shown - n); }
  return n;
};
/** The media time now (-Infinity before the clock starts), and the clock started (if it has not): for a
 * source that places its frames by its own clock (the microphone). */
state.mediaNow = mediaTime;
state.startClock = startClock;

function setStatus() {
  const s = state;
  statusBox.textContent = [
    s.ready ? `head ready${head.deformerNote ? ` (${head.deformerNote})` : ""}` : "loading the head…",
    ws ? "connected" : "not connected",
    ...(s.statusLines && s.statusLines()) || [  // another source's own lines while it runs (the microphone)
      `frames ${s.frames.length} (shown ${s.shownFrames}), audio chunks ${s.audioChunks}, FBA ${s.fbaBytes} bytes in ${s.segments.length} segments`,
      `first frame ${s.latencyMs === null ? "-" : s.latencyMs.toFixed(0) + " ms"}, underruns ${s.underruns}, clock ${s.clock}`],
    s.done ? `done: ${s.done.duration.toFixed(2)} s${s.done.stopped ? " (stopped)" : ""}` : "",
    ...s.errors.slice(-2).map((e) => `error (${e.where}): ${e.error}`),
  ].filter(Boolean).join("\n");
}
setInterval(setStatus, 250);
