// The FBA player page: decodes a .fba in the browser (fba.js), plays it on the head with its .wav.
//
// The head is fap-head.glb posed by the face engine's own rig (head.js, facerig.js: every vertex where
// the Python face puts it). The clock is the audio element's when the stream has speech, else the wall
// clock; each frame is shown from its presentation time on.
import { FbaError, StreamDecoder, summary } from "./fba/fba.js";
import { Shown } from "./fba/shown.js";
import { createView, loadHead } from "./head.js";

const $ = (id) => document.getElementById(id);
const view = $("view"), info = $("info"), message = $("message"), audio = $("audio");
const playButton = $("play"), scrub = $("scrub"), timeText = $("time");
const CHUNK = 64 * 1024;  // bytes handed to the decoder at a time (frames come out as they complete)

const scene = createView(view);
let head = null;
let headInfo = { name: "generic head" };  // or the FDP it is calibrated to

/** Calibrate the head to a sender's FDP (a File or Blob named ``name``): the server does it (POST /api/head)
 * and answers with the head's GLB and rig; a page opened from a folder has its head baked in instead. */
async function applyFdp(name, blob) {
  if (window.FBA_PLAYER_HEAD || location.protocol === "file:") {
    setMessage(`${name}: this page carries its head; to apply an FDP open the player from mpeg4fa serve, ` +
      "or bake it in: tools/fbaplayer_static.py --fdp FILE");
    return;
  }
  headInfo = { name: `${name} (calibrating…)` };
  describe();
  let answer;
  try {
    const response = await fetch(`/api/head?name=${encodeURIComponent(name)}`, { method: "POST", body: blob });
    answer = await response.json();
    if (!response.ok) throw new Error(answer.error ? `${answer.where}: ${answer.error}` : `the server answered ${response.status}`);
  } catch (e) {
    headInfo = { name: "generic head" };
    setMessage(e.message.startsWith(name) ? e.message : `${name}: ${e.message}`);
    describe();
    return;
  }
  const next = await loadHead(scene, { key: answer.key, glb: answer.glb });
  if (head) head.remove();
  head = next;
  headInfo = { name, points: answer.points, texture: answer.texture };
  state.headName = name;
  if (state.shownK >= 0) head.pose(state.shown[state.shownK]);
  describe();
}

function headSource() {
  // a page made to open from a folder (tools/fbaplayer_static.py) carries its head; else it is fetched
  const embedded = window.FBA_PLAYER_HEAD;
  return embedded ? { key: embedded.key, glb: embedded.glb } : { key: "fap-head.json", glb: "fap-head.glb" };
}

// ---- the stream --------------------------------------------------------------------------------
const state = { name: "", bytes: 0, frames: [], shown: [], error: null, done: false, clock0: null, paused: true,
  offset: 0, audio: false, shownK: -1, decodeMs: 0 };

function setMessage(text) {
  message.textContent = text;
  message.classList.toggle("shown", !!text);
}

function duration() {
  const f = state.frames;
  if (!f.length) return 0;
  const last = f[f.length - 1];
  return last.timestamp - f[0].timestamp + (last.skip + 1) / streamFps();
}

function streamFps() {
  for (const f of state.frames) if (f.params && f.params.frameRate) return f.params.frameRate.fps;
  return 30;
}

function describe() {
  const f = state.frames;
  if (!f.length) { info.textContent = state.error ? `${state.name}: no frame decoded` : "decoding…"; return; }
  const s = summary({ frames: f, fps: streamFps() }, state.bytes);
  const first = f.find((x) => x.params && x.params.face);
  const face = first ? first.params.face : null;
  const osc = state.decoder.objectStartCode;
  info.textContent = [
    `${state.name}  ${(state.bytes / 1024).toFixed(1)} KiB${state.done ? "" : " (receiving)"}`,
    `object start code 0x${osc.toString(16).toUpperCase().padStart(8, "0")}  ${s.face ? "face" : ""}${s.face && s.body ? " + " : ""}${s.body ? "body" : ""}`,
    `${s.frames} frames (${s.intra} intra)  ${s.fps.toFixed(3)} fps  ${s.duration.toFixed(3)} s`,
    face ? `fap_quant ${face.quant}  mask types ${face.maskTypes.join("")}` : "no face header",
    `${s.bitsPerFrame.toFixed(1)} bits/frame  ${s.kbps.toFixed(2)} kbit/s`,
    `audio: ${state.audio ? "yes" : "none"}  decoded in ${state.decodeMs.toFixed(1)} ms`,
    `head: ${headInfo.name}${headInfo.points ? ` (${headInfo.points} points${headInfo.texture ? `, texture ${headInfo.texture}` : ""})` : ""}`
      + (head && head.deformerNote ? ` — ${head.deformerNote}` : ""),
  ].join("\n");
}

