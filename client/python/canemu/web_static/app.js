// canemu web's page: one EventSource (/events) brings a snapshot, then an update per look at
// canemud; the page keeps the last minute of simulated time and draws it with Chart.js.
"use strict";

const WINDOW_S = 60;
const view = {                 // what the tests read (docs/web.md, "Tests")
  updates: 0,                  // updates handled
  handleMs: [],                // how long each took, in ms
  stateLog: [],                // [node, state, simulated ns, Date.now()] at each change shown
  charts: {},                  // bus -> {load, counters}
  settings: { allow_control: false, effects: [] },
};
window.canemuView = view;

let firedEvents = [];
const nodeStates = {};
const $ = (sel) => document.querySelector(sel);
const el = (tag, attrs = {}, text) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
};
const fmt = (x, digits = 1) => (x === null || x === undefined ? "-" : Number(x).toFixed(digits));
const esc = (s) => CSS.escape(s);

// Lines across a chart: the TEC/REC limits, and the instants faults fired.
const marks = {
  id: "canemuMarks",
  afterDatasetsDraw(chart, args, opts) {
    const { ctx, chartArea: a, scales: { x, y } } = chart;
    ctx.save();
    ctx.setLineDash([4, 3]);
    ctx.lineWidth = 1;
    for (const level of opts.levels || []) {
      const py = y.getPixelForValue(level);
      if (py < a.top || py > a.bottom) continue;
      ctx.strokeStyle = level >= 255 ? "#c62020" : level >= 128 ? "#e06c00" : "#d9a400";
      ctx.beginPath(); ctx.moveTo(a.left, py); ctx.lineTo(a.right, py); ctx.stroke();
      ctx.fillStyle = ctx.strokeStyle;
      ctx.fillText(String(level), a.left + 2, py - 2);
    }
    ctx.strokeStyle = "#7a3db8";
    ctx.fillStyle = "#7a3db8";
    for (const f of firedEvents) {
      const px = x.getPixelForValue(f.t / 1e9);
      if (px < a.left || px > a.right) continue;
      ctx.beginPath(); ctx.moveTo(px, a.top); ctx.lineTo(px, a.bottom); ctx.stroke();
      const w = ctx.measureText(f.effect).width;
      ctx.fillText(f.effect, px + 2 + w > a.right ? px - 2 - w : px + 2, a.top + 10);
    }
    ctx.restore();
  },
};

const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf",
  "#7f7f7f", "#bcbd22", "#ff7f0e"];

function makeChart(canvas, yTitle, levels, yMax) {
  return new Chart(canvas, {
    type: "line",
    data: { datasets: [] },
    options: {
      animation: false, responsive: true, maintainAspectRatio: false, parsing: false,
      normalized: true, spanGaps: true,
      elements: { point: { radius: 0 }, line: { borderWidth: 1.5 } },
      scales: {
        x: { type: "linear", title: { display: true, text: "simulated s" } },
        y: { min: 0, suggestedMax: yMax, title: { display: true, text: yTitle } },
      },
      plugins: { legend: { labels: { boxWidth: 10 } }, canemuMarks: { levels } },
    },
    plugins: [marks],
  });
}

function dataset(chart, label, colour, dashed) {
  let d = chart.data.datasets.find((s) => s.label === label);
  if (!d) {
    d = { label, data: [], borderColor: colour, backgroundColor: colour, stepped: true,
      borderDash: dashed ? [5, 3] : [] };
    chart.data.datasets.push(d);
  }
  return d;
}

function busCard(bus) {
  if (view.charts[bus.name]) return view.charts[bus.name];
  const card = el("div", { class: "card", id: `bus-${bus.name}`, "data-bus": bus.name });
  card.append(el("h3", {}, `${bus.name} (${bus.kind}, ${bus.bitrate} bit/s)`));
  const figures = el("div", { class: "figures" });
  card.append(figures);
  const wrap = el("div", { class: "chart" });
  const canvas = el("canvas");
  wrap.append(canvas);
  card.append(wrap);
  $("#buses").append(card);
  const entry = { figures, load: makeChart(canvas, "load %", [], 100), counters: null };
  entry.load.options.scales.y.max = 100;
  view.charts[bus.name] = entry;
  return entry;
}

function countersChart(bus) {
  const entry = view.charts[bus];
  if (entry.counters) return entry.counters;
  const card = el("div", { class: "card", id: `counters-${bus}` });
  card.append(el("h3", {}, `${bus}: TEC (solid) and REC (dashed)`));
  const wrap = el("div", { class: "chart" });
  const canvas = el("canvas");
  wrap.append(canvas);
  card.append(wrap);
  $("#counters").append(card);
  entry.counters = makeChart(canvas, "error counter", [96, 128, 255], 140);
  return entry.counters;
}

function trim(data, now) {
  let i = 0;
  while (i < data.length && data[i].x < now - WINDOW_S) i++;
  if (i) data.splice(0, i);
}

