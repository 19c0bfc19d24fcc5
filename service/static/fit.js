// The Fit card: data files -> POST /v1/fits/datasets (by hash), the config as JSON ->
// POST /v1/fits (a job), progress over server-sent events, the study's files as links.
// Self-contained (its own requests), so the page's other cards are untouched.

const $ = (id) => document.getElementById(id);
const fit = { job: null, source: null };

// a small smooth-model study: minutes at most on the example data (docs/fit.md)
const EXAMPLE_CONFIG = {
  parameters: {
    film_thickness_nm: { prior: "normal", mean: 430.0, sd: 10.0 },
    film_ior: { prior: "normal", mean: 1.83, sd: 0.02 },
  },
  model: { thickness_nodes: 1 },
  sampler: { walkers: 8, max_steps: 200, check_every: 50, map_starts: 1 },
  appearance: { draws: 4, renders: 0, angles_deg: [0, 30] },
};

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

function done() {
  $("fit-button").disabled = false;
  $("fit-cancel").hidden = true;
  if (fit.source) fit.source.close();
  fit.source = null;
}

async function showStudy(hash) {
  const { data } = await call(`/v1/fits/${hash}`);
  $("fit-progress").style.width = "100%";
  const list = $("fit-files");
  list.replaceChildren(...data.files.map((name) => {
    const a = document.createElement("a");
    a.href = data.links[name];
    a.textContent = name;
    a.target = "_blank";
    const li = document.createElement("li");
    li.append(a);
    return li;
  }));
  const mean = data.summary.posterior_mean || {};
  $("fit-summary").textContent = data.summary.free
    .map((n) => `${n} = ${Number(mean[n]).toPrecision(5)}`).join(" · ")
    + ` (${data.summary.converged ? "converged" : "not converged"})`;
  const corner = $("fit-corner");
  corner.src = data.links["corner.png"];
  corner.hidden = false;
  $("fit-out").dataset.hash = hash;
}

function follow(job) {
  fit.job = job;
  $("fit-cancel").hidden = false;
  const source = new EventSource(job.links.events);
  fit.source = source;
  source.addEventListener("progress", (e) => {
    const j = JSON.parse(e.data);
    $("fit-progress").style.width = `${Math.round(100 * j.progress)}%`;
    say(`${j.state} · ${Math.round(100 * j.progress)}% · ${j.elapsed_s.toFixed(1)} s`);
  });
  source.addEventListener("done", async (e) => {
    const j = JSON.parse(e.data);
    done();
    say(`done in ${j.elapsed_s.toFixed(1)} s`);
    await showStudy(j.hash).catch((err) => say(err.message));
  });
  for (const name of ["failed", "cancelled"]) {
    source.addEventListener(name, (e) => {
      const j = JSON.parse(e.data);
      say(`${name}${j.error ? ": " + j.error : ""}`);
      done();
    });
  }
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) done(); };
}

async function startFit(event) {
  event.preventDefault();
  const files = [...$("fit-data").files];
  if (!files.length) { say("choose the data files first"); return; }
  let config, sidecar = null;
  try {
    config = JSON.parse($("fit-config").value);
    if ($("fit-sidecar").value.trim()) sidecar = JSON.parse($("fit-sidecar").value);
  } catch (e) { say(`not JSON: ${e.message}`); return; }
  $("fit-button").disabled = true;
  $("fit-corner").hidden = true;
  $("fit-files").replaceChildren();
  $("fit-summary").textContent = "";
  $("fit-progress").style.width = "0";
  try {
    const data = [];
    for (const file of files) {
      say(`uploading ${file.name}…`);
      const { data: up } = await call(`/v1/fits/datasets?name=${encodeURIComponent(file.name)}`,
        { method: "POST", headers: { "Content-Type": "application/octet-stream" }, body: file });
      data.push({ hash: up.hash, name: file.name });
    }
    say("submitting…");
    const { status: code, data: answer } = await call("/v1/fits", {
      method: "POST", headers: { "Content-Type": "application/json" },
      body: JSON.stringify({ config, data, sidecar }),
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

$("fit-config").value = JSON.stringify(EXAMPLE_CONFIG, null, 1);
$("fit-form").addEventListener("submit", startFit);
$("fit-cancel").addEventListener("click", cancelFit);
