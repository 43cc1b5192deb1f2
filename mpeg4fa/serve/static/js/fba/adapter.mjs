#!/usr/bin/env node
// fba.js behind the conformance suite's decoder protocol (conformance/README.md):
//   node adapter.mjs STREAM OUT.json [--fdp FDP]
// Exit 0: decoded, OUT holds {timestamps, shown, sent}. Exit 1: the stream is refused; stderr names
// the bit, and OUT holds the frames decoded before the fault (if any). Exit 3: anything else.
// Feature points are not reported (the FDP is accepted and not used), so those checks read
// "not supported".
import { readFileSync, renameSync, writeFileSync } from "node:fs";
import { decode, FbaError } from "./fba.js";
import { shownValues } from "./shown.js";

function output(stream) {
  const frames = stream.frames;
  const rows = (key) => frames.map((f) => Array.from(f[key]));
  return {
    timestamps: frames.map((f) => f.timestamp),
    shown: shownValues(frames).map((row) => Array.from(row)),
    sent: { mask: rows("fapMask"), values: rows("fapValues"), viseme: rows("viseme"), expression: rows("expression") },
  };
}

function write(path, doc) {
  const tmp = `${path}.part`;
  writeFileSync(tmp, JSON.stringify(doc));
  renameSync(tmp, path);
}

function main(argv) {
  const args = argv.filter((a, i) => a !== "--fdp" && argv[i - 1] !== "--fdp");
  if (args.length !== 2) {
    process.stderr.write("usage: node adapter.mjs STREAM OUT.json [--fdp FDP]\n");
    return 2;
  }
  const [stream, out] = args;
  let bytes;
  try {
    bytes = readFileSync(stream);
  } catch (e) {
    process.stderr.write(`rejected: cannot read stream file ${stream}: ${e.message}\n`);
    return 1;
  }
  try {
    write(out, output(decode(bytes)));
    return 0;
  } catch (e) {
    if (!(e instanceof FbaError)) {
      process.stderr.write(`crash: ${e && e.name}: ${e && e.message}\n`);
      return 3;
    }
    if (e.partial && e.partial.frames.length) {
      try { write(out, output(e.partial)); } catch { /* the refusal is the answer */ }
    }
    process.stderr.write(`rejected: ${e.toString()}\n`);
    return 1;
  }
}

process.exitCode = main(process.argv.slice(2));
