// Node half of tools/bench_fbajs.py: decode each file R times with fba.js, print one JSON line each
// with the best and the first CPU time (the first includes V8's warm-up). CPU time, not wall time:
// the machines these run on are shared, and a busy neighbour stretches wall time, not CPU time.
//   node tools/bench_fbajs.mjs R FILE...
import { readFileSync } from "node:fs";
import { decode } from "../mpeg4fa/serve/static/js/fba/fba.js";
import { shownValues } from "../mpeg4fa/serve/static/js/fba/shown.js";

const [reps, ...files] = process.argv.slice(2);
for (const path of files) {
  const bytes = new Uint8Array(readFileSync(path));
  let best = Infinity, first = null, frames = 0, bestShown = Infinity;
  for (let i = 0; i < Number(reps); i++) {
    const t0 = process.cpuUsage();
    const s = decode(bytes);
    const d0 = process.cpuUsage(t0);
    const dt = (d0.user + d0.system) / 1000;
    const t1 = process.cpuUsage();
    shownValues(s.frames);
    const d1 = process.cpuUsage(t1);
    bestShown = Math.min(bestShown, (d1.user + d1.system) / 1000);
    if (first === null) first = dt;
    best = Math.min(best, dt);
    frames = s.frames.length;
  }
  process.stdout.write(JSON.stringify({ path, frames, best_s: best / 1000, first_s: first / 1000,
    shown_best_s: bestShown / 1000 }) + "\n");
}