function reset(name) {
  audio.pause();
  if (audio.src && audio.src.startsWith("blob:")) URL.revokeObjectURL(audio.src);
  audio.removeAttribute("src");
  audio.load();
  Object.assign(state, { name, bytes: 0, frames: [], shown: [], error: null, done: false, clock0: null, paused: true,
    offset: 0, audio: false, shownK: -1, decodeMs: 0, resolver: new Shown(), decoder: new StreamDecoder() });
  setMessage("");
  playButton.disabled = true;
  scrub.disabled = true;
}

/** Feed bytes to the decoder; a fault stops decoding and says where, keeping the frames before it. */
function feed(chunk, last) {
  if (state.error) return;
  const t0 = performance.now();
  let frames = [];
  try {
    frames = last ? state.decoder.end() : state.decoder.push(chunk);
  } catch (e) {
    if (!(e instanceof FbaError)) throw e;
    frames = e.partial ? e.partial.frames : [];
    state.error = e;
  }
  state.bytes += chunk ? chunk.length : 0;
  for (const f of frames) { state.frames.push(f); state.shown.push(state.resolver.push(f)); }
  state.decodeMs += performance.now() - t0;
  if (last || state.error) state.done = true;
  if (state.error) {
    const kept = state.frames.length;
    setMessage(`${state.name}: ${state.error.toString()}` +
      (kept ? ` — playing the ${kept} frame${kept === 1 ? "" : "s"} before it` : ""));
  }
  if (state.frames.length) { playButton.disabled = false; scrub.disabled = false; }
  scrub.max = String(duration());
  describe();
}

async function openFiles(list) {
  const files = Array.from(list);
  const fdp = files.find((f) => /\.fdp$/i.test(f.name));
  // the .fba, else the first file that is not a .wav or .fdp: the decoder says what it is if it is no stream
  const stream = files.find((f) => /\.fba$/i.test(f.name)) || files.find((f) => !/\.(wav|fdp)$/i.test(f.name));
  if (fdp) applyFdp(fdp.name, fdp);  // calibrating takes a moment: the stream decodes meanwhile
  if (!stream) { if (!fdp) setMessage("only audio given: choose a .fba stream (and its .wav)"); return; }
  reset(stream.name);
  const base = stream.name.replace(/\.[^.]*$/, "").toLowerCase();
  const wav = files.find((f) => /\.wav$/i.test(f.name) && f.name.replace(/\.[^.]*$/, "").toLowerCase() === base)
    || files.find((f) => /\.wav$/i.test(f.name));
  if (wav) { audio.src = URL.createObjectURL(wav); state.audio = true; }
  const bytes = new Uint8Array(await stream.arrayBuffer());
  for (let i = 0; i < bytes.length && !state.error; i += CHUNK) feed(bytes.subarray(i, i + CHUNK), false);
  feed(null, true);
}

async function openUrl(url) {
  const name = decodeURIComponent(new URL(url, location.href).pathname.split("/").pop() || url);
  reset(name);
  let response;
  try {
    response = await fetch(url);
  } catch (e) {
    setMessage(`${name}: cannot fetch it (${e.message})`);
    return;
  }
  if (!response.ok) { setMessage(`${name}: the server answered ${response.status} ${response.statusText}`); return; }
  const wavUrl = new URL(url, location.href);
  wavUrl.pathname = wavUrl.pathname.replace(/\.[^./]*$/, ".wav");
  fetch(wavUrl, { method: "HEAD" }).then((r) => {
    if (r.ok && state.name === name) { audio.src = wavUrl.href; state.audio = true; describe(); }
  }).catch(() => {});
  const fdpUrl = new URL(url, location.href);  // the sender's FDP beside it, if there is one
  fdpUrl.pathname = fdpUrl.pathname.replace(/\.[^./]*$/, ".fdp");
  fetch(fdpUrl).then((r) => (r.ok && state.name === name ? r.blob() : null)).then((blob) => {
    if (blob) applyFdp(decodeURIComponent(fdpUrl.pathname.split("/").pop()), blob);
  }).catch(() => {});
  const reader = response.body.getReader();
  for (;;) {
    const { done, value } = await reader.read();
    if (done) break;
    feed(value, false);
    if (state.error) { reader.cancel(); return; }
  }
  feed(null, true);
}

// ---- playback ----------------------------------------------------------------------------------
/** The media time shown: where it was paused or sought to; while playing, the audio's clock once it runs
 * (a .wav served without range requests cannot seek: paused, the picture still shows where it was put). */
