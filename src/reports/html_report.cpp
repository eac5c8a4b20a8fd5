// report.html: the run overview, one self-contained file (inline CSS, SVG and script, nothing
// fetched): summary, a map of the footprints coloured by status or RMSE, histograms, the worst
// buildings with their reason, and a 3D view of a chosen building. The data is embedded as JSON;
// the page draws itself with plain DOM/SVG/canvas code.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "city3d/error.hpp"
#include "city3d/run_outputs.hpp"
#include "files/atomic_file.hpp"

namespace city3d {
namespace {

// JSON text, safe inside a <script> element ('<' escaped, so no "</script>" can appear).
void json_string(std::string& out, const std::string& s) {
  out += '"';
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c == '<' || c == '>' || c == '&') {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  out += '"';
}

void json_number(std::string& out, double v, int decimals) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  // Trim trailing zeros to keep the page small ("12.50" -> "12.5", "3.000" -> "3").
  std::string s = buf;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  out += s;
}

// The outline a model stands on, in plan (world coordinates): its ground faces' rings. For a
// single-building cloud, the outline city3d inferred from its points.
std::vector<Ring2> ground_rings(const BuildingModel& m) {
  std::vector<Ring2> rings;
  const std::vector<SurfaceType> types = surface_types(m);
  for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
    if (types[f] != SurfaceType::ground) continue;
    Ring2 ring;
    for (std::uint32_t v : m.mesh.faces[f]) ring.push_back({m.mesh.vertices[v].x + m.origin.x, m.mesh.vertices[v].y + m.origin.y});
    rings.push_back(std::move(ring));
  }
  return rings;
}

// Vertex coordinates of models embedded for the 3D view, at most (keeps a 10,000-building page light).
constexpr std::size_t kModelVertexBudget = 150000;

// The records of the first pass kept for the two passes after it instead of being read (and their
// CityJSONFeature parsed) again: up to this many records and vertices of models and footprints in
// all (a kept record of the Delft block holds about 15 KB: at most a few MB whatever the size of
// the run), every record of a city block, the first ones of a large run.
constexpr std::size_t kKeptRecords = 200;
constexpr std::size_t kKeptVertexBudget = 50000;

