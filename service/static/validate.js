// The Validate card: choose a level and families, start a validation job (POST /v1/validations),
// follow its progress (GET /v1/jobs/{id}) and open its self-contained HTML report.
// Its own module: app.js knows nothing of it; it shares only the page's API-key box.

const $ = (id) => document.getElementById(id);
const POLL_MS = 500;

function headers(json = true) {
  const h = json ? { "Content-Type": "application/json" } : {};
  const key = $("api-key") ? $("api-key").value : "";
  if (key) h["X-API-Key"] = key;
  return h;
}

async function call(path, body) {
  const response = await fetch(path, {
    method: body === undefined ? "GET" : "POST", headers: headers(), body: body && JSON.stringify(body),
  });
  const data = await response.json().catch(() => ({}));
  if (!response.ok) {
    const detail = typeof data.detail === "string" ? data.detail : JSON.stringify(data.detail);
    throw new Error(`${response.status}: ${detail}`);
  }
  return { status: response.status, data };
}

function say(text, isError = false) {
  const el = $("validate-status");
  el.textContent = text;
  el.classList.toggle("error", isError);
}

function chosenFamilies() {
  return [...document.querySelectorAll("#validate-families input:checked")].map((b) => b.value);
}

// The report is fetched with the page's key (a plain link could not send it) and opened from a blob URL.
async function showReport(info) {
  const response = await fetch(info.links.html, { headers: headers(false) });
  if (!response.ok) throw new Error(`report: ${response.status}`);
  const url = URL.createObjectURL(await response.blob());
  const link = $("validate-report");
  link.href = url;
  link.hidden = false;
  const s = info.summary;
  say(`done: ${s.pass} pass, ${s.fail} fail, ${s.error} error, ${s.skipped} skipped, ${s.study} studies`,
    info.exit_status !== 0);
  $("validate-progress").style.width = "100%";
}

async function follow(job, hash) {
  const state = { job };
  $("validate-cancel").hidden = false;
  $("validate-cancel").onclick = () => fetch(`/v1/jobs/${job.id}`, { method: "DELETE", headers: headers(false) });
  while (!["done", "failed", "cancelled"].includes(state.job.state)) {
    await new Promise((resolve) => setTimeout(resolve, POLL_MS));
    state.job = (await call(`/v1/jobs/${job.id}`)).data;
    $("validate-progress").style.width = `${Math.round(100 * state.job.progress)}%`;
    say(`${state.job.state} · ${Math.round(100 * state.job.progress)}% · ${state.job.elapsed_s.toFixed(0)} s`);
  }
  $("validate-cancel").hidden = true;
  if (state.job.state !== "done") {
    say(`${state.job.state}${state.job.error ? ": " + state.job.error : ""}`, true);
    return;
  }
  await showReport((await call(`/v1/validations/${hash}`)).data);
}

async function start(event) {
  event.preventDefault();
  const request = { level: $("validate-level").value };
  const families = chosenFamilies();
  if (families.length) request.families = families;
  $("validate-button").disabled = true;
  $("validate-report").hidden = true;
  $("validate-progress").style.width = "0%";
  say("submitting…");
  try {
    const { status, data } = await call("/v1/validations", request);
    if (status === 200) await showReport(data);    // this request ran before: the stored report
    else await follow(data, data.hash);
  } catch (e) {
    say(e.message, true);
  } finally {
    $("validate-button").disabled = false;
  }
}

function build(card, families) {
  card.innerHTML = `
    <h2>Validate <small>the report of <code>bsdflab validate</code>, as a job</small></h2>
    <form id="validate-form" class="validate-form">
      <label>Level <select id="validate-level">
        <option value="quick" selected>quick</option><option value="standard">standard</option>
        <option value="full">full</option></select></label>
      <fieldset id="validate-families"><legend>Families <small>(none ticked: all)</small></legend></fieldset>
      <button id="validate-button" type="submit">Run validation</button>
      <button id="validate-cancel" type="button" hidden>Cancel</button>
    </form>
    <div class="progress"><div id="validate-progress"></div></div>
    <p id="validate-status" class="muted small" role="status"></p>
    <a id="validate-report" target="_blank" rel="noopener" hidden>Open the report</a>`;
  for (const f of families) {
    const label = document.createElement("label");
    label.className = "validate-family";
    const box = document.createElement("input");
    Object.assign(box, { type: "checkbox", value: f.name, name: "family" });
    label.append(box, ` ${f.name} (${f.checks})`);
    $("validate-families").append(label);
  }
  $("validate-form").addEventListener("submit", start);
}

async function init() {
  const card = $("validate-card");
  if (!card) return;
  try {
    build(card, (await call("/v1/validations/families")).data);
  } catch (e) {    // a key may be needed first: build without families, retry when the key changes
    build(card, []);
    say(e.message, true);
    if ($("api-key")) $("api-key").addEventListener("change", () => init(), { once: true });
  }
}

init();
