// The Fit card: data files -> POST /v1/fits/datasets (by hash), the config as JSON ->
// POST /v1/fits (a job), progress over server-sent events (polled with an API key), then the
// study: its parameters, predictive checks, warnings, figures and files. Self-contained (its
// own requests), so the page's other cards are untouched. The examples are fit_examples.json
// (examples/fit/).

const $ = (id) => document.getElementById(id);
const fit = { job: null, source: null, examples: [] };
const FINISHED = ["done", "failed", "cancelled"];
const POLL_MS = 500;

function key() {
  const input = $("api-key");
  return input && input.value ? { "X-API-Key": input.value } : {};
}

async function call(path, init) {
  const response = await fetch(path, { ...init, headers: { ...key(), ...(init && init.headers) } });
  const data = await response.json().catch(() => ({}));
  if (!response.ok) {
    const detail = typeof data.detail === "string" ? data.detail : JSON.stringify(data.detail);
    throw new Error(`${response.status}: ${detail}`);
  }
  return { status: response.status, data };
}

function say(text) { $("fit-status").textContent = text; }

const fmt = (x) => (typeof x === "number" && Number.isFinite(x) ? x.toPrecision(5) : "–");

function done() {
  $("fit-button").disabled = false;
  $("fit-cancel").hidden = true;
  if (fit.source) fit.source.close();
  fit.source = null;
}

function clearStudy() {
  for (const id of ["fit-corner", "fit-predictive", "fit-parameters", "fit-checks", "fit-warnings"]) $(id).hidden = true;
  for (const id of ["fit-corner", "fit-predictive"]) {
    if ($(id).src.startsWith("blob:")) URL.revokeObjectURL($(id).src);   // the last study's, fetched with a key
  }
  $("fit-parameters").tBodies[0].replaceChildren();
  $("fit-warnings").replaceChildren();
  $("fit-files").replaceChildren();
  $("fit-summary").textContent = "";
  $("fit-checks").textContent = "";
  $("fit-progress").style.width = "0";
  delete $("fit-out").dataset.hash;
}

function cells(tag, values) {
  const tr = document.createElement("tr");
  tr.append(...values.map((v) => { const c = document.createElement(tag); c.textContent = v; return c; }));
  return tr;
}

// a structure study's table (summary.parameters: median, 90 % interval, MAP); the snake
// study's brief carries its posterior means instead
function showParameters(s) {
  if (!Array.isArray(s.parameters)) {
    const mean = s.posterior_mean || {};
    return s.free.map((n) => `${n} = ${fmt(mean[n])}`).join(" · ");
  }
  $("fit-parameters").tBodies[0].replaceChildren(...s.parameters.map((r) => cells("td", [
    r.parameter, r.unit || "", fmt(r.median), `[${fmt(r.ci90_low)}, ${fmt(r.ci90_high)}]`, fmt(r.map)])));
  $("fit-parameters").hidden = false;
  const facts = [`${s.rows} rows`];
  if (s.datasets) facts.push(`datasets ${s.datasets.join(", ")}`);
  if (s.steps) facts.push(`${s.steps} steps`);
  if (s.emulator) facts.push(`emulator of ${s.emulator.solves} solves, error up to ${fmt(s.emulator.max_error_sigma)} σ`);
  return `${s.model} study · ${facts.join(" · ")}`;
}

function showChecks(checks) {
  if (!checks || !Array.isArray(checks.series)) return;
  const failed = checks.series.filter((c) => c.flagged);
  const list = failed.map((c) => `${c.series} (p = ${c.p_value.toPrecision(2)})`).join("; ");
  $("fit-checks").textContent = `predictive checks (all rows, then each curve): ${failed.length} of `
    + `${checks.series.length} fail (α = ${checks.alpha}, ${checks.level_per_check.toPrecision(2)} per check)`
    + (list ? `: ${list}` : "");
  $("fit-checks").classList.toggle("error", failed.length > 0);
  $("fit-checks").hidden = false;
}

function showWarnings(warnings) {
  const list = $("fit-warnings");
  list.replaceChildren(...(warnings || []).map((w) => {
    const li = document.createElement("li");
    li.textContent = `[${w.code}] ${w.message}`;
    return li;
  }));
  list.hidden = !list.children.length;
}

// An <img> or a link cannot send the API key: with a key the figures are fetched with it and
// shown from blob URLs, and a file opens from one when clicked (as the Validate card's report).
async function blobURL(path) {
  const response = await fetch(path, { headers: key() });
  if (!response.ok) throw new Error(`${response.status}: ${path}`);
  return URL.createObjectURL(await response.blob());
}

function fileLink(name, href) {
  const a = document.createElement("a");
  a.href = href;
  a.textContent = name;
  a.target = "_blank";
  a.addEventListener("click", (e) => {
    if (!Object.keys(key()).length) return;
    e.preventDefault();
    blobURL(href).then((url) => window.open(url, "_blank")).catch((err) => say(err.message));
  });
  const li = document.createElement("li");
  li.append(a);
  return li;
}

async function showStudy(hash) {
  const { data } = await call(`/v1/fits/${hash}`);
  $("fit-progress").style.width = "100%";
  $("fit-files").replaceChildren(...data.files.map((name) => fileLink(name, data.links[name])));
  const s = data.summary;
  $("fit-summary").textContent = `${showParameters(s)} (${s.converged ? "converged" : "not converged"})`;
  showChecks(s.predictive_checks);
  showWarnings(s.warnings);
  for (const [id, name] of [["fit-corner", "corner.png"], ["fit-predictive", "predictive.png"]]) {
    if (!data.links[name]) continue;
    $(id).src = Object.keys(key()).length ? await blobURL(data.links[name]) : data.links[name];
    $(id).hidden = false;
  }
  $("fit-out").dataset.hash = hash;
}

