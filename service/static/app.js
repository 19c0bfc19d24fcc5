// The lobe explorer: controls -> the bsdflab HTTP API -> plotly.js figures.
// All numbers come from the API; this file only arranges requests and pictures.
/* global Plotly */

const $ = (id) => document.getElementById(id);
const SLIDERS = ["theta_i", "film_thickness_nm", "film_ior", "pigment_absorption", "roughness"];
const MODEL_PARAMS = ["film_thickness_nm", "film_ior", "pigment_absorption", "roughness", "base_albedo"];
const SWATCH_ANGLES = Array.from({ length: 18 }, (_, i) => 5 * i);
const CHANNEL_COLOURS = ["#ff5a5a", "#4cd07d", "#5a9cff"];
const FONT = { color: "#cfd6e4", family: "Inter, system-ui, sans-serif", size: 12 };
const BASE_LAYOUT = {
  paper_bgcolor: "rgba(0,0,0,0)", plot_bgcolor: "rgba(0,0,0,0)", font: FONT,
  margin: { l: 48, r: 16, t: 12, b: 40 }, showlegend: true,
  legend: { orientation: "h", x: 0, y: -0.18, font: { size: 11 } },
};
// matplotlib's "inferno" at 9 stops (plotly.js has no inferno of its own)
const INFERNO = ["#000004", "#1f0c48", "#550f6d", "#88226a", "#ba3655", "#e35933", "#f98e09", "#f5c72b", "#fcffa4"]
  .map((c, i, all) => [i / (all.length - 1), c]);
const DECADES = 3;   // the heat map shows the top three decades of luminance
const CONFIG = { displaylogo: false, responsive: true, modeBarButtonsToRemove: ["lasso2d", "select2d"] };

const state = { presets: {}, preset: null, lobeRequest: null, filmRequest: null, source: null, job: null };

// -- talking to the API ----------------------------------------------------------------------
function headers() {
  const h = { "Content-Type": "application/json" };
  const key = $("api-key").value;
  if (key) h["X-API-Key"] = key;
  return h;
}

export async function api(path, body, signal, retries = 3) {
  const response = await fetch(path, {
    method: body === undefined ? "GET" : "POST", headers: headers(),
    body: body === undefined ? undefined : JSON.stringify(body), signal,
  });
  if (response.status === 429 && retries > 0) {   // busy: again after the server's Retry-After
    await new Promise((ok) => setTimeout(ok, 1000 * Math.min(30, +response.headers.get("Retry-After") || 1)));
    return api(path, body, signal, retries - 1);
  }
  const data = await response.json().catch(() => ({}));
  if (!response.ok) {
    const detail = typeof data.detail === "string" ? data.detail : JSON.stringify(data.detail);
    throw new Error(`${response.status}: ${detail}`);
  }
  return { status: response.status, data };
}

function status(text, isError = false) {
  const el = $("status");
  el.textContent = text;
  el.classList.toggle("error", isError);
}

// -- controls ---------------------------------------------------------------------------------
const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055);

function hexToLinear(hex) {
  return [1, 3, 5].map((i) => +srgbToLinear(parseInt(hex.slice(i, i + 2), 16) / 255).toFixed(4));
}

function linearToHex(rgb) {
  return "#" + rgb.map((c) => Math.round(255 * Math.min(1, Math.max(0, linearToSrgb(c))))
    .toString(16).padStart(2, "0")).join("");
}

function showValue(input) {
  const out = input.closest(".control").querySelector("output");
  if (input.type === "color") {
    out.textContent = hexToLinear(input.value).map((c) => c.toFixed(3)).join(", ");
  } else {
    out.textContent = `${(+input.value).toFixed(input.step.includes(".") ? 2 : 0)}${input.dataset.unit}`;
  }
}

function applyPreset(name) {
  const preset = state.presets[name];
  state.preset = name;
  $("preset-description").textContent = preset.description;
  for (const param of MODEL_PARAMS) {
    const input = $(param);
    const control = input.closest(".control");
    const has = param in preset.parameters;
    control.classList.toggle("disabled", !has);
    input.disabled = !has;
    if (has) {
      const value = preset.parameters[param];
      input.value = param === "base_albedo" ? linearToHex(value) : value;
    }
    showValue(input);
  }
  const hasFilm = "film_thickness_nm" in preset.parameters;
  $("film-card").classList.toggle("disabled", !hasFilm);
  $("film-note").textContent = hasFilm ? "thin film on keratin, unpolarised"
    : "this material has no single adjustable film: showing the slider values";
}

