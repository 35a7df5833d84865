#include "server/dashboard_page.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

namespace penumbra::farm {

namespace {

// The page. Everything the browser needs is here; the data comes from /api/* (JSON, polled
// every second). Text from the coordinator is inserted with textContent only (never as HTML).
constexpr std::string_view kPage = R"PAGE(<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>Penumbra farm</title>
<style>
  body { font: 14px/1.4 system-ui, sans-serif; margin: 1.2em; color: #222; background: #fafafa; }
  h1 { font-size: 1.3em; margin: 0 0 .3em 0; }
  h2 { font-size: 1.05em; margin: 1.2em 0 .4em 0; }
  #summary span { margin-right: 1.4em; }
  #summary b { font-variant-numeric: tabular-nums; }
  table { border-collapse: collapse; background: #fff; }
  th, td { padding: .25em .6em; border-bottom: 1px solid #ddd; text-align: left;
           font-variant-numeric: tabular-nums; white-space: nowrap; }
  tr.job { cursor: pointer; }
  tr.job.selected { background: #e8f0fe; }
  .bar { width: 160px; height: 10px; background: #e4e4e4; border-radius: 3px; overflow: hidden;
         display: inline-block; vertical-align: middle; }
  .bar > div { height: 100%; background: #3b7dd8; }
  .bar.done > div { background: #3a9a4a; }
  .bar.failed > div { background: #c33; }
  #detail { display: flex; gap: 1.5em; flex-wrap: wrap; align-items: flex-start; }
  #chart { background: #fff; border: 1px solid #ddd; }
  #chart .curve { fill: none; stroke: #3b7dd8; stroke-width: 2; }
  #chart .axis { stroke: #888; stroke-width: 1; }
  #chart text { font-size: 11px; fill: #555; }
  #preview { border: 1px solid #ddd; image-rendering: pixelated; min-width: 288px; max-width: 480px;
             background: #000; }
  .muted { color: #888; }
  #error { color: #c33; }
</style>
</head>
<body>
<h1>Penumbra farm</h1>
<div id="summary" class="muted">loading&hellip;</div>
<div id="error"></div>
<h2>Jobs</h2>
<table id="jobs">
  <thead><tr><th>job</th><th>name</th><th>scene</th><th>method</th><th>state</th>
    <th>progress</th><th>spp</th><th>MRSE</th><th>compute s</th></tr></thead>
  <tbody></tbody>
</table>
<h2 id="detail-title">Selected job</h2>
<div id="detail">
  <svg id="chart" width="480" height="300" viewBox="0 0 480 300"
       xmlns="http://www.w3.org/2000/svg"></svg>
  <div><img id="preview" alt="preview of the selected job"><div id="preview-note" class="muted"></div></div>
</div>
<h2>Workers</h2>
<table id="workers">
  <thead><tr><th>worker</th><th>name</th><th>threads</th><th>alive</th><th>load</th>
    <th>leased</th><th>completed</th><th>compute s</th><th>last heartbeat</th></tr></thead>
  <tbody></tbody>
</table>
<p class="muted">Updated <span id="updated">never</span>. Read-only; refreshes every second.</p>
<script>
"use strict";
const SVG = "http://www.w3.org/2000/svg";
let selected = null;        // job id the user clicked (or the one picked automatically)
let previewPasses = -1;     // passes of the preview on screen, to reload only when it changes
let previewJob = null;

function el(tag, attributes, ...children) {
  const node = tag.startsWith("svg:") ? document.createElementNS(SVG, tag.slice(4))
                                      : document.createElement(tag);
  for (const [key, value] of Object.entries(attributes || {})) node.setAttribute(key, value);
  for (const child of children)
    node.append(child instanceof Node ? child : document.createTextNode(String(child)));
  return node;
}
// A token in the page's address (?token=...) goes to the JSON API as a header; only images,
// which cannot carry headers, put it in their address.
const token = new URLSearchParams(location.search).get("token");
async function getJSON(url) {
  const headers = token ? {Authorization: "Bearer " + token} : {};
  const response = await fetch(url, {cache: "no-store", headers: headers});
  if (!response.ok) throw new Error(url + ": HTTP " + response.status);
  return response.json();
}
const num = (value) => Number(value || 0);
const stateName = (state) => String(state || "").replace("JOB_STATE_", "").toLowerCase();
const terminal = (state) => ["done", "failed", "cancelled"].includes(stateName(state));
function progress(job) {
  if (stateName(job.state) === "done") return 1;
  if (num(job.spp_budget) > 0) return Math.min(1, num(job.passes_complete) / num(job.spp_budget));
  if (num(job.seconds_budget) > 0)
    return Math.min(1, num(job.compute_seconds) / num(job.seconds_budget));
  return 0;
}
function bar(fraction, state) {
  const outer = el("div", {class: "bar " + stateName(state)});
  outer.append(el("div", {style: "width:" + (100 * fraction).toFixed(1) + "%"}));
  return outer;
}
function fixed(value, digits) { return num(value).toFixed(digits); }

function renderSummary(s) {
  const box = document.getElementById("summary");
  box.className = "";
  box.replaceChildren(
    el("span", {}, "queue depth ", el("b", {id: "queue-depth"}, s.queue_depth)),
    el("span", {}, "leased ", el("b", {}, s.leased_tasks)),
    el("span", {}, "tasks/s (1 min) ", el("b", {id: "tasks-per-second"}, fixed(s.tasks_per_second, 2))),
    el("span", {}, "completed ", el("b", {id: "tasks-completed"}, s.tasks_completed)),
    el("span", {}, "active workers ", el("b", {id: "workers-active"}, s.workers_active)),
    el("span", {}, "lease expiries ", el("b", {}, s.leases_expired)),
    el("span", {}, "late results ", el("b", {}, s.late_results)));
}

function renderJobs(jobs) {
  const body = document.querySelector("#jobs tbody");
  const rows = jobs.slice().reverse().map((job) => {
    const fraction = progress(job);
    const row = el("tr", {class: "job" + (job.job_id === selected ? " selected" : ""),
                          "data-job-id": job.job_id, "data-state": stateName(job.state),
                          "data-passes": num(job.passes_complete),
                          "data-progress": fraction.toFixed(4)},
      el("td", {}, job.job_id), el("td", {}, job.name), el("td", {}, job.scene_name),
      el("td", {}, job.method), el("td", {}, stateName(job.state)),
      el("td", {}, bar(fraction, job.state), " " + (100 * fraction).toFixed(0) + "%"),
      el("td", {}, num(job.passes_complete) + (num(job.spp_budget) ? " / " + job.spp_budget : "")),
      el("td", {}, job.has_mrse ? num(job.mrse).toExponential(3) : "\u2013"),
      el("td", {}, fixed(job.compute_seconds, 1)));
    row.addEventListener("click", () => { selected = job.job_id; tick(); });
    return row;
  });
  body.replaceChildren(...rows);
}

function renderWorkers(workers) {
  const body = document.querySelector("#workers tbody");
  body.replaceChildren(...workers.map((w) => {
    const load = num(w.threads) > 0 ? Math.min(1, num(w.tasks_leased) / num(w.threads)) : 0;
    return el("tr", {class: "worker", "data-worker-id": w.worker_id, "data-alive": String(!!w.alive)},
      el("td", {}, w.worker_id), el("td", {}, w.name), el("td", {}, num(w.threads)),
      el("td", {}, w.alive ? "yes" : "no"), el("td", {}, bar(load, w.alive ? "" : "failed")),
      el("td", {}, num(w.tasks_leased)), el("td", {}, num(w.tasks_completed)),
      el("td", {}, fixed(w.compute_seconds, 1)),
      el("td", {}, fixed(w.seconds_since_heartbeat, 1) + " s ago"));
  }));
}

// MRSE (log scale) against wall seconds since the job's first lease.
function renderChart(job) {
  const svg = document.getElementById("chart");
  const W = 480, H = 300, left = 56, right = 12, top = 14, bottom = 34;
  const points = (job.curve || []).filter((p) => num(p.mrse) > 0);
  const children = [
    el("svg:line", {class: "axis", x1: left, y1: H - bottom, x2: W - right, y2: H - bottom}),
    el("svg:line", {class: "axis", x1: left, y1: top, x2: left, y2: H - bottom}),
    el("svg:text", {x: (left + W - right) / 2, y: H - 6, "text-anchor": "middle"}, "wall seconds"),
    el("svg:text", {x: 12, y: (top + H - bottom) / 2, "text-anchor": "middle",
                    transform: "rotate(-90 12 " + (top + H - bottom) / 2 + ")"}, "MRSE (log)")];
  if (points.length === 0) {
    children.push(el("svg:text", {x: W / 2, y: H / 2, "text-anchor": "middle"},
      job.has_reference ? "no pass block sealed yet" : "no reference: no error curve"));
    svg.replaceChildren(...children);
    return;
  }
  const xs = points.map((p) => num(p.wall_seconds));
  const ys = points.map((p) => Math.log10(num(p.mrse)));
  const xMax = Math.max(...xs, 1e-3);
  let yMin = Math.min(...ys), yMax = Math.max(...ys);
  if (yMax - yMin < 0.1) { yMin -= 0.05; yMax += 0.05; }
  const sx = (x) => left + (W - left - right) * x / xMax;
  const sy = (y) => top + (H - top - bottom) * (yMax - y) / (yMax - yMin);
  const d = points.map((p, i) => (i ? "L" : "M") + sx(xs[i]).toFixed(1) + " " + sy(ys[i]).toFixed(1)).join(" ");
  children.push(el("svg:path", {class: "curve", d: d, "data-points": points.length}));
  for (let i = 0; i < points.length && points.length <= 200; ++i)
    children.push(el("svg:circle", {cx: sx(xs[i]).toFixed(1), cy: sy(ys[i]).toFixed(1), r: 2.5,
                                    fill: "#3b7dd8"}));
  children.push(el("svg:text", {x: left - 4, y: top + 4, "text-anchor": "end"}, Math.pow(10, yMax).toExponential(1)));
  children.push(el("svg:text", {x: left - 4, y: H - bottom, "text-anchor": "end"}, Math.pow(10, yMin).toExponential(1)));
  children.push(el("svg:text", {x: W - right, y: H - bottom + 14, "text-anchor": "end"}, xMax.toFixed(1)));
  svg.replaceChildren(...children);
}

function renderPreview(job) {
  const passes = num(job.passes_complete);
  const note = document.getElementById("preview-note");
  note.textContent = job.job_id + ": " + passes + " spp" + (terminal(job.state) ? "" : " so far");
  if (job.job_id === previewJob && passes === previewPasses) return;
  previewJob = job.job_id;
  previewPasses = passes;
  document.getElementById("preview").src =
      "/api/jobs/" + encodeURIComponent(job.job_id) + "/preview.png?passes=" + passes +
      (token ? "&token=" + encodeURIComponent(token) : "");
}

function pick(jobs) {
  if (selected && jobs.some((job) => job.job_id === selected)) return selected;
  const running = jobs.filter((job) => !terminal(job.state));
  const candidates = running.length ? running : jobs;
  return candidates.length ? candidates[candidates.length - 1].job_id : null;
}

let ticking = false;
async function tick() {
  if (ticking) return;
  ticking = true;
  try {
    const [summary, jobList, workerList] = await Promise.all(
      [getJSON("/api/summary"), getJSON("/api/jobs"), getJSON("/api/workers")]);
    const jobs = jobList.jobs || [];
    selected = pick(jobs);
    renderSummary(summary);
    renderJobs(jobs);
    renderWorkers(workerList.workers || []);
    if (selected) {
      const job = await getJSON("/api/jobs/" + encodeURIComponent(selected));
      document.getElementById("detail-title").textContent =
          "Job " + job.job_id + (job.name ? " (" + job.name + ")" : "") + ": " + job.method;
      renderChart(job);
      renderPreview(job);
    }
    document.getElementById("error").textContent = "";
    document.getElementById("updated").textContent = new Date().toLocaleTimeString();
  } catch (error) {
    document.getElementById("error").textContent = String(error);
  } finally {
    ticking = false;
  }
}
tick();
setInterval(tick, 1000);
</script>
</body>
</html>
)PAGE";

std::string escape_html(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string state_name(v1::JobState state) {
  std::string name = v1::JobState_Name(state);
  if (name.rfind("JOB_STATE_", 0) == 0) name = name.substr(10);
  for (char& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
  return name;
}

bool is_terminal(v1::JobState state) {
  return state == v1::JOB_STATE_DONE || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED;
}

// The script's progress(): passes for an spp budget, compute seconds for a seconds budget.
double progress(const v1::JobStatus& job) {
  if (job.state() == v1::JOB_STATE_DONE) return 1;
  if (job.spp_budget() > 0) return std::min(1.0, double(job.passes_complete()) / job.spp_budget());
  if (job.seconds_budget() > 0) return std::min(1.0, job.compute_seconds() / job.seconds_budget());
  return 0;
}

std::string bar(double fraction, const std::string& state) {
  char text[160];
  std::snprintf(text, sizeof text, "<div class=\"bar %s\"><div style=\"width:%.1f%%\"></div></div>",
                state.c_str(), 100 * fraction);
  return text;
}

std::string cell(const std::string& text) {
  return "<td>" + escape_html(text) + "</td>";
}

std::string fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", digits, value);
  return text;
}

void replace_once(std::string& page, const std::string& from, const std::string& to,
                  size_t& from_position) {
  size_t at = page.find(from, from_position);
  if (at == std::string::npos) return;
  page.replace(at, from.size(), to);
  from_position = at + to.size();
}

}  // namespace

std::string_view dashboard_page() {
  return kPage;
}

std::string dashboard_page(const DashboardSnapshot& snapshot) {
  std::string page(kPage);
  int active = 0;
  for (const v1::WorkerInfo& worker : snapshot.workers) active += worker.alive();
  // The job the script would select first.
  const v1::JobStatus* selected = nullptr;
  for (const v1::JobStatus& job : snapshot.jobs)
    if (!is_terminal(job.state())) selected = &job;
  if (!selected && !snapshot.jobs.empty()) selected = &snapshot.jobs.back();

  std::string summary = "<div id=\"summary\"><span>queue depth <b id=\"queue-depth\">" +
                        std::to_string(snapshot.queue_depth) + "</b></span><span>leased <b>" +
                        std::to_string(snapshot.leased_tasks) +
                        "</b></span><span>completed <b id=\"tasks-completed\">" +
                        std::to_string(snapshot.tasks_completed) +
                        "</b></span><span>active workers <b id=\"workers-active\">" +
                        std::to_string(active) + "</b></span></div>";
  std::string jobs;
  for (auto it = snapshot.jobs.rbegin(); it != snapshot.jobs.rend(); ++it) {
    const v1::JobStatus& job = *it;
    const double fraction = progress(job);
    const std::string state = state_name(job.state());
    char mrse[32] = "\u2013";
    if (job.has_mrse()) std::snprintf(mrse, sizeof mrse, "%.3e", job.mrse());
    jobs += "<tr class=\"job" + std::string(selected == &job ? " selected" : "") +
            "\" data-job-id=\"" + escape_html(job.job_id()) + "\" data-state=\"" + state +
            "\" data-passes=\"" + std::to_string(job.passes_complete()) + "\" data-progress=\"" +
            fixed(fraction, 4) + "\">" + cell(job.job_id()) + cell(job.name()) +
            cell(job.scene_name()) + cell(job.method()) + cell(state) + "<td>" +
            bar(fraction, state) + " " + fixed(100 * fraction, 0) + "%</td>" +
            cell(std::to_string(job.passes_complete()) +
                 (job.spp_budget() ? " / " + std::to_string(job.spp_budget()) : "")) +
            cell(mrse) + cell(fixed(job.compute_seconds(), 1)) + "</tr>\n";
  }
  std::string workers;
  for (const v1::WorkerInfo& worker : snapshot.workers) {
    const double load =
        worker.threads() > 0 ? std::min(1.0, double(worker.tasks_leased()) / worker.threads()) : 0;
    workers +=
        "<tr class=\"worker\" data-worker-id=\"" + escape_html(worker.worker_id()) +
        "\" data-alive=\"" + (worker.alive() ? "true" : "false") + "\">" +
        cell(worker.worker_id()) + cell(worker.name()) + cell(std::to_string(worker.threads())) +
        cell(worker.alive() ? "yes" : "no") + "<td>" + bar(load, worker.alive() ? "" : "failed") +
        "</td>" + cell(std::to_string(worker.tasks_leased())) +
        cell(std::to_string(worker.tasks_completed())) + cell(fixed(worker.compute_seconds(), 1)) +
        cell(fixed(worker.seconds_since_heartbeat(), 1) + " s ago") + "</tr>\n";
  }
  size_t at = 0;
  replace_once(page, "<div id=\"summary\" class=\"muted\">loading&hellip;</div>", summary, at);
  replace_once(page, "<tbody></tbody>", "<tbody>\n" + jobs + "</tbody>", at);
  if (selected) {
    replace_once(page, "<h2 id=\"detail-title\">Selected job</h2>",
                 "<h2 id=\"detail-title\">Job " + escape_html(selected->job_id()) +
                     (selected->name().empty() ? "" : " (" + escape_html(selected->name()) + ")") +
                     ": " + escape_html(selected->method()) + "</h2>",
                 at);
    replace_once(page, "<img id=\"preview\"",
                 "<img id=\"preview\" src=\"/api/jobs/" + escape_html(selected->job_id()) +
                     "/preview.png?passes=" + std::to_string(selected->passes_complete()) +
                     (snapshot.token_parameter.empty()
                          ? ""
                          : "&amp;token=" + escape_html(snapshot.token_parameter)) +
                     "\"",
                 at);
  }
  replace_once(page, "<tbody></tbody>", "<tbody>\n" + workers + "</tbody>", at);
  replace_once(page, "<span id=\"updated\">never</span>",
               "<span id=\"updated\">" + escape_html(snapshot.updated) + "</span>", at);
  return page;
}

}  // namespace penumbra::farm
