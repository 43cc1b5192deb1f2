// Node half of tools/bench_fbajs.py: decode each file R times with fba.js, print one JSON line each
// with every call's CPU time (the first includes V8's warm-up) and what the calls decoded (frames and
// the sum of every frame's FAP values: the Python half checks both, so both sides did the same work).
// CPU time, not wall time: the machines these run on are shared, and a busy neighbour stretches wall
// time, not CPU time. The process's CPU time counts V8's helper threads (GC, compiler) too.
//   node tools/bench_fbajs.mjs R FILE...
import { readFileSync } from "node:fs";
import { decode } from "../mpeg4fa/serve/static/js/fba/fba.js";
import { shownValues } from "../mpeg4fa/serve/static/js/fba/shown.js";

const cpuSeconds = (since) => { const d = process.cpuUsage(since); return (d.user + d.system) / 1e6; };

const [reps, ...files] = process.argv.slice(2);
for (const path of files) {
  const bytes = new Uint8Array(readFileSync(path));
  const times = [], shownTimes = [];
  let frames = -1, valueSum = 0;
  for (let i = 0; i < Number(reps); i++) {
    const t0 = process.cpuUsage();
    const s = decode(bytes);
    times.push(cpuSeconds(t0));
    const t1 = process.cpuUsage();
    shownValues(s.frames);
    shownTimes.push(cpuSeconds(t1));
    // outside the timing: every call must have decoded the whole stream, its values there to read
    let sum = 0;
    for (const f of s.frames) for (let j = 0; j < f.fapValues.length; j++) sum += f.fapValues[j];
    if (frames !== -1 && (s.frames.length !== frames || sum !== valueSum)) throw new Error(`call ${i} decoded differently`);
    frames = s.frames.length;
    valueSum = sum;
  }
  process.stdout.write(JSON.stringify({ path, frames, value_sum: valueSum, times_s: times,
    shown_times_s: shownTimes }) + "\n");
}