export function modelSpec() {
  const preset = state.presets[state.preset];
  const overrides = {};
  for (const param of MODEL_PARAMS) {
    if (!(param in preset.parameters)) continue;
    const input = $(param);
    overrides[param] = param === "base_albedo" ? hexToLinear(input.value) : +input.value;
  }
  return { preset: state.preset, overrides };
}

// -- the figures -------------------------------------------------------------------------------
function plotPolar(lobe) {
  const { angle_deg: angles, values } = lobe.plane;
  const traces = ["R", "G", "B"].map((name, c) => ({
    type: "scatterpolar", mode: "lines", name, theta: angles, r: values.map((v) => v[c]),
    line: { color: CHANNEL_COLOURS[c], width: 2 },
  }));
  const peak = Math.max(1e-9, ...values.flat().filter(Number.isFinite));
  traces.push({
    type: "scatterpolar", mode: "lines+markers", name: "incident", theta: [-lobe.theta_i, -lobe.theta_i],
    r: [peak, 0], line: { color: "#9aa4b8", dash: "dot", width: 1.5 },
    marker: { size: [9, 0], symbol: "triangle-down", color: "#9aa4b8" },
  });
  const transmits = Math.max(...angles) > 90;
  const layout = {
    ...BASE_LAYOUT, margin: { l: 30, r: 30, t: 20, b: 20 },
    polar: {
      bgcolor: "rgba(0,0,0,0)", sector: transmits ? [0, 360] : [0, 180],
      angularaxis: { rotation: 90, direction: "clockwise", gridcolor: "#2a3242", linecolor: "#3a4458",
        dtick: 30, ticksuffix: "°" },
      radialaxis: { gridcolor: "#2a3242", linecolor: "#3a4458", angle: 90, tickangle: 90 },
    },
    legend: { orientation: "h", x: 0.5, xanchor: "center", y: 0, font: { size: 11 } },
  };
  Plotly.react("polar", traces, layout, CONFIG);
}

function plotHemisphere(lobe) {
  const h = lobe.hemisphere;
  const s = Math.sin((lobe.theta_i * Math.PI) / 180);
  const circle = Array.from({ length: 121 }, (_, i) => (2 * Math.PI * i) / 120);
  const peak = Math.max(1e-12, ...h.luminance.flat().filter(Number.isFinite));
  const floor = Math.log10(peak) - DECADES;
  const z = h.luminance.map((row) => row.map((y) => (y == null ? null : Math.max(floor, Math.log10(Math.max(y, 1e-30))))));
  const ticks = Array.from({ length: DECADES + 1 }, (_, i) => Math.ceil(floor) + i).filter((t) => t <= Math.log10(peak));
  const traces = [
    { type: "heatmap", x: h.x, y: h.y, z, customdata: h.luminance, colorscale: INFERNO, hoverongaps: false, zsmooth: "best",
      zmin: floor, zmax: Math.log10(peak),
      colorbar: { thickness: 10, outlinewidth: 0, tickfont: { size: 10 }, tickvals: ticks,
        ticktext: ticks.map((t) => `1e${t}`) },
      hovertemplate: "x %{x:.2f}, y %{y:.2f}<br>Y = %{customdata:.4g}<extra></extra>" },
    { type: "scatter", mode: "lines", x: circle.map(Math.cos), y: circle.map(Math.sin), showlegend: false,
      line: { color: "#3a4458", width: 1 }, hoverinfo: "skip" },
    { type: "scatter", mode: "markers+text", x: [-s, s], y: [0, 0], text: ["ωi", "mirror"],
      textposition: "top center", textfont: { color: "#e6ebf5", size: 11 }, showlegend: false,
      marker: { color: ["#9aa4b8", "#ffffff"], size: 8, symbol: ["x", "circle-open"] }, hoverinfo: "skip" },
  ];
  const axis = { range: [-1.05, 1.05], zeroline: false, gridcolor: "#232a38", tickfont: { size: 10 } };
  Plotly.react("hemisphere", traces, {
    ...BASE_LAYOUT, showlegend: false, margin: { l: 36, r: 8, t: 8, b: 30 },
    xaxis: { ...axis, title: { text: "x", standoff: 4 } },
    yaxis: { ...axis, scaleanchor: "x", title: { text: "y", standoff: 4 } },
  }, CONFIG);
}