// One point of every line: bus load, then TEC and REC of each CAN node.
function addPoint(p, nodes) {
  const t = p.t / 1e9;
  for (const [bus, load] of Object.entries(p.load)) {
    const entry = view.charts[bus];
    if (!entry) continue;
    const d = dataset(entry.load, "load", "#1f77b4", false);
    d.data.push({ x: t, y: load });
  }
  nodes.forEach((n) => {
    if (n.state === "online" || n.state === "offline" || !view.charts[n.bus]) return;
    const chart = countersChart(n.bus);
    const i = chart.data.datasets.length / 2;
    const known = chart.data.datasets.find((s) => s.label === `${n.name} TEC`);
    const colour = known ? known.borderColor : COLOURS[i % COLOURS.length];
    dataset(chart, `${n.name} TEC`, colour, false).data.push({ x: t, y: p.tec[n.name] });
    dataset(chart, `${n.name} REC`, colour, true).data.push({ x: t, y: p.rec[n.name] });
  });
}

function redraw(now) {
  for (const entry of Object.values(view.charts)) {
    for (const chart of [entry.load, entry.counters]) {
      if (!chart) continue;
      chart.data.datasets.forEach((d) => trim(d.data, now));
      chart.options.scales.x.min = Math.max(0, now - WINDOW_S);
      chart.options.scales.x.max = Math.max(now, 1);
      chart.update("none");
    }
  }
}

function showStatus(s, rates) {
  $("#time").textContent = `simulated time ${(s.sim_time_ns / 1e9).toFixed(6)} s`;
  $("#time").dataset.ns = s.sim_time_ns;
  $("#mode").textContent = `time ${s.time_mode}` + (s.time_mode === "scaled" ? ` x${s.time_scale}` : "");
  for (const b of s.buses) {
    const entry = busCard(b);
    const r = rates && rates[b.name];
    entry.figures.innerHTML = "";
    entry.figures.append(
      `load ${fmt(b.load_percent)} % · ${r ? fmt(r[0]) : "-"} frames/s · ` +
      `${r ? fmt(r[1]) : "-"} error frames/s · ${b.frames} frames, ${b.error_frames} error frames`);
    entry.figures.dataset.frames = b.frames;
  }
  const body = $("#nodes tbody");
  const seen = new Set();
  for (const n of s.nodes) {
    seen.add(n.name);
    let row = body.querySelector(`tr[data-node="${esc(n.name)}"]`);
    if (!row) {
      row = el("tr", { "data-node": n.name });
      for (const c of ["name", "bus", "state", "tec", "rec", "sent", "received", "errors"]) {
        row.append(el("td", { class: c }));
      }
      const ctl = el("td", { class: "ctl" });
      if (view.settings.allow_control) {
        ctl.append(button("unplug", () => act("unplug", { node: n.name })),
          button("plug", () => act("plug", { node: n.name })));
      }
      row.append(ctl);
      body.append(row);
    }
    const cells = row.children;
    cells[0].textContent = n.name; cells[1].textContent = n.bus;
    cells[2].textContent = n.state; cells[2].className = `state ${n.state}`;
    cells[3].textContent = n.tec; cells[4].textContent = n.rec;
    cells[5].textContent = n.frames_sent; cells[6].textContent = n.frames_received;
    cells[7].textContent = n.errors;
    if (nodeStates[n.name] !== n.state) {
      nodeStates[n.name] = n.state;
      view.stateLog.push([n.name, n.state, s.sim_time_ns, Date.now()]);
    }
  }
  body.querySelectorAll("tr").forEach((r) => { if (!seen.has(r.dataset.node)) r.remove(); });
  const faults = $("#faults tbody");
  faults.innerHTML = "";
  for (const f of s.faults || []) {
    const row = el("tr", { "data-fault": `${f.scenario}:${f.line}` });
    const at = f.at_ns === undefined ? "" : `${(f.at_ns / 1e9).toFixed(3)} s` +
      (f.until_ns === undefined ? "" : ` .. ${(f.until_ns / 1e9).toFixed(3)} s`);
    for (const v of [f.scenario, f.line, f.effect, f.target, at, f.seen, f.hits, f.state]) {
      row.append(el("td", {}, v === undefined ? "" : String(v)));
    }
    faults.append(row);
  }
  showBridges(s);
}

function showBridges(s) {
  const bridges = s.bridges || [];
  const remote = (s.distributed && s.distributed.remote_buses) || [];
  $("#bridges-section").hidden = bridges.length === 0 && remote.length === 0;
  const b = $("#bridges tbody");
  b.innerHTML = "";
  for (const x of bridges) {
    const dropped = (x.to_interface_dropped || 0) + (x.kernel_dropped || 0) + (x.queue_dropped || 0);
    const row = el("tr");
    for (const v of [x.bus, x.interface, x.state, x.to_interface, x.from_interface, dropped, x.rejected]) {
      row.append(el("td", {}, v === undefined ? "" : String(v)));
    }
    b.append(row);
  }
  const r = $("#remote tbody");
  r.innerHTML = "";
  for (const x of remote) {
    const row = el("tr");
    for (const v of [x.bus, x.owner, x.state, x.reason, x.nodes]) row.append(el("td", {}, String(v ?? "")));
    r.append(row);
  }
}

