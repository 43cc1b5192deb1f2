// Validate a glTF/GLB file with the Khronos glTF validator; print its JSON report on stdout.
// usage: node tools/npm/validate_gltf.mjs FILE.glb   (exit 0 when the report was made, 2 on bad usage)
import { readFile } from "node:fs/promises";
import validator from "gltf-validator";

const file = process.argv[2];
if (!file) {
    console.error("usage: node validate_gltf.mjs FILE.glb");
    process.exit(2);
}
const data = new Uint8Array(await readFile(file));
const report = await validator.validateBytes(data, {
    uri: file,
    maxIssues: 0,  // every issue
    externalResourceFunction: () => Promise.reject(new Error("external resources are not allowed")),
});
process.stdout.write(JSON.stringify(report, null, 1));
