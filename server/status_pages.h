#pragma once
// Server-rendered pages of one job and one batch, served by server/http_frontend.h at
// GET /jobs/<id> and GET /batches/<id>. Everything is in the HTML as sent (no script needed):
// state, progress bar, rates and ETA, errors, the live preview (an <img> of
// /api/jobs/<id>/preview.png), the MRSE-against-time chart as inline SVG, and for a batch its
// methods, runs (linked to their job pages) and refusals, with the comparison viewer
// (core/report/comparison_viewer.h) of its images when the reference is there. A page whose job
// or batch still runs refreshes itself every 2 seconds (<meta http-equiv="refresh">).

#include <string>

#include "penumbra/v1/farm.pb.h"

namespace penumbra::farm {

//
// `link_query` ("?token=..." URL-encoded, or empty) is appended to every link and image address
// the page holds, so a browser that came with its token in the address keeps it (see
// server/http_frontend.h).
std::string job_page_html(const v1::JobStatus& status, const std::string& link_query = "");
// `viewer_html`: the viewer's section, or empty; `viewer_note` says why there is none.
std::string batch_page_html(const v1::BatchStatus& status, const std::string& viewer_html,
                            const std::string& viewer_note, const std::string& link_query = "");
// A small page for an error (404 and the like).
std::string error_page_html(int http_status, const std::string& message,
                            const std::string& link_query = "");

// The MRSE curve as an inline SVG (log-log MRSE against compute seconds); empty without two
// positive points.
std::string mrse_chart_svg(const v1::JobStatus& status, int width = 480, int height = 260);

}  // namespace penumbra::farm
