// Pose a head with facerig.js: node tests/js/pose_rig.mjs RIG.json ROWS.json -> OUT (float64 vertices, one row per pose)
import { readFileSync, writeFileSync } from "node:fs";
import { FaceRig } from "../../mpeg4fa/serve/static/js/facerig.js";

const [rigPath, rowsPath, outPath] = process.argv.slice(2);
const rig = new FaceRig(JSON.parse(readFileSync(rigPath, "utf8")));
const rows = JSON.parse(readFileSync(rowsPath, "utf8"));
const out = new Float64Array(rows.length * rig.rest.length);
const t0 = performance.now();
rows.forEach((row, k) => out.set(rig.pose(row), k * rig.rest.length));
const ms = (performance.now() - t0) / rows.length;
writeFileSync(outPath, Buffer.from(out.buffer));
console.log(JSON.stringify({ poses: rows.length, ms_per_pose: ms }));
