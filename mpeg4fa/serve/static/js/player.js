// The live player: the head (GLB with ARKit-named morph targets) in three.js, moved by the per-frame ARKit
// weights the server sends (mpeg4fa/serve/protocol.py), the speech through WebAudio. Frames and audio chunks
// carry media times; both are placed on the AudioContext's clock (media time 0 plays at `base`), so mouth
// and voice stay together whatever the network does. Buffer reports go back every 100 ms: the server sends
// no more than its window ahead of our playhead. The page does not decode the FBA bitstream itself (the
// server's weights are the decoded stream's); it keeps each segment's bytes, counted in the status.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const PREBUFFER = 0.3;   // s of media held before playing starts
const REPORT_MS = 100;
const AUDIO = "AUD1", FBA = "FBA1";

const view = document.getElementById("view");
const statusBox = document.getElementById("status");
const caption = document.getElementById("caption");
const speakButton = document.getElementById("speak");

const state = {            // read by the browser test (window.player)
  ready: false, hello: null, units: [], frames: [], audioChunks: 0, fbaBytes: 0, segments: [],
  shown: -1, shownFrames: 0, latencyMs: null, underruns: 0, done: null, errors: [], reports: 0,
  weightsNow: [], mediaTime: 0, clock: "none", received: 0, maxAhead: 0,
};
window.player = state;

// ---- the scene ----
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
renderer.setClearColor(0x2b2f36);
renderer.outputColorSpace = THREE.SRGBColorSpace;
view.prepend(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 100);
scene.add(new THREE.HemisphereLight(0xffffff, 0x505050, 1.8));
const key = new THREE.DirectionalLight(0xffffff, 1.8);
key.position.set(0.4, 0.6, 1.0);
camera.add(key);
scene.add(camera);
const controls = new OrbitControls(camera, renderer.domElement);
let targets = [];          // per morphing mesh: {mesh, index: unit -> morph slot or -1}

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener("resize", resize);

new GLTFLoader().load("/head.glb", (gltf) => {
  scene.add(gltf.scene);
  const box = new THREE.Box3().setFromObject(gltf.scene);
  const size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
  const face = new THREE.Vector3(centre.x, centre.y + 0.1 * size.y, centre.z);  // the face, not the neck
  camera.position.set(face.x, face.y, face.z + 2.6 * Math.max(size.x, size.y));
  controls.target.copy(face);
  controls.update();
  gltf.scene.traverse((o) => { if (o.isMesh && o.morphTargetDictionary) targets.push({ mesh: o, index: [] }); });
  mapUnits();
  state.ready = true;
  speakButton.disabled = false;
  setStatus();
}, undefined, (err) => { state.errors.push({ error: String(err), where: "head.glb" }); setStatus(); });

function mapUnits() {
  for (const t of targets) t.index = state.units.map((name) => t.mesh.morphTargetDictionary[name] ?? -1);
}

// ---- the clock: the AudioContext's when it runs, else the page's ----
let audio = null, base = null, t0wall = null;
function now() {
  if (audio && audio.state === "running") return audio.currentTime - (audio.outputLatency || 0);
  return performance.now() / 1000;
}
function mediaTime() { return base === null ? -Infinity : now() - base; }
function startClock() {
  if (base === null) { base = now() + PREBUFFER; state.clock = audio && audio.state === "running" ? "audio" : "page"; }
}

// ---- the connection ----
let ws = null, sayAt = 0, nextFbaFor = null, rate = 22050;
function connect() {
  ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = "arraybuffer";
  ws.onmessage = (e) => (typeof e.data === "string" ? onText(JSON.parse(e.data)) : onBinary(e.data));
  ws.onclose = () => { ws = null; setStatus(); };
  return new Promise((resolve) => { ws.onopen = resolve; });
}

function onText(m) {
  if (m.type === "hello") { state.hello = m; state.units = m.units; mapUnits(); }
  else if (m.type === "segment") { state.segments.push(m); rate = m.rate; nextFbaFor = m; caption.textContent = m.text; }
  else if (m.type === "frames") {
    if (state.latencyMs === null) state.latencyMs = performance.now() - sayAt;
    startClock();
    if (m.times[0] < mediaTime()) state.underruns++;
    for (let i = 0; i < m.times.length; i++) state.frames.push({ t: m.times[i], w: m.weights[i] });
    received(m.times[m.times.length - 1] + 1 / state.hello.fps);
  } else if (m.type === "done") { state.done = m; }
  else if (m.type === "error") { state.errors.push(m); }
  setStatus();
}

function onBinary(buffer) {
  const head = new DataView(buffer, 0, 12);
  const kind = String.fromCharCode(head.getUint8(0), head.getUint8(1), head.getUint8(2), head.getUint8(3));
  const t = head.getFloat64(4, true);
  if (kind === FBA) { state.fbaBytes += buffer.byteLength - 12; nextFbaFor = null; return; }
  if (kind !== AUDIO) return;
  const pcm = new Int16Array(buffer, 12, (buffer.byteLength - 12) >> 1);
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

function received(end) {
  state.received = Math.max(state.received, end);
  state.maxAhead = Math.max(state.maxAhead, state.received - Math.max(0, mediaTime()));
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
  Object.assign(state, { frames: [], segments: [], audioChunks: 0, fbaBytes: 0, shown: -1, shownFrames: 0,
                         latencyMs: null, underruns: 0, done: null, received: 0, maxAhead: 0 });
  base = null;
  sayAt = performance.now();
  ws.send(JSON.stringify({ type: "say", text: document.getElementById("text").value }));
}
speakButton.addEventListener("click", speak);
document.getElementById("stop").addEventListener("click", () => ws && ws.send(JSON.stringify({ type: "stop" })));
connect();

// ---- drawing: the latest frame whose time has come ----
function apply(weights) {
  state.weightsNow = weights;
  for (const t of targets) {
    const influences = t.mesh.morphTargetInfluences;
    for (let u = 0; u < t.index.length; u++) if (t.index[u] >= 0) influences[t.index[u]] = weights[u];
  }
}

function frame() {
  requestAnimationFrame(frame);
  const m = mediaTime();
  state.mediaTime = m;
  let k = state.shown;
  while (k + 1 < state.frames.length && state.frames[k + 1].t <= m) k++;
  if (k !== state.shown) { state.shown = k; state.shownFrames++; apply(state.frames[k].w); }
  if (state.done && k === state.frames.length - 1 && m > state.done.duration && state.weightsNow.some((w) => w)) {
    apply(state.weightsNow.map(() => 0));  // back to rest after the last frame's time
  }
  if (renderer.domElement.width !== Math.round(view.clientWidth * renderer.getPixelRatio())) resize();
  renderer.render(scene, camera);
}
resize();
frame();

function setStatus() {
  const s = state;
  statusBox.textContent = [
    s.ready ? `head: ${targets.length} morphing meshes, ${s.units.length} units` : "loading the head…",
    ws ? "connected" : "not connected",
    `frames ${s.frames.length} (shown ${s.shownFrames}), audio chunks ${s.audioChunks}, FBA ${s.fbaBytes} bytes in ${s.segments.length} segments`,
    `first frame ${s.latencyMs === null ? "-" : s.latencyMs.toFixed(0) + " ms"}, underruns ${s.underruns}, clock ${s.clock}`,
    s.done ? `done: ${s.done.duration.toFixed(2)} s${s.done.stopped ? " (stopped)" : ""}` : "",
    ...s.errors.slice(-2).map((e) => `error (${e.where}): ${e.error}`),
  ].filter(Boolean).join("\n");
}
setInterval(setStatus, 250);
