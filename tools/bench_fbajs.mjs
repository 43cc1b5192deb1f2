// Node half of tools/bench_fbajs.py: decode each file R times with fba.js, print one JSON line each
// with every call's CPU time (the first includes V8's warm-up) and what the calls decoded (frames and
// the sum of every frame's FAP values: the Python half checks both, so both sides did the same work).
// CPU time, not wall time: the machines these run on are shared, and a busy neighbour stretches wall
// time, not CPU time. The process's CPU time counts V8's helper threads (GC, compiler) too. The timed
// calls run back to back, with nothing between them that allocates (each pays for the garbage of the
// one before, as a decoder in a page would); the checks and shown.js's timing come after them.
//   node tools/bench_fbajs.mjs R FILE...   (R calls per file, all reported: the caller drops V8's warm-up)
import { readFileSync } from "node:fs";
import { decode } from "../mpeg4fa/serve/static/js/fba/fba.js";
import { shownValues } from "../mpeg4fa/serve/static/js/fba/shown.js";

const cpuSeconds = (since) => { const d = process.cpuUsage(since); return (d.user + d.system) / 1e6; };

const [reps, ...files] = process.argv.slice(2);
for (const path of files) {
  const bytes = new Uint8Array(readFileSync(path));
  const n = Number(reps), times = new Float64Array(n), counts = new Int32Array(n), ends = new Float64Array(n);
  let s = null;
  for (let i = 0; i < n; i++) {
    const t0 = process.cpuUsage();
    s = decode(bytes);
    times[i] = cpuSeconds(t0);
    counts[i] = s.frames.length;
    ends[i] = s.frames[s.frames.length - 1].timestamp;
  }
  if (counts.some((c) => c !== counts[0]) || ends.some((t) => t !== ends[0])) throw new Error("the calls decoded differently");
  let valueSum = 0;  // the last call's values, every one read
  for (const f of s.frames) for (let j = 0; j < f.fapValues.length; j++) valueSum += f.fapValues[j];
  const shownTimes = [];
  for (let i = 0; i < n; i++) {
    const t1 = process.cpuUsage();
    shownValues(s.frames);
    shownTimes.push(cpuSeconds(t1));
  }
  process.stdout.write(JSON.stringify({ path, frames: counts[0], value_sum: valueSum, times_s: Array.from(times),
    shown_times_s: shownTimes }) + "\n");
}
