// The Tables card: tabulate the material being edited (POST /v1/tables, a job when the table
// is new) and show what the table holds. The card builds its own markup, so the page's
// index.html only loads this file.
import { api, modelSpec } from "./app.js";

const $ = (id) => document.getElementById(id);
const GRIDS = {
  "4x8x5": { n_theta_i: 4, n_theta_o: 8, n_phi: 5 },
  "8x16x9": { n_theta_i: 8, n_theta_o: 16, n_phi: 9 },
  "12x24x13": { n_theta_i: 12, n_theta_o: 24, n_phi: 13 },
};

function card() {
  const el = document.createElement("article");
  el.className = "card wide";
  el.id = "tables-card";
  el.innerHTML = `
    <h2>Table <small>the material being edited, tabulated as a job (the server's table cache)</small></h2>
    <form id="tables-form">
      <label>Grid θi × θo × φ <select id="tables-grid">
        ${Object.keys(GRIDS).map((g) => `<option value="${g}">${g.replaceAll("x", " × ")}</option>`).join("")}
      </select></label>
      <label>Method <select id="tables-method">
        <option value="auto">auto (adding-doubling where it covers the model)</option>
        <option value="adding-doubling">adding-doubling</option><option value="pfmc">PFMC (Monte Carlo)</option>
      </select></label>
      <label>Target relative error <select id="tables-error">
        <option value="0.05">5 %</option><option value="0.02" selected>2 %</option><option value="0.01">1 %</option>
      </select></label>
      <button id="tables-button" type="submit">Tabulate</button>
    </form>
    <p id="tables-status" class="muted small" role="status"></p>
    <dl id="tables-result" class="small" hidden></dl>`;
  return el;
}

function request() {
  return { ...modelSpec(), grid: GRIDS[$("tables-grid").value], method: $("tables-method").value,
    rel_error: +$("tables-error").value };
}

function show(table) {
  const rows = [
    ["hash", table.hash],
    ["model", table.model.type],
    ["method", table.meta.method || "pfmc"],
    ["channels", table.channels.join(" ")],
    ["lobes", table.lobes.join(", ")],
    ["luminance error (p95 / target)", `${(100 * table.error.p95).toFixed(2)} % / ${(100 * table.rel_error_target).toFixed(1)} %`],
    ["walks per cell (mean)", table.samples.mean.toFixed(0)],
    ["size", `${(table.bytes / 1024).toFixed(1)} KiB`],
  ];
  const dl = $("tables-result");
  dl.replaceChildren(...rows.flatMap(([name, value]) => {
    const dt = document.createElement("dt");
    dt.textContent = name;
    const dd = document.createElement("dd");
    dd.textContent = value;
    dd.dataset.field = name;
    return [dt, dd];
  }));
  const link = document.createElement("a");
  link.href = table.links.file;
  link.textContent = "download (OpenEXR)";
  dl.append(link);
  dl.hidden = false;
  document.body.dataset.tableHash = table.hash;
}

function follow(job) {
  return new Promise((resolve, reject) => {
    const source = new EventSource(job.links.events);
    source.addEventListener("progress", (e) => {
      const j = JSON.parse(e.data);
      $("tables-status").textContent = `${j.state} · ${Math.round(100 * j.progress)}% · ${j.elapsed_s.toFixed(1)} s`;
    });
    source.addEventListener("done", () => { source.close(); resolve(); });
    for (const name of ["failed", "cancelled"]) {
      source.addEventListener(name, (e) => {
        source.close();
        const j = JSON.parse(e.data);
        reject(new Error(`${name}${j.error ? ": " + j.error : ""}`));
      });
    }
  });
}

async function tabulate(event) {
  event.preventDefault();
  $("tables-button").disabled = true;
  $("tables-result").hidden = true;
  $("tables-status").textContent = "submitting…";
  try {
    const { status: code, data } = await api("/v1/tables", request());
    if (code === 202) {
      await follow(data);
      show((await api(`/v1/tables/${data.hash}`)).data);
      $("tables-status").textContent = "tabulated";
    } else {
      show(data);
      $("tables-status").textContent = "from the table cache (made before)";
    }
  } catch (e) {
    $("tables-status").textContent = e.message;
  } finally {
    $("tables-button").disabled = false;
  }
}

function start() {
  const views = $("views");
  if (!views || $("tables-card")) return;
  views.append(card());
  $("tables-form").addEventListener("submit", tabulate);
}

start();