function plotSpectrum(film, theta) {
  const last = film.angles.length - 1;   // the request put θi last
  const traces = [
    { type: "scatter", mode: "lines", name: "reflectance R", x: film.wavelengths, y: film.reflectance[last],
      line: { color: "#f5c46b", width: 2.2 }, fill: "tozeroy", fillcolor: "rgba(245,196,107,0.10)" },
    { type: "scatter", mode: "lines", name: "transmittance T", x: film.wavelengths, y: film.transmittance[last],
      line: { color: "#6bc7f5", width: 2 }, yaxis: "y2" },
  ];
  Plotly.react("spectrum", traces, {
    ...BASE_LAYOUT,
    xaxis: { title: { text: "wavelength [nm]", standoff: 6 }, gridcolor: "#232a38", range: [380, 780] },
    yaxis: { title: { text: "R", standoff: 4 }, gridcolor: "#232a38", rangemode: "tozero" },
    yaxis2: { title: { text: "T", standoff: 4 }, overlaying: "y", side: "right", showgrid: false,
      rangemode: "tozero" },
    margin: { l: 48, r: 44, t: 12, b: 40 },
    annotations: [{ text: `θi = ${theta}°`, x: 1, y: 1.02, xref: "paper", yref: "paper", xanchor: "right",
      showarrow: false, font: { size: 11, color: "#9aa4b8" } }],
  }, CONFIG);
}

function drawSwatches(film, theta) {
  const strip = $("swatches");
  strip.replaceChildren(...SWATCH_ANGLES.map((angle, i) => {
    const cell = document.createElement("div");
    cell.className = "swatch" + (Math.abs(angle - theta) < 2.5 ? " current" : "");
    cell.style.background = film.srgb[i];
    cell.title = `${angle}°: linear sRGB ${film.rgb[i].map((c) => c.toFixed(4)).join(", ")}`;
    cell.dataset.colour = film.srgb[i];
    const label = document.createElement("span");
    label.textContent = `${angle}°`;
    cell.append(label);
    return cell;
  }));
  const last = film.angles.length - 1;
  $("swatch-now").style.background = film.srgb[last];
  $("swatch-now-label").textContent =
    `at θi = ${theta}°: ${film.srgb[last]} (display exposure ×${film.exposure.toFixed(2)})`;
}

// -- updating -----------------------------------------------------------------------------------
let lobeAbort = null;
let timer = null;

async function updateFilm() {
  const theta = +$("theta_i").value;
  const request = { film_ior: +$("film_ior").value, thickness_nm: +$("film_thickness_nm").value,
    angles: [...SWATCH_ANGLES, theta] };
  try {
    const { data } = await api("/v1/thinfilm/spectrum", request);
    plotSpectrum(data, theta);
    drawSwatches(data, theta);
  } catch (e) {
    status(`film: ${e.message}`, true);
  }
}

async function updateLobe() {
  if (lobeAbort) lobeAbort.abort();
  lobeAbort = new AbortController();
  const request = { ...modelSpec(), theta_i: +$("theta_i").value, points: 91, resolution: 33,
    samples: +$("quality").value };
  status("computing the lobe…");
  const started = performance.now();
  try {
    const { data } = await api("/v1/bsdf/lobe", request, lobeAbort.signal);
    plotPolar(data);
    plotHemisphere(data);
    document.body.dataset.lobeUpdates = String(+(document.body.dataset.lobeUpdates || 0) + 1);
    const seconds = ((performance.now() - started) / 1000).toFixed(2);
    status(`${data.model.type} model · ${data.stochastic ? `${request.samples} walks per direction · ` : ""}${seconds} s`);
  } catch (e) {
    if (e.name !== "AbortError") status(e.message, true);
  }
}

function scheduleUpdate() {
  updateFilm();
  clearTimeout(timer);
  timer = setTimeout(updateLobe, 120);
}

// -- rendering ---------------------------------------------------------------------------------
function setProgress(job) {
  const pct = Math.round(100 * job.progress);
  $("progress-bar").style.width = `${pct}%`;
  const eta = job.eta_s == null ? "" : ` · about ${job.eta_s.toFixed(0)} s left`;
  $("render-status").textContent = `${job.state} · ${pct}% · ${job.elapsed_s.toFixed(1)} s${eta}`;
}

function showImage(hash) {
  const img = $("render-image");
  img.src = `/v1/renders/${hash}/image.png`;
  img.hidden = false;
  $("progress-bar").style.width = "100%";
}

function endRender() {
  $("render-button").disabled = false;
  $("cancel-button").hidden = true;
  if (state.source) state.source.close();
  state.source = null;
}