function progressed(j) {
  $("fit-progress").style.width = `${Math.round(100 * j.progress)}%`;
  say(`${j.state} · ${Math.round(100 * j.progress)}% · ${j.elapsed_s.toFixed(1)} s`);
}

async function finished(j) {
  done();
  if (j.state !== "done") { say(`${j.state}${j.error ? ": " + j.error : ""}`); return; }
  say(`done in ${j.elapsed_s.toFixed(1)} s`);
  await showStudy(j.hash).catch((err) => say(err.message));
}

// an EventSource cannot send the API key: with a key the job is polled (its rate is the key's)
async function poll(job) {
  try {
    for (;;) {
      const { data: j } = await call(`/v1/jobs/${job.id}`);
      if (FINISHED.includes(j.state)) { await finished(j); return; }
      progressed(j);
      await new Promise((ok) => setTimeout(ok, POLL_MS));
    }
  } catch (e) {
    say(e.message);
    done();
  }
}

function follow(job) {
  fit.job = job;
  $("fit-cancel").hidden = false;
  if (Object.keys(key()).length) { poll(job); return; }
  const source = new EventSource(job.links.events);
  fit.source = source;
  source.addEventListener("progress", (e) => progressed(JSON.parse(e.data)));
  for (const name of FINISHED) source.addEventListener(name, (e) => finished(JSON.parse(e.data)));
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) done(); };
}

// A [[dataset]] names a chosen file as bsdflab fit names a path (data = "session_a.csv");
// over HTTP it names the upload by hash, so the page swaps the name for the hash. The
// checks run before any upload and name the file, which the server's (by hash) cannot.
function datasetProblem(config, names) {
  if (!Array.isArray(config.dataset)) return null;
  const named = new Set();
  for (const [i, e] of config.dataset.entries()) {
    if (!e || typeof e !== "object" || typeof e.data !== "string") continue;
    if (!names.includes(e.data)) {
      return `config.dataset[${i}].data "${e.data}" is not one of the chosen files (${names.join(", ")})`;
    }
    named.add(e.data);
  }
  if (config.dataset.some((e) => e && typeof e === "object" && "hash" in e)) return null;
  const unnamed = names.filter((n) => !named.has(n));
  return unnamed.length ? `no [[dataset]] names ${unnamed.join(", ")} (data = "<file name>")` : null;
}

function byHash(config, hashes) {
  if (!Array.isArray(config.dataset)) return config;
  const dataset = config.dataset.map((e) => {
    if (!e || typeof e !== "object" || typeof e.data !== "string") return e;
    const { data, ...rest } = e;
    return { ...rest, hash: hashes.get(data) };
  });
  return { ...config, dataset };
}

function parseJSON(text, what) {
  try {
    return JSON.parse(text);
  } catch (e) {
    const toml = /^\s*\[|^\s*[A-Za-z_][\w.]*\s*=/m.test(text) ? " (this looks like TOML: write its tables as JSON objects, or start from an example)" : "";
    throw new Error(`${what} is not JSON: ${e.message}${toml}`);
  }
}

async function startFit(event) {
  event.preventDefault();
  const files = [...$("fit-data").files];
  if (!files.length) { say("choose the data files first"); return; }
  let config, sidecar = null;
  try {
    config = parseJSON($("fit-config").value, "the config");
    if ($("fit-sidecar").value.trim()) sidecar = parseJSON($("fit-sidecar").value, "the sidecar");
  } catch (e) { say(e.message); return; }
  const problem = datasetProblem(config, files.map((f) => f.name));
  if (problem) { say(problem); return; }
  $("fit-button").disabled = true;
  clearStudy();
  try {
    const data = [], hashes = new Map();
    for (const file of files) {
      say(`uploading ${file.name}…`);
      const { data: up } = await call(`/v1/fits/datasets?name=${encodeURIComponent(file.name)}`,
        { method: "POST", headers: { "Content-Type": "application/octet-stream" }, body: file });
      data.push({ hash: up.hash, name: file.name });
      hashes.set(file.name, up.hash);
    }
    say("submitting…");
    const { status: code, data: answer } = await call("/v1/fits", {
      method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ config: byHash(config, hashes), data, sidecar }),
    });
    if (code === 200) {
      done();
      say("from the artefact store (fitted before)");
      await showStudy(answer.hash);
    } else {
      follow(answer);
    }
  } catch (e) {
    say(e.message);
    done();
  }
}

async function cancelFit() {
  if (!fit.job) return;
  await fetch(`/v1/jobs/${fit.job.id}`, { method: "DELETE", headers: key() });
}

function useExample() {
  const ex = fit.examples.find((e) => e.id === $("fit-example").value);
  if (!ex) return;
  $("fit-config").value = JSON.stringify(ex.config, null, 1);
  $("fit-sidecar").value = ex.sidecar ? JSON.stringify(ex.sidecar, null, 1) : "";
  $("fit-example-note").textContent = `For ${ex.files.join(" and ")}: ${ex.note}.`;
}

async function loadExamples() {
  const response = await fetch("/static/fit_examples.json");
  if (!response.ok) { say(`the examples did not load (${response.status})`); return; }
  fit.examples = await response.json();
  $("fit-example").replaceChildren(...fit.examples.map((e) => {
    const option = document.createElement("option");
    option.value = e.id;
    option.textContent = e.label;
    return option;
  }));
  if (!$("fit-config").value) useExample();   // never over what was typed while they loaded
}

$("fit-form").addEventListener("submit", startFit);
$("fit-cancel").addEventListener("click", cancelFit);
$("fit-example").addEventListener("change", useExample);
loadExamples();
