(() => {
"use strict";
// The explorer's plot: SVG, one panel (shared axes) or one panel per unit, zoom by
// dragging or with the wheel (time axis), double-click to reset, a cursor whose values the
// page reads out, events marked on the time axis. No external library: the figure is the
// SVG in the page, so its SVG export is exactly what is seen and its PNG export is that
// SVG drawn on a canvas.

const SVGNS = "http://www.w3.org/2000/svg";
const PALETTE = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
                 "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"];
const DASHES = ["", "7 4", "2 3", "9 3 2 3", "4 2"];
const MARGIN = {left: 72, right: 14, top: 8, bottom: 34, legend: 18};

function el(tag, attrs, parent) {
  const node = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) node.setAttribute(k, v);
  if (parent) parent.appendChild(node);
  return node;
}

// Round numbers covering [lo, hi], about n of them.
function niceTicks(lo, hi, n) {
  const span = hi - lo;
  if (!(span > 0) || !isFinite(span)) return [lo];
  const raw = span / Math.max(n, 1);
  const mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 2.5, 5, 10].map(f => f * mag).find(s => s >= raw) || 10 * mag;
  const ticks = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) {
    ticks.push(Math.abs(v) < step * 1e-9 ? 0 : v);
  }
  return ticks;
}

function fmt(v) {
  if (v === null || v === undefined || !isFinite(v)) return "–";
  if (v === 0) return "0";
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-3) return v.toExponential(3).replace(/\.?0+e/, "e");
  return String(parseFloat(v.toPrecision(5)));
}

// Value of a trace at time t: linear interpolation between its (possibly decimated)
// points; null outside its time range.
function valueAt(trace, t) {
  const ts = trace.t, ys = trace.y;
  if (!ts || ts.length === 0 || t < ts[0] || t > ts[ts.length - 1]) return null;
  let lo = 0, hi = ts.length - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (ts[mid] <= t) lo = mid; else hi = mid;
  }
  if (ts[hi] === ts[lo] || ys[lo] === null || ys[hi] === null) return ys[lo];
  return ys[lo] + (ys[hi] - ys[lo]) * (t - ts[lo]) / (ts[hi] - ts[lo]);
}

class Plot {
  constructor(container, {onView, onCursor} = {}) {
    this.container = container;
    this.onView = onView || (() => {});
    this.onCursor = onCursor || (() => {});
    this.traces = [];          // {key, label, unit, color, dash, t, y, events, t0, t1}
    this.separate = false;
    this.view = null;          // [t0, t1] or null: everything
    this.panels = [];
    this.svg = null;
    this.cursorT = null;
    new ResizeObserver(() => this.render()).observe(container);
  }

  setTraces(traces) { this.traces = traces; this.render(); }
  setSeparate(on) { this.separate = on; this.render(); }

  fullRange() {
    let lo = Infinity, hi = -Infinity;
    for (const tr of this.traces) { lo = Math.min(lo, tr.t0); hi = Math.max(hi, tr.t1); }
    return isFinite(lo) ? [lo, hi > lo ? hi : lo + 1] : [0, 1];
  }

  range() { return this.view || this.fullRange(); }

  setView(view, notify = true) {
    if (view) {
      const [a, b] = this.fullRange();
      let [t0, t1] = view;
      t0 = Math.max(t0, a); t1 = Math.min(t1, b);
      view = t1 > t0 ? [t0, t1] : null;
      if (view && t0 <= a && t1 >= b) view = null;
    }
    this.view = view;
    this.render();
    if (notify) this.onView(this.view);
  }

  // Pixel width of the plotting area (what the server decimates to).
  plotWidth() {
    return Math.max(50, Math.round((this.container.clientWidth || 800) - MARGIN.left - MARGIN.right));
  }

  groups() {
    if (!this.separate) return [this.traces];
    const byUnit = new Map();
    for (const tr of this.traces) {
      if (!byUnit.has(tr.unit)) byUnit.set(tr.unit, []);
      byUnit.get(tr.unit).push(tr);
    }
    return [...byUnit.values()];
  }

