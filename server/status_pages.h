#pragma once
// Server-rendered pages of one job and one batch, served by server/http_frontend.h at
// GET /jobs/<id> and GET /batches/<id>. Everything is in the HTML as sent (no script needed):
// state, progress bar, rates and ETA, errors, the live preview (an <img> of
// /api/jobs/<id>/preview.png), its tasks by state, the workers of this job with the tasks they
// hold and completed and their recent throughput on it, the convergence charts (MRSE against
// compute seconds and against spp, drawn by the batch report's chart code,
// core/report/batch_charts.h), the comparison viewer (core/report/comparison_viewer.h, the
// static report's) of the job's image and its reference; for a batch its methods, runs (linked
// to their job pages) and refusals, with the comparison viewer of its images when the reference
// is there. A page without the viewer refreshes itself every 2 seconds while its job or batch
// runs (<meta http-equiv="refresh">); a running job's or batch's page with the viewer does not (a
// refresh would reset the viewer) and links to its newer state instead.

#include <string>
#include <vector>

#include "core/image/chart.h"
#include "penumbra/v1/farm.pb.h"
#include "server/job_workers.h"

namespace penumbra::farm {

// `link_query` ("?token=..." URL-encoded, or empty) is appended to every link and image address
// the page holds, so a browser that came with its token in the address keeps it (see
// server/http_frontend.h).
//
// A job's page lists the workers that rendered or hold its tasks (`workers`, this job's counts:
// Coordinator::job_workers). Its comparison viewer (`viewer`): the section, or a note saying why
// there is none, or for a running job (whose page refreshes itself, which would reset the viewer)
// a link to the same page with the viewer, ?viewer=1, which then does not refresh.
struct JobPageViewer {
  std::string html;    // the viewer's section, or empty
  std::string note;    // why there is none
  bool offer = false;  // no viewer here: link to the page with it
};
std::string job_page_html(const v1::JobStatus& status, const std::string& link_query = "",
                          const std::vector<JobWorkerActivity>& workers = {},
                          const JobPageViewer& viewer = {});
// `viewer_html`: the viewer's section, or empty; `viewer_note` says why there is none.
std::string batch_page_html(const v1::BatchStatus& status, const std::string& viewer_html,
                            const std::string& viewer_note, const std::string& link_query = "");
// A small page for an error (404 and the like).
std::string error_page_html(int http_status, const std::string& message,
                            const std::string& link_query = "");

// A job's convergence charts, MRSE (full image) against compute seconds and against spp, from
// its pass-boundary curve: the batch report's charts (mrse_time_chart, mrse_spp_chart) of a
// batch of this one run. None when the curve is empty.
std::vector<ChartSpec> job_convergence_charts(const v1::JobStatus& status);
// A chart as SVG text, drawn by core/image/chart.h through a temporary file (removed).
std::string chart_svg(const ChartSpec& spec);

}  // namespace penumbra::farm