const char* kPage1 = R"HTML(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>city3d run overview</title>
<style>
:root { --ok: #2e9e5b; --fallback: #e0a526; --partial: #8e5bd6; --skipped: #9aa3ad; --failed: #d64545; --ink: #1d2733; --muted: #5f6b78;
        --line: #dde3ea; --panel: #ffffff; --bg: #f3f5f8; --accent: #2f6fdf; }
* { box-sizing: border-box; }
body { margin: 0; font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
       color: var(--ink); background: var(--bg); }
header { padding: 18px 28px 10px; }
h1 { margin: 0 0 2px; font-size: 22px; font-weight: 650; letter-spacing: -0.01em; }
h2 { margin: 0 0 10px; font-size: 15px; font-weight: 650; }
.sub { color: var(--muted); font-size: 13px; }
.cards { display: flex; flex-wrap: wrap; gap: 10px; padding: 6px 28px 14px; }
.card { background: var(--panel); border: 1px solid var(--line); border-radius: 10px; padding: 10px 16px; min-width: 118px; }
.card .v { font-size: 22px; font-weight: 650; }
.card .k { color: var(--muted); font-size: 12px; text-transform: uppercase; letter-spacing: 0.04em; }
.card.ok .v { color: var(--ok); } .card.fallback .v { color: #b7811a; } .card.failed .v { color: var(--failed); }
.card.skipped .v { color: #6f7983; } .card.partial .v { color: var(--partial); }
main { display: grid; grid-template-columns: minmax(0, 1.35fr) minmax(0, 1fr); gap: 16px; padding: 0 28px 28px; }
.panel { background: var(--panel); border: 1px solid var(--line); border-radius: 12px; padding: 14px 16px; min-width: 0; }
.wide { grid-column: 1 / -1; }
.toolbar { display: flex; align-items: center; gap: 8px; margin-bottom: 8px; }
.toolbar h2 { margin: 0; flex: 1; }
button.tab { border: 1px solid var(--line); background: #f7f9fb; border-radius: 7px; padding: 4px 10px; font: inherit;
             font-size: 13px; cursor: pointer; color: var(--ink); }
button.tab.on { background: var(--accent); border-color: var(--accent); color: #fff; }
.mapbox { position: relative; }
#map { width: 100%; height: 460px; display: block; background: #fbfcfd; border-radius: 8px; border: 1px solid var(--line); }
#scalebar { position: absolute; left: 12px; bottom: 10px; font-size: 11px; color: var(--ink); pointer-events: none; }
#scalebar .bar { height: 6px; border: 1.5px solid var(--ink); border-top: none; margin-bottom: 2px; }
table.params { border-collapse: collapse; font-size: 12.5px; width: 100%; }
table.params td { padding: 2px 10px 2px 0; vertical-align: top; border-bottom: 1px solid #f0f2f5; }
table.params td:first-child { color: var(--muted); white-space: nowrap; width: 1%; }
.runinfo { font-size: 13px; }
.runinfo .warn { color: #9a5b00; }
details summary { cursor: pointer; color: var(--accent); margin: 8px 0 4px; }
#map path { stroke: #ffffff; stroke-width: 0.6; vector-effect: non-scaling-stroke; cursor: pointer; }
#map path:hover { stroke: var(--ink); stroke-width: 1.5; }
#map path.sel { stroke: #111; stroke-width: 2.5; }
.legend { display: flex; flex-wrap: wrap; gap: 12px; margin-top: 8px; font-size: 12px; color: var(--muted); align-items: center; }
.sw { display: inline-block; width: 12px; height: 12px; border-radius: 3px; margin-right: 5px; vertical-align: -2px; }
.ramp { width: 140px; height: 10px; border-radius: 3px; display: inline-block; vertical-align: -1px; margin: 0 6px; }
#view { width: 100%; height: 300px; display: block; background: linear-gradient(#eef3fa, #fdfdfe); border-radius: 8px;
        border: 1px solid var(--line); cursor: grab; }
#details { margin-top: 10px; font-size: 13px; }
#details table { border-collapse: collapse; width: 100%; }
#details td { padding: 2px 6px 2px 0; vertical-align: top; }
#details td:first-child { color: var(--muted); width: 38%; }
.hists { display: grid; grid-template-columns: repeat(3, minmax(0, 1fr)); gap: 16px; }
.hist svg { width: 100%; height: 170px; display: block; }
.hist .t { font-size: 13px; font-weight: 600; margin-bottom: 4px; }
.hist .n { color: var(--muted); font-weight: 400; }
table.worst { border-collapse: collapse; width: 100%; font-size: 13px; }
table.worst th { text-align: left; color: var(--muted); font-weight: 600; border-bottom: 1px solid var(--line); padding: 6px 8px; }
table.worst td { border-bottom: 1px solid #eef1f4; padding: 5px 8px; vertical-align: top; }
table.worst tr { cursor: pointer; }
table.worst tr:hover td { background: #f5f8fc; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.pill { display: inline-block; padding: 0 8px; border-radius: 10px; font-size: 12px; color: #fff; }
.reason { color: var(--muted); max-width: 520px; }
#tip { position: fixed; pointer-events: none; background: rgba(29, 39, 51, 0.92); color: #fff; padding: 5px 8px; border-radius: 6px;
       font-size: 12px; display: none; z-index: 5; max-width: 360px; }
.empty { color: var(--muted); padding: 30px 0; text-align: center; }
footer { color: var(--muted); font-size: 12px; padding: 0 28px 24px; }
@media (max-width: 1000px) { main { grid-template-columns: 1fr; } .hists { grid-template-columns: 1fr; } }
</style>
</head>
<body>
<header><h1>city3d run overview</h1><div class="sub" id="subtitle"></div></header>
<div class="cards" id="cards"></div>
<main>
  <section class="panel">
    <div class="toolbar"><h2 id="map-title">Footprints</h2>
      <button class="tab on" id="by-status">Status</button><button class="tab" id="by-rmse">RMSE</button></div>
    <div class="mapbox"><svg id="map" role="img" aria-label="map of the footprints"></svg><div id="scalebar"></div></div>
    <div class="legend" id="legend"></div>
  </section>
  <section class="panel">
    <div class="toolbar"><h2 id="view-title">3D view</h2></div>
    <canvas id="view" width="600" height="300"></canvas>
    <div id="details"></div>
  </section>
  <section class="panel wide"><h2>Distributions</h2><div class="hists" id="hists"></div></section>
  <section class="panel wide"><h2>Worst buildings</h2><div id="worst"></div></section>
  <section class="panel wide"><h2>Inputs and parameters</h2><div id="run" class="runinfo"></div></section>
</main>
<footer>Written by city3d. Drag the 3D view to turn the model; point at a footprint for its figures, click it or a table row to choose a building.</footer>
<div id="tip"></div>
<script id="data" type="application/json">)HTML";

const char* kPage2 = R"HTML(</script>
<script>
"use strict";
const D = JSON.parse(document.getElementById("data").textContent);
const B = D.buildings;
const COLORS = { ok: "#2e9e5b", fallback: "#e0a526", partial: "#8e5bd6", skipped: "#9aa3ad", failed: "#d64545" };
const SVGNS = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const fmt = (v, d) => (v === null || v === undefined ? "–" : Number(v).toFixed(d));
function el(tag, attrs, parent) {
  const e = tag === "svg" || ["path", "rect", "line", "text", "g"].includes(tag) ? document.createElementNS(SVGNS, tag)
                                                                                 : document.createElement(tag);
  for (const k in attrs || {}) e.setAttribute(k, attrs[k]);
  if (parent) parent.appendChild(e);
  return e;
}
function median(xs) {
  if (!xs.length) return null;
  const s = xs.slice().sort((a, b) => a - b), m = s.length >> 1;
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2;
}

// Summary.
const counts = { ok: 0, fallback: 0, partial: 0, skipped: 0, failed: 0 };
B.forEach((b) => { counts[b.s] = (counts[b.s] || 0) + 1; });
const rmses = B.filter((b) => b.rmse !== null).map((b) => b.rmse);
const faces = B.filter((b) => b.f > 0).map((b) => b.f);
const secs = B.map((b) => b.t);
$("subtitle").textContent = B.length + " buildings" + (D.crs ? " · " + D.crs : "") + " · city3d " + D.version;

// Inputs, CRS and parameters: what made these outputs.
(function drawRun() {
  const box = $("run"), I = D.inputs || {}, P = D.parameters || {};
  const line = (label, text, cls) => {
    const p = el("div", cls ? { class: cls } : {}, box);
    el("b", {}, p).textContent = label + ": ";
    p.appendChild(document.createTextNode(text));
  };
  const clouds = I.point_clouds || [];
  const name = (path) => String(path).split("/").pop();
  line("point clouds", clouds.length + (clouds.length === 1 ? " file: " : " files: ") +
       clouds.slice(0, 12).map(name).join(", ") + (clouds.length > 12 ? ", ..." : ""));
  if (I.footprints) line("footprints", I.footprints + " (layer " + I.layer + ", id field " + (I.id_field || "the feature id") + ")");
  else line("footprints", "none: every point cloud is one building, its outline inferred from its points");
  const source = { "--crs": "given with --crs", "point clouds": "as the point clouds record it",
                   "footprints": "taken from the footprints: the point clouds record none" }[D.crs_source] || "";
  line("CRS", D.crs ? D.crs + (source ? " (" + source + ")" : "") : "none recorded (give --crs)",
       D.crs_source === "footprints" || !D.crs ? "warn" : "");
  const details = el("details", {}, box);
  el("summary", {}, details).textContent = Object.keys(P).length + " parameters";
  const table = el("table", { class: "params" }, details);
  Object.keys(P).forEach((k) => {
    const tr = el("tr", {}, table);
    el("td", {}, tr).textContent = "--" + k;
    const v = P[k];
    el("td", {}, tr).textContent = v === null ? "–" : Array.isArray(v) ? v.join(",") : String(v);
  });
})();
[["buildings", B.length, ""], ["ok", counts.ok, "ok"], ["fallback", counts.fallback, "fallback"],
 ["partial", counts.partial, "partial"], ["skipped", counts.skipped, "skipped"], ["failed", counts.failed, "failed"],
 ["median RMSE (m)", fmt(median(rmses), 3), ""], ["faces", faces.reduce((a, b) => a + b, 0), ""],
 ["seconds (sum)", fmt(secs.reduce((a, b) => a + b, 0), 1), ""]].forEach(([k, v, c]) => {
  const card = el("div", { class: "card " + c }, $("cards"));
  el("div", { class: "v" }, card).textContent = v;
  el("div", { class: "k" }, card).textContent = k;
});

// RMSE colour ramp: green (good) through yellow to red at the 95th percentile or 0.5 m.
const rmseMax = Math.max(0.05, Math.min(0.5, rmses.length ? rmses.slice().sort((a, b) => a - b)[Math.floor(0.95 * (rmses.length - 1))] : 0.5));
function rampColor(t) {
  t = Math.max(0, Math.min(1, t));
  const stops = [[46, 158, 91], [240, 200, 60], [214, 69, 69]];
  const u = t < 0.5 ? t * 2 : (t - 0.5) * 2, a = stops[t < 0.5 ? 0 : 1], c = stops[t < 0.5 ? 1 : 2];
  return "rgb(" + a.map((v, i) => Math.round(v + (c[i] - v) * u)).join(",") + ")";
}

// Map.
const map = $("map"), tip = $("tip");
let mode = "status", selected = -1;
const paths = [];
(function drawMap() {
  let minx = Infinity, miny = Infinity, maxx = -Infinity, maxy = -Infinity;
  B.forEach((b) => (b.fp || []).forEach((ring) => ring.forEach(([x, y]) => {
    minx = Math.min(minx, x); maxx = Math.max(maxx, x); miny = Math.min(miny, y); maxy = Math.max(maxy, y);
  })));
  if (D.inferred) {
    $("map-title").textContent = "Outlines inferred from the points";
    map.setAttribute("aria-label", "outlines inferred from the points, one single-building cloud per cell, at one scale");
  }
  if (!isFinite(minx)) {
    const t = el("text", { x: "50%", y: "50%", "text-anchor": "middle", fill: "#5f6b78" }, map);
    t.textContent = "no footprint and no model in this run";
    return;
  }
  const pad = 0.03 * Math.max(maxx - minx, maxy - miny, 1);
  map.setAttribute("viewBox", [minx - pad, -(maxy + pad), maxx - minx + 2 * pad, maxy - miny + 2 * pad].join(" "));
  map.setAttribute("preserveAspectRatio", "xMidYMid meet");
  B.forEach((b, i) => {
    if (!b.fp || !b.fp.length) return;
    const d = b.fp.map((ring) => "M" + ring.map(([x, y]) => x + "," + -y).join("L") + "Z").join("");
    const p = el("path", { d: d, "fill-rule": "evenodd" }, map);
    p.addEventListener("mousemove", (e) => {
      tip.style.display = "block";
      tip.style.left = e.clientX + 12 + "px";
      tip.style.top = e.clientY + 12 + "px";
      tip.textContent = hoverText(b);
    });
    p.addEventListener("mouseleave", () => { tip.style.display = "none"; });
    p.addEventListener("click", () => select(i));
    paths[i] = p;
  });
  // Inferred outlines are side by side in cells of their own: each named under it (up to a hundred).
  const named = paths.filter((p) => p);
  if (D.inferred && named.length <= 100) {
    const size = Math.max(maxx - minx, maxy - miny) / Math.max(8, 4 * Math.sqrt(named.length));
    paths.forEach((p, i) => {
      if (!p) return;
      const box = p.getBBox();
      const t = el("text", { x: box.x + box.width / 2, y: box.y + box.height + size * 0.9, "text-anchor": "middle",
                             "font-size": size * 0.55, fill: "#5f6b78" }, map);
      t.textContent = B[i].id;
    });
  }
})();
// What pointing at a footprint shows: the building's id, status, level and main figures.
function hoverText(b) {
  return b.id + " · " + b.s + " · " + b.l + (b.h !== null ? " · roof " + fmt(b.h, 1) + " m" : "") +
         (b.rmse !== null ? " · RMSE " + fmt(b.rmse, 3) + " m" : "") + (b.f ? " · " + b.f + " faces" : "") +
         (b.r ? " · " + b.r : "");
}

// A scale bar under the map: a round length (1, 2 or 5 times a power of ten metres) of about a
// fifth of the map's width, redrawn when the page is resized.
function drawScaleBar() {
  const box = $("scalebar");
  box.innerHTML = "";
  const vb = map.viewBox && map.viewBox.baseVal;
  if (!vb || !vb.width) return;
  const r = map.getBoundingClientRect();
  const perMetre = Math.min(r.width / vb.width, r.height / vb.height);  // preserveAspectRatio "meet"
  if (!(perMetre > 0)) return;
  const target = r.width / 5 / perMetre;
  const power = Math.pow(10, Math.floor(Math.log10(target)));
  const metres = [5, 2, 1].map((f) => f * power).find((m) => m <= target) || power;
  const bar = el("div", { class: "bar" }, box);
  bar.style.width = Math.round(metres * perMetre) + "px";
  el("div", {}, box).textContent = (metres >= 1000 ? metres / 1000 + " km" : metres + " m");
  box.dataset.metres = metres;
  box.dataset.pixels = Math.round(metres * perMetre);
}
window.addEventListener("resize", drawScaleBar);

function colourMap() {
  B.forEach((b, i) => {
    if (!paths[i]) return;
    const c = mode === "status" ? COLORS[b.s] : b.rmse === null ? "#c9ced4" : rampColor(b.rmse / rmseMax);
    paths[i].setAttribute("fill", c);
  });
  const lg = $("legend");
  lg.innerHTML = "";
  if (mode === "status") {
    Object.keys(COLORS).forEach((k) => {
      const s = el("span", {}, lg);
      el("span", { class: "sw", style: "background:" + COLORS[k] }, s);
      s.appendChild(document.createTextNode(k + " (" + (counts[k] || 0) + ")"));
    });
  } else {
    const s = el("span", {}, lg);
    s.appendChild(document.createTextNode("RMSE 0 m"));
    el("span", { class: "ramp", style: "background:linear-gradient(90deg," + rampColor(0) + "," + rampColor(0.5) + "," + rampColor(1) + ")" }, s);
    s.appendChild(document.createTextNode(fmt(rmseMax, 2) + " m and more"));
    const n = el("span", {}, lg);
    el("span", { class: "sw", style: "background:#c9ced4" }, n);
    n.appendChild(document.createTextNode("no model"));
  }
}
$("by-status").addEventListener("click", () => { mode = "status"; $("by-status").classList.add("on"); $("by-rmse").classList.remove("on"); colourMap(); });
$("by-rmse").addEventListener("click", () => { mode = "rmse"; $("by-rmse").classList.add("on"); $("by-status").classList.remove("on"); colourMap(); });
colourMap();
drawScaleBar();

// Histograms.
function histogram(title, values, unit, decimals) {
  const box = el("div", { class: "hist" }, $("hists"));
  const t = el("div", { class: "t" }, box);
  t.textContent = title + " ";
  el("span", { class: "n" }, t).textContent = values.length ? "median " + fmt(median(values), decimals) + " " + unit + ", n = " + values.length : "no values";
  const W = 360, H = 170, L = 36, R = 8, T = 8, Bm = 26;
  const svg = el("svg", { viewBox: "0 0 " + W + " " + H }, box);
  if (!values.length) return;
  const lo = Math.min(...values), hi = Math.max(...values);
  const n = Math.max(1, Math.min(24, Math.ceil(Math.sqrt(values.length)) + 2));
  const width = hi > lo ? (hi - lo) / n : 1;
  const bins = new Array(n).fill(0);
  values.forEach((v) => { bins[Math.min(n - 1, Math.floor((v - lo) / width))]++; });
  const top = Math.max(...bins);
  const bw = (W - L - R) / n;
  for (let k = 0; k <= 4; k++) {
    const y = T + (H - T - Bm) * (1 - k / 4);
    el("line", { x1: L, x2: W - R, y1: y, y2: y, stroke: "#eef1f4" }, svg);
    el("text", { x: L - 5, y: y + 4, "text-anchor": "end", "font-size": 10, fill: "#5f6b78" }, svg).textContent = Math.round(top * k / 4);
  }
  bins.forEach((c, i) => {
    const h = (H - T - Bm) * c / top;
    const r = el("rect", { x: L + i * bw + 1, y: H - Bm - h, width: Math.max(1, bw - 2), height: h, rx: 2, fill: "#2f6fdf" }, svg);
    r.addEventListener("mousemove", (e) => {
      tip.style.display = "block"; tip.style.left = e.clientX + 12 + "px"; tip.style.top = e.clientY + 12 + "px";
      tip.textContent = fmt(lo + i * width, decimals) + "–" + fmt(lo + (i + 1) * width, decimals) + " " + unit + ": " + c;
    });
    r.addEventListener("mouseleave", () => { tip.style.display = "none"; });
  });
  [0, 0.5, 1].forEach((f) => {
    el("text", { x: L + f * (W - L - R), y: H - 8, "text-anchor": f === 0 ? "start" : f === 1 ? "end" : "middle", "font-size": 10, fill: "#5f6b78" }, svg)
      .textContent = fmt(lo + f * (hi - lo), decimals) + (f === 1 ? " " + unit : "");
  });
}
histogram("RMSE", rmses, "m", 3);
histogram("Faces", faces, "", 0);
histogram("Seconds", secs, "s", 2);

// Worst buildings: failed, then partly covered, then fallback, then the least faithful models both ways
// (the share of the points farther than 1 m from the model, plus the share of the footprint's area that
// the model covers with surface no point supports), then the highest RMSE.
const rank = { failed: 0, partial: 1, fallback: 2, ok: 3, skipped: 4 };
const unfaithful = (b) => (b.us || 0) + (b.ua && b.fa ? b.ua / b.fa : 0);
const worst = B.map((b, i) => i).filter((i) => B[i].s !== "skipped" || B[i].r)
  .sort((a, b) => rank[B[a].s] - rank[B[b].s] || unfaithful(B[b]) - unfaithful(B[a]) ||
                  (B[b].rmse || 0) - (B[a].rmse || 0) || a - b).slice(0, 25);
(function drawWorst() {
  if (!worst.length) { el("div", { class: "empty" }, $("worst")).textContent = "no buildings"; return; }
  const table = el("table", { class: "worst" }, $("worst"));
  const head = el("tr", {}, el("thead", {}, table));
  ["building", "status", "level", "RMSE (m)", "points > 1 m", "unsupported (m²)", "faces", "seconds", "reason"]
    .forEach((h, k) => { el("th", k >= 3 && k <= 7 ? { class: "num" } : {}, head).textContent = h; });
  const body = el("tbody", {}, table);
  worst.forEach((i) => {
    const b = B[i], tr = el("tr", {}, body);
    el("td", {}, tr).textContent = b.id;
    el("span", { class: "pill", style: "background:" + COLORS[b.s] }, el("td", {}, tr)).textContent = b.s;
    el("td", {}, tr).textContent = b.l;
    el("td", { class: "num" }, tr).textContent = fmt(b.rmse, 3);
    el("td", { class: "num" }, tr).textContent = b.us === null || b.us === undefined ? "–" : fmt(100 * b.us, 1) + "%";
    el("td", { class: "num" }, tr).textContent = fmt(b.ua, 1);
    el("td", { class: "num" }, tr).textContent = b.f;
    el("td", { class: "num" }, tr).textContent = fmt(b.t, 2);
    el("td", { class: "reason" }, tr).textContent = b.r || (b.n || "");
    tr.addEventListener("click", () => select(i));
  });
})();

// 3D view: the chosen building's model, flat-shaded polygons sorted back to front, turned by dragging.
const canvas = $("view"), ctx = canvas.getContext("2d");
let yaw = -0.7, pitch = 0.55, model = null;
function resize() {
  const r = canvas.getBoundingClientRect(), s = window.devicePixelRatio || 1;
  canvas.width = Math.max(1, Math.round(r.width * s));
  canvas.height = Math.max(1, Math.round(r.height * s));
  draw();
}
function draw() {
  const W = canvas.width, H = canvas.height;
  ctx.clearRect(0, 0, W, H);
  if (!model) {
    ctx.fillStyle = "#5f6b78";
    ctx.font = Math.round(13 * (window.devicePixelRatio || 1)) + "px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.fillText(selected >= 0 ? "no model for this building" : "choose a building", W / 2, H / 2);
    return;
  }
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const P = model.v.map(([x, y, z]) => {
    const x1 = x * cy - y * sy, y1 = x * sy + y * cy;
    return [x1, y1 * sp + z * cp, -y1 * cp + z * sp];  // screen x, screen y (up), depth (towards viewer)
  });
  let ylo = Infinity, yhi = -Infinity;
  P.forEach((p) => { ylo = Math.min(ylo, p[1]); yhi = Math.max(yhi, p[1]); });
  const zc = (ylo + yhi) / 2;
  let r = 1e-9;
  P.forEach(([x, y]) => { r = Math.max(r, Math.abs(x), Math.abs(y - zc)); });
  const scale = 0.42 * Math.min(W, H) / r;
  const light = [0.35, 0.55, 0.75];
  const faces = model.f.map((f, k) => {
    let nx = 0, ny = 0, nz = 0, depth = 0;
    for (let i = 0; i < f.length; i++) {
      const a = model.v[f[i]], b = model.v[f[(i + 1) % f.length]];
      nx += (a[1] - b[1]) * (a[2] + b[2]); ny += (a[2] - b[2]) * (a[0] + b[0]); nz += (a[0] - b[0]) * (a[1] + b[1]);
      depth += P[f[i]][2];
    }
    const len = Math.hypot(nx, ny, nz) || 1;
    return { f: f, k: k, depth: depth / f.length, shade: Math.abs((nx * light[0] + ny * light[1] + nz * light[2]) / len) };
  }).sort((a, b) => a.depth - b.depth);
  const base = { 0: [150, 150, 150], 1: [236, 232, 222], 2: [205, 92, 72] };  // ground, wall, roof
  faces.forEach(({ f, k, shade }) => {
    const c = base[model.s[k]] || [200, 200, 200], m = 0.55 + 0.45 * shade;
    ctx.beginPath();
    f.forEach((i, j) => {
      const X = W / 2 + P[i][0] * scale, Y = H / 2 - (P[i][1] - zc) * scale;
      if (j) ctx.lineTo(X, Y); else ctx.moveTo(X, Y);
    });
    ctx.closePath();
    ctx.fillStyle = "rgb(" + c.map((v) => Math.round(v * m)).join(",") + ")";
    ctx.fill();
    ctx.strokeStyle = "rgba(40,40,40,0.35)";
    ctx.lineWidth = 1;
    ctx.stroke();
  });
}
let drag = null;
canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
canvas.addEventListener("pointermove", (e) => {
  if (!drag) return;
  yaw -= (e.clientX - drag[0]) * 0.01;
  pitch = Math.max(-0.2, Math.min(1.5, pitch + (e.clientY - drag[1]) * 0.01));
  drag = [e.clientX, e.clientY];
  draw();
});
canvas.addEventListener("pointerup", () => { drag = null; });
window.addEventListener("resize", resize);

function select(i) {
  if (paths[selected]) paths[selected].classList.remove("sel");
  selected = i;
  if (paths[i]) paths[i].classList.add("sel");
  const b = B[i];
  model = b.m >= 0 ? D.models[b.m] : null;
  $("view-title").textContent = "3D view · " + b.id + (model ? " · LoD" + model.lod : "");
  const rows = [["status", b.s], ["level", b.l], ["levels written", b.lods || "–"], ["RMSE", fmt(b.rmse, 3) + " m"],
                ["points farther than 1 m", b.us === null || b.us === undefined ? "–" : fmt(100 * b.us, 1) + "%"],
                ["surface no point supports", fmt(b.ua, 1) + " m² (up to " + fmt(b.he, 1) + " m above the points)"],
                ["faces", b.f], ["points", b.p], ["roof height (70th percentile)", fmt(b.h, 2) + " m"],
                ["roof type", b.rt || "–"], ["seconds", fmt(b.t, 2)], ["reason", b.r || "–"], ["note", b.n || "–"]];
  const d = $("details");
  d.innerHTML = "";
  const table = el("table", {}, d);
  rows.forEach(([k, v]) => { const tr = el("tr", {}, table); el("td", {}, tr).textContent = k; el("td", {}, tr).textContent = v; });
  draw();
}
resize();
// Start with the worst building that has a model, else the first building with one.
const first = worst.find((i) => B[i].m >= 0);
const start = first !== undefined ? first : B.findIndex((b) => b.m >= 0);
if (start >= 0) select(start);
// With "#check" in its address the page checks its own map as a person would use it (the tests do):
// points at the first outline and logs what the hover shows, and logs the scale bar.
if (location.hash === "#check") {
  const first = paths.findIndex((p) => p);
  if (first >= 0) {
    const r = paths[first].getBoundingClientRect();
    paths[first].dispatchEvent(new MouseEvent("mousemove", { clientX: r.left + r.width / 2, clientY: r.top + r.height / 2, bubbles: true }));
    console.log("city3d report hover: " + (tip.style.display === "block" ? tip.textContent : "(nothing shown)"));
  }
  const sb = $("scalebar");
  const r = map.getBoundingClientRect(), vb = map.viewBox.baseVal;
  console.log("city3d report map: " + paths.filter((p) => p).length + " outlines; scale bar " + (sb.dataset.metres || "none") +
              " m = " + (sb.dataset.pixels || 0) + " px; map " + r.width.toFixed(1) + " x " + r.height.toFixed(1) + " px, " +
              (vb ? vb.width.toFixed(3) + " x " + vb.height.toFixed(3) : "0 x 0") + " m");
}
console.log("city3d report ready");
</script>
</body>
</html>
)HTML";

}  // namespace

void write_report_html(const std::string& path, const OverviewSource& records, const RunDescription& run) {
  const std::string& crs = run.crs;
  // A first pass over the records: the footprints' extent (the map is drawn relative to the run's
  // corner, in centimetres), what orders the models (status, faithfulness both ways, RMSE) and each highest level's size.
  struct Key {
    bool fallback = false;
    double unfaithful = 0.0;  // as the page's worst buildings: both ways, then RMSE
    double rmse = 0.0;
    std::size_t vertices = 0;
    bool model = false;
  };
  std::vector<Key> keys(records.size());
  std::vector<std::optional<OverviewRecord>> kept(records.size());
  std::size_t kept_vertices = 0;
  // Record k, as kept or read again (into `read`).
  const auto record = [&](std::size_t k, bool levels, OverviewRecord& read) -> const OverviewRecord& {
    if (kept[k]) return *kept[k];
    read = records.at(k, levels);
    return read;
  };
  Box2 extent;
  double outline_size = 0;  // the widest inferred outline (single-building clouds)
  std::size_t outlines = 0;
  for (std::size_t k = 0; k < records.size(); ++k) {
    OverviewRecord r = records.at(k, true);
    for (const Polygon2& p : r.footprint)
      for (const Point2& v : p.outer) extent.add(v);
    if (r.footprint.empty() && !r.lods.empty()) {
      Box2 box;
      for (const Ring2& ring : ground_rings(r.lods.back().model))
        for (const Point2& v : ring) box.add(v);
      if (!box.empty()) {
        outline_size = std::max({outline_size, box.max.x - box.min.x, box.max.y - box.min.y});
        ++outlines;
      }
    }
    const BuildingReport& b = r.report;
    const double unfaithful = (std::isfinite(b.unexplained_share) ? b.unexplained_share : 0.0) +
                              (std::isfinite(b.unsupported_area) && b.footprint_area > 0 ? b.unsupported_area / b.footprint_area : 0.0);
    keys[k] = {b.status == BuildingStatus::fallback || b.status == BuildingStatus::partial, unfaithful, b.rmse,
               r.lods.empty() ? 0 : r.lods.back().model.mesh.vertices.size(), !r.lods.empty()};
    std::size_t vertices = 0;
    for (const Polygon2& p : r.footprint) {
      vertices += p.outer.size();
      for (const Ring2& h : p.holes) vertices += h.size();
    }
    for (const CityGeometry& level : r.lods) vertices += level.model.mesh.vertices.size();
    if (k < kKeptRecords && kept_vertices + vertices <= kKeptVertexBudget) {
      kept_vertices += vertices;
      kept[k] = std::move(r);
    }
  }
  const bool have_footprints = !extent.empty();
  const Point2 corner = have_footprints ? Point2{std::floor(extent.min.x), std::floor(extent.min.y)} : Point2{0, 0};
  // Without footprints (single-building clouds, each in a frame of its own) the map shows the
  // outlines inferred from the points side by side: each centred in a cell of a grid, all at one
  // scale, in output order, row by row from the top.
  const bool inferred = !have_footprints && outlines > 0;
  const double cell = std::ceil(outline_size * 1.25 + 1.0);
  const std::size_t columns = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(std::sqrt(double(outlines)))));
  const std::size_t rows = (outlines + columns - 1) / std::max<std::size_t>(1, columns);

  std::string models = "[";
  std::size_t model_count = 0, vertex_budget = kModelVertexBudget;
  // Models of the worst buildings first (failed ones have none), then in order, within the budget.
  std::vector<std::size_t> order(records.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (keys[a].fallback != keys[b].fallback) return keys[a].fallback;
    if (keys[a].unfaithful != keys[b].unfaithful) return keys[a].unfaithful > keys[b].unfaithful;
    return keys[a].rmse > keys[b].rmse;
  });
  std::vector<long> model_of(records.size(), -1);
  for (std::size_t i : order) {
    if (!keys[i].model || keys[i].vertices > vertex_budget) continue;
    // Only the models shown are read again.
    OverviewRecord read;
    const OverviewRecord& r = record(i, true, read);
    const BuildingModel& m = r.lods.back().model;
    vertex_budget -= m.mesh.vertices.size();
    // Centred on the model's plan-view centre, floor at z = 0.
    Box3 box;
    for (const Point3& p : m.mesh.vertices) box.add(p);
    const Point3 c{(box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2, box.min.z};
    if (model_count) models += ',';
    models += "{\"lod\":";
    json_string(models, r.lods.back().lod);
    models += ",\"v\":[";
    for (std::size_t k = 0; k < m.mesh.vertices.size(); ++k) {
      const Point3& p = m.mesh.vertices[k];
      models += k ? ",[" : "[";
      json_number(models, p.x - c.x, 2);
      models += ',';
      json_number(models, p.y - c.y, 2);
      models += ',';
      json_number(models, p.z - c.z, 2);
      models += ']';
    }
    models += "],\"f\":[";
    for (std::size_t f = 0; f < m.mesh.faces.size(); ++f) {
      models += f ? ",[" : "[";
      for (std::size_t k = 0; k < m.mesh.faces[f].size(); ++k) models += (k ? "," : "") + std::to_string(m.mesh.faces[f][k]);
      models += ']';
    }
    models += "],\"s\":[";
    const std::vector<SurfaceType> types = surface_types(m);
    for (std::size_t f = 0; f < types.size(); ++f) models += (f ? "," : "") + std::to_string(static_cast<int>(types[f]));
    models += "]}";
    model_of[i] = static_cast<long>(model_count++);
  }
  models += ']';

  // The page, written as it is made: a row per record, one record at a time, then the models.
  detail::AtomicFile file(path);
  std::FILE* out = file.file();
  std::fputs(kPage1, out);
  std::string data = "{\"crs\":";
  json_string(data, crs);
  data += ",\"crs_source\":";
  json_string(data, run.crs_source);
  // The inputs and parameters are JSON objects already (made by nlohmann in the pipeline): only '<'
  // must not reach the page as it is, so that no "</script>" can appear.
  const auto safe = [](const std::string& json) {
    std::string out;
    for (char c : json) out += c == '<' ? std::string("\\u003c") : std::string(1, c);
    return out.empty() ? std::string("{}") : out;
  };
  data += ",\"inputs\":" + safe(run.inputs) + ",\"parameters\":" + safe(run.parameters);
  data += ",\"inferred\":" + std::string(inferred ? "true" : "false");
  data += ",\"version\":";
  json_string(data, CITY3D_VERSION);
  data += ",\"buildings\":[";
  std::fputs(data.c_str(), out);
  std::size_t placed = 0;  // inferred outlines laid out so far
  for (std::size_t i = 0; i < records.size(); ++i) {
    OverviewRecord read;
    const OverviewRecord& r = record(i, inferred, read);
    const BuildingReport& b = r.report;
    data.clear();
    if (i) data += ',';
    data += "\n{\"id\":";
    json_string(data, b.id);
    data += ",\"s\":";
    json_string(data, to_string(b.status));
    data += ",\"l\":";
    json_string(data, to_string(b.level));
    data += ",\"r\":";
    json_string(data, b.reason);
    data += ",\"n\":";
    json_string(data, b.note);
    data += ",\"lods\":";
    json_string(data, b.lods);
    data += ",\"rt\":";
    json_string(data, b.roof_type);
    data += ",\"rmse\":";
    json_number(data, b.rmse >= 0 ? b.rmse : NAN, 4);
    data += ",\"us\":";
    json_number(data, b.unexplained_share, 4);
    data += ",\"ua\":";
    json_number(data, b.unsupported_area, 2);
    data += ",\"he\":";
    json_number(data, b.height_excess, 2);
    data += ",\"fa\":";
    json_number(data, b.footprint_area, 2);
    data += ",\"f\":" + std::to_string(b.faces) + ",\"p\":" + std::to_string(b.points) + ",\"t\":";
    json_number(data, b.seconds, 3);
    data += ",\"h\":";
    json_number(data, b.h_roof_70p, 2);
    data += ",\"m\":" + std::to_string(model_of[i]) + ",\"fp\":[";
    bool first_ring = true;
    const auto add_ring = [&](const Ring2& ring) {
      if (!first_ring) data += ',';
      first_ring = false;
      data += '[';
      for (std::size_t k = 0; k < ring.size(); ++k) {
        data += k ? ",[" : "[";
        json_number(data, ring[k].x - corner.x, 2);
        data += ',';
        json_number(data, ring[k].y - corner.y, 2);
        data += ']';
      }
      data += ']';
    };
    for (const Polygon2& p : r.footprint) {
      add_ring(p.outer);
      for (const Ring2& h : p.holes) add_ring(h);
    }
    if (inferred && !r.lods.empty()) {
      std::vector<Ring2> rings = ground_rings(r.lods.back().model);
      Box2 box;
      for (const Ring2& ring : rings)
        for (const Point2& v : ring) box.add(v);
      if (!box.empty()) {
        // The centre of its cell, the grid's top row first (y grows upwards on the map).
        const double cx = (static_cast<double>(placed % columns) + 0.5) * cell;
        const double cy = (static_cast<double>(rows - 1 - placed / columns) + 0.5) * cell;
        const Point2 shift{cx - (box.min.x + box.max.x) / 2, cy - (box.min.y + box.max.y) / 2};
        for (Ring2& ring : rings) {
          for (Point2& v : ring) v = {v.x + shift.x, v.y + shift.y};
          add_ring(ring);
        }
        ++placed;
      }
    }
    data += "]}";
    std::fputs(data.c_str(), out);
  }
  std::fputs("],\"models\":", out);
  std::fputs(models.c_str(), out);
  std::fputs("}", out);
  std::fputs(kPage2, out);
  file.commit();
}

}  // namespace city3d