  render() {
    const box = this.container;
    box.replaceChildren();
    this.svg = null;
    if (this.traces.length === 0) {
      const p = document.createElement("p");
      p.className = "hint";
      p.textContent = "Click a variable on the left to plot it. Drag to zoom, wheel to zoom in time, double-click to reset.";
      box.appendChild(p);
      return;
    }
    const W = Math.max(box.clientWidth, 300), H = Math.max(box.clientHeight, 300);
    const svg = el("svg", {xmlns: SVGNS, width: W, height: H, viewBox: `0 0 ${W} ${H}`,
                           "font-family": "DejaVu Sans, sans-serif", "font-size": 11});
    el("rect", {x: 0, y: 0, width: W, height: H, fill: "#ffffff"}, svg);
    const [t0, t1] = this.range();
    const x0 = MARGIN.left, x1 = W - MARGIN.right;
    const sx = t => x0 + (t - t0) / (t1 - t0) * (x1 - x0);
    this.tOf = x => t0 + (x - x0) / (x1 - x0) * (t1 - t0);
    const groups = this.groups();
    const usable = H - MARGIN.top - MARGIN.bottom;
    const each = usable / groups.length;
    this.panels = [];
    const xticks = niceTicks(t0, t1, Math.max(2, Math.floor((x1 - x0) / 90)));
    groups.forEach((traces, k) => {
      const top = MARGIN.top + k * each + MARGIN.legend, bottom = MARGIN.top + (k + 1) * each - (k < groups.length - 1 ? 14 : 0);
      // y range from the points in the window
      let lo = Infinity, hi = -Infinity;
      for (const tr of traces) {
        for (let i = 0; i < tr.t.length; i++) {
          const y = tr.y[i];
          if (y === null || tr.t[i] < t0 || tr.t[i] > t1) continue;
          if (y < lo) lo = y; if (y > hi) hi = y;
        }
      }
      if (!isFinite(lo)) { lo = -1; hi = 1; }
      if (hi - lo <= Math.abs(hi) * 1e-12) { const d = Math.abs(hi) * 0.1 || 1; lo -= d; hi += d; }
      const pad = (hi - lo) * 0.05; lo -= pad; hi += pad;
      const sy = y => bottom - (y - lo) / (hi - lo) * (bottom - top);
      const panel = {top, bottom, traces, sy};
      this.panels.push(panel);
      const g = el("g", {}, svg);
      // grid and ticks
      for (const v of niceTicks(lo, hi, Math.max(2, Math.floor((bottom - top) / 40)))) {
        const y = sy(v);
        el("line", {x1: x0, x2: x1, y1: y, y2: y, stroke: "#eceff1"}, g);
        const label = el("text", {x: x0 - 5, y: y + 4, "text-anchor": "end", fill: "#455a64"}, g);
        label.textContent = fmt(v);
      }
      for (const v of xticks) {
        const x = sx(v);
        el("line", {x1: x, x2: x, y1: top, y2: bottom, stroke: "#eceff1"}, g);
        if (k === groups.length - 1) {
          const label = el("text", {x, y: bottom + 15, "text-anchor": "middle", fill: "#455a64"}, g);
          label.textContent = fmt(v);
        }
      }
      const units = [...new Set(traces.map(tr => tr.unit || "1"))].join(", ");
      const ylab = el("text", {x: 12, y: (top + bottom) / 2, "text-anchor": "middle", fill: "#455a64",
                               transform: `rotate(-90 12 ${(top + bottom) / 2})`}, g);
      ylab.textContent = `[${units}]`;
      // clip to the panel
      const clipId = `clip${k}`;
      const clip = el("clipPath", {id: clipId}, svg);
      el("rect", {x: x0, y: top, width: x1 - x0, height: bottom - top}, clip);
      const inside = el("g", {"clip-path": `url(#${clipId})`}, g);
      // events of the runs shown
      const seen = new Set();
      for (const tr of traces) {
        for (const te of tr.events || []) {
          if (te < t0 || te > t1 || seen.has(te)) continue;
          seen.add(te);
          el("line", {x1: sx(te), x2: sx(te), y1: top, y2: bottom, stroke: "#ff9800",
                      "stroke-dasharray": "3 3", "stroke-width": 1, class: "event"}, inside);
        }
      }
      for (const tr of traces) {
        let pts = [];
        const flush = () => {
          if (pts.length > 1) {
            el("polyline", {points: pts.join(" "), fill: "none", stroke: tr.color,
                            "stroke-width": 1.6, "stroke-dasharray": tr.dash,
                            "stroke-linejoin": "round", "data-key": tr.key, class: "trace"}, inside);
          } else if (pts.length === 1) {
            const [x, y] = pts[0].split(",");
            el("circle", {cx: x, cy: y, r: 2, fill: tr.color, "data-key": tr.key, class: "trace"}, inside);
          }
          pts = [];
        };
        for (let i = 0; i < tr.t.length; i++) {
          if (tr.y[i] === null) { flush(); continue; }
          pts.push(`${sx(tr.t[i]).toFixed(1)},${sy(tr.y[i]).toFixed(1)}`);
        }
        flush();
      }
      el("rect", {x: x0, y: top, width: x1 - x0, height: bottom - top, fill: "none", stroke: "#90a4ae"}, g);
      // legend above the panel
      let lx = x0;
      for (const tr of traces) {
        el("line", {x1: lx, x2: lx + 22, y1: top - 6, y2: top - 6, stroke: tr.color, "stroke-width": 2,
                    "stroke-dasharray": tr.dash}, g);
        const t = el("text", {x: lx + 26, y: top - 2, fill: "#263238"}, g);
        t.textContent = `${tr.label} [${tr.unit || "1"}]`;
        lx += 34 + 6.5 * t.textContent.length;
      }
    });
    const tl = el("text", {x: (x0 + x1) / 2, y: H - 4, "text-anchor": "middle", fill: "#455a64"}, svg);
    tl.textContent = "t [s]";
    // cursor and zoom rectangle (not part of the exported figure)
    this.cursor = el("line", {y1: MARGIN.top, y2: H - MARGIN.bottom, stroke: "#37474f",
                              "stroke-width": 1, visibility: "hidden", class: "overlay"}, svg);
    this.band = el("rect", {y: MARGIN.top, height: H - MARGIN.top - MARGIN.bottom,
                            fill: "#4fc3f7", "fill-opacity": 0.2, visibility: "hidden", class: "overlay"}, svg);
    this.svg = svg;
    this.x0 = x0; this.x1 = x1;
    box.appendChild(svg);
    this.attach(svg);
    if (this.cursorT !== null) this.showCursor(this.cursorT);
  }

