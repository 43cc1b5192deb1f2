// Decode .fba files with fba.js and print one JSON line per file (for the Python tests to compare).
// node tests/js/dump.mjs [--shown] [--chunk N] FILE...   (--shown: + the values shown, shown.js)   (--chunk: feed the bytes N at a time to StreamDecoder)
import { readFileSync } from "node:fs";
import { decode, StreamDecoder, FbaError } from "../../mpeg4fa/serve/static/js/fba/fba.js";
import { shownValues } from "../../mpeg4fa/serve/static/js/fba/shown.js";

const args = process.argv.slice(2);
let chunk = 0, shown = false;
if (args[0] === "--shown") { shown = true; args.splice(0, 1); }
if (args[0] === "--chunk") { chunk = Number(args[1]); args.splice(0, 2); }

function frameJson(f) {
  const sparse = (mask, values) => { const out = []; mask.forEach((m, i) => { if (m) out.push([i, values[i]]); }); return out; };
  return { t: f.timestamp, om: f.objectMask, mask: Array.from(f.fapMask), values: Array.from(f.fapValues),
    viseme: Array.from(f.viseme), expression: Array.from(f.expression), baps: sparse(f.bapMask, f.bapValues),
    skip: f.skip, sc: f.startCode, bits: f.bits, intra: f.params !== null };
}

for (const path of args) {
  const bytes = new Uint8Array(readFileSync(path));
  const frames = [];
  let error = null, osc = null;
  try {
    if (chunk) {
      const dec = new StreamDecoder();
      try {
        for (let i = 0; i < bytes.length; i += chunk) frames.push(...dec.push(bytes.subarray(i, i + chunk)));
        frames.push(...dec.end());
      } finally { osc = dec.objectStartCode; }
    } else {
      const s = decode(bytes);
      frames.push(...s.frames);
      osc = s.objectStartCode;
    }
  } catch (e) {
    if (!(e instanceof FbaError)) throw e;
    if (e.partial) { frames.push(...e.partial.frames); osc = e.partial.objectStartCode; }  // whole: all; pieces: this call's
    error = { message: e.message, bit: e.bitOffset, frame: e.frame, text: e.toString() };
  }
  const doc = { path, osc, frames: frames.map(frameJson), error };
  if (shown) doc.shown = shownValues(frames).map((row) => Array.from(row));
  process.stdout.write(JSON.stringify(doc) + "\n");
}