function now() {
  if (state.paused || state.clock0 === null) return state.offset;
  if (state.audio && audio.src && !Number.isNaN(audio.duration) && !audio.paused) return audio.currentTime;
  return state.offset + (performance.now() - state.clock0) / 1000;
}

function seek(t) {
  t = Math.max(0, Math.min(t, duration()));
  state.offset = t;
  state.clock0 = state.paused ? null : performance.now();
  if (state.audio && audio.src) audio.currentTime = t;
  showAt(t);
}

function play() {
  if (!state.frames.length) return;
  if (now() >= duration()) seek(0);
  state.paused = false;
  state.clock0 = performance.now();
  if (state.audio && audio.src) audio.play().catch(() => {});
  playButton.textContent = "Pause";
}

function pause() {
  state.offset = now();
  state.paused = true;
  state.clock0 = null;
  audio.pause();
  playButton.textContent = "Play";
}

/** The frame shown at media time ``t`` (seconds from the first frame): the last one presented by then. */
function frameAt(t) {
  const f = state.frames;
  if (!f.length) return -1;
  const target = f[0].timestamp + t + 1e-9;
  let lo = 0, hi = f.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (f[mid].timestamp <= target) lo = mid; else hi = mid - 1;
  }
  return lo;
}

function showFrame(k) {
  if (k < 0 || k === state.shownK) return;
  state.shownK = k;
  if (head) head.pose(state.shown[k]);
}

function showAt(t) {
  showFrame(frameAt(t));
  timeText.textContent = `${t.toFixed(3)} / ${duration().toFixed(3)} s  frame ${Math.max(state.shownK, 0)}`;
  if (document.activeElement !== scrub) scrub.value = String(t);
}

function loop() {
  requestAnimationFrame(loop);
  if (state.frames.length) {
    let t = now();
    if (!state.paused && t >= duration() && (!state.audio || audio.ended || !audio.src)) { pause(); t = duration(); }
    showAt(Math.min(t, duration()));
    state.tick = { t, k: state.shownK, at: performance.now() };  // what this picture shows, and when
  }
  scene.render();
}

// ---- wiring ------------------------------------------------------------------------------------
playButton.addEventListener("click", () => (state.paused ? play() : pause()));
scrub.addEventListener("input", () => seek(Number(scrub.value)));
// audio that arrives after a seek (a URL's .wav loads while the frames play) starts where the picture is
audio.addEventListener("loadedmetadata", () => { audio.currentTime = state.paused ? state.offset : now(); });
$("files").addEventListener("change", (e) => openFiles(e.target.files));
$("open").addEventListener("click", () => { const url = $("url").value.trim(); if (url) openUrl(url); });
window.addEventListener("keydown", (e) => {
  if (e.target.tagName === "INPUT" && e.target.type !== "range") return;
  if (e.code === "Space") { e.preventDefault(); playButton.click(); }
  if (e.code === "ArrowLeft") seek(now() - 1 / streamFps());
  if (e.code === "ArrowRight") seek(now() + 1 / streamFps());
});
for (const type of ["dragenter", "dragover"]) {
  window.addEventListener(type, (e) => { e.preventDefault(); document.body.classList.add("dragging"); });
}
window.addEventListener("dragleave", (e) => { if (e.target === document.body || e.clientX <= 0) document.body.classList.remove("dragging"); });
window.addEventListener("drop", (e) => {
  e.preventDefault();
  document.body.classList.remove("dragging");
  if (e.dataTransfer.files.length) openFiles(e.dataTransfer.files);
});

window.fbaPlayer = {
  ready: false, state, openFiles, openUrl, seek, play, pause, frameAt,
  /** Feature points of the drawn head (mm), read back from its vertices. */
  featurePoints: () => head.featurePoints(),
  /** The lash cards' vertices (mm; null on a head without lashes); showLashes draws them or leaves them out. */
  lashVertices: () => head.lashVertices(),
  showLashes(shown) { if (head.lashes) head.lashes.mesh.visible = shown; scene.render(); },
  /** Show frame ``k`` now (paused), for tests and frame stepping. */
  showFrame(k) { pause(); seek(state.frames[k].timestamp - state.frames[0].timestamp); showFrame(k); scene.render(); },
  now,
};

loadHead(scene, headSource()).then((h) => {
  head = h;
  const url = new URLSearchParams(location.search).get("url");
  window.fbaPlayer.ready = true;
  document.body.dataset.ready = "1";
  if (url) { $("url").value = url; openUrl(url); }
}, (e) => setMessage(`the head did not load: ${e.message}`));
loop();
