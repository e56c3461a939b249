(() => {
"use strict";
// Mechatron explorer: the page's logic. Talks to the JSON API of mechatron.explore.server;
// the plot is MtPlot.Plot (plot.js). Everything a test or a link needs is reachable from
// window.app and from the address: ?view=&model=&run=&plot=RUN:PATH;RUN:PATH&t0=&t1=&separate=1&cursor=T
// (&scenario=NAME runs /static/scenario_NAME.js, used by the browser tests).

const {Plot, PALETTE, DASHES, fmt, valueAt} = window.MtPlot;
const $ = sel => document.querySelector(sel);
const h = (tag, props = {}, ...children) => {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(props)) {
    if (k === "class") node.className = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else if (k === "text") node.textContent = v;
    else node.setAttribute(k, v);
  }
  for (const c of children) node.append(c);
  return node;
};

const state = {
  runs: [],            // run summaries, in creation order
  active: null,        // id of the run whose variables and parameters are shown
  vars: {},            // run id -> {names, units, descriptions, index}
  plotted: [],         // [{run, name}]
  data: {},            // "run|name" -> signal answer {t, y, unit, decimated}
  colors: new Map(),   // variable path -> colour
  expanded: new Set(), // tree nodes open
  model: null,         // entry shown in the Models tab
  generation: 0,       // drops answers of superseded fetches
  lastSimulation: null // {seconds, total} of the last parameter change
};

// ------------------------------------------------------------------ API and errors
async function api(path, options = {}) {
  const init = {...options};
  if (init.json !== undefined) {
    init.method = init.method || "POST";
    init.headers = {"Content-Type": "application/json"};
    init.body = JSON.stringify(init.json);
    delete init.json;
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (err) {
    throw new Error(`the explorer's server does not answer (${err.message}). Is \`mechatron explore\` still running?`);
  }
  const type = response.headers.get("Content-Type") || "";
  const body = type.startsWith("application/json") ? await response.json() : await response.text();
  if (!response.ok) throw new Error(body && body.error ? body.error : `HTTP ${response.status}`);
  return body;
}

function showError(message) {
  $("#error-text").textContent = message;
  $("#error").hidden = false;
}
function clearError() { $("#error").hidden = true; $("#error-text").textContent = ""; }
function status(text) { $("#status").textContent = text; }

// Run an action; its failure is shown in the page (the server keeps serving).
async function guarded(action) {
  try { clearError(); return await action(); }
  catch (err) { showError(err.message); return undefined; }
}

// ------------------------------------------------------------------ views
function showView(view) {
  for (const v of VIEWS) $(`#view-${v}`).hidden = v !== view;
  document.querySelectorAll("nav .tab").forEach(b => b.classList.toggle("active", b.dataset.view === view));
  if (view === "models" && !$("#models").children.length) guarded(loadModels);
  if (view === "library" && !$("#sections").children.length) guarded(loadLibrary);
  if (view === "studies") guarded(refreshStudies);
  if (view === "results") plot.render();
}

// ------------------------------------------------------------------ runs
const VIEWS = ["results", "models", "library", "studies"];
const runById = id => state.runs.find(r => r.id === id);
const runIndex = id => state.runs.findIndex(r => r.id === id);

async function refreshRuns() {
  state.runs = await api("/api/runs");
  renderRuns();
}

function renderRuns() {
  const list = $("#runs");
  list.replaceChildren();
  state.runs.forEach((run, i) => {
    const dash = h("span", {class: "dash"});
    dash.style.borderTopStyle = ["solid", "dashed", "dotted", "dashed", "dashed"][i % 5];
    const li = h("li", {class: run.id === state.active ? "active" : "", title: `${run.n_vars} variables, ${run.n_t} points, t = ${fmt(run.t0)} to ${fmt(run.t1)} s`,
                        "data-run": run.id, onclick: () => guarded(() => setActive(run.id))},
                 dash, h("span", {class: "label", text: `${run.id}: ${run.label}`}),
                 h("button", {title: "forget this run", text: "×",
                              onclick: ev => { ev.stopPropagation(); guarded(() => removeRun(run.id)); }}));
    list.appendChild(li);
  });
}

async function removeRun(id) {
  await api(`/api/runs/${id}`, {method: "DELETE"});
  state.plotted = state.plotted.filter(p => p.run !== id);
  delete state.vars[id];
  if (state.active === id) state.active = null;
  await refreshRuns();
  if (!state.active && state.runs.length) await setActive(state.runs[state.runs.length - 1].id);
  else { renderTree(); renderParams(); }
  updatePlot();
}

async function setActive(id) {
  state.active = id;
  renderRuns();
  if (!state.vars[id]) {
    const v = await api(`/api/runs/${id}/variables`);
    v.index = new Map(v.names.map((n, i) => [n, i]));
    state.vars[id] = v;
  }
  renderTree();
  await renderParams();
}

async function addRun(summary, {activate = true} = {}) {
  await refreshRuns();
  if (activate) await setActive(summary.id);
  return summary;
}

async function openPath(path) {
  const answer = await api("/api/open", {json: {path}});
  if (answer.study) return showStudy(answer.study);
  return addRun(answer);
}

// ------------------------------------------------------------------ studies
async function refreshStudies() {
  const studies = await api("/api/studies");
  $("#studies").replaceChildren(...studies.map(st => h("li", {"data-study": st.id, onclick: () => showStudy(st)},
                                                   h("b", {text: `${st.id}: ${st.kind}`}), " ", st.label)));
  return studies;
}

async function showStudy(study) {
  await refreshStudies();
  showView("studies");
  document.querySelectorAll("#studies li").forEach(li => li.classList.toggle("active", li.dataset.study === study.id));
  const box = $("#study");
  box.replaceChildren(h("h2", {text: `${study.kind}: ${study.label}`}),
    ...study.summary.map(line => h("p", {text: line})),
    ...study.warnings.map(line => h("p", {class: "warning", text: line})));
  for (const t of study.tables) {
    box.append(h("h2", {text: t.title}),
      h("table", {class: "data"}, h("tr", {}, ...t.headers.map(x => h("th", {text: x}))),
        ...t.rows.map(r => h("tr", {}, ...r.map((c, i) => h("td", {class: i ? "num" : "", text: c}))))));
  }
  if (study.images.length) {
    box.append(h("h2", {text: "Plots"}), h("div", {class: "study-images"},
      ...study.images.map(name => h("figure", {}, h("img", {src: `/api/studies/${study.id}/image/${encodeURIComponent(name)}`, alt: name}),
                                        h("figcaption", {text: name})))));
  }
  state.study = study.id;
  writeAddress();
  return study;
}

async function upload(file) {
  const body = await file.arrayBuffer();
  const run = await api(`/api/upload?filename=${encodeURIComponent(file.name)}`, {method: "POST", body});
  return addRun(run);
}

// ------------------------------------------------------------------ variable tree
function buildTree(names) {
  const root = {children: new Map(), path: ""};
  names.forEach((name, i) => {
    let node = root;
    const parts = name.split(".");
    parts.forEach((part, k) => {
      const path = parts.slice(0, k + 1).join(".");
      if (!node.children.has(part)) node.children.set(part, {children: new Map(), path, leaf: -1});
      node = node.children.get(part);
      if (k === parts.length - 1) node.leaf = i;
    });
  });
  return root;
}

const LIMIT = 300;

function leafRow(run, v, i, text) {
  const name = v.names[i];
  const plotted = state.plotted.some(p => p.run === run && p.name === name);
  return h("div", {class: "row leaf" + (plotted ? " plotted" : ""), "data-name": name,
                   title: v.descriptions[i] || name,
                   onclick: () => guarded(() => togglePlot(run, name))},
           text, h("span", {class: "unit", text: v.units[i] ? `[${v.units[i]}]` : ""}));
}

function renderTree() {
  const box = $("#tree");
  box.replaceChildren();
  const run = state.active;
  const v = run && state.vars[run];
  $("#var-count").textContent = v ? `(${v.names.length})` : "";
  if (!v) return;
  const filter = $("#filter").value.trim().toLowerCase();
  if (filter) {
    let shown = 0, total = 0;
    v.names.forEach((name, i) => {
      if (!name.toLowerCase().includes(filter)) return;
      total++;
      if (shown++ < LIMIT) box.appendChild(leafRow(run, v, i, name));
    });
    if (total > LIMIT) box.appendChild(h("div", {class: "more", text: `${total - LIMIT} more: refine the filter`}));
    return;
  }
  if (!v.tree) v.tree = buildTree(v.names);
  const draw = (node, parent) => {
    let count = 0;
    for (const [part, child] of node.children) {
      if (count++ >= LIMIT) {
        parent.appendChild(h("div", {class: "more", text: `${node.children.size - LIMIT} more: use the filter`}));
        break;
      }
      if (child.children.size === 0) { parent.appendChild(leafRow(run, v, child.leaf, part)); continue; }
      const open = state.expanded.has(child.path);
      const row = h("div", {class: "row", "data-node": child.path,
                            onclick: () => { open ? state.expanded.delete(child.path) : state.expanded.add(child.path); renderTree(); }},
                    `${open ? "▾" : "▸"} ${part}`);
      if (child.leaf >= 0) row.appendChild(h("span", {class: "unit", text: `[${v.units[child.leaf]}]`}));
      parent.appendChild(row);
      if (open) {
        const sub = h("div", {class: "node"});
        if (child.leaf >= 0) sub.appendChild(leafRow(run, v, child.leaf, "(value)"));
        draw(child, sub);
        parent.appendChild(sub);
      }
    }
  };
  draw(v.tree, box);
}

// ------------------------------------------------------------------ plotting
const key = (run, name) => `${run}|${name}`;

function colorOf(name) {
  if (!state.colors.has(name)) state.colors.set(name, PALETTE[state.colors.size % PALETTE.length]);
  return state.colors.get(name);
}

// The run a curve is compared with in difference mode: the first run plotting that
// variable (none for that run itself).
function reference(run, name) {
  if (!state.differences) return null;
  const first = state.plotted.find(p => p.name === name);
  return first && first.run !== run ? first.run : null;
}

async function fetchSignal(run, name) {
  const view = plot.view;
  const q = new URLSearchParams({name, width: plot.plotWidth()});
  const ref = reference(run, name);
  if (ref) q.set("minus", ref);
  if (view) { q.set("t0", view[0]); q.set("t1", view[1]); }
  return api(`/api/runs/${run}/signal?${q}`);
}

async function togglePlot(run, name, on) {
  const i = state.plotted.findIndex(p => p.run === run && p.name === name);
  if (i >= 0 && on !== true) { state.plotted.splice(i, 1); delete state.data[key(run, name)]; }
  else if (i < 0 && on !== false) {
    state.plotted.push({run, name});
    state.data[key(run, name)] = await fetchSignal(run, name);
  }
  renderTree();
  updatePlot();
  writeAddress();
}

// Fetch every plotted signal again (after a zoom or a new simulation), then redraw.
async function refetch(runs = null) {
  const generation = ++state.generation;
  const todo = state.plotted.filter(p => !runs || runs.includes(p.run));
  const answers = await Promise.all(todo.map(p => fetchSignal(p.run, p.name)));
  if (generation !== state.generation) return;
  todo.forEach((p, i) => { state.data[key(p.run, p.name)] = answers[i]; });
  updatePlot();
}

function updatePlot() {
  const many = new Set(state.plotted.map(p => p.run)).size > 1 || state.runs.length > 1;
  const traces = [];
  // a CSV log carries no units: a variable without one takes the unit of the same
  // variable in another run, so that a measurement shares the simulation's axis
  const known = new Map();
  for (const p of state.plotted) {
    const d = state.data[key(p.run, p.name)];
    if (d && d.unit && !known.has(p.name)) known.set(p.name, d.unit);
  }
  for (const p of state.plotted) {
    const d = state.data[key(p.run, p.name)];
    const run = runById(p.run);
    if (!d || !run) continue;
    traces.push({key: key(p.run, p.name), name: p.name, run: p.run, minus: d.minus,
                 label: d.minus ? `${p.name} (${p.run} − ${d.minus})` : many ? `${p.name} (${p.run})` : p.name,
                 // differences get an axis of their own ("one axis per unit")
                 unit: (d.minus ? "Δ " : "") + (d.unit || known.get(p.name) || ""),
                 color: colorOf(p.name), dash: DASHES[runIndex(p.run) % DASHES.length],
                 t: d.t, y: d.y, events: run.events, t0: run.t0, t1: run.t1,
                 decimated: d.decimated});
  }
  plot.setTraces(traces);
  renderReadout(plot.cursorT);
}

function renderReadout(t) {
  const table = $("#readout");
  table.replaceChildren();
  if (!plot.traces.length) return;
  const time = t === null || t === undefined ? null : t;
  table.appendChild(h("tr", {}, h("th", {text: ""}), h("th", {text: "variable"}), h("th", {text: "run"}),
                      h("th", {text: time === null ? "value (move over the plot)" : `at t = ${fmt(time)} s`}),
                      h("th", {text: "unit"}), h("th", {text: "Δ to first run"})));
  const first = new Map();
  for (const tr of plot.traces) {
    const value = time === null ? null : valueAt(tr, time);
    if (!first.has(tr.name)) first.set(tr.name, value);
    const ref = tr.minus ? 0 : first.get(tr.name);
    const swatch = h("td", {});
    swatch.style.borderLeft = `14px solid ${tr.color}`;
    const run = runById(tr.run);
    table.appendChild(h("tr", {"data-key": tr.key}, swatch, h("td", {text: tr.name}),
                        h("td", {text: run ? `${run.id}: ${run.label}` : tr.run}),
                        h("td", {class: "num", text: tr.minus ? "" : (tr.decimated ? "≈ " : "") + fmt(value)}),
                        h("td", {text: tr.unit || "1"}),
                        h("td", {class: "num", text: tr.minus ? (tr.decimated ? "≈ " : "") + fmt(value) :
                                                     ref === value || ref === null || value === null ? "" : fmt(value - ref)})));
  }
}

// Plot the shown variables from every run that has them.
async function overlayRuns() {
  const names = [...new Set(state.plotted.map(p => p.name))];
  for (const run of state.runs) {
    if (!state.vars[run.id]) {
      const v = await api(`/api/runs/${run.id}/variables`);
      v.index = new Map(v.names.map((n, i) => [n, i]));
      state.vars[run.id] = v;
    }
    for (const name of names) {
      if (state.vars[run.id].index.has(name) && !state.plotted.some(p => p.run === run.id && p.name === name)) {
        state.plotted.push({run: run.id, name});
      }
    }
  }
  await refetch();
  renderTree();
  writeAddress();
}

// ------------------------------------------------------------------ parameters live
async function renderParams() {
  const box = $("#params");
  const run = runById(state.active);
  if (!run || run.kind !== "simulation") {
    box.replaceChildren(h("p", {class: "hint", text: run ? "A loaded file has no parameters; simulate a model (Models tab) to change them." :
                                                      "Simulate a model (Models tab) to change its parameters here."}));
    return;
  }
  const params = await api(`/api/models/${encodeURIComponent(run.model)}/parameters?variant=${encodeURIComponent(run.variant)}`);
  const table = h("table", {});
  for (const p of params) {
    const value = p.path in run.params ? run.params[p.path] : p.default;
    const input = h("input", {type: "text", value: fmt(value), "data-path": p.path, "data-default": fmt(p.default),
                              title: `default ${fmt(p.default)} ${p.unit}; a number in ${p.unit} or a value with its unit, e.g. "2 ${p.unit}"`});
    if (p.path in run.params) input.classList.add("changed");
    input.addEventListener("change", () => guarded(() => resimulate()));
    table.appendChild(h("tr", {}, h("td", {class: "path", text: p.path, title: p.path}), h("td", {}, input),
                        h("td", {class: "unit", text: p.unit === "1" ? "" : p.unit})));
  }
  let find = null;
  if (params.length > 12) {            // a large model: find parameters by path
    find = h("input", {type: "search", placeholder: `filter ${params.length} parameters`});
    find.addEventListener("input", () => {
      const text = find.value.trim().toLowerCase();
      for (const row of table.rows) row.hidden = text && !row.cells[0].textContent.toLowerCase().includes(text);
    });
  }
  const keep = h("input", {type: "checkbox", id: "keep-run"});
  const tstop = h("input", {type: "text", id: "t-stop", value: fmt(run.t1), title: "stop time in s"});
  box.replaceChildren(
    h("p", {class: "hint", text: `${run.model} (${run.variant}), compiled once: a change re-simulates without recompiling.`}),
    ...(find ? [find] : []),
    table,
    h("table", {}, h("tr", {}, h("td", {text: "stop time"}), h("td", {}, tstop), h("td", {class: "unit", text: "s"}))),
    h("label", {}, keep, " keep this run and add the new one (to overlay)"),
    h("div", {}, h("button", {id: "resimulate", text: "Simulate", onclick: () => guarded(() => resimulate())}),
      " ", h("button", {text: "Defaults", onclick: () => guarded(() => resimulate(true))})),
    h("p", {class: "hint", id: "sim-time", text: run.seconds ? `last run: ${(run.seconds * 1e3).toFixed(1)} ms` : ""}));
  tstop.addEventListener("change", () => guarded(() => resimulate()));
}

async function resimulate(defaults = false) {
  const run = runById(state.active);
  if (!run || run.kind !== "simulation") throw new Error("no simulation is selected: choose a simulated run on the left.");
  const params = {};
  document.querySelectorAll("#params input[data-path]").forEach(input => {
    input.classList.remove("bad");
    const text = input.value.trim();
    // a plain number is in the SI unit shown; text with a unit ("340 uH") is converted
    if (!defaults && text && text !== input.dataset.default) {
      params[input.dataset.path] = /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(text) ? Number(text) : text;
    }
  });
  const keep = $("#keep-run") && $("#keep-run").checked;
  const tstop = parseFloat($("#t-stop") ? $("#t-stop").value : "");
  const start = performance.now();
  let summary;
  try {
    summary = await api("/api/simulate", {json: {model: run.model, variant: run.variant, params,
                                                 t_stop: isFinite(tstop) ? tstop : null,
                                                 replace: keep ? null : run.id}});
  } catch (err) {
    document.querySelectorAll("#params input[data-path]").forEach(input => {
      if (err.message.includes(input.dataset.path)) input.classList.add("bad");
    });
    throw err;
  }
  if (keep) {
    for (const p of state.plotted.filter(p => p.run === run.id)) state.plotted.push({run: summary.id, name: p.name});
  }
  delete state.vars[summary.id];
  await refreshRuns();
  await refetch([summary.id]);
  const total = performance.now() - start;
  state.lastSimulation = {seconds: summary.seconds, total: total / 1e3};
  await setActive(summary.id);
  status(`simulated in ${(summary.seconds * 1e3).toFixed(1)} ms, plotted ${total.toFixed(0)} ms after the change`);
  writeAddress();
  return summary;
}

// ------------------------------------------------------------------ models tab
async function loadModels() {
  const models = await api("/api/models");
  const list = $("#models");
  list.replaceChildren(...models.map(m => h("li", {"data-model": m.name, title: m.description,
                                                   onclick: () => guarded(() => loadModel(m.name))},
                                            h("b", {text: m.name}), h("small", {text: m.description}))));
  filterList("#model-filter", "#models li");
}

function filterList(input, items) {
  const text = $(input).value.trim().toLowerCase();
  document.querySelectorAll(items).forEach(li => { li.hidden = text && !li.textContent.toLowerCase().includes(text); });
}

async function loadModel(name, variant = null) {
  const m = await api(`/api/models/${encodeURIComponent(name)}`);
  state.model = m;
  variant = variant || m.default_variant;
  document.querySelectorAll("#models li").forEach(li => li.classList.toggle("active", li.dataset.model === name));
  const box = $("#model");
  const select = h("select", {id: "variant"}, ...m.variants.map(v => {
    const o = h("option", {value: v, text: v}); if (v === variant) o.selected = true; return o; }));
  select.addEventListener("change", () => guarded(() => loadModel(name, select.value)));
  const params = h("table", {class: "data"}, h("tr", {}, ...["name", "default", "unit", "description", "source"].map(t => h("th", {text: t}))),
    ...m.parameters.map(p => h("tr", {}, h("td", {text: p.name}), h("td", {class: "num", text: fmt(p.default)}),
                                 h("td", {text: p.unit}), h("td", {text: p.description}), h("td", {text: p.source}))));
  const outputs = h("table", {class: "data"}, h("tr", {}, h("th", {text: "output"}), h("th", {text: "unit"}), ...m.variants.map(v => h("th", {text: v}))),
    ...m.outputs.map(o => h("tr", {}, h("td", {text: o.label}), h("td", {text: o.unit}), ...m.variants.map(v => h("td", {text: o.paths[v] || "–"})))));
  const e = m.experiment;
  const diagram = h("div", {class: "diagram", id: "diagram", text: "drawing the diagram…"});
  const parts = h("div", {id: "parts", text: "…"});
  box.replaceChildren(
    h("h2", {text: m.name}), h("p", {text: m.description}),
    h("p", {}, ...m.tags.map(t => h("span", {class: "tag", text: t}))),
    h("p", {}, "variant ", select, " ", h("button", {id: "simulate-model", text: "Simulate and plot",
                                                      onclick: () => guarded(() => simulateModel(name, select.value))})),
    h("p", {text: `experiment: t_stop ${fmt(e.t_stop)} s, solver ${e.solver}, rtol ${fmt(e.rtol)}, atol ${fmt(e.atol)}` + (e.dt ? `, dt ${fmt(e.dt)} s` : "")}),
    h("h2", {text: "Diagram"}), diagram,
    h("h2", {text: "Parameters"}), params,
    h("h2", {text: "Outputs"}), outputs,
    h("h2", {text: "Expected values at t_stop"}),
    h("table", {class: "data"}, ...Object.entries(m.expected).map(([k, v]) => h("tr", {}, h("td", {text: k}), h("td", {class: "num", text: fmt(v)})))),
    h("h2", {text: "Parts"}), parts);
  const q = variant ? `?variant=${encodeURIComponent(variant)}` : "";
  try {
    const svg = await api(`/api/models/${encodeURIComponent(name)}/diagram${q}`);
    diagram.innerHTML = svg;
  } catch (err) { diagram.textContent = `no diagram: ${err.message}`; }
  const list = await api(`/api/models/${encodeURIComponent(name)}/parts${q}`);
  parts.replaceChildren(...list.map(p => h("details", {}, h("summary", {}, h("b", {text: p.path}), ` (${p.class})`),
                                           h("pre", {class: "doc", text: p.doc || "(no documentation)"}))));
  writeAddress();
  return m;
}

async function simulateModel(name, variant) {
  status(`simulating ${name}…`);
  const run = await api("/api/simulate", {json: {model: name, variant}});
  await addRun(run);
  showView("results");
  const m = state.model && state.model.name === name ? state.model : await api(`/api/models/${encodeURIComponent(name)}`);
  const paths = m.outputs.map(o => o.paths[run.variant]).filter(Boolean);
  for (const path of paths.slice(0, 4)) {
    if (state.vars[run.id].index.has(path)) state.plotted.push({run: run.id, name: path});
  }
  await refetch([run.id]);
  renderTree();
  status(`${name} simulated in ${(run.seconds * 1e3).toFixed(1)} ms`);
  writeAddress();
  return run;
}

// ------------------------------------------------------------------ library tab
async function loadLibrary() {
  const sections = await api("/api/library");
  state.library = sections;
  $("#sections").replaceChildren(...sections.map(s => h("li", {}, h("span", {text: s.name}),
    h("ul", {}, ...s.components.map(c => h("li", {"data-component": c.class, onclick: () => showComponent(s, c)}, c.name))))));
}

function showComponent(section, c) {
  document.querySelectorAll("#sections li li").forEach(li => li.classList.toggle("active", li.dataset.component === c.class));
  const ports = h("table", {class: "data"}, h("tr", {}, ...["port", "kind", "domain", "unit", "description"].map(t => h("th", {text: t}))),
    ...c.ports.map(p => h("tr", {}, h("td", {text: p.name}), h("td", {text: p.kind}), h("td", {text: p.domain}), h("td", {text: p.unit}), h("td", {text: p.doc}))));
  const params = h("table", {class: "data"}, h("tr", {}, ...["parameter", "default", "unit", "min", "max", "description"].map(t => h("th", {text: t}))),
    ...c.parameters.map(p => h("tr", {}, h("td", {text: p.name}), h("td", {class: "num", text: p.default === null ? "(required)" : typeof p.default === "number" ? fmt(p.default) : String(p.default)}),
                                 h("td", {text: p.unit}), h("td", {text: p.min === null ? "" : fmt(p.min)}), h("td", {text: p.max === null ? "" : fmt(p.max)}), h("td", {text: p.doc}))));
  $("#component").replaceChildren(h("h2", {text: `${c.name} (${section.name})`}), h("p", {text: c.class}),
    h("pre", {class: "doc", text: c.doc || c.description}), h("h2", {text: "Ports"}), ports, h("h2", {text: "Parameters"}), params,
    h("details", {}, h("summary", {text: `about the ${section.name} section`}), h("pre", {class: "doc", text: section.doc})));
}

// ------------------------------------------------------------------ export
function download(href, filename) {
  const a = h("a", {href, download: filename});
  document.body.appendChild(a); a.click(); a.remove();
}

function exportData(format) {
  if (!state.plotted.length) throw new Error("export: nothing is plotted. Plot the variables to export first.");
  const byRun = new Map();
  for (const p of state.plotted) { if (!byRun.has(p.run)) byRun.set(p.run, []); byRun.get(p.run).push(p.name); }
  const urls = [];
  for (const [run, names] of byRun) {
    const q = new URLSearchParams({format});
    names.forEach(n => q.append("name", n));
    if (plot.view) { q.set("t0", plot.view[0]); q.set("t1", plot.view[1]); }
    const url = `/api/runs/${run}/export?${q}`;
    urls.push(url);
    download(url, `${run}.${format}`);
  }
  return urls;
}

async function exportPNG(save = true) {
  const url = await plot.png(2);
  if (save) download(url, "mechatron-plot.png");
  return url;
}

function exportSVG() {
  const text = plot.svgText();
  if (!text) throw new Error("export: nothing is plotted. Plot a variable first.");
  download(URL.createObjectURL(new Blob([text], {type: "image/svg+xml"})), "mechatron-plot.svg");
  return text;
}

// ------------------------------------------------------------------ the address
function writeAddress() {
  const q = new URLSearchParams(location.search);
  const view = VIEWS.find(v => !$(`#view-${v}`).hidden);
  q.set("view", view);
  if (state.plotted.length) q.set("plot", state.plotted.map(p => `${p.run}:${p.name}`).join(";")); else q.delete("plot");
  if (plot.view) { q.set("t0", plot.view[0]); q.set("t1", plot.view[1]); } else { q.delete("t0"); q.delete("t1"); }
  if (state.active) q.set("run", state.active);
  if (state.model) q.set("model", state.model.name);
  if (state.study) q.set("study", state.study);
  q.set("separate", plot.separate ? "1" : "0");
  if (state.differences) q.set("diff", "1"); else q.delete("diff");
  history.replaceState(null, "", `?${q}`);
}

async function readAddress(startup) {
  const q = new URLSearchParams(location.search);
  const run = q.get("run") || startup.run;
  state.differences = q.get("diff") === "1";
  $("#diff").checked = state.differences;
  const separate = q.get("separate") !== "0";          // one axis per unit unless asked
  $("#separate").checked = separate; plot.separate = separate;
  if (run && runById(run)) await setActive(run);
  else if (state.runs.length) await setActive(state.runs[state.runs.length - 1].id);
  const studyId = q.get("study") || startup.study;
  if (studyId) {
    const study = (await api("/api/studies")).find(st => st.id === studyId);
    if (study) await showStudy(study);
  }
  const model = q.get("model") || startup.model;
  if (model) await loadModel(model);
  let wanted = (q.get("plot") || "").split(";").filter(Boolean).map(s => {
    const i = s.indexOf(":"); return {run: s.slice(0, i), name: s.slice(i + 1)}; });
  if (!wanted.length && startup.run && startup.model && state.model) {
    const r = runById(startup.run);
    wanted = state.model.outputs.map(o => ({run: startup.run, name: o.paths[r.variant]})).filter(p => p.name).slice(0, 4);
  }
  state.plotted = wanted.filter(p => runById(p.run));
  const t0 = parseFloat(q.get("t0")), t1 = parseFloat(q.get("t1"));
  if (isFinite(t0) && isFinite(t1)) plot.view = [t0, t1];
  showView(q.get("view") || startup.view || "results");
  await refetch();
  renderTree();
  const cursor = parseFloat(q.get("cursor"));
  if (isFinite(cursor)) plot.showCursor(cursor);
}

// ------------------------------------------------------------------ wiring
let viewTimer = null;
const plot = new Plot($("#plot"), {
  onView: () => { clearTimeout(viewTimer); viewTimer = setTimeout(() => guarded(async () => { await refetch(); writeAddress(); }), 60); },
  onCursor: t => renderReadout(t),
});

document.querySelectorAll("nav .tab").forEach(b => b.addEventListener("click", () => { showView(b.dataset.view); writeAddress(); }));
$("#error-close").addEventListener("click", clearError);
$("#filter").addEventListener("input", renderTree);
$("#model-filter").addEventListener("input", () => filterList("#model-filter", "#models li"));
$("#lib-filter").addEventListener("input", () => filterList("#lib-filter", "#sections li li"));
$("#separate").addEventListener("change", ev => plot.setSeparate(ev.target.checked));
$("#zoom-reset").addEventListener("click", () => plot.setView(null));
$("#overlay").addEventListener("click", () => guarded(overlayRuns));
$("#diff").addEventListener("change", ev => { state.differences = ev.target.checked; guarded(async () => { await refetch(); writeAddress(); }); });
$("#clear").addEventListener("click", () => { state.plotted = []; state.data = {}; updatePlot(); renderTree(); writeAddress(); });
$("#export-csv").addEventListener("click", () => guarded(() => exportData("csv")));
$("#export-parquet").addEventListener("click", () => guarded(() => exportData("parquet")));
$("#export-png").addEventListener("click", () => guarded(() => exportPNG()));
$("#export-svg").addEventListener("click", () => guarded(() => exportSVG()));
$("#study-open").addEventListener("click", () => guarded(() => openPath($("#study-path").value.trim())));
$("#study-path").addEventListener("keydown", ev => { if (ev.key === "Enter") guarded(() => openPath(ev.target.value.trim())); });
$("#open-button").addEventListener("click", () => guarded(() => openPath($("#open-path").value.trim())));
$("#open-path").addEventListener("keydown", ev => { if (ev.key === "Enter") guarded(() => openPath(ev.target.value.trim())); });
$("#upload").addEventListener("change", ev => { const f = ev.target.files[0]; if (f) guarded(() => upload(f)); ev.target.value = ""; });

window.app = {state, plot, api, guarded, showView, setActive, togglePlot, refetch, overlayRuns, resimulate,
              loadModel, simulateModel, loadLibrary, openPath, showStudy, upload, exportData, exportPNG, exportSVG, runById};

window.app.ready = (async () => {
  const s = await guarded(() => api("/api/state"));
  if (s) {
    state.runs = s.runs;
    renderRuns();
    await guarded(() => readAddress(s.startup || {}));
  }
  const scenario = new URLSearchParams(location.search).get("scenario");
  if (scenario && /^[a-z0-9_]+$/.test(scenario)) {
    const script = h("script", {src: `/static/scenario_${scenario}.js`});
    document.body.appendChild(script);
  }
})();
})();
