#pragma once
// The coordinator's read-only dashboard: one self-contained HTML page (inline CSS and JS, no
// external resources) served at GET / by server/http_frontend.h. Its script polls the JSON API
// every second and draws jobs with progress bars, the selected job's MRSE-against-time chart
// (inline SVG), its live preview image, and the workers with their load.
//
// Elements the tests look for: tr.job[data-job-id][data-state][data-passes][data-progress],
// svg#chart path.curve[data-points], img#preview, tr.worker[data-worker-id], #updated.

#include <string>
#include <string_view>
#include <vector>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

// The page as a template (its tables empty, filled by the script).
std::string_view dashboard_page();

// What the page shows before its script has run (or without JavaScript at all).
struct DashboardSnapshot {
  std::vector<v1::JobStatus> jobs;  // by id
  std::vector<v1::WorkerInfo> workers;
  uint64_t queue_depth = 0, leased_tasks = 0, tasks_completed = 0;
  std::string updated;  // the time of the snapshot, for people
  // The page's token as its address carried it (URL-encoded; empty: none): the preview image's
  // address carries it too (the script sends it to the JSON API as a header).
  std::string token_parameter;
};

// The page with the snapshot rendered into it on the server: the summary, the job and worker
// rows (the same elements the script draws), and the preview of the job the script would pick
// (the newest unfinished one, else the newest). Text is HTML-escaped.
std::string dashboard_page(const DashboardSnapshot& snapshot);

}  // namespace penumbra::farm