  showCursor(t) {
    const [t0, t1] = this.range();
    if (!this.svg || t < t0 || t > t1) return;
    const x = this.x0 + (t - t0) / (t1 - t0) * (this.x1 - this.x0);
    this.cursor.setAttribute("x1", x); this.cursor.setAttribute("x2", x);
    this.cursor.setAttribute("visibility", "visible");
    this.cursorT = t;
    this.onCursor(t);
  }

  attach(svg) {
    const xOf = ev => ev.clientX - svg.getBoundingClientRect().left;
    let drag = null;
    svg.addEventListener("mousemove", ev => {
      const x = Math.min(Math.max(xOf(ev), this.x0), this.x1);
      this.showCursor(this.tOf(x));
      if (drag !== null) {
        this.band.setAttribute("x", Math.min(drag, x));
        this.band.setAttribute("width", Math.abs(x - drag));
        this.band.setAttribute("visibility", "visible");
      }
    });
    svg.addEventListener("mousedown", ev => {
      if (ev.button === 0) drag = Math.min(Math.max(xOf(ev), this.x0), this.x1);
    });
    svg.addEventListener("mouseup", ev => {
      if (drag === null) return;
      const x = Math.min(Math.max(xOf(ev), this.x0), this.x1);
      const a = drag; drag = null;
      this.band.setAttribute("visibility", "hidden");
      if (Math.abs(x - a) > 4) this.setView([this.tOf(Math.min(a, x)), this.tOf(Math.max(a, x))]);
    });
    svg.addEventListener("mouseleave", () => { drag = null; this.band.setAttribute("visibility", "hidden"); });
    svg.addEventListener("dblclick", () => this.setView(null));
    svg.addEventListener("wheel", ev => {
      ev.preventDefault();
      const [t0, t1] = this.range();
      const t = this.tOf(Math.min(Math.max(xOf(ev), this.x0), this.x1));
      const f = ev.deltaY > 0 ? 1.25 : 0.8;
      this.setView([t - (t - t0) * f, t + (t1 - t) * f]);
    }, {passive: false});
  }

  // The figure as a standalone SVG document (cursor and zoom band left out).
  svgText() {
    if (!this.svg) return null;
    const copy = this.svg.cloneNode(true);
    copy.querySelectorAll(".overlay").forEach(n => n.remove());
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(copy);
  }

  // The figure as a PNG data URL, drawn at `scale` times its size on the screen.
  png(scale = 2) {
    const text = this.svgText();
    if (!text) return Promise.reject(new Error("nothing is plotted: plot a variable first."));
    const w = +this.svg.getAttribute("width"), h = +this.svg.getAttribute("height");
    return new Promise((resolve, reject) => {
      const img = new Image();
      img.onload = () => {
        const canvas = document.createElement("canvas");
        canvas.width = w * scale; canvas.height = h * scale;
        const ctx = canvas.getContext("2d");
        ctx.scale(scale, scale);
        ctx.drawImage(img, 0, 0, w, h);
        resolve(canvas.toDataURL("image/png"));
      };
      img.onerror = () => reject(new Error("the figure could not be drawn as PNG."));
      img.src = "data:image/svg+xml;charset=utf-8," + encodeURIComponent(text);
    });
  }
}

window.MtPlot = {Plot, PALETTE, DASHES, fmt, valueAt, niceTicks};
})();
