#pragma once
// The coordinator's read-only dashboard: one self-contained HTML page (inline CSS and JS, no
// external resources) served at GET / by server/http_frontend.h. Its script polls the JSON API
// every second and draws jobs with progress bars, the selected job's MRSE-against-time chart
// (inline SVG), its live preview image, and the workers with their load.
//
// Elements the tests look for: tr.job[data-job-id][data-state][data-passes][data-progress],
// svg#chart path.curve[data-points], img#preview, tr.worker[data-worker-id], #updated.

#include <string_view>

namespace penumbra::farm {

std::string_view dashboard_page();

}  // namespace penumbra::farm