function follow(job) {
  state.job = job;
  $("cancel-button").hidden = false;
  const source = new EventSource(job.links.events);
  state.source = source;
  source.addEventListener("progress", (e) => setProgress(JSON.parse(e.data)));
  source.addEventListener("done", (e) => {
    const done = JSON.parse(e.data);
    setProgress(done);
    showImage(done.hash);
    $("render-status").textContent = `done in ${done.elapsed_s.toFixed(1)} s`;
    endRender();
  });
  for (const name of ["failed", "cancelled"]) {
    source.addEventListener(name, (e) => {
      const job = JSON.parse(e.data);
      $("render-status").textContent = `${name}${job.error ? ": " + job.error : ""}`;
      endRender();
    });
  }
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) endRender(); };
}

// The page's light presets (the API takes any list of light dicts: docs/scene_format.md).
const LIGHTS = {
  "sun-60": { type: "sun", elevation_deg: 60, azimuth_deg: -40 },
  "sun-20": { type: "sun", elevation_deg: 20, azimuth_deg: -60, turbidity: 4 },
  "spot": { type: "spot", position: [0, 120, 0], direction: [0, -1, 0], intensity: 30000, cutoff_angle_deg: 30 },
};

// "edited": the material on the controls (tabulated when layered: a table per hit, not walks)
export function editedMaterial() {
  const spec = modelSpec();
  return state.presets[state.preset].model.type === "layered" ? { type: "tabulated", model: spec } : spec;
}

function renderMaterial(scene) {
  const choice = $("material").value;
  if (choice === "edited") return editedMaterial();
  return scene === "sphere" && !["table", "direct"].includes(choice) ? { preset: choice } : choice;
}

async function startRender(event) {
  event.preventDefault();
  const [width, height] = $("size").value.split("x").map(Number);
  const scene = $("scene").value;
  const request = { scene, width, height, spp: +$("spp").value,
    options: { ...(scene === "sphere" ? { variant: $("variant").value } : {}), material: renderMaterial(scene) } };
  const light = LIGHTS[$("light").value];
  if (light) request.lights = [light];
  $("render-button").disabled = true;
  $("progress-bar").style.width = "0%";
  $("render-image").hidden = true;
  $("render-status").textContent = "submitting…";
  try {
    const { status: code, data } = await api("/v1/renders", request);
    if (code === 200) {
      showImage(data.hash);
      $("render-status").textContent = "from the artefact store (rendered before)";
      endRender();
    } else {
      follow(data);
    }
  } catch (e) {
    $("render-status").textContent = e.message;
    endRender();
  }
}

async function cancelRender() {
  if (!state.job) return;
  await fetch(`/v1/jobs/${state.job.id}`, { method: "DELETE", headers: headers() });
}

// -- start -------------------------------------------------------------------------------------
async function main() {
  // the key first: with keys configured every /v1 route needs one (a 401 asks for it)
  $("api-key").value = localStorage.getItem("bsdflab-api-key") || "";
  $("api-key").addEventListener("change", () => {
    localStorage.setItem("bsdflab-api-key", $("api-key").value);
    location.reload();
  });
  let presets, version;
  try {
    [{ data: presets }, { data: version }] = await Promise.all([api("/v1/presets"), api("/v1/version")]);
  } catch (e) {
    if (!String(e.message).startsWith("401")) throw e;
    $("key-box").hidden = false;
    status("this server needs an API key: enter it above", true);
    return;
  }
  $("version").textContent = `bsdflab ${version.bsdflab} · ${version.executor}`;
  $("key-box").hidden = !version.api_key_required;
  const select = $("preset");
  for (const p of presets) {
    state.presets[p.name] = p;
    select.add(new Option(p.name, p.name));
  }
  applyPreset(presets[0].name);
  select.addEventListener("change", () => { applyPreset(select.value); scheduleUpdate(); });
  for (const id of [...SLIDERS, "base_albedo"]) {
    const input = $(id);
    showValue(input);
    input.addEventListener("input", () => { showValue(input); scheduleUpdate(); });
  }
  $("quality").addEventListener("change", scheduleUpdate);
  $("scene").addEventListener("change", () => {
    $("variant-box").hidden = $("scene").value !== "sphere";
  });
  $("render-form").addEventListener("submit", startRender);
  $("cancel-button").addEventListener("click", cancelRender);
  scheduleUpdate();
}

main().catch((e) => status(e.message, true));
