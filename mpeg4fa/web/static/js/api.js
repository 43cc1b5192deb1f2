// The editor's calls to its JSON API. A fault ({"error", "where"}) is shown in the status bar and thrown.
const bar = () => document.getElementById("status");
let pending = 0;

export class ApiError extends Error {
  constructor(error, where, status) {
    super(`${where}: ${error}`);
    this.error = error; this.where = where; this.status = status;
  }
}

export function setStatus(text, kind = "info") {
  const el = bar();
  if (!el) return;
  el.textContent = text;
  el.dataset.kind = kind;
  el.className = `status ${kind}`;
}

function busy(delta) {
  pending += delta;
  document.body.dataset.busy = pending > 0 ? "1" : "0";
}

async function answer(response) {
  let body = null;
  try { body = await response.json(); } catch { body = null; }
  if (!response.ok) {
    const error = body && body.error ? body.error : `HTTP ${response.status}`;
    const where = body && body.where ? body.where : response.url;
    throw new ApiError(error, where, response.status);
  }
  return body;
}

// GET when body is undefined, else POST it as JSON. quiet: do not show a fault in the status bar.
export async function api(path, body, { quiet = false } = {}) {
  busy(+1);
  try {
    const init = body === undefined ? {} : {
      method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(body),
    };
    return await answer(await fetch(path, init));
  } catch (e) {
    if (!quiet) setStatus(e instanceof ApiError ? `error in ${e.where}: ${e.error}` : `error: ${e.message}`, "error");
    throw e;
  } finally {
    busy(-1);
  }
}

// One model file and its companions (a .gltf's .bin and images; NAME.points.json / NAME.parts.json of an OBJ
// saved by the editor), all in one request: the server finds each by name among them.
export async function upload(files) {
  busy(+1);
  try {
    const form = new FormData();
    for (const file of files) form.append("file", file, file.name);
    return await answer(await fetch("/api/upload", { method: "POST", body: form }));
  } catch (e) {
    setStatus(e instanceof ApiError ? `error in ${e.where}: ${e.error}` : `error: ${e.message}`, "error");
    throw e;
  } finally {
    busy(-1);
  }
}
