// Node half of tools/bench_fbajs.py: a process that decodes files with fba.js on request, so that the
// Python half can take turns with it call by call (a busy spell on a shared machine then hits both).
// Requests on stdin, one JSON line each: {"path": FILE, "calls": N, "arrays": BOOL}; answers on stdout,
// one JSON line each: {path, frames, value_sum, times_s (N calls), shown_times_s}. With "arrays", each
// timed call also makes every frame's four typed arrays (fba.js makes them on first read). The N calls run back to back with
// nothing between them that allocates (each pays for the garbage of the one before, as a decoder in a
// page would); then the checks (frame count and last time of every call; the sum of every FAP value
// of the last call, every value read) and shown.js on the last call's frames, timed apart.
// CPU time, not wall time: the machines these run on are shared, and a busy neighbour stretches wall
// time, not CPU time. The process's CPU time counts V8's helper threads (GC, compiler) too.
//   node tools/bench_fbajs.mjs < requests
import { readFileSync } from "node:fs";
import { createInterface } from "node:readline";
import { decode } from "../mpeg4fa/serve/static/js/fba/fba.js";
import { shownValues } from "../mpeg4fa/serve/static/js/fba/shown.js";

const cpuSeconds = (since) => { const d = process.cpuUsage(since); return (d.user + d.system) / 1e6; };
const files = new Map();

/** Every frame's fapMask, fapValues, viseme and expression made (their lengths summed, so that they are). */
function makeArrays(frames) {
  let n = 0;
  for (const f of frames) n += f.fapMask.length + f.fapValues.length + f.viseme.length + f.expression.length;
  return n;
}

function measure(path, n, arrays) {
  if (!files.has(path)) files.set(path, new Uint8Array(readFileSync(path)));
  const bytes = files.get(path);
  const times = new Float64Array(n), counts = new Int32Array(n), ends = new Float64Array(n);
  let s = null;
  for (let i = 0; i < n; i++) {
    const t0 = process.cpuUsage();
    s = decode(bytes);
    if (arrays && makeArrays(s.frames) !== s.frames.length * 146) throw new Error("a frame's arrays are short");
    times[i] = cpuSeconds(t0);
    counts[i] = s.frames.length;
    ends[i] = s.frames[s.frames.length - 1].timestamp;
  }
  if (counts.some((c) => c !== counts[0]) || ends.some((t) => t !== ends[0])) throw new Error("the calls decoded differently");
  let valueSum = 0;
  for (const f of s.frames) for (let j = 0; j < f.fapValues.length; j++) valueSum += f.fapValues[j];
  const t1 = process.cpuUsage();
  shownValues(s.frames);
  const shown = cpuSeconds(t1);
  return { path, frames: counts[0], value_sum: valueSum, times_s: Array.from(times), shown_times_s: [shown] };
}

for await (const line of createInterface({ input: process.stdin })) {
  if (!line.trim()) continue;
  const { path, calls, arrays } = JSON.parse(line);
  process.stdout.write(JSON.stringify(measure(path, calls, Boolean(arrays))) + "\n");
}