function showIds(ids) {
  for (const [bus, rows] of Object.entries(ids || {})) {
    let table = document.getElementById(`ids-${bus}`);
    if (!table) {
      const card = el("div", { class: "card" });
      card.append(el("h3", {}, bus));
      table = el("table", { id: `ids-${bus}`, "data-bus": bus });
      table.innerHTML = "<thead><tr><th>ID</th><th>count</th><th>period ms</th><th>data</th>" +
        "<th>signals</th></tr></thead><tbody></tbody>";
      card.append(table);
      $("#ids").append(card);
    }
    const body = table.tBodies[0];
    for (const r of rows) {
      let row = body.querySelector(`tr[data-id="${esc(r.id)}"]`);
      if (!row) {
        row = el("tr", { "data-id": r.id });
        for (const c of ["id", "count", "period", "data", "signals"]) row.append(el("td", { class: c }));
        row.children[0].textContent = r.id;
        body.append(row);
      }
      row.children[1].textContent = r.count;
      row.children[2].textContent = fmt(r.period_ms, 2);
      const data = row.children[3];
      data.className = "data";
      data.innerHTML = "";
      if (r.data === "R") data.append("remote");
      for (let i = 0; r.data !== "R" && i < r.data.length; i += 2) {
        const byte = r.data.slice(i, i + 2);
        data.append((r.changed >> (i / 2)) & 1 ? el("b", {}, byte) : byte, " ");
      }
      // Through the DBC files of --dbc: "MESSAGE: signal=value ...", or why not decoded.
      const text = r.signals ? r.signals.map(([k, v]) => `${k}=${v}`).join(" ") : (r.note || "");
      row.children[4].textContent = r.message ? `${r.message}: ${text}` : text;
    }
  }
}

function showFired(events) {
  const list = $("#fired");
  for (const f of events) {
    firedEvents.push(f);
    list.append(el("li", {}, `${(f.t / 1e9).toFixed(6)} s  ${f.scenario}:${f.line} ${f.effect} ` +
      `on ${f.target}: ${f.hits} hit(s), ${f.state}`));
  }
  firedEvents = firedEvents.slice(-200);
}

function handle(msg) {
  const start = performance.now();
  if (msg.type === "error") {
    $("#problem").hidden = false;
    $("#problem").textContent = msg.error;
    return;
  }
  $("#problem").hidden = !msg.error;
  if (msg.error) $("#problem").textContent = msg.error;
  if (msg.type === "snapshot") {  // the first message, and again after a reconnection
    for (const entry of Object.values(view.charts)) {
      for (const chart of [entry.load, entry.counters]) if (chart) chart.data.datasets = [];
    }
    firedEvents = [];
    $("#fired").innerHTML = "";
    if (msg.status) showStatus(msg.status, null);
    showFired(msg.faults_fired || []);
    for (const p of msg.history || []) addPoint(p, msg.status ? msg.status.nodes : []);
  } else {
    showStatus(msg.status, msg.rates);
    showFired(msg.fired || []);
    addPoint(msg.point, msg.status.nodes);
  }
  showIds(msg.ids);
  $("#capture").textContent = (msg.listening && msg.listening.length
    ? `counting the frames of ${msg.listening.join(", ")} through listen-only nodes. ` : "") +
    (msg.capture_note || "");
  if (msg.lin) { $("#lin-section").hidden = false; $("#lin").textContent = msg.lin; }
  if (msg.status) redraw(msg.status.sim_time_ns / 1e9);
  view.updates += 1;
  view.handleMs.push(performance.now() - start);
  if (view.handleMs.length > 1000) view.handleMs.shift();
}

function button(text, onclick) {
  const b = el("button", { type: "button" }, text);
  b.addEventListener("click", onclick);
  return b;
}

async function act(action, body) {
  const r = await fetch(`/api/${action}`, {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  $("#action-result").textContent = `${action}: ${r.status} ${await r.text()}`;
}

function setUpControl() {
  $("#control").hidden = !view.settings.allow_control;
  if (!view.settings.allow_control) return;
  for (const e of view.settings.effects) $("#effect").append(el("option", {}, e));
  $("#step-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    act("step", { duration: $("#step").value.trim() });
  });
  $("#fault-form").addEventListener("submit", (ev) => {
    ev.preventDefault();
    const body = { effect: $("#effect").value };
    for (const word of $("#fault-keys").value.split(/\s+/).filter(Boolean)) {
      const [k, ...v] = word.split("=");
      body[k] = v.join("=");
    }
    act("fault", body);
  });
}

async function start() {
  try {
    view.settings = await (await fetch("/api/settings")).json();
  } catch (e) { /* read-only */ }
  setUpControl();
  const source = new EventSource("/events");
  source.onopen = () => { $("#link").textContent = "live"; $("#link").className = "up"; };
  source.onerror = () => { $("#link").textContent = "reconnecting"; $("#link").className = "down"; };
  source.onmessage = (ev) => handle(JSON.parse(ev.data));
}

start();
